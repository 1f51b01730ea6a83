#!/usr/bin/env python3
"""Bake a scene's render meshes to point caches for Blender: the rest mesh as OBJ plus a PC2
(and optionally MDD and glTF) of every K-th step, as `softbody run --export-pc2` does.

    python3 bake_point_cache.py SCENE OUT_PREFIX [--seconds 5] [--fps 30] [--mdd] [--gltf]

In Blender: import OUT_PREFIX.obj (Forward Y, Up Z), add a Mesh Cache modifier, open
OUT_PREFIX.pc2; scene frame k shows baked frame k (frame start 0).
"""
import argparse

import softbody as sb


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("out_prefix")
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--fps", type=float, default=30.0)
    p.add_argument("--mdd", action="store_true")
    p.add_argument("--gltf", action="store_true")
    args = p.parse_args()

    scene = sb.load_scene(args.scene)
    dt = scene.world.settings.time_step
    every = max(1, round(1.0 / (args.fps * dt)))  # steps per baked frame
    frames = int(round(args.seconds / (every * dt))) + 1
    writers = [sb.PointCache(scene, args.out_prefix + ".pc2", sb.PointCacheFormat.PC2, frames,
                             every * dt)]
    if args.mdd:
        writers.append(sb.PointCache(scene, args.out_prefix + ".mdd", sb.PointCacheFormat.MDD,
                                     frames, every * dt))
    if args.gltf:
        writers.append(sb.GltfTake(scene, args.out_prefix + ".glb", frames, every * dt))
    sb.write_render_obj(scene, args.out_prefix + ".obj", one_object=True)
    for k in range(frames):
        if k:
            scene.step(every)
        for w in writers:
            w.add_frame(scene)
    for w in writers:
        w.finish()  # the files appear here, complete
    print(f"baked {frames} frames ({every} steps of {dt:.6g} s each) to {args.out_prefix}.*")


if __name__ == "__main__":
    main()
