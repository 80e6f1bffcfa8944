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
args = [
    "-kernel", kernel, "-initrd", os.path.join(work, "initrd.gz"),
    "-append", "console=ttyS0 quiet panic=-1 rdinit=/init",
]
text = boot(work, out, args)
# The guest's kernel panicked before the kiosk's first run got going (seen
# once in 20 boots of 6.12 under TCG, in an interrupt, before any marks):
# said, and booted once more. A panic later, with the kiosk running, fails.
if "Kernel panic" in text and not os.path.exists(os.path.join(out, "rest.ppm")):
    print("vm test: the guest's kernel panicked while booting; booting again. Its console:\n"
          + text[-3000:])
    text = boot(work, out, args)
if "Kernel panic" in text:
    raise SystemExit("vm test: the guest's kernel panicked:\n" + text[-4000:])
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
# Timings under emulation are reported, not judged; a ratio past this is
# no noise but a buffer mapped or imported the wrong way.
GROSS = 3.0
for name, text in [("gbm", log), ("dumb", svc)]:
    m = re.search(r'buffers="' + name + r'" frames=(\d+) copy_ms_mean=([0-9.]+) copy_ms_median=([0-9.]+)', text)
    if m:
        # The median: a build or another guest beside the test slows a few
        # frames by whole milliseconds, which a mean follows.
        costs[name] = float(m.group(3))
        print(f"copy into {name} buffers: {float(m.group(3)):.3f} ms a frame (median; mean {float(m.group(2)):.3f}) over {m.group(1)} frames")
    else:
        failures.append(f"no copy cost said for the {name} buffers")
if len(costs) == 2:
    ratio = costs["gbm"] / max(costs["dumb"], 1e-9)
    print(f"gbm / dumb copy: {ratio:.2f}")
    # Under emulation on a shared machine the ratio wanders (0.97 to 1.61
    # over runs); the gate catches a copy read back through uncached or
    # write-combined memory, which costs tens of times as much.
    if ratio > GROSS:
        failures.append(f"the copy through gbm costs {ratio:.2f} times the copy through dumb buffers")
# The kiosk above ran on Debian's lavapipe 22.3: zero copy refused, with
# the missing extensions named.
m = re.search(r"the gbm zero-copy presenter is not available here reason=([^\n]*)", log)
print("zero copy on lavapipe 22.3: " + (m.group(1) if m else "(not said)"))
if not m or "VK_EXT_image_drm_format_modifier" not in m.group(1):
    failures.append("the kiosk on lavapipe 22.3 should say that zero copy needs VK_EXT_image_drm_format_modifier")
# Zero copy: Mesa 25's lavapipe renders straight into gbm's buffers.
zc = open(os.path.join(out, "zc.log")).read() if os.path.exists(os.path.join(out, "zc.log")) else ""
for want in ["presenter: gbm, zero copy (chosen automatically)", "zero_copy=true", "modifier=linear",
             "frames rendered straight into scanout buffers", "first frame on screen"]:
    if want not in zc:
        failures.append(f"expected '{want}' in the zero-copy run's log")
for want in ["play5 rc=0", "zero copy rc=0"]:
    if want not in rc:
        failures.append(f"zero copy: expected '{want}' in the guest's exit codes")
if "panicked" in zc:
    failures.append("zero copy: a panic:\n" + zc[-1500:])
for name in ["zc-rest", "zc-posed1", "zc-posed2", "zc-posed3", "zc-posed4"]:
    path = os.path.join(out, f"{name}.ppm")
    if os.path.exists(path):
        screens[name] = ppm(path)[2]
    else:
        failures.append(f"no screen grabbed at '{name}'")
if "zc-rest" in screens and "rest" in screens:
    # The same character in the same colours as through the copy (a
    # channel swap would turn the shirt red).
    zc_blue, blue = bluish(screens["zc-rest"]), bluish(screens["rest"])
    print(f"zc-rest: {zc_blue} shirt-blue pixels (through the copy: {blue})")
    if not 0.8 * blue <= zc_blue <= 1.25 * blue:
        failures.append(f"zero copy: {zc_blue} shirt-blue pixels at rest against {blue} through the copy")
check_moved(screens, "zc-rest", "zc-posed", failures)
m = re.search(r"frames=(\d+) draw_ms_mean=([0-9.]+) draw_ms_median=([0-9.]+)", zc)
if m:
    print(f"zero copy: {float(m.group(3)):.1f} ms to draw a frame into the scanout buffer (median; mean {float(m.group(2)):.1f}) over {m.group(1)} frames")
# The frame's cost per presenter: the kiosk's mean time to draw and show a
# frame, the first frame (shaders compiled under emulation) left out, and
# the latency from a touch to the flip that first showed it.
def read(name):
    path = os.path.join(out, name)
    return open(path).read() if os.path.exists(path) else ""
zcr, zcc = read("zcr.log"), read("zcc.log")
for want in ["zcr rc=0", "zcc rc=0"]:
    if want not in rc:
        failures.append(f"the runs at rest on Mesa 25's lavapipe: expected '{want}'")
if "presenter: gbm, zero copy" not in zcr or "presenter: copy (as configured)" not in zcc:
    failures.append("the runs at rest should draw into gbm's buffers and copy into dumb buffers")
frame = {}
for name, text in [("gbm copy, lavapipe 22.3, dragged", log), ("dumb copy, lavapipe 22.3, dragged", svc),
                   ("gbm zero copy, lavapipe 25.0, dragged", zc),
                   ("gbm zero copy, lavapipe 25.0, at rest", zcr), ("dumb copy, lavapipe 25.0, at rest", zcc)]:
    m = re.search(r"stopped seconds=\S+ frames=(\d+) .*render_ms_mean=([0-9.]+) render_ms_max=([0-9.]+)"
                  r" touch_to_flip_ms_mean=([0-9.]+) touch_to_flip_n=(\d+)", text)
    if m and int(m.group(1)) > 1:
        n, mean, worst = int(m.group(1)), float(m.group(2)), float(m.group(3))
        frame[name] = (mean * n - worst) / (n - 1)
        touch = f", touch to flip {float(m.group(4)):.0f} ms over {m.group(5)} touches" if int(m.group(5)) else ""
        print(f"frame ({name}): {frame[name]:.1f} ms mean over {n - 1} frames{touch}")
    else:
        failures.append(f"no frame cost said by the {name} run")
rest = [frame.get(f"{p}, lavapipe 25.0, at rest") for p in ("gbm zero copy", "dumb copy")]
if None not in rest:
    print(f"zero copy / copy, a frame at rest: {rest[0] / rest[1]:.2f}")
    if rest[0] > GROSS * rest[1]:
        failures.append(f"a frame drawn into gbm's buffers costs {rest[0] / rest[1]:.2f} times one copied")
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
