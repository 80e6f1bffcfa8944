# Shared by the VM tests: Debian's kernel with the modules marionette needs,
# and a busybox initramfs with the marionette binary and its libraries.
# Expects $bin (the binary) and $cache (kernel cache folder).

for tool in qemu-system-x86_64 cpio python3; do
    command -v "$tool" >/dev/null || { echo "vm test: $tool is missing: apt-get install qemu-system-x86 busybox-static cpio python3" >&2; exit 69; }
done
busybox=/bin/busybox
linkage=$(ldd "$busybox" 2>&1 || true)
if [ ! -x "$busybox" ] || [[ "$linkage" != *"not a dynamic executable"* ]]; then
    echo "vm test: a static busybox is needed at $busybox: apt-get install busybox-static" >&2
    exit 69
fi
[ -x "$bin" ] || { echo "vm test: $bin not built (cargo build)" >&2; exit 66; }

# The kernel modules, in load order: evdev and uinput, and virtio-gpu with
# what it needs (a real KMS device).
modules="evdev uinput virtio_ring virtio virtio_pci_modern_dev virtio_pci_legacy_dev virtio_pci drm drm_kms_helper drm_shmem_helper virtio_dma_buf virtio-gpu"
# And for a root file system on a virtio disk (ext4), in load order.
root_modules="virtio_blk crc16 mbcache jbd2 crc32c_generic ext4"

# Fetch the kernel and the modules into $kcache (once): Debian's
# (bookworm), or with an argument the kernel of that suite
# (bookworm-backports: 6.12, whose virtio core is built in and which has
# udmabuf). Modules a kernel has built in are left out of $modules.
vm_kernel() {
    local suite=${1:-}
    kcache=$cache${suite:+/kernel-$suite}
    mkdir -p "$kcache"
    if [ -f "$kcache/vmlinuz" ] && [ -f "$kcache/modules" ]; then
        modules=$(cat "$kcache/modules")
        return
    fi
    local pkg tmp f m kept=""
    # awk reads to the end (leaving early would end apt-cache with
    # SIGPIPE, an exit status of 141 under pipefail).
    pkg=$(apt-cache depends ${suite:+-t "$suite"} linux-image-amd64 | awk '/Depends: linux-image-[0-9]/ && !found {found = $2} END {print found}')
    [ -n "$pkg" ] || { echo "vm test: cannot find Debian's kernel package${suite:+ in $suite} (apt-get update first)" >&2; exit 69; }
    tmp=$(mktemp -d)
    (cd "$tmp" && apt-get download ${suite:+-t "$suite"} "$pkg" >/dev/null 2>&1) || { echo "vm test: cannot download $pkg" >&2; exit 69; }
    dpkg -x "$tmp"/*.deb "$tmp/x"
    for m in $modules $root_modules; do
        f=$(find "$tmp/x/lib/modules" -name "$m.ko*" -print -quit)
        if [ -z "$f" ]; then
            grep -q "/$m\.ko$" "$tmp"/x/lib/modules/*/modules.builtin \
                || { echo "vm test: $pkg has no $m module" >&2; exit 69; }
            continue   # built in
        fi
        case " $modules " in *" $m "*) kept="$kept $m" ;; esac
        case "$f" in
            *.xz) xz -dc "$f" > "$kcache/$m.ko" ;;
            *.zst) zstd -qdc "$f" > "$kcache/$m.ko" ;;
            *) cp "$f" "$kcache/$m.ko" ;;
        esac
    done
    cp "$tmp"/x/boot/vmlinuz-* "$kcache/vmlinuz"
    modules=${kept# }
    echo "$modules" > "$kcache/modules"
    rm -rf "$tmp"
}

# Mesa 25's lavapipe and the libdrm it needs, from bookworm-backports, into
# $cache/mesa25 (once).
vm_mesa_backport() {
    local tmp
    [ -f "$cache/mesa25/libvulkan_lvp.so" ] && [ -f "$cache/mesa25/libdrm.so.2" ] && return
    tmp=$(mktemp -d)
    if ! (cd "$tmp" && apt-get download -t bookworm-backports mesa-vulkan-drivers libdrm2 >/dev/null 2>&1); then
        rm -rf "$tmp"
        echo "vm test: the zero-copy run needs Mesa 25's lavapipe from bookworm-backports:" >&2
        echo "  echo 'deb http://deb.debian.org/debian bookworm-backports main' > /etc/apt/sources.list.d/backports.list && apt-get update" >&2
        exit 69
    fi
    for d in "$tmp"/*.deb; do dpkg -x "$d" "$tmp/x"; done
    mkdir -p "$cache/mesa25"
    cp -L "$tmp"/x/usr/lib/x86_64-linux-gnu/libvulkan_lvp.so "$tmp"/x/usr/lib/x86_64-linux-gnu/libdrm.so.2 "$cache/mesa25/"
    rm -rf "$tmp"
}

# Copy a binary or library and the shared libraries it needs, at their own
# paths, into the initramfs $1.
vm_copy_with_libs() {
    local ird=$1 file=$2 lib
    mkdir -p "$ird$(dirname "$file")"
    cp -L "$file" "$ird$file"
    ldd "$file" | awk '/=> \// {print $3} /^\t\// {print $1}' | while read -r lib; do
        [ -f "$ird$lib" ] && continue
        mkdir -p "$ird$(dirname "$lib")"
        cp -L "$lib" "$ird$lib"
    done
}

# The initramfs tree in $1: busybox, marionette (as /bin/marionette) with
# its libraries, the modules and their load order.
vm_initrd_base() {
    local ird=$1 m
    mkdir -p "$ird"/{bin,dev,proc,sys,tmp,modules}
    cp "$busybox" "$ird/bin/busybox"
    vm_copy_with_libs "$ird" "$bin"
    # Without debug information the guest needs far less memory.
    if command -v strip >/dev/null; then
        strip --strip-debug -o "$ird/bin/marionette" "$ird$bin"
        rm "$ird$bin"
    else
        mv "$ird$bin" "$ird/bin/marionette"
    fi
    for m in $modules; do cp "$kcache/$m.ko" "$ird/modules/"; done
    echo "$modules" > "$ird/modules/order"
}

# The demo recording's first 3.2 s into $1: a finger takes the left hand
# and drags it (the panel goes away with the finger still down).
vm_demo_drag() {
    python3 - "$root/assets/recordings/demo.evemu" "$1" <<'PY'
import sys
out = []
for line in open(sys.argv[1]):
    if line.startswith("E:") and float(line.split()[1]) > 3.2:
        break
    out.append(line)
open(sys.argv[2], "w").writelines(out)
PY
}
