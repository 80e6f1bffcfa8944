"""Boot the systemd guest of kiosk_systemd.sh and check what it reports.

usage: systemd_vm.py WORK VMLINUZ OUT
"""

import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vmlib import bluish, boot, check_moved, ppm  # noqa: E402

work, kernel, out = sys.argv[1:4]


def guest(append, out):
    return boot(work, out, [
        "-kernel", kernel, "-initrd", os.path.join(work, "initrd.gz"),
        "-drive", f"file={os.path.join(work, 'root.img')},if=virtio,format=raw",
        "-append", "console=ttyS0 quiet panic=-1 rdinit=/init systemd.show_status=0" + append,
    ], timeout_s=900)


text = guest("", out)
if not os.path.exists(os.path.join(out, "rc")):
    raise SystemExit("vm test: the guest did not report back; console:\n" + text[-6000:])

failures = []
rc = open(os.path.join(out, "rc")).read()
journal = open(os.path.join(out, "journal.txt")).read()
print(rc)
if not re.search(r"^active=active sub=running", rc, re.M):
    failures.append("the service did not become active (READY=1)")
for want in ["play1 rc=0", "play2 rc=0", "restarts=1 active=active"]:
    if want not in rc:
        failures.append(f"expected '{want}' in the guest's report")
m = re.search(r"stop took (\S+) (\S+) result=(\S+) status=(\S+)", rc)
if not m:
    failures.append("no report of the stop")
else:
    took = float(m.group(2)) - float(m.group(1))
    print(f"systemctl stop took {took:.2f} s")
    if m.group(3) != "success" or m.group(4) != "0" or took > 5.0:
        failures.append(f"stopping was not clean: {m.groups()}")
for want in ['presenter="copy"', "first frame on screen", "touchscreen added",
             "touchscreen removed", "stopped"]:
    if want not in journal:
        failures.append(f"expected '{want}' in the journal")
screens = {}
for name in ["sd-ready", "sd-posed1", "sd-posed2", "sd-posed3", "sd-posed4",
             "sd-before-replug", "sd-replugged1", "sd-replugged2", "sd-replugged3",
             "sd-replugged4", "sd-restarted"]:
    path = os.path.join(out, f"{name}.ppm")
    if os.path.exists(path):
        screens[name] = ppm(path)[2]
    else:
        failures.append(f"no screen grabbed at '{name}'")
for name in ["sd-ready", "sd-restarted"]:
    if name in screens:
        blue = bluish(screens[name])
        print(f"{name}: {blue} shirt-blue pixels")
        if blue < 700:
            failures.append(f"the character is not on screen at '{name}' ({blue} shirt pixels)")
for a, b in [("sd-ready", "sd-posed"), ("sd-before-replug", "sd-replugged")]:
    check_moved(screens, a, b, failures)
# The record of visits after the hard reset: booted again, it opens, is
# whole, and holds what it held two seconds before the reset.
if "hard reset at" not in rc or "play3 rc=0" not in rc:
    failures.append("the guest did not reach the hard reset after a drag")
else:
    after_out = os.path.join(out, "after-reset")
    os.makedirs(after_out, exist_ok=True)
    after_text = guest(" kiosk_check=after-reset", after_out)

    def visits(dir_, name):
        try:
            return json.load(open(os.path.join(dir_, f"{name}.json")))
        except (OSError, ValueError):
            return {}

    before, after = visits(out, "before"), visits(after_out, "after")
    print("visits before the reset:", {k: before.get(k) for k in ["sessions", "touches", "grabs", "integrity"]})
    print("visits after the reset:", {k: after.get(k) for k in ["sessions", "touches", "grabs", "integrity"]})
    if not before.get("touches"):
        failures.append("the record held no touches before the reset: " + open(os.path.join(out, "before.txt")).read()[-2000:])
    if after.get("integrity") != "ok":
        failures.append("after the reset the record does not open whole: "
                        + (open(os.path.join(after_out, "after.txt")).read()[-2000:]
                           if os.path.exists(os.path.join(after_out, "after.txt")) else after_text[-3000:]))
    for k in ["sessions", "touches", "grabs", "actions_started"]:
        if after.get(k, -1) < before.get(k, 0):
            failures.append(f"after the reset the record lost {k}: {before.get(k)} -> {after.get(k)}")
if failures:
    print("journal:\n" + journal[-4000:])
    raise SystemExit("vm test failed:\n  " + "\n  ".join(failures))
print("kiosk under systemd: ok")
