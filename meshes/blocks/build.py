#!/usr/bin/python3
"""The paper's two-block example: block 1, a 100 m cube of 10x10x10 hex8, under block 2, 100 m
in plan (20x20) and 100 m high (10 layers); E = 10 GPa, nu = 0, density 10 kg/m3, damping
C = 200 M, mu = 0.6; block 1's base fixed normally; block 2 loaded suddenly by a body force of
100 N/m3. Exact steady state: top of block 2 at -1.5e-4 m, contact face at -1.0e-4 m.

  meshes/blocks/build.py OUTDIR [--dt 0.01] [--final-time 2.5]   writes blocks.msh, blocks.yaml, blocks.h5
"""
import argparse
import os
import sys


HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402


def scene(dt, final_time):
    material = {"E": 1.0e10, "nu": 0.0, "density": 10.0, "damping": 200.0}
    return {
        "title": "two blocks (Li, Liu, Xiao, Ma)",
        "meshes": {"m": "blocks.msh"},
        "bodies": {"block1": {"mesh": "m", "regions": ["block1"], "material": material},
                   "block2": {"mesh": "m", "regions": ["block2"], "material": material}},
        "couples": [{"k": 1, "master": "block2_zmin", "slave": "block1_zmax", "mu": 0.6}],
        "dirichlet": [{"surface": "block1_zmin", "components": ["z"]}],
        "loads": [{"kind": "body_force", "vector": [0, 0, -100.0], "time": "sudden", "bodies": ["block2"]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": final_time},
        "output": {"every": 1000000, "fields": ["displacement"],
                   "points": {"top": {"x": [50, 50, 200], "body": "block2"}, "face": {"x": [50, 50, 100], "body": "block2"}}},
    }


def build(outdir, dt=0.01, final_time=2.5):
    os.makedirs(outdir, exist_ok=True)
    meshgen.boxes(os.path.join(outdir, "blocks.msh"),
                  [dict(lo=(0, 0, 0), hi=(100, 100, 100), n=(10, 10, 10), cell="hex8", name="block1"),
                   dict(lo=(0, 0, 100), hi=(100, 100, 200), n=(20, 20, 10), cell="hex8", name="block2")])
    return prepare(outdir, "blocks", scene(dt, final_time))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--final-time", type=float, default=2.5)
    a = ap.parse_args()
    print(build(a.outdir, a.dt, a.final_time))
