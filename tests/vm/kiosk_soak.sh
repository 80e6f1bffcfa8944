#!/usr/bin/env bash
# The real kiosk for ten minutes under a uinput stream, its resident memory
# and open descriptors read from /proc every 10 s.
#
# The guest of kiosk_kms.sh (Debian's kernel under qemu, virtio-vga, a
# busybox initramfs with marionette and lavapipe) runs `marionette run`
# and, until SOAK_S seconds have passed, plays the demo's hand drag through
# uinput again and again (each play is a panel plugged, dragged and
# unplugged). The host checks that after a two-minute warm-up resident
# memory grew by at most 4 MB, that once the plays stop the kiosk holds no
# more descriptors than the fewest it held after warm-up (a sample taken
# while a panel is plugged counts that panel's; after the plays, the fewest
# of ten counts), and that it stopped cleanly.
#
# usage: tests/vm/kiosk_soak.sh
# env:   MARIONETTE_BIN (default target/debug/marionette; a release build
#        keeps up better under emulation), MARIONETTE_VM_CACHE,
#        MARIONETTE_VM_OUT, SOAK_S (default 600)
# needs: as kiosk_kms.sh: apt-get install qemu-system-x86 busybox-static
#        cpio python3 mesa-vulkan-drivers libvulkan1
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=${MARIONETTE_BIN:-$root/target/debug/marionette}
cache=${MARIONETTE_VM_CACHE:-$root/target/vm-cache}
soak_s=${SOAK_S:-600}

icd=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
loader=$(ldconfig -p | awk '/libvulkan\.so\.1 / && !found {found = $NF} END {print found}')
if [ ! -f "$icd" ] || [ -z "$loader" ]; then
    echo "vm test: lavapipe is needed: apt-get install mesa-vulkan-drivers libvulkan1" >&2
    exit 69
fi
. "$here/common.sh"
vm_kernel
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ird="$work/initrd"
vm_initrd_base "$ird"
vm_copy_with_libs "$ird" "$loader"
lvp=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["ICD"]["library_path"])' "$icd")
vm_copy_with_libs "$ird" "$lvp"
mkdir -p "$ird$(dirname "$icd")"
cp "$icd" "$ird$icd"
mkdir -p "$ird/library"
cp "$root"/assets/library/* "$ird/library/"
vm_demo_drag "$ird/drag.evemu"
cat > "$ird/m.toml" <<'TOML'
[character]
library = "/library"
[input]
rescan_interval_ms = 100
grab = true
[kiosk]
visits = "/tmp/visits.db"
[display]
status_line = false
TOML
echo "$soak_s" > "$ird/soak_s"
cat > "$ird/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin HOME=/tmp XDG_RUNTIME_DIR=/tmp XDG_CACHE_HOME=/tmp/cache
export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
export LP_NATIVE_VECTOR_WIDTH=128
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for k in $(cat /modules/order); do insmod /modules/$k.ko; done
m="marionette --config /m.toml"
$m run > /tmp/run.log 2>&1 &
pid=$!
i=0
while ! grep -q "first frame on screen" /tmp/run.log; do
    sleep 0.5; i=$((i + 1))
    if [ $i -gt 400 ] || ! kill -0 $pid 2>/dev/null; then break; fi
done
echo "ready after $i half-seconds" >> /tmp/rc
read start rest < /proc/uptime
soak=$(cat /soak_s)
plays=0
# The drags, one after another, in the background of the sampling.
# The loop ends at the end of a play, once /tmp/stop exists, so that no
# panel is left plugged when the last descriptors are counted.
( while [ ! -e /tmp/stop ]; do $m play /drag.evemu --settle-ms 300 2>> /tmp/play.log || echo "play failed" >> /tmp/rc; done ) &
player=$!
while :; do
    read now rest < /proc/uptime
    el=$(awk -v a="$start" -v b="$now" 'BEGIN {printf "%d", b - a}')
    rss=$(awk '/^VmRSS/ {print $2}' /proc/$pid/status 2>/dev/null)
    fds=$(ls /proc/$pid/fd 2>/dev/null | wc -l)
    echo "sample $el $rss $fds" >> /tmp/rss
    [ "$el" -ge "$soak" ] && break
    kill -0 $pid 2>/dev/null || break
    sleep 10
done
touch /tmp/stop; wait $player; sleep 2
# Descriptors with no panel plugged: the host compares them with the
# fewest seen after warm-up (a sample taken mid-play counts the panel's).
# The fewest of ten counts half a second apart: a descriptor open for a
# moment (a rescan reading /dev/input, the last unplug not yet read by a
# kiosk slowed by emulation) is not a leak, and a leaked one is in all ten.
fds=
for i in 1 2 3 4 5 6 7 8 9 10; do
    n=$(ls /proc/$pid/fd 2>/dev/null | wc -l)
    if [ -z "$fds" ] || [ "$n" -lt "$fds" ]; then fds=$n; fi
    sleep 0.5
done
echo "final $fds" >> /tmp/rss
read up0 rest < /proc/uptime
kill -TERM $pid
wait $pid; echo "run rc=$?" >> /tmp/rc
read up1 rest < /proc/uptime
echo "stop took $up0 $up1" >> /tmp/rc
grep -c "touchscreen added" /tmp/run.log | sed 's/^/panels added /' >> /tmp/rc
for f in rc rss run.log; do
    echo "=== BEGIN $f"; cat /tmp/$f; echo "=== END $f"
done
poweroff -f
INIT
chmod +x "$ird/init"
(cd "$ird" && find . | cpio -o -H newc --quiet | gzip -1 > "$work/initrd.gz")
out=${MARIONETTE_VM_OUT:-$work/out}
mkdir -p "$out"
python3 "$here/soak_vm.py" "$work" "$kcache/vmlinuz" "$out" "$soak_s"
