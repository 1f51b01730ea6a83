# Blender's side of the export round trip (run by roundtrip.sh inside `blender -b`): the real
# client reads softbody's exports and its evaluated vertices are compared with softbody's own
# per-frame OBJ sequence, read here by a parser of this script's own.
#
#   blender -b --factory-startup --python-exit-code 1 --python blender_check.py -- \
#       REST_OBJ SEQ_DIR EVERY FRAMES PC2 MDD GLB FRAME_SECONDS
#
# REST_OBJ: the rest mesh (--export-mesh); SEQ_DIR: the OBJ sequence (--export-meshes), file
# frame_STEP.obj for STEP = k * EVERY, k = 0 .. FRAMES-1; PC2, MDD: the caches. Blender frame k
# shows cache frame k (Mesh Cache modifier: frame start 0, scale 1, time mode "frame").
# GLB: the glTF take (--export-gltf), an object per body, frame k keyed at k * FRAME_SECONDS s,
# which Blender's importer puts at scene frame (that time) * fps; its axes are glTF's (y up),
# turned by the importer to Blender's (z up): Blender (x, y, z) is softbody (x, -z, y).
# Passes when every vertex at every frame is within 1e-5 of the rest mesh's bounding-box diagonal.
import math
import os
import sys

import bpy
import numpy

# Debian's Blender 3.4 glTF importer still uses numpy.bool, which Debian's numpy 1.24 removed
# (it was an alias of the built-in bool); without the alias the importer fails.
if "bool" not in vars(numpy):
    numpy.bool = bool


def fail(message):
    print("blender_check: FAIL: " + message)
    sys.exit(1)


def read_obj_objects(path):
    """The objects of an OBJ ('o NAME'), each its 'v' lines in file order."""
    objects = {}
    current = None
    with open(path) as f:
        for line in f:
            if line.startswith("o "):
                current = objects.setdefault(line[2:].rstrip("\n"), [])
            elif line.startswith("v "):
                x, y, z = line.split()[1:4]
                current.append((float(x), float(y), float(z)))
    return objects


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
rest_path, seq_dir, every, frames, pc2_path, mdd_path, glb_path, frame_seconds = args
every, frames, frame_seconds = int(every), int(frames), float(frame_seconds)

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
# The glTF take, in a fresh scene.
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb_path)
scene = bpy.context.scene
bodies = read_obj_objects(os.path.join(seq_dir, "frame_000000.obj"))
imported = {o.name: o for o in scene.objects if o.type == "MESH"}
if sorted(imported) != sorted(bodies):
    fail(f"{glb_path}: Blender made the objects {sorted(imported)}, the bodies are {sorted(bodies)}")
sequence = [read_obj_objects(os.path.join(seq_dir, f"frame_{k * every:06d}.obj"))
            for k in range(frames)]
worst = 0.0
# Every frame k, and halfway between frames (k + 0.5), where the linear blend of the morph
# weights must show the midpoint of the two frames.
for half_steps in range(2 * frames - 1):
    k, between = divmod(half_steps, 2)
    frame = (k + 0.5 * between) * frame_seconds * scene.render.fps
    scene.frame_set(int(math.floor(frame)), subframe=frame - math.floor(frame))
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for name, obj in imported.items():
        if between:
            expected = [tuple((a + b) / 2 for a, b in zip(p, q))
                        for p, q in zip(sequence[k][name], sequence[k + 1][name])]
        else:
            expected = sequence[k][name]
        evaluated = obj.evaluated_get(depsgraph)
        # Blender (x, y, z) -> softbody (x, z, -y); the importer leaves the objects untransformed.
        world = [obj.matrix_world @ v.co for v in evaluated.data.vertices]
        got = [(p.x, p.z, -p.y) for p in world]
        if len(got) != len(expected):
            fail(f"glTF frame {k}, {name}: {len(got)} vertices, expected {len(expected)}")
        error = max_distance(got, expected)
        worst = max(worst, error)
        if error > tolerance:
            fail(f"glTF frame {k + 0.5 * between} (step {(k + 0.5 * between) * every}), {name}: "
                 f"a vertex is {error:.3g} m off (tolerance {tolerance:.3g} m)")
print(f"blender_check: glTF {glb_path}: {frames} frames and the {frames - 1} midpoints x "
      f"{len(imported)} objects, "
      f"largest error {worst:.3g} m (tolerance {tolerance:.3g} m)")
print("blender_check: PASS")
