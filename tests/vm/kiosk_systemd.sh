#!/usr/bin/env bash
# The kiosk as an operator installs it: a Debian guest (debootstrap,
# cached) with the package built by systemd/deb/build.sh installed with
# apt and the unit enabled, as the README says, booted with systemd under
# qemu (TCG, no network, virtio-vga display). Checked from the host:
# - the service reaches READY on KMS (active, the character on screen);
# - `marionette play` drags the character through a uinput panel, the
#   panel goes away and comes back and drags it again;
# - killing the process gets it restarted by systemd;
# - stopping the service is clean (exit 0, within its timeout);
# - the journal holds the kiosk's log;
# - the record of visits (/var/lib/marionette/visits.db) survives a hard
#   reset of the guest in the middle of a drag: booted again, it opens,
#   SQLite's integrity_check says ok, and it holds every row it held two
#   seconds before the reset.
#
# usage: tests/vm/kiosk_systemd.sh   (as root: debootstrap, chroot)
# env:   MARIONETTE_BIN (default target/release/marionette, else debug),
#        MARIONETTE_VM_CACHE (default target/vm-cache), MARIONETTE_VM_OUT
# needs: apt-get install qemu-system-x86 busybox-static cpio python3
#        debootstrap e2fsprogs
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=${MARIONETTE_BIN:-$root/target/release/marionette}
[ -x "$bin" ] || bin=$root/target/debug/marionette
cache=${MARIONETTE_VM_CACHE:-$root/target/vm-cache}
[ "$(id -u)" = 0 ] || { echo "vm test: run as root (debootstrap and chroot need it)" >&2; exit 77; }
for tool in debootstrap mke2fs chroot; do
    command -v "$tool" >/dev/null || { echo "vm test: $tool is missing: apt-get install debootstrap e2fsprogs" >&2; exit 69; }
done
. "$here/common.sh"
vm_kernel

# The Debian guest, once.
base="$cache/rootfs-bookworm"
if [ ! -f "$base/.complete" ]; then
    rm -rf "$base"
    echo "vm test: debootstrap of the guest (cached in $base)..." >&2
    debootstrap --variant=minbase \
        --include=systemd,systemd-sysv,udev,kmod,mesa-vulkan-drivers,libvulkan1,libgbm1,libdrm2 \
        bookworm "$base" http://deb.debian.org/debian >"$cache/debootstrap.log" 2>&1 \
        || { tail -n 20 "$cache/debootstrap.log" >&2; echo "vm test: debootstrap failed" >&2; exit 69; }
    touch "$base/.complete"
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rootfs="$work/rootfs"
cp -a "$base" "$rootfs"

# Installed as the operator's guide's "Installing a kiosk" says: the package built
# (from the binary under test), `apt install`ed, the unit enabled (started
# when the guest boots: a chroot runs no services).
deb=$(MARIONETTE_DEB_BIN="$bin" bash "$root/systemd/deb/build.sh" | tail -n 1)
cp "$root/$deb" "$rootfs/root/"
chroot "$rootfs" sh -c "cd /root && apt install -y ./$(basename "$deb")" >"$work/apt.log" 2>&1 \
    || { cat "$work/apt.log" >&2; echo "vm test: the package does not install" >&2; exit 1; }
rm "$rootfs/root/$(basename "$deb")"
chroot "$rootfs" systemctl enable marionette.service
for f in /usr/bin/marionette /lib/systemd/system/marionette.service /etc/marionette/marionette.toml \
         /usr/share/marionette/library/library.toml /usr/share/marionette/recordings/demo.evemu \
         /usr/share/doc/marionette/README.md /usr/share/doc/marionette/docs/operator.md; do
    [ -e "$rootfs$f" ] || { echo "vm test: the package did not install $f" >&2; exit 1; }
done
chroot "$rootfs" id -nG marionette | grep -qw render \
    || { echo "vm test: the marionette user lacks its groups" >&2; exit 1; }
mkdir -p "$rootfs/etc/systemd/system/multi-user.target.wants"
# Test only: the CPU renderer is quicker with 128-bit vectors under TCG.
mkdir -p "$rootfs/etc/systemd/system/marionette.service.d"
printf '[Service]\nEnvironment=LP_NATIVE_VECTOR_WIDTH=128\n' \
    > "$rootfs/etc/systemd/system/marionette.service.d/tcg.conf"
# No login prompt on the serial console the host reads.
ln -sf /dev/null "$rootfs/etc/systemd/system/serial-getty@ttyS0.service"

# The checks, run in the guest as a service of their own.
vm_demo_drag "$rootfs/root/drag.evemu"
cat > "$rootfs/usr/local/bin/kiosk-check" <<'CHECK'
#!/bin/sh
say() { echo "$*" > /dev/ttyS0; }
state() { systemctl show -p "$1" --value marionette.service; }
up() { cut -d' ' -f1 /proc/uptime | cut -d. -f1; }
hand_over() {
    for f in "$@"; do
        say "=== BEGIN $f"; cat /tmp/$f > /dev/ttyS0; say "=== END $f"
    done
}
report() {
    journalctl -u marionette.service --no-pager -o short-monotonic > /tmp/journal.txt 2>&1
    systemctl status --no-pager marionette.service > /tmp/status.txt 2>&1
    hand_over rc journal.txt status.txt play1.log play2.log
    systemctl poweroff --force
    exit 0
}
visits() {
    marionette report --db /var/lib/marionette/visits.db --since all --out /tmp/$1 > /tmp/$1.txt 2>&1
    echo "report rc=$?" >> /tmp/$1.txt
    cp /tmp/$1/report.json /tmp/$1.json 2>/dev/null || echo '{}' > /tmp/$1.json
}
# Booted again after the hard reset: what the record holds now.
if grep -qw kiosk_check=after-reset /proc/cmdline; then
    sleep 5
    visits after
    hand_over after.txt after.json
    systemctl poweroff --force
    exit 0
fi
# Wait (at most $2 seconds of uptime) until `$1` holds.
until_up() {
    limit=$(( $(up) + $2 ))
    while ! eval "$1"; do
        [ "$(up)" -lt "$limit" ] || return 1
        sleep 1
    done
}
until_up '[ "$(state ActiveState)" = active ]' 240 || { echo "never active: $(state ActiveState) $(state SubState)" >> /tmp/rc; report; }
echo "active=$(state ActiveState) sub=$(state SubState) at $(up) s" >> /tmp/rc
sleep 4; say "MARK sd-ready"; sleep 2
marionette play /root/drag.evemu --settle-ms 800 2> /tmp/play1.log &
sleep 2; say "MARK sd-posed1"; sleep 1; say "MARK sd-posed2"; sleep 1; say "MARK sd-posed3"
wait $!; echo "play1 rc=$?" >> /tmp/rc
# The finger has lifted and the pose holds: a last look, for a CPU renderer
# whose first frame with overlays came after the grabs above.
sleep 1; say "MARK sd-posed4"
sleep 3; say "MARK sd-before-replug"; sleep 2
marionette play /root/drag.evemu --settle-ms 800 2> /tmp/play2.log &
sleep 2; say "MARK sd-replugged1"; sleep 1; say "MARK sd-replugged2"; sleep 1; say "MARK sd-replugged3"
wait $!; echo "play2 rc=$?" >> /tmp/rc
sleep 1; say "MARK sd-replugged4"
old=$(state MainPID)
echo "killing $old at $(up) s" >> /tmp/rc
kill -KILL "$old"
sleep 3
until_up '[ "$(state NRestarts)" = 1 ] && [ "$(state ActiveState)" = active ]' 240 \
    || echo "no restart: NRestarts=$(state NRestarts) $(state ActiveState) $(state SubState)" >> /tmp/rc
echo "restarts=$(state NRestarts) active=$(state ActiveState) pid $old -> $(state MainPID) at $(up) s" >> /tmp/rc
sleep 4; say "MARK sd-restarted"; sleep 1
t0=$(cut -d' ' -f1 /proc/uptime); systemctl stop marionette.service; t1=$(cut -d' ' -f1 /proc/uptime)
echo "stop took $t0 $t1 result=$(state Result) status=$(state ExecMainStatus)" >> /tmp/rc
# A hard reset in the middle of a drag (no sync: the kernel's reboot, as
# a power cut), two seconds after the record was read.
systemctl start marionette.service
until_up '[ "$(state ActiveState)" = active ]' 240 || echo "not active again" >> /tmp/rc
sleep 2
marionette play /root/drag.evemu --settle-ms 800 2> /tmp/play3.log; echo "play3 rc=$?" >> /tmp/rc
sleep 3
visits before
sleep 2
marionette play /root/drag.evemu --settle-ms 800 2> /tmp/play4.log &
sleep 3
journalctl -u marionette.service --no-pager -o short-monotonic > /tmp/journal.txt 2>&1
systemctl status --no-pager marionette.service > /tmp/status.txt 2>&1
echo "hard reset at $(up) s" >> /tmp/rc
hand_over rc journal.txt status.txt play1.log play2.log before.txt before.json
echo b > /proc/sysrq-trigger
sleep 30
CHECK
chmod 755 "$rootfs/usr/local/bin/kiosk-check"
cat > "$rootfs/etc/systemd/system/kiosk-check.service" <<'UNIT'
[Unit]
Description=checks the kiosk for the VM test
After=marionette.service
[Service]
ExecStart=/usr/local/bin/kiosk-check
[Install]
WantedBy=multi-user.target
UNIT
ln -s /etc/systemd/system/kiosk-check.service "$rootfs/etc/systemd/system/multi-user.target.wants/"

mke2fs -q -t ext4 -d "$rootfs" "$work/root.img" 3G
rm -rf "$rootfs"

# A small initramfs: the modules, then the disk as root and systemd.
ird="$work/initrd"
mkdir -p "$ird"/{bin,dev,proc,sys,newroot,modules}
cp "$busybox" "$ird/bin/busybox"
for m in $modules $root_modules; do cp "$kcache/$m.ko" "$ird/modules/"; done
echo "$modules $root_modules" > "$ird/modules/order"
cat > "$ird/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for k in $(cat /modules/order); do insmod /modules/$k.ko 2>/dev/null; done
mount -t ext4 /dev/vda /newroot || { echo "cannot mount the root disk"; poweroff -f; }
umount /proc /sys
mount --move /dev /newroot/dev
exec switch_root /newroot /sbin/init
INIT
chmod +x "$ird/init"
(cd "$ird" && find . | cpio -o -H newc --quiet | gzip -1 > "$work/initrd.gz")

out=${MARIONETTE_VM_OUT:-$work/out}
mkdir -p "$out"
python3 "$here/systemd_vm.py" "$work" "$kcache/vmlinuz" "$out"
