"""Running a guest for the kiosk tests: qemu under TCG with a virtio-vga
display, the serial console in a file, QMP for screen grabs. The guest
prints `MARK name` lines when the host should grab the screen (to
OUT/name.ppm) and `=== BEGIN f` ... `=== END f` blocks for files it hands
back (to OUT/f)."""

import json
import os
import re
import socket
import subprocess
import time


# The guest's CPU: everything TCG emulates, said to be an Intel Haswell.
# qemu 10's "max" alone says AMD family 0, which LLVM 15 (lavapipe 22.3's)
# takes for a 32-bit CPU ("64-bit code requested on a subtarget that
# doesn't support it"); the features lavapipe uses come from CPUID either
# way.
CPU = "max,vendor=GenuineIntel,family=6,model=60,stepping=3"


def boot(work, out, qemu_args, timeout_s=600):
    """Run qemu with `qemu_args` (kernel, disks, ...) until the guest powers
    off; grab screens at its marks; return the console text."""
    console = os.path.join(work, "console.log")
    qmp_path = os.path.join(work, "qmp.sock")
    open(console, "w").close()
    qemu = subprocess.Popen(
        [
            "qemu-system-x86_64", "-accel", "tcg", "-cpu", CPU, "-m", "2048",
            "-smp", "2", "-nic", "none", "-display", "none",
            "-device", "virtio-vga,xres=640,yres=360",
            "-serial", f"file:{console}", "-monitor", "none", "-no-reboot",
            "-qmp", f"unix:{qmp_path},server=on,wait=off",
        ]
        + qemu_args
    )
    qmp = None
    for _ in range(100):
        try:
            s = socket.socket(socket.AF_UNIX)
            s.connect(qmp_path)
            qmp = s.makefile("rw")
            json.loads(qmp.readline())  # greeting
            qmp.write(json.dumps({"execute": "qmp_capabilities"}) + "\n")
            qmp.flush()
            json.loads(qmp.readline())
            break
        except OSError:
            time.sleep(0.1)
    if qmp is None:
        qemu.kill()
        raise SystemExit("vm test: cannot reach qemu's QMP socket")

    def screendump(path):
        qmp.write(json.dumps({"execute": "screendump", "arguments": {"filename": path}}) + "\n")
        qmp.flush()
        while True:
            reply = json.loads(qmp.readline())
            if "return" in reply or "error" in reply:
                return reply

    seen = 0
    deadline = time.time() + timeout_s
    while qemu.poll() is None and time.time() < deadline:
        text = open(console, errors="replace").read().replace("\r", "")
        # Only whole lines: the guest may be half way through writing one
        # (a mark read as "MARK sd-before-r" grabbed under the wrong name).
        text = text[: text.rfind("\n") + 1]
        marks = re.findall(r"^MARK (\S+)[ \t]*$", text, re.M)
        for name in marks[seen:]:
            reply = screendump(os.path.join(out, f"{name}.ppm"))
            print(f"screen '{name}' grabbed: {reply}", flush=True)
        seen = len(marks)
        time.sleep(0.1)
    if qemu.poll() is None:
        qemu.kill()
        raise SystemExit(
            "vm test: the guest ran out of time; console:\n"
            + open(console, errors="replace").read()[-4000:]
        )
    text = open(console, errors="replace").read().replace("\r", "")
    for name, body in re.findall(r"=== BEGIN (\S+)\n(.*?)=== END \1", text, re.S):
        open(os.path.join(out, name), "w").write(body)
    return text


def ppm(path):
    """Width, height and RGB bytes of a PPM screen grab."""
    data = open(path, "rb").read()
    parts = data.split(maxsplit=4)
    assert parts[0] == b"P6", parts[0]
    w, h = int(parts[1]), int(parts[2])
    return w, h, parts[4][: w * h * 3]


def bluish(px):
    """Pixels of the character's shirt: blue well above red."""
    return sum(
        1 for i in range(0, len(px), 3) if px[i + 2] > 120 and px[i + 2] > px[i] + 50
    )


def differ(a, b):
    """Pixels that changed clearly between two grabs."""
    return sum(
        1
        for i in range(0, len(a), 3)
        if abs(a[i] - b[i]) + abs(a[i + 1] - b[i + 1]) + abs(a[i + 2] - b[i + 2]) > 60
    )


def check_moved(screens, a, b, failures):
    """Of the grabs `b`1..4 (three while a finger drags, one after it lifts
    with the pose held), the most changed against `a` must show the
    character moved (the CPU renderer is slow under emulation: its first
    frame with overlays can take seconds)."""
    changed = [differ(screens[a], screens[f"{b}{k}"])
               for k in (1, 2, 3, 4) if a in screens and f"{b}{k}" in screens]
    print(f"{a} -> {b}1..4: {changed} pixels changed")
    if max(changed, default=0) < 500:
        failures.append(f"the character did not move under the finger ({a} -> {b}: {changed})")
