#!/usr/bin/python3
"""Run time per phase and peak memory of one elastic body against its DOFs.

A cube of n^3 hex8 cells (or 6 n^3 tet4 with --cell tet4), base fixed, self-weight,
dynamic analysis of --steps Newmark steps. Phase times come from -log_view's mbcontact
events; peak memory from the kernel (max RSS). Prints a table and writes a PNG.

  bench/body_phases.py [--sizes 8 16 24 32] [--cell hex8] [--steps 20] [--solver petsc|mumps|cholmod]
"""
import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402

import plot  # noqa: E402  (bench/plot.py)

EVENTS = ("MBCBodyLoad", "MBCBodyAssemble", "MBCBodyFactor", "MBCBodySolve", "MBCOutput")


def run(n, cell, steps, solver, work):
    msh = os.path.join(work, f"cube{n}.msh")
    meshgen.box(msh, (0, 0, 0), (1, 1, 1), n=(n, n, n), cell=cell, volume_name="cube")
    scene = {
        "meshes": {"m": msh},
        "bodies": {"cube": {"mesh": "m", "regions": ["cube"], "material": {"E": 30e9, "nu": 0.2, "density": 2500.0}}},
        "dirichlet": [{"surface": "zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "time": "sudden"}],
        "analysis": {"type": "dynamic", "dt": 1e-4, "final_time": steps * 1e-4},
        "output": {"every": steps, "fields": ["displacement"]},
    }
    yml = os.path.join(work, f"cube{n}.yaml")
    with open(yml, "w") as f:
        yaml.safe_dump(scene, f)
    h5 = os.path.join(work, f"cube{n}.h5")
    subprocess.run([os.path.join(ROOT, "python", "mbcontact-prep"), yml, "-o", h5], check=True, capture_output=True)
    cmd = [os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact"), "-scene", h5, "-log_view", "-body_pc_factor_mat_solver_type", solver]
    t0 = time.perf_counter()
    r = subprocess.run(cmd, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0  # MiB, max over children so far
    times = {}
    for line in r.stdout.splitlines():
        w = line.split()
        if w and w[0] in EVENTS:
            times[w[0]] = float(w[3])
    return 3 * (n + 1) ** 3, wall, peak, times


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 24, 32])
    ap.add_argument("--cell", default="hex8", choices=["hex8", "tet4"])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--solver", default="mumps", help="mumps (default), cholmod, petsc (natural ordering: slow)")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "body_phases.png"))
    a = ap.parse_args()
    print(f"\none body, {a.cell}, {a.steps} Newmark steps, factorization: {a.solver}\n")
    print(f"{'DOFs':>9} {'load [s]':>9} {'assemble':>9} {'factor':>9} {'solve/step':>11} {'output':>9} {'wall':>8} {'peak RSS MiB':>13}", flush=True)
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for n in a.sizes:
            dofs, wall, peak, t = run(n, a.cell, a.steps, a.solver, work)
            rows.append((dofs, wall, peak, t))
            print(f"{dofs:9d} {t.get('MBCBodyLoad', 0):9.3f} {t.get('MBCBodyAssemble', 0):9.3f} {t.get('MBCBodyFactor', 0):9.3f} "
                  f"{t.get('MBCBodySolve', 0) / (a.steps + 1):11.5f} {t.get('MBCOutput', 0):9.3f} {wall:8.2f} {peak:13.0f}", flush=True)
    dofs = [r[0] for r in rows]
    plot.loglog(a.plot, f"one body, {a.cell}, {a.steps} steps, {a.solver}", "DOFs",
                [(dofs, [r[3].get(ev, 0) for r in rows], "o-", label)
                 for ev, label in (("MBCBodyAssemble", "assembly"), ("MBCBodyFactor", "factorization + mass CG"), ("MBCBodySolve", "all solves"))])

if __name__ == "__main__":
    main()
