#!/usr/bin/env python3
"""Python read-back benchmark (run by hand, never by CTest: timings are not tests).

    PYTHONPATH=build/release/python python3 tests/bench/bench_python.py [SCENE]

Times, over 200 repetitions (median), getting every body's render vertices as NumPy views
(zero-copy: the cost is per body, not per vertex) and the same copied into one array
(for comparison: what a copying API would cost).
Default scene: assets/scenes/seed-scale.json (384 bodies, 584k render vertices).
"""
import os
import statistics
import sys
import time

import numpy as np

import softbody as sb

here = os.path.dirname(os.path.abspath(__file__))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "assets", "scenes",
                                                           "seed-scale.json")
scene = sb.load_scene(path)
scene.step(1)
n = scene.body_count
vertices = sum(scene.render_vertices(i).shape[0] for i in range(n))


def median_ms(fn, reps=200):
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


views = median_ms(lambda: [scene.render_vertices(i) for i in range(n)])
copied = median_ms(lambda: np.concatenate([scene.render_vertices(i) for i in range(n)]), 50)
print(f"{os.path.basename(path)}: {n} bodies, {vertices} render vertices")
print(f"  views of every body's render vertices: {views:.3f} ms "
      f"({views * 1e6 / vertices:.2f} ns per vertex, {views * 1e3 / n:.2f} us per body)")
print(f"  the same copied into one array:        {copied:.3f} ms")
print(f"  per million vertices, views: {views * 1e6 / vertices:.3f} ms")
