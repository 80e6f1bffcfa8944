#!/usr/bin/env bash
# The kiosk on real KMS and real evdev.
#
# Boots Debian's kernel (bookworm-backports' 6.12) under qemu (TCG, no
# network) with a virtio-vga display at 640x360 (a small picture keeps the
# CPU renderer quick under emulation) and a busybox initramfs holding
# marionette, Mesa's lavapipe (Debian's 22.3, and 25.0 from backports) and
# the demo recording's first seconds. Inside, `marionette run` drives the
# display (frames rendered offscreen, written into gbm's buffers, page
# flips); `marionette play` recreates the demo panel through uinput and
# drags the character's hand, the panel goes away (unplug) and comes back
# as a new node (replug) and drags again; then SIGTERM. The host grabs the
# screen through QMP at marks the guest prints and checks that the picture
# shows the character, that it moved under the fingers both times, and
# that the kiosk stopped cleanly within a second. Then the service view on
# dumb buffers, calibration, the kiosk on lavapipe 25.0 drawing straight
# into gbm's buffers (zero copy: their dma-bufs imported into Vulkan), the
# frame's cost with and without the copy, and kiosks that cannot start.
#
# usage: tests/vm/kiosk_kms.sh
# env:   MARIONETTE_BIN (default target/debug/marionette),
#        MARIONETTE_VM_CACHE (kernel cache, default target/vm-cache),
#        MARIONETTE_VM_OUT (keep the screens and logs there)
# needs: qemu-system-x86_64, busybox (static), cpio, python3, Mesa's
#        lavapipe: apt-get install qemu-system-x86 busybox-static cpio
#        python3 mesa-vulkan-drivers libvulkan1
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=${MARIONETTE_BIN:-$root/target/debug/marionette}
cache=${MARIONETTE_VM_CACHE:-$root/target/vm-cache}

icd=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
# awk reads to the end: leaving early would end ldconfig with SIGPIPE,
# which pipefail turns into this script's exit status (141).
loader=$(ldconfig -p | awk '/libvulkan\.so\.1 / && !found {found = $NF} END {print found}')
if [ ! -f "$icd" ] || [ -z "$loader" ]; then
    echo "vm test: lavapipe is needed: apt-get install mesa-vulkan-drivers libvulkan1" >&2
    exit 69
fi
. "$here/common.sh"
# bookworm-backports' kernel (6.12): its udmabuf lets lavapipe import
# dma-bufs (the zero-copy run below).
vm_kernel bookworm-backports
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ird="$work/initrd"
vm_initrd_base "$ird"
# Vulkan: the loader, lavapipe and what they load.
vm_copy_with_libs "$ird" "$loader"
lvp=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["ICD"]["library_path"])' "$icd")
vm_copy_with_libs "$ird" "$lvp"
mkdir -p "$ird$(dirname "$icd")"
cp "$icd" "$ird$icd"
# Mesa's gbm (libgbm, linked by marionette, comes with it) and the DRI
# drivers it opens the card with: virtio-gpu's, and the software KMS one
# it falls back to on a card without 3D.
# (Where Mesa's loader looks for them: /usr/lib/<multiarch>/dri.)
dri=/usr/lib/x86_64-linux-gnu/dri
for d in kms_swrast_dri.so virtio_gpu_dri.so; do
    [ -f "$dri/$d" ] || { echo "vm test: $dri/$d is missing: apt-get install libgl1-mesa-dri" >&2; exit 69; }
    vm_copy_with_libs "$ird" "$dri/$d"
done
# A newer lavapipe (Mesa 25, bookworm-backports) that imports dma-bufs
# (VK_EXT_external_memory_dma_buf, VK_EXT_image_drm_format_modifier): with
# it the kiosk renders straight into gbm's scanout buffers (zero copy).
# At /opt/mesa25 with the libdrm it needs; the other kiosk runs keep
# Debian's lavapipe 22.3, which offers neither (gbm copy).
vm_mesa_backport
mkdir -p "$ird/opt/mesa25"
cp -L "$cache/mesa25/libvulkan_lvp.so" "$cache/mesa25/libdrm.so.2" "$ird/opt/mesa25/"
# Its other libraries are Debian's (LLVM 15, as lavapipe 22.3's).
LD_LIBRARY_PATH="$cache/mesa25" ldd "$cache/mesa25/libvulkan_lvp.so" | awk '/=> \// {print $3}' | while read -r lib; do
    case "$lib" in "$cache"/*) continue ;; esac
    [ -f "$ird$lib" ] || { mkdir -p "$ird$(dirname "$lib")"; cp -L "$lib" "$ird$lib"; }
done
printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "/opt/mesa25/libvulkan_lvp.so", "api_version": "1.3.0"}}\n' > "$ird/opt/mesa25/lvp_icd.json"
# The motion library the kiosk loads (next to the binary's source tree is
# not in the guest).
mkdir -p "$ird/library"
cp "$root"/assets/library/* "$ird/library/"
vm_demo_drag "$ird/drag.evemu"
# Taps on the five calibration targets of a panel that is off: its raw
# positions map to the screen through [1.05 0 -0.03; 0 0.95 0.02], which
# `marionette calibrate` must find.
python3 - "$root/assets/recordings/demo.evemu" "$ird/taps.evemu" <<'PY'
import sys
head = [l for l in open(sys.argv[1]) if l[:2] in ("# ", "N:", "I:", "P:", "B:", "A:")]
targets = [(0.1, 0.1), (0.9, 0.1), (0.9, 0.9), (0.1, 0.9), (0.5, 0.5)]
ev, t = [], 0.0
def e(t, typ, code, val):
    ev.append(f"E: {t:.6f} {typ:04x} {code:04x} {val:04d}\n")
for k, (sx, sy) in enumerate(targets):
    x = round((sx + 0.03) / 1.05 * 4095)
    y = round((sy - 0.02) / 0.95 * 4095)
    t += 1.2
    e(t, 3, 0x39, k + 1); e(t, 3, 0x35, x); e(t, 3, 0x36, y)
    e(t, 1, 0x14a, 1); e(t, 3, 0, x); e(t, 3, 1, y); e(t, 0, 0, 0)
    t += 0.6
    e(t, 3, 0x39, -1); e(t, 1, 0x14a, 0); e(t, 0, 0, 0)
open(sys.argv[2], "w").writelines(head + ev)
PY
cat > "$ird/m.toml" <<'TOML'
[character]
library = "/library"
[input]
rescan_interval_ms = 100
grab = true
[kiosk]
metrics_textfile = "/tmp/marionette.prom"
[display]
status_line = false
TOML
cat > "$ird/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin HOME=/tmp XDG_RUNTIME_DIR=/tmp XDG_CACHE_HOME=/tmp/cache
export VK_DRIVER_FILES=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json
# 128-bit vectors: emulated AVX is slow under TCG.
export LP_NATIVE_VECTOR_WIDTH=128
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for k in $(cat /modules/order); do insmod /modules/$k.ko; done
m="marionette --config /m.toml"
# The direct presenter forced where the driver (lavapipe) cannot: one
# clear line and exit 69, no panic, the display left as it was.
{ cat /m.toml; echo 'presenter = "direct"'; } > /direct.toml   # [display] is last
marionette --config /direct.toml run --seconds 20 > /tmp/direct.log 2>&1
echo "direct rc=$?" >> /tmp/rc
$m run > /tmp/run.log 2>&1 &
pid=$!
i=0
while ! grep -q "first frame on screen" /tmp/run.log; do
    sleep 0.5; i=$((i + 1))
    if [ $i -gt 400 ] || ! kill -0 $pid 2>/dev/null; then break; fi
done
echo "ready after $i half-seconds" >> /tmp/rc
sleep 3; echo "MARK rest"; sleep 2
$m play /drag.evemu --settle-ms 800 2> /tmp/play1.log &
sleep 2; echo "MARK posed1"; sleep 1; echo "MARK posed2"; sleep 1; echo "MARK posed3"
wait $!; echo "play1 rc=$?" >> /tmp/rc
# The finger has lifted and the pose holds: a last look, for a CPU renderer
# whose first frame with overlays came after the grabs above.
sleep 1; echo "MARK posed4"
sleep 3; echo "MARK before-replug"; sleep 2
$m play /drag.evemu --settle-ms 800 2> /tmp/play2.log &
sleep 2; echo "MARK replugged1"; sleep 1; echo "MARK replugged2"; sleep 1; echo "MARK replugged3"
wait $!; echo "play2 rc=$?" >> /tmp/rc
sleep 1; echo "MARK replugged4"
sleep 1
read up0 rest < /proc/uptime
kill -TERM $pid
wait $pid; echo "run rc=$?" >> /tmp/rc
read up1 rest < /proc/uptime
echo "stop took $up0 $up1" >> /tmp/rc
# On-screen calibration of the panel, touched through uinput.
cp /m.toml /m.orig.toml
$m calibrate --device "marionette demo panel" --timeout 60 > /tmp/cal.out 2> /tmp/cal.log &
cal=$!
sleep 1
$m play /taps.evemu --settle-ms 1500 2> /tmp/play3.log &
sleep 5; echo "MARK calibrating"
wait $!; echo "play3 rc=$?" >> /tmp/rc
wait $cal; echo "calibrate rc=$?" >> /tmp/rc
cp /m.toml /tmp/m.toml
cmp -s /m.toml.bak /m.orig.toml && echo "backup kept" >> /tmp/rc
# The service view on: the panel's name, the figures and the finger's
# trail over the scene.
# (With the dumb buffers of the copy presenter: `auto` took gbm above.)
{ cat /m.orig.toml; echo 'service_view = true'; echo 'presenter = "copy"'; } > /svc.toml   # [display] is last
marionette --config /svc.toml run --seconds 60 > /tmp/svc.log 2>&1 &
svc=$!
# Under emulation the start takes seconds: drag once the first frame is up.
i=0
while ! grep -q "first frame on screen" /tmp/svc.log; do
    sleep 0.5; i=$((i + 1))
    if [ $i -gt 60 ] || ! kill -0 $svc 2>/dev/null; then break; fi
done
sleep 1
$m play /drag.evemu --settle-ms 800 2> /tmp/play4.log &
sleep 2; echo "MARK service"
wait $!; sleep 1; kill -TERM $svc; wait $svc; echo "service rc=$?" >> /tmp/rc
# Zero copy: with Mesa 25's lavapipe, `auto` renders straight into gbm's
# scanout buffers (dma-bufs imported into Vulkan); dragged as above (its
# metrics in a file of their own).
sed 's#/tmp/marionette.prom#/tmp/zc.prom#' /m.orig.toml > /zc.toml
RUST_LOG=info,wgpu_hal=warn VK_DRIVER_FILES=/opt/mesa25/lvp_icd.json LD_LIBRARY_PATH=/opt/mesa25 \
    marionette --config /zc.toml run > /tmp/zc.log 2>&1 &
zc=$!
i=0
while ! grep -q "first frame on screen" /tmp/zc.log; do
    sleep 0.5; i=$((i + 1))
    if [ $i -gt 200 ] || ! kill -0 $zc 2>/dev/null; then break; fi
done
sleep 3; echo "MARK zc-rest"; sleep 2
$m play /drag.evemu --settle-ms 800 2> /tmp/play5.log &
sleep 2; echo "MARK zc-posed1"; sleep 1; echo "MARK zc-posed2"; sleep 1; echo "MARK zc-posed3"
wait $!; echo "play5 rc=$?" >> /tmp/rc
sleep 1; echo "MARK zc-posed4"
sleep 1; kill -TERM $zc; wait $zc; echo "zero copy rc=$?" >> /tmp/rc
# The frame's cost at rest on one lavapipe (Mesa 25): drawn straight into
# gbm's buffers, and copied into dumb buffers.
{ cat /zc.toml; echo 'presenter = "copy"'; } > /zcc.toml   # [display] is last
for run in zcr zcc; do
    cfg=/zc.toml; [ $run = zcc ] && cfg=/zcc.toml
    VK_DRIVER_FILES=/opt/mesa25/lvp_icd.json LD_LIBRARY_PATH=/opt/mesa25 \
        marionette --config $cfg run --seconds 25 > /tmp/$run.log 2>&1
    echo "$run rc=$?" >> /tmp/rc
done
# A library folder that does not exist: the reason on the display for
# kiosk.error_screen_s, then exit 78.
printf '[character]\nlibrary = "/no-such-library"\n[kiosk]\nerror_screen_s = 8\n[display]\nstatus_line = false\n' > /bad.toml
marionette --config /bad.toml run > /tmp/bad.log 2>&1 &
bad=$!
sleep 4; echo "MARK cannot-start"
wait $bad; echo "bad library rc=$?" >> /tmp/rc
# A character mesh that is no glTF: the reason on the display, then 65.
printf 'glTF\002\000\000\000' > /bad.glb
printf '[character]\nlibrary = "/library"\nmesh = "/bad.glb"\n[kiosk]\nerror_screen_s = 2\n[display]\nstatus_line = false\n' > /badmesh.toml
marionette --config /badmesh.toml run > /tmp/badmesh.log 2>&1; echo "bad mesh rc=$?" >> /tmp/rc
cp /tmp/marionette.prom /tmp/prom.txt 2>/dev/null
for f in rc direct.log run.log play1.log play2.log cal.out cal.log m.toml bad.log badmesh.log svc.log prom.txt zc.log play5.log zcr.log zcc.log; do
    echo "=== BEGIN $f"; cat /tmp/$f; echo "=== END $f"
done
poweroff -f
INIT
chmod +x "$ird/init"
(cd "$ird" && find . | cpio -o -H newc --quiet | gzip -1 > "$work/initrd.gz")

out=${MARIONETTE_VM_OUT:-$work/out}
mkdir -p "$out"
python3 "$here/kiosk_vm.py" "$work" "$kcache/vmlinuz" "$out"
