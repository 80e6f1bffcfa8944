#!/usr/bin/env bash
# Real kernel, real evdev, real uinput.
#
# Boots Debian's kernel under qemu (TCG, no network) with a busybox
# initramfs. Inside, `marionette watch` reads the touchscreens through evdev
# while `marionette play` recreates a recorded panel with uinput and replays
# it, twice: the panel disappears when the first play ends (unplug) and comes
# back as a new node with the second (replug). Then a burst of events that
# overflows the reader's buffer (a real SYN_DROPPED, resynchronised with
# EVIOCGMTSLOTS), a panel unplugged with two fingers down, and
# `marionette record` of the panel while it plays. On the host, what watch saw
# is compared with `marionette replay --contacts` of the same recording.
#
# usage: tests/vm/input_uinput.sh [RECORDING.evemu]
# env:   MARIONETTE_BIN (default target/debug/marionette),
#        MARIONETTE_VM_CACHE (kernel cache, default target/vm-cache)
# needs: qemu-system-x86_64, busybox (static), cpio, python3
#        apt-get install qemu-system-x86 busybox-static cpio python3
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin=${MARIONETTE_BIN:-$root/target/debug/marionette}
cache=${MARIONETTE_VM_CACHE:-$root/target/vm-cache}
rec=${1:-$root/../shared/recordings/evemu/atmel-maxtouch.4-finger-drag-down.evemu}

[ -f "$rec" ] || { echo "vm test: recording $rec not found" >&2; exit 66; }
. "$here/common.sh"
vm_kernel
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ird="$work/initrd"
vm_initrd_base "$ird"
cp "$rec" "$ird/rec.evemu"
cp "$root/tests/data/burst-overflow.evemu" "$ird/burst.evemu"
cp "$root/tests/data/unplug-mid-drag.evemu" "$ird/middrag.evemu"
cat > "$ird/m.toml" <<'TOML'
[input]
rescan_interval_ms = 100
grab = true
TOML
cat > "$ird/init" <<'INIT'
#!/bin/busybox sh
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc; mount -t sysfs sys /sys; mount -t devtmpfs dev /dev
for k in $(cat /modules/order); do insmod /modules/$k.ko; done
m="marionette --config /m.toml"
# The virtio-vga display as a KMS device.
$m list-outputs --json > /tmp/outputs.txt 2>&1; echo "outputs rc=$?" >> /tmp/rc
$m watch --seconds 12 > /tmp/watch.jsonl 2> /tmp/watch.log &
watcher=$!
sleep 1
$m play /rec.evemu --settle-ms 600 2> /tmp/play1.log; echo "play1 rc=$?" >> /tmp/rc
sleep 1
$m play /rec.evemu --settle-ms 600 2> /tmp/play2.log &
sleep 0.3
$m list-devices > /tmp/list.txt 2>&1; echo "list rc=$?" >> /tmp/rc
wait $!; echo "play2 rc=$?" >> /tmp/rc
sleep 1
# A burst that overflows the reader's buffer: SYN_DROPPED, resync from the kernel.
$m play /burst.evemu --settle-ms 600 2> /tmp/play3.log; echo "play3 rc=$?" >> /tmp/rc
sleep 1
# A panel that disappears with two fingers down.
$m play /middrag.evemu --settle-ms 600 2> /tmp/play4.log; echo "play4 rc=$?" >> /tmp/rc
wait $watcher; echo "watch rc=$?" >> /tmp/rc
# Record the panel while it plays (watch has let go of its grab by now).
$m play /rec.evemu --settle-ms 1200 2> /tmp/play5.log &
player=$!
sleep 0.5
$m record --out /tmp/recorded.evemu --seconds 3 2> /tmp/record.log; echo "record rc=$?" >> /tmp/rc
wait $player; echo "play5 rc=$?" >> /tmp/rc
for f in rc outputs.txt list.txt watch.log play1.log play2.log play3.log play4.log record.log recorded.evemu watch.jsonl; do
    echo "=== BEGIN $f"; cat /tmp/$f; echo "=== END $f"
done
poweroff -f
INIT
chmod +x "$ird/init"
(cd "$ird" && find . | cpio -o -H newc --quiet | gzip -1 > "$work/initrd.gz")

# The guest CPU as tests/vm/vmlib.py says it (LLVM 15 reads qemu 10's "max"
# as a 32-bit CPU).
timeout 300 qemu-system-x86_64 -accel tcg -cpu max,vendor=GenuineIntel,family=6,model=60,stepping=3 -m 1024 -smp 1 -nic none -display none \
    -device virtio-vga \
    -serial "file:$work/console.log" -monitor none -no-reboot \
    -kernel "$kcache/vmlinuz" -initrd "$work/initrd.gz" \
    -append "console=ttyS0 quiet panic=-1 rdinit=/init" || true

out=${MARIONETTE_VM_OUT:-$work/out}
mkdir -p "$out"
python3 - "$work/console.log" "$out" <<'PY'
import re, sys
text = open(sys.argv[1], errors="replace").read().replace("\r", "")
for name, body in re.findall(r"=== BEGIN (\S+)\n(.*?)=== END \1", text, re.S):
    open(f"{sys.argv[2]}/{name}", "w").write(body)
PY
if [ ! -f "$out/watch.jsonl" ]; then
    echo "vm test: the guest did not report back; console:" >&2
    tail -n 40 "$work/console.log" >&2
    exit 1
fi
"$bin" replay "$rec" --contacts > "$out/expected.jsonl"
"$bin" replay "$root/tests/data/burst-overflow.evemu" --contacts > "$out/expected-burst.jsonl"
"$bin" replay "$out/recorded.evemu" --contacts > "$out/recorded.jsonl" || true
python3 "$here/check_watch.py" "$out"
