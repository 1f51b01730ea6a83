#!/usr/bin/env python3
"""Writes assets/meshes/box_cage.obj: a 0.4 m cube centred at the origin, the surface points of a
5 x 5 x 5 lattice (4 x 4 quads per face, 98 vertices), each quad split into two outward-oriented
triangles (192). Usage: scripts/make_box_cage.py > assets/meshes/box_cage.obj"""

EDGE, N = 0.4, 4

index = {}
vertices = []
triangles = []


def vertex(q):
    if q not in index:
        index[q] = len(vertices) + 1  # OBJ indices start at 1
        vertices.append(tuple(EDGE * (c / N - 0.5) for c in q))
    return index[q]


for axis in range(3):
    u, v = (axis + 1) % 3, (axis + 2) % 3  # (u, v, axis) is right-handed
    for side in (0, 1):
        for i in range(N):
            for j in range(N):
                def at(a, b):
                    q = [0, 0, 0]
                    q[axis], q[u], q[v] = side * N, a, b
                    return vertex(tuple(q))
                c00, c10, c11, c01 = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
                if side == 1:  # normal +axis: counter-clockwise seen from outside
                    triangles += [(c00, c10, c11), (c00, c11, c01)]
                else:
                    triangles += [(c00, c11, c10), (c00, c01, c11)]

print("# softbody: a 0.4 m cube centred at the origin: the surface points of a 5 x 5 x 5 lattice")
print("# (98 vertices), each lattice square split into two triangles (192), outward oriented")
print("# (made by scripts/make_box_cage.py for the stack, restitution and slope scenes).")
print("# Licence: as the project.")
for p in vertices:
    print("v %.9g %.9g %.9g" % tuple(0.0 if abs(c) < 1e-12 else c for c in p))
for t in triangles:
    print("f %d %d %d" % t)
