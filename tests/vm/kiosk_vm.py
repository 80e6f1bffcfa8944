"""Boot the kiosk guest, grab its screen at the marks it prints, check.

usage: kiosk_vm.py WORK VMLINUZ OUT
WORK holds initrd.gz; screens (PPM) and the guest's logs go to OUT.
"""

import json
import os
import re
import socket
import subprocess
import sys
import time

work, kernel, out = sys.argv[1:4]
console = os.path.join(work, "console.log")
qmp_path = os.path.join(work, "qmp.sock")
open(console, "w").close()

qemu = subprocess.Popen(
    [
        "qemu-system-x86_64", "-accel", "tcg", "-cpu", "max", "-m", "2048",
        "-smp", "2", "-nic", "none", "-display", "none",
        "-device", "virtio-vga,xres=640,yres=360",
        "-serial", f"file:{console}", "-monitor", "none", "-no-reboot",
        "-qmp", f"unix:{qmp_path},server=on,wait=off",
        "-kernel", kernel, "-initrd", os.path.join(work, "initrd.gz"),
        "-append", "console=ttyS0 quiet panic=-1 rdinit=/init",
    ]
)


def qmp_connect():
    for _ in range(100):
        try:
            s = socket.socket(socket.AF_UNIX)
            s.connect(qmp_path)
            f = s.makefile("rw")
            json.loads(f.readline())  # greeting
            f.write(json.dumps({"execute": "qmp_capabilities"}) + "\n")
            f.flush()
            json.loads(f.readline())
            return f
        except OSError:
            time.sleep(0.1)
    raise SystemExit("vm test: cannot reach qemu's QMP socket")


def screendump(f, path):
    f.write(json.dumps({"execute": "screendump", "arguments": {"filename": path}}) + "\n")
    f.flush()
    while True:
        reply = json.loads(f.readline())
        if "return" in reply or "error" in reply:
            return reply


qmp = qmp_connect()
seen = 0
marks = []
deadline = time.time() + 600
while qemu.poll() is None and time.time() < deadline:
    text = open(console, errors="replace").read().replace("\r", "")
    for name in re.findall(r"^MARK (\S+)$", text, re.M)[seen:]:
        path = os.path.join(out, f"{name}.ppm")
        reply = screendump(qmp, path)
        marks.append(name)
        print(f"screen '{name}' grabbed: {reply}", flush=True)
    seen = len(marks)
    time.sleep(0.1)
if qemu.poll() is None:
    qemu.kill()
    raise SystemExit("vm test: the guest ran out of time; console:\n" + open(console, errors="replace").read()[-4000:])

text = open(console, errors="replace").read().replace("\r", "")
for name, body in re.findall(r"=== BEGIN (\S+)\n(.*?)=== END \1", text, re.S):
    open(os.path.join(out, name), "w").write(body)
if not os.path.exists(os.path.join(out, "rc")):
    raise SystemExit("vm test: the guest did not report back; console:\n" + text[-4000:])


def ppm(path):
    data = open(path, "rb").read()
    parts = data.split(maxsplit=4)
    assert parts[0] == b"P6", parts[0]
    w, h = int(parts[1]), int(parts[2])
    pixels = parts[4][: w * h * 3]
    return w, h, pixels


def bluish(px):
    # The character's shirt: blue well above red.
    return sum(
        1 for i in range(0, len(px), 3) if px[i + 2] > 120 and px[i + 2] > px[i] + 50
    )


def differ(a, b):
    return sum(
        1
        for i in range(0, len(a), 3)
        if abs(a[i] - b[i]) + abs(a[i + 1] - b[i + 1]) + abs(a[i + 2] - b[i + 2]) > 60
    )


failures = []
rc = open(os.path.join(out, "rc")).read()
log = open(os.path.join(out, "run.log")).read()
print(rc)
for want in ["play1 rc=0", "play2 rc=0", "run rc=0"]:
    if want not in rc:
        failures.append(f"expected '{want}' in the guest's exit codes")
m = re.search(r"stop took (\S+) (\S+)", rc)
if not m or float(m.group(2)) - float(m.group(1)) > 1.0:
    failures.append(f"SIGTERM should stop the kiosk within 1 s: {m and m.groups()}")
for want in ["presenter=\"copy\"", "first frame on screen", "touchscreen added",
             "touchscreen removed", "stopped"]:
    if want not in log:
        failures.append(f"expected '{want}' in the kiosk's log")
if log.count("touchscreen added") < 2:
    failures.append("the replugged panel was not picked up again")
screens = {}
for name in ["rest", "posed1", "posed2", "posed3", "before-replug",
             "replugged1", "replugged2", "replugged3"]:
    path = os.path.join(out, f"{name}.ppm")
    if not os.path.exists(path):
        failures.append(f"no screen grabbed at '{name}'")
        continue
    w, h, px = ppm(path)
    if (w, h) != (640, 360):
        failures.append(f"{name}: screen is {w}x{h}, not 640x360")
    screens[name] = px
if "rest" in screens:
    blue = bluish(screens["rest"])
    print(f"rest: {blue} shirt-blue pixels")
    if blue < 700:
        failures.append(f"the character is not on screen at rest ({blue} shirt pixels)")
# The CPU renderer is slow under emulation: of three grabs while the
# finger drags, the most changed counts.
for a, b in [("rest", "posed"), ("before-replug", "replugged")]:
    changed = [differ(screens[a], screens[f"{b}{k}"])
               for k in (1, 2, 3) if a in screens and f"{b}{k}" in screens]
    print(f"{a} -> {b}1..3: {changed} pixels changed")
    if max(changed, default=0) < 500:
        failures.append(f"the character did not move under the finger ({a} -> {b}: {changed} pixels)")
# Calibration: the matrix found is the panel's, the old file kept.
for want in ["play3 rc=0", "calibrate rc=0", "backup kept"]:
    if want not in rc:
        failures.append(f"calibration: expected '{want}' in the guest's exit codes")
cal = open(os.path.join(out, "m.toml")).read() if os.path.exists(os.path.join(out, "m.toml")) else ""
print(open(os.path.join(out, "cal.out")).read() if os.path.exists(os.path.join(out, "cal.out")) else "no calibrate output")
m = re.search(r'match_name = "marionette demo panel"\s*\ncalibration = \[([^\]]*)\]', cal)
if not m:
    failures.append("calibration: no [[input.device]] entry written:\n" + cal[-800:])
else:
    got = [float(v) for v in m.group(1).split(",")]
    want = [1.05, 0.0, -0.03, 0.0, 0.95, 0.02]
    if any(abs(g - w) > 0.01 for g, w in zip(got, want)):
        failures.append(f"calibration: matrix {got}, expected about {want}")
if failures:
    print("kiosk log:\n" + log[-3000:])
    raise SystemExit("vm test failed:\n  " + "\n  ".join(failures))
print("kiosk on KMS: ok")
