"""Boot the kiosk guest, grab its screen at the marks it prints, check.

usage: kiosk_vm.py WORK VMLINUZ OUT
WORK holds initrd.gz; screens (PPM) and the guest's logs go to OUT.
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vmlib import bluish, boot, check_moved, ppm  # noqa: E402

work, kernel, out = sys.argv[1:4]
text = boot(work, out, [
    "-kernel", kernel, "-initrd", os.path.join(work, "initrd.gz"),
    "-append", "console=ttyS0 quiet panic=-1 rdinit=/init",
])
if not os.path.exists(os.path.join(out, "rc")):
    raise SystemExit("vm test: the guest did not report back; console:\n" + text[-4000:])

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
for want in ["direct presenter is not available here", "presenter: gbm (chosen automatically)",
             "presenter=\"gbm\"", "first frame on screen", "touchscreen added",
             "touchscreen removed", "stopped", "no touchscreen is read"]:
    if want not in log:
        failures.append(f"expected '{want}' in the kiosk's log")
# presenter = "direct" where the driver cannot: exit 69 with the reason.
direct = open(os.path.join(out, "direct.log")).read() if os.path.exists(os.path.join(out, "direct.log")) else ""
print("forced direct: " + (direct.strip().splitlines() or ["(no output)"])[-1])
if "direct rc=69" not in rc:
    failures.append("presenter = \"direct\" on lavapipe should exit 69")
if "Vulkan cannot drive the display directly" not in direct:
    failures.append("presenter = \"direct\" on lavapipe should say why:\n" + direct[-1500:])
for name, text in [("forced direct", direct), ("kiosk", log)]:
    if "panicked" in text:
        failures.append(f"{name}: a panic:\n" + text[-1500:])
if log.count("touchscreen added") < 2:
    failures.append("the replugged panel was not picked up again")
screens = {}
for name in ["rest", "posed1", "posed2", "posed3", "posed4", "before-replug",
             "replugged1", "replugged2", "replugged3", "replugged4"]:
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
for a, b in [("rest", "posed"), ("before-replug", "replugged")]:
    check_moved(screens, a, b, failures)
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
# The metrics textfile, in Prometheus text format.
prom = open(os.path.join(out, "prom.txt")).read() if os.path.exists(os.path.join(out, "prom.txt")) else ""
# Two starts wrote it: the kiosk, then the service view run, which read
# the count back.
for want in ["marionette_starts_total 2", "marionette_touchscreens ", "marionette_fps "]:
    if want not in prom:
        failures.append(f"expected '{want}' in the metrics textfile:\n" + prom[-800:])
# The service view ran on dumb buffers (presenter = "copy").
svc = open(os.path.join(out, "svc.log")).read() if os.path.exists(os.path.join(out, "svc.log")) else ""
for want in ["presenter: copy (as configured)", "presenter=\"copy\""]:
    if want not in svc:
        failures.append(f"expected '{want}' in the service view run's log")
# The copy's cost: into gbm's buffers (the kiosk) and into dumb buffers
# (the service view), the same output and picture size.
costs = {}
for name, text in [("gbm", log), ("dumb", svc)]:
    m = re.search(r'buffers="' + name + r'" frames=(\d+) copy_ms_mean=([0-9.]+)', text)
    if m:
        costs[name] = float(m.group(2))
        print(f"copy into {name} buffers: {float(m.group(2)):.3f} ms a frame over {m.group(1)} frames")
    else:
        failures.append(f"no copy cost said for the {name} buffers")
if len(costs) == 2:
    ratio = costs["gbm"] / max(costs["dumb"], 1e-9)
    print(f"gbm / dumb copy: {ratio:.2f}")
    if ratio > 1.5:
        failures.append(f"the copy through gbm costs {ratio:.2f} times the copy through dumb buffers")
# The service view: its cyan text and the finger's trail on the screen.
if "service rc=0" not in rc:
    failures.append("the kiosk with the service view should run and stop cleanly")
path = os.path.join(out, "service.ppm")
if not os.path.exists(path):
    failures.append("no screen grabbed at 'service'")
else:
    w, h, px = ppm(path)
    cyan = sum(1 for i in range(0, len(px), 3) if px[i + 1] > 200 and px[i + 2] > 200 and px[i + 1] > px[i] + 60)
    print(f"service: {cyan} cyan pixels")
    if cyan < 400:
        failures.append(f"service view: no panel or trail on the screen ({cyan} cyan pixels)")
# A kiosk that cannot start says why on the display, then exits 78.
if "bad library rc=78" not in rc:
    failures.append("a missing library folder should exit 78 after the error screen")
bad = open(os.path.join(out, "bad.log")).read() if os.path.exists(os.path.join(out, "bad.log")) else ""
if "the reason is on the display" not in bad:
    failures.append("the error screen was not shown:\n" + bad[-1500:])
# So does one whose character mesh is broken, with the file and reason.
if "bad mesh rc=65" not in rc:
    failures.append("a broken character mesh should exit 65 after the error screen")
badmesh = open(os.path.join(out, "badmesh.log")).read() if os.path.exists(os.path.join(out, "badmesh.log")) else ""
if "bad.glb: not a glTF 2.0 file" not in badmesh or "the reason is on the display" not in badmesh:
    failures.append("the broken mesh was not reported on the display:\n" + badmesh[-1500:])
path = os.path.join(out, "cannot-start.ppm")
if not os.path.exists(path):
    failures.append("no screen grabbed at 'cannot-start'")
else:
    w, h, px = ppm(path)
    # Warm title and hint text and light reason text on the dark screen.
    warm = sum(1 for i in range(0, len(px), 3) if px[i] > 200 and 80 < px[i + 1] < 230 and px[i + 2] < 150)
    light = sum(1 for i in range(0, len(px), 3) if px[i] > 200 and px[i + 1] > 200 and px[i + 2] > 200)
    dark = sum(1 for i in range(0, len(px), 3) if px[i] < 60 and px[i + 1] < 60 and px[i + 2] < 70)
    print(f"cannot-start: {warm} warm, {light} light, {dark} dark pixels of {w * h}")
    if warm < 300 or light < 300 or dark < 0.7 * w * h:
        failures.append(f"cannot-start: no error text on the screen ({warm} warm, {light} light, {dark} dark)")
if failures:
    print("kiosk log:\n" + log[-3000:])
    raise SystemExit("vm test failed:\n  " + "\n  ".join(failures))
print("kiosk on KMS: ok")
