"""Boot the guest of kiosk_soak.sh and judge its samples.

usage: soak_vm.py WORK VMLINUZ OUT SOAK_S
"""

import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from vmlib import boot  # noqa: E402

WARM_UP_S = 120
MAX_GROWTH_KB = 4096

work, kernel, out, soak_s = sys.argv[1:5]
text = boot(work, out, [
    "-kernel", kernel, "-initrd", os.path.join(work, "initrd.gz"),
    "-append", "console=ttyS0 quiet panic=-1 rdinit=/init",
], timeout_s=int(soak_s) + 600)
if not os.path.exists(os.path.join(out, "rss")):
    raise SystemExit("vm test: the guest did not report back; console:\n" + text[-6000:])
rc = open(os.path.join(out, "rc")).read()
print(rc)
samples = [tuple(int(v) for v in m.groups())
           for m in re.finditer(r"^sample (\d+) (\d+) (\d+)$", open(os.path.join(out, "rss")).read(), re.M)]
failures = []
after = [s for s in samples if s[0] >= WARM_UP_S]
if not samples or samples[-1][0] < int(soak_s):
    failures.append(f"the kiosk did not run {soak_s} s (samples to {samples[-1][0] if samples else 0} s)")
if after:
    base_rss, base_fds = after[0][1], after[0][2]
    peak = max(s[1] for s in after)
    fds = max(s[2] for s in after)
    print(f"rss at {after[0][0]} s: {base_rss / 1024:.1f} MB, at {after[-1][0]} s: "
          f"{after[-1][1] / 1024:.1f} MB, peak after warm-up {peak / 1024:.1f} MB; "
          f"descriptors {base_fds} -> {after[-1][2]} (most {fds}); {len(samples)} samples")
    if peak - base_rss > MAX_GROWTH_KB:
        failures.append(f"resident memory grew {(peak - base_rss) / 1024:.1f} MB after warm-up")
    # A sample taken while a play's panel is plugged counts its descriptor:
    # the count once the plays have stopped must not pass the fewest seen
    # after warm-up (a descriptor left by each of hundreds of plugs would).
    least = min(s[2] for s in after)
    m = re.search(r"^final (\d+)$", open(os.path.join(out, "rss")).read(), re.M)
    if not m:
        failures.append("the guest did not count descriptors after the plays stopped")
    else:
        print(f"descriptors after the plays stopped: {m.group(1)} (fewest after warm-up {least})")
        if int(m.group(1)) > least:
            failures.append(f"descriptors {least} -> {m.group(1)} once the plays stopped")
for want in ["run rc=0", "panels added"]:
    if want not in rc:
        failures.append(f"expected '{want}' in the guest's report")
if "play failed" in rc:
    failures.append("a uinput play failed")
m = re.search(r"stop took (\S+) (\S+)", rc)
if not m or float(m.group(2)) - float(m.group(1)) > 2.0:
    failures.append(f"the kiosk did not stop within 2 s: {m.groups() if m else None}")
if failures:
    raise SystemExit("vm soak failed:\n  " + "\n  ".join(failures))
print("kiosk soak: ok")
