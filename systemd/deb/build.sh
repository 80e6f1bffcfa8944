#!/usr/bin/env bash
# Build the Debian package: target/debian/marionette_VERSION_ARCH.deb.
#
#   bash systemd/deb/build.sh     (then, as root: apt install ./target/debian/marionette_*.deb)
#
# It holds the release binary (/usr/bin/marionette), the unit
# (/lib/systemd/system/marionette.service), the configuration
# (/etc/marionette/marionette.toml, a conffile: an edited one is kept on
# upgrade), the default library and the bundled recordings
# (/usr/share/marionette/{library,recordings}) and the documentation
# (/usr/share/doc/marionette). Its maintainer scripts make the `marionette`
# system user with the input, video and render groups. Needs dpkg-deb
# (dpkg, on every Debian) and cargo.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
command -v dpkg-deb >/dev/null || { echo "deb: dpkg-deb is missing: apt-get install dpkg" >&2; exit 69; }
version=$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)
arch=$(dpkg --print-architecture)
[ -n "$version" ] || { echo "deb: no version in Cargo.toml" >&2; exit 1; }
# MARIONETTE_DEB_BIN packages a binary built already (the VM test's).
bin=${MARIONETTE_DEB_BIN:-}
if [ -z "$bin" ]; then
    cargo build --release --locked
    bin=target/release/marionette
fi
[ -x "$bin" ] || { echo "deb: $bin is missing" >&2; exit 1; }

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
pkg="$stage/marionette"
install -d "$pkg/DEBIAN" "$pkg/usr/bin" "$pkg/lib/systemd/system" "$pkg/etc/marionette" \
    "$pkg/usr/share/marionette" "$pkg/usr/share/doc/marionette"
strip --strip-debug -o "$pkg/usr/bin/marionette" "$bin"
chmod 755 "$pkg/usr/bin/marionette"
install -m 644 systemd/marionette.service "$pkg/lib/systemd/system/marionette.service"
install -m 644 config/marionette.toml "$pkg/etc/marionette/marionette.toml"
cp -r assets/library "$pkg/usr/share/marionette/library"
install -d "$pkg/usr/share/marionette/recordings"
install -m 644 assets/recordings/*.evemu "$pkg/usr/share/marionette/recordings/"
install -m 644 ARCHITECTURE.md "$pkg/usr/share/doc/marionette/"
install -m 644 systemd/README.md "$pkg/usr/share/doc/marionette/README.systemd.md"
install -m 644 README.md "$pkg/usr/share/doc/marionette/README.md"
install -d "$pkg/usr/share/doc/marionette/docs"
install -m 644 docs/*.md "$pkg/usr/share/doc/marionette/docs/"
cat > "$pkg/usr/share/doc/marionette/copyright" <<COPYRIGHT
Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/
Upstream-Name: marionette
License: MIT OR Apache-2.0

Files: *
License: MIT OR Apache-2.0
COPYRIGHT
find "$pkg/usr/share/marionette" -type d -exec chmod 755 {} +
find "$pkg/usr/share/marionette" -type f -exec chmod 644 {} +
for s in postinst prerm postrm; do
    install -m 755 "systemd/deb/$s" "$pkg/DEBIAN/$s"
done
echo /etc/marionette/marionette.toml > "$pkg/DEBIAN/conffiles"
size=$(du -sk --exclude=DEBIAN "$pkg" | cut -f1)
cat > "$pkg/DEBIAN/control" <<CONTROL
Package: marionette
Version: $version
Architecture: $arch
Maintainer: marionette developers <marionette@localhost>
Installed-Size: $size
Depends: libc6, libgcc-s1, libgbm1, libvulkan1, mesa-vulkan-drivers, passwd, systemd
Section: misc
Priority: optional
Description: touch-table kiosk: drag a 3-D character to pose it and act
 Visitors drag a 3-D character's body parts with their fingers: it takes
 natural poses and performs whole actions in the visitor's own style
 (example-based posture synthesis). Runs fullscreen on the KMS display
 under systemd, reading multitouch panels through evdev.
CONTROL
mkdir -p target/debian
out="target/debian/marionette_${version}_${arch}.deb"
dpkg-deb --root-owner-group -Zxz --build "$pkg" "$out" >/dev/null
echo "$out"
