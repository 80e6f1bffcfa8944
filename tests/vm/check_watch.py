#!/usr/bin/env python3
"""Check what `marionette watch` read from uinput devices inside the VM:
- the real recording, played twice (plug, unplug, replug): each plug gives
  the same touch frames as `marionette replay --contacts` (phases and raw
  positions, in order);
- the burst: events were lost (SYN_DROPPED), yet after the resync the
  fingers lift where the recording lifts them and none stays down;
- the panel unplugged mid-drag: its two fingers are cancelled;
- `marionette record` of the panel while it played gives a recording whose
  replay has the same touch frames as the original's;
- every command exits 0."""
import json
import sys

out = sys.argv[1]
read = lambda name: open(f"{out}/{name}").read()
events = [json.loads(l) for l in read("watch.jsonl").splitlines() if l.strip()]
expected = [json.loads(l) for l in read("expected.jsonl").splitlines() if l.strip()]
shape = lambda contacts: [(c["phase"], c["raw"]["x"], c["raw"]["y"], c["tool"]) for c in contacts]
want = [shape(f["contacts"]) for f in expected]
expected_burst = [json.loads(l) for l in read("expected-burst.jsonl").splitlines() if l.strip()]

failures = []
rcs = dict(l.split(" rc=") for l in read("rc").split("\n") if " rc=" in l)
for cmd, rc in sorted(rcs.items()):
    if rc != "0":
        failures.append(f"{cmd} exited {rc}")
added = [e for e in events if e["event"] == "added"]
removed = [e for e in events if e["event"] == "removed"]
if len(added) != 4:
    failures.append(f"devices added {len(added)} times, want 4 (plug, replug, burst, mid-drag)")
if not removed:
    failures.append("the unplugged device was never removed")
for a in added[:2]:
    got = [shape(e["contacts"]) for e in events if e["event"] == "touch" and e["device"] == a["device"]]
    if got != want:
        first = next((i for i, (g, w) in enumerate(zip(got, want)) if g != w), min(len(got), len(want)))
        failures.append(f"device {a['device']} ({a['path']}): {len(got)} touch frames vs {len(want)} expected; first difference at frame {first}: "
                        f"{got[first] if first < len(got) else None} vs {want[first] if first < len(want) else None}")
def frames_of(device):
    return [e for e in events if e["event"] == "touch" and e["device"] == device]

def down_at_end(frames):
    return [c for c in frames[-1]["contacts"] if c["phase"] in ("down", "move", "hold")] if frames else []

if len(added) >= 3:
    burst = frames_of(added[2]["device"])
    want_end = sorted((c["phase"], c["raw"]["x"], c["raw"]["y"]) for c in expected_burst[-1]["contacts"])
    got_end = sorted((c["phase"], c["raw"]["x"], c["raw"]["y"]) for c in burst[-1]["contacts"]) if burst else []
    if "SYN_DROPPED" not in read("watch.log"):
        failures.append("the burst did not overflow the reader (no SYN_DROPPED logged): the resync path was not exercised")
    if got_end != want_end:
        failures.append(f"after the burst the fingers lifted at {got_end}, the recording lifts them at {want_end}")
    if down_at_end(burst):
        failures.append(f"fingers stuck down after the burst: {down_at_end(burst)}")
    print(f"vm: burst: {len(burst)} touch frames read of {len(expected_burst)} sent; events lost and resynchronised")
if len(added) >= 4:
    mid = frames_of(added[3]["device"])
    cancelled = [c for c in mid[-1]["contacts"] if c["phase"] == "cancel"] if mid else []
    if len(cancelled) != 2 or down_at_end(mid):
        failures.append(f"unplug mid-drag: last frame {mid[-1] if mid else None}, want 2 cancelled and none down")
recorded = [shape(json.loads(l)["contacts"]) for l in read("recorded.jsonl").splitlines() if l.strip()]
if recorded != want:
    failures.append(f"the recording made in the VM replays to {len(recorded)} touch frames, the original to {len(want)}"
                    + ("" if len(recorded) != len(want) else " (different contents)"))
else:
    print(f"vm: record: the recording made in the VM replays identically ({len(recorded)} touch frames)")
# list-outputs on the guest's virtio-vga: a connected connector whose
# preferred mode is the device's default, 1280x800.
outputs = [json.loads(l) for l in read("outputs.txt").splitlines() if l.startswith("{")]
connected = [o for o in outputs if o["connected"]]
preferred = [m for o in connected for m in o["modes"] if m["preferred"]]
if not connected or (preferred[0]["width"], preferred[0]["height"]) != (1280, 800):
    failures.append("list-outputs did not show a connected virtio-gpu output preferring 1280x800: " + read("outputs.txt"))
else:
    o = connected[0]
    print(f"vm: list-outputs: {o['card']} ({o['driver']}) {o['name']} connected, {len(o['modes'])} modes, preferred {preferred[0]['width']}x{preferred[0]['height']}@{preferred[0]['refresh_hz']}")
if "touchscreen" not in read("list.txt"):
    failures.append("list-devices did not show the touchscreen: " + read("list.txt"))
print(f"vm: {len(added)} plugs, {len(removed)} unplugs, {len(want)} touch frames per plug")
print(read("list.txt").strip())
for f in failures:
    print("FAIL", f)
print(f"{0 if failures else 1} passed, {1 if failures else 0} failed")
sys.exit(1 if failures else 0)
