#!/usr/bin/env python3
"""Writes assets/scenes/seed-scale.json: the scale of the source's big scene
(shape-matching-seminar.de, section 5.1, Abb. 7: 55,200 particles in 384 objects, 2,448 clusters).

384 bodies (bunnies, suzannes and boxes; rigid, linear and quadratic, one cluster or a grid of
clusters) in 6 layers of 8 x 8 above a walled pen, dropped so that they pile and collide. Every
body has a render mesh (the box is its own cage). Deterministic: the same file every run.
Usage: scripts/make_seed_scale_scene.py > assets/scenes/seed-scale.json"""

import json
import math
import random

rng = random.Random(2448)

# Mesh, render mesh, scale and the cage's bounding-box centre (metres, at scale 1), so each body
# can be placed by its centre. Particles per body: bunny 164, suzanne 144, box 98.
SHAPES = {
    "bunny": ("../meshes/bunny_cage.obj", "../meshes/bunny.obj", 0.05, (-0.038, 4.841, 0.082)),
    "suzanne": ("../meshes/suzanne_cage.obj", "../meshes/suzanne.obj", 0.18, (-0.005, 0.014, -0.031)),
    "box": ("../meshes/box_cage.obj", None, 1.1, (0.0, 0.0, 0.0)),
}
COUNTS = {"bunny": 160, "suzanne": 150, "box": 74}  # 55,092 particles
# (mode, clusters): a quarter rigid, the rest linear or quadratic, most with a grid of clusters.
MODES = [("rigid", None)] * 4 + [("linear", None), ("quadratic", None)] + \
    [("linear", 0.285)] * 5 + [("quadratic", 0.285)] * 5

SIDE, LAYERS = 8, 6
PITCH, LAYER_PITCH, FIRST_LAYER = 0.72, 0.75, 0.45
PEN_HALF, WALL_HALF_THICKNESS, WALL_HALF_HEIGHT = 3.0, 0.1, 1.5


def rotation(deg):
    """R = Rz Ry Rx (the scene file rotates about X, then Y, then Z)."""
    x, y, z = (math.radians(d) for d in deg)
    cx, sx, cy, sy, cz, sz = math.cos(x), math.sin(x), math.cos(y), math.sin(y), math.cos(z), math.sin(z)
    rx = [[1, 0, 0], [0, cx, -sx], [0, sx, cx]]
    ry = [[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]
    rz = [[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]]

    def mul(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]

    return mul(rz, mul(ry, rx))


shapes = [name for name, n in COUNTS.items() for _ in range(n)]
rng.shuffle(shapes)
bodies = []
for k, shape in enumerate(shapes):
    layer, cell = divmod(k, SIDE * SIDE)
    row, col = divmod(cell, SIDE)
    centre = (
        (col - (SIDE - 1) / 2) * PITCH + rng.uniform(-0.05, 0.05),
        FIRST_LAYER + layer * LAYER_PITCH,
        (row - (SIDE - 1) / 2) * PITCH + rng.uniform(-0.05, 0.05),
    )
    deg = [round(rng.uniform(-25, 25), 2), round(rng.uniform(0, 360), 2), round(rng.uniform(-25, 25), 2)]
    mesh, render, scale, c = SHAPES[shape]
    r = rotation(deg)
    rc = [sum(r[i][j] * scale * c[j] for j in range(3)) for i in range(3)]
    mode, cell_size = MODES[k % len(MODES)]
    body = {"name": f"{shape} {k + 1:03d}", "mesh": mesh}
    if render:
        body["renderMesh"] = render
    body.update({
        "translation": [round(centre[i] - rc[i], 4) for i in range(3)],
        "rotationDegrees": deg,
        "scale": scale,
        "mass": 1.0,
        "mode": mode,
        "alpha": 1.0 if mode == "rigid" else round(rng.uniform(0.35, 0.65), 2),
        "beta": 0.0 if mode == "rigid" else 0.5,
        "damping": 0.2,
    })
    if cell_size:
        body["clusters"] = {"kind": "grid", "cellSize": cell_size, "overlap": 0.05}
    bodies.append(body)

walls = []
for axis in (0, 2):
    for sign in (-1, 1):
        centre = [0.0, WALL_HALF_HEIGHT, 0.0]
        centre[axis] = sign * (PEN_HALF + WALL_HALF_THICKNESS)
        half = [PEN_HALF + 2 * WALL_HALF_THICKNESS, WALL_HALF_HEIGHT, PEN_HALF + 2 * WALL_HALF_THICKNESS]
        half[axis] = WALL_HALF_THICKNESS
        walls.append({"type": "box", "centre": centre, "halfExtents": half, "friction": 0.4})

# One body per line, as the other shipped scenes.
out = ['{', '  "world": ' + json.dumps({"gravity": [0, -9.81, 0], "timeStep": 0.016666667, "substeps": 4}) + ',',
       '  "colliders": [']
colliders = [{"type": "plane", "normal": [0, 1, 0], "offset": 0, "friction": 0.6}] + walls
out += ['    ' + json.dumps(c) + (',' if i + 1 < len(colliders) else '') for i, c in enumerate(colliders)]
out += ['  ],', '  "bodies": [']
out += ['    ' + json.dumps(b, ensure_ascii=False) + (',' if i + 1 < len(bodies) else '') for i, b in enumerate(bodies)]
out += ['  ]', '}']
print('\n'.join(out))
