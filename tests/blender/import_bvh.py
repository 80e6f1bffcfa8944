"""Open BVH files with Blender's own BVH importer and check what it built
against what marionette says about the same files: one bone per joint, the
clip's frame count, and the rest skeleton's bone lengths.

usage: blender -b --python tests/blender/import_bvh.py -- MARIONETTE_BINARY FILE.bvh...
(Debian: apt-get install blender)
"""
import json
import math
import subprocess
import sys

import builtins

import bpy

# Debian's Blender 3.4 runs on Python 3.11, whose open() no longer takes the
# "rU" mode that its BVH importer passes: map it to "r" (same meaning).
_open = builtins.open


def _open_without_u(file, mode="r", *a, **k):
    return _open(file, mode.replace("U", "") if isinstance(mode, str) else mode, *a, **k)


builtins.open = _open_without_u

args = sys.argv[sys.argv.index("--") + 1:]
binary, files = args[0], args[1:]
failed = 0
for path in files:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_anim.bvh(filepath=path, global_scale=1.0, update_scene_fps=True, update_scene_duration=True)
    ours = json.loads(subprocess.run([binary, "inspect", path], capture_output=True, check=True).stdout)
    arm = next((o for o in bpy.context.scene.objects if o.type == "ARMATURE"), None)
    problems = []
    if result != {"FINISHED"} or arm is None:
        problems.append(f"import failed: {result}")
    else:
        bones = len(arm.data.bones)
        if bones != ours["joints"]:
            problems.append(f"{bones} bones, marionette reads {ours['joints']} joints")
        action = arm.animation_data.action if arm.animation_data else None
        frames = int(round(action.frame_range[1] - action.frame_range[0])) + 1 if action else 0
        if frames != ours["frames"]:
            problems.append(f"{frames} frames, marionette reads {ours['frames']}")
        # Bone lengths of the rest skeleton: the distance between a bone's
        # head and its child's head is the child's OFFSET length.
        text = open(path).read()
        offsets = {}
        name = None
        for line in text.split("MOTION")[0].splitlines():
            w = line.split()
            if w and w[0] in ("ROOT", "JOINT"):
                name = " ".join(w[1:])
            elif w and w[0] == "OFFSET" and name is not None:
                offsets[name] = math.dist((0, 0, 0), [float(x) for x in w[1:4]])
                name = None
        worst = 0.0
        for b in arm.data.bones:
            if b.parent is not None:
                d = (b.head_local - b.parent.head_local).length
                worst = max(worst, abs(d - offsets[b.name]))
        if worst > 1e-4:
            problems.append(f"bone lengths differ by up to {worst * 1000:.3f} mm")
    status = "FAIL" if problems else "ok  "
    print(f"{status} {path}: " + ("; ".join(problems) if problems else f"{ours['joints']} bones, {ours['frames']} frames, bone lengths equal"))
    failed += bool(problems)
print(f"{len(files) - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
