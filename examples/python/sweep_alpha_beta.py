#!/usr/bin/env python3
"""Parameter sweep: drop the bunny cage (scaled to 0.5 m) on the floor for every (alpha, beta)
and record how high it settles, how much it sags and whether it came to rest, into a CSV.

    python3 sweep_alpha_beta.py [--out sweep.csv] [--seconds 3] [--alphas 0.1,0.5,0.9]
                                [--betas 0,0.5,1] [--mode linear]

Needs the softbody module on PYTHONPATH (build/release/python, or installed by cmake --install).
"""
import argparse
import csv
import os

import numpy as np

import softbody as sb

HERE = os.path.dirname(os.path.abspath(__file__))
CAGE = os.path.join(HERE, "..", "..", "assets", "meshes", "bunny_cage.obj")


def floats(text):
    return [float(v) for v in text.split(",")]


def settle(vertices, triangles, mode, alpha, beta, seconds):
    world = sb.World()
    world.add_collider(sb.Collider.plane([0, 1, 0], 0.0))
    d = sb.BodyDef()
    d.name = "bunny"
    d.positions = vertices - [0, vertices[:, 1].min() - 0.3, 0]  # 0.3 m above the floor
    d.surface = triangles
    d.params.mode = mode
    d.params.alpha = alpha
    d.params.beta = beta
    body = world.add_body(d)
    rest_height = np.ptp(vertices[:, 1])
    steps = int(round(seconds / world.settings.time_step))
    world.step(steps)
    x = world.positions(body)  # a view: no copy
    v = world.velocities(body)
    return {
        "alpha": alpha,
        "beta": beta,
        "centre_height_m": float(world.centre_of_mass(body)[1]),
        "sag": float(1.0 - np.ptp(x[:, 1]) / rest_height),
        "fastest_m_per_s": float(np.linalg.norm(v, axis=1).max()),
        "asleep": world.is_sleeping(body),
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="sweep.csv")
    p.add_argument("--seconds", type=float, default=3.0)
    p.add_argument("--alphas", type=floats, default=[0.05, 0.2, 0.5, 0.9])
    p.add_argument("--betas", type=floats, default=[0.0, 0.5, 1.0])
    p.add_argument("--mode", choices=["linear", "quadratic"], default="linear")
    args = p.parse_args()
    mode = sb.Mode.LINEAR if args.mode == "linear" else sb.Mode.QUADRATIC
    vertices, triangles = sb.read_mesh(CAGE)
    vertices = (vertices - vertices.mean(axis=0)) * (0.5 / np.ptp(vertices[:, 1]))  # 0.5 m tall
    rows = [settle(vertices, triangles, mode, a, b, args.seconds)
            for a in args.alphas for b in args.betas]
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"{len(rows)} runs of {args.seconds} s written to {args.out}")


if __name__ == "__main__":
    main()
