# Blender's side of the export round trip (run by roundtrip.sh inside `blender -b`): the real
# client reads softbody's exports and its evaluated vertices are compared with softbody's own
# per-frame OBJ sequence, read here by a parser of this script's own.
#
#   blender -b --factory-startup --python-exit-code 1 --python blender_check.py -- \
#       REST_OBJ SEQ_DIR EVERY FRAMES PC2 MDD
#
# REST_OBJ: the rest mesh (--export-mesh); SEQ_DIR: the OBJ sequence (--export-meshes), file
# frame_STEP.obj for STEP = k * EVERY, k = 0 .. FRAMES-1; PC2, MDD: the caches. Blender frame k
# shows cache frame k (Mesh Cache modifier: frame start 0, scale 1, time mode "frame").
# Passes when every vertex at every frame is within 1e-5 of the rest mesh's bounding-box diagonal.
import math
import os
import sys

import bpy


def fail(message):
    print("blender_check: FAIL: " + message)
    sys.exit(1)


def read_obj_vertices(path):
    """All 'v' lines of an OBJ in file order (every object of the file, concatenated)."""
    vertices = []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = line.split()[1:4]
                vertices.append((float(x), float(y), float(z)))
    return vertices


def max_distance(a, b):
    return max(math.dist(p, q) for p, q in zip(a, b))


args = sys.argv[sys.argv.index("--") + 1:]
rest_path, seq_dir, every, frames, pc2_path, mdd_path = args
every, frames = int(every), int(frames)

bpy.ops.wm.read_factory_settings(use_empty=True)
# softbody and the point caches are both in the same (y-up) axes: import without conversion.
bpy.ops.wm.obj_import(filepath=rest_path, forward_axis="Y", up_axis="Z")
objects = list(bpy.context.scene.objects)
if len(objects) != 1:
    fail(f"{rest_path}: imported as {len(objects)} objects, expected one")
obj = objects[0]

expected = [read_obj_vertices(os.path.join(seq_dir, f"frame_{k * every:06d}.obj"))
            for k in range(frames)]
rest = [tuple(v.co) for v in obj.data.vertices]
if len(rest) != len(expected[0]):
    fail(f"Blender sees {len(rest)} vertices, the sequence has {len(expected[0])}")
lo = [min(p[c] for p in rest) for c in range(3)]
hi = [max(p[c] for p in rest) for c in range(3)]
tolerance = 1e-5 * math.dist(lo, hi)
# The rest mesh is the sequence's first frame, in the same vertex order.
if max_distance(rest, expected[0]) > tolerance:
    fail("the rest mesh differs from the first frame of the sequence")
# The comparison means something only if the frames differ by far more than the tolerance.
travel = max_distance(expected[0], expected[-1])
if travel < 100 * tolerance:
    fail(f"the sequence hardly moves ({travel} m); the check would prove nothing")

for fmt, path in (("PC2", pc2_path), ("MDD", mdd_path)):
    modifier = obj.modifiers.new("softbody cache", "MESH_CACHE")
    modifier.cache_format = fmt
    modifier.filepath = path
    modifier.frame_start = 0.0
    modifier.frame_scale = 1.0
    worst = 0.0
    for k in range(frames):
        bpy.context.scene.frame_set(k)
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
        got = [tuple(v.co) for v in evaluated.data.vertices]
        if len(got) != len(expected[k]):
            fail(f"{fmt} frame {k}: {len(got)} vertices, expected {len(expected[k])}")
        error = max_distance(got, expected[k])
        worst = max(worst, error)
        if error > tolerance:
            fail(f"{fmt} frame {k} (step {k * every}): a vertex is {error:.3g} m off "
                 f"(tolerance {tolerance:.3g} m)")
    obj.modifiers.remove(modifier)
    print(f"blender_check: {fmt} {path}: {frames} frames x {len(rest)} vertices, "
          f"largest error {worst:.3g} m (tolerance {tolerance:.3g} m, travel {travel:.3g} m)")
print("blender_check: PASS")
