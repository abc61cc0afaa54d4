#!/usr/bin/python3
"""Projected Gauss-Seidel on the public FCLIB problems (shared/benchmarks/fclib): sweeps, time
and FCLIB error for each, and sweeps against the tolerance for a chosen problem.

  bench/fclib.py [--max-it 20000] [--tolerance-problem Capsules-i97-269.hdf5]
"""
import argparse
import glob
import os
import re
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FCLIB = os.path.join(os.path.dirname(ROOT), "shared", "benchmarks", "fclib")
SOLVER = os.path.join(ROOT, "build", "mbcontact")


def solve(path, *options):
    out = subprocess.run([SOLVER, "-fclib", path, *map(str, options)], capture_output=True, text=True).stdout
    kind = re.search(r": (local|global)", out).group(1)
    nc = int(re.search(r"(\d+) contacts", out).group(1))
    reason, its, t, err = re.search(r"PGS (\w+) in (\d+) sweeps, ([0-9.eE+-]+) s, FCLIB error ([0-9.eE+-]+)", out).groups()
    return kind, nc, reason, int(its), float(t), float(err)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-it", type=int, default=20000)
    ap.add_argument("--tolerance-problem", default="Capsules-i97-269.hdf5")
    a = ap.parse_args()
    print(f"\nPGS on the public FCLIB problems, rtol 1e-8, at most {a.max_it} sweeps, one core\n")
    print(f"{'problem':44s} {'kind':>6s} {'contacts':>8s} {'result':>15s} {'sweeps':>7s} {'time [s]':>9s} {'FCLIB error':>12s}")
    for path in sorted(glob.glob(os.path.join(FCLIB, "*.hdf5"))):
        kind, nc, reason, its, t, err = solve(path, "-mbc_pgs_max_it", a.max_it)
        print(f"{os.path.basename(path):44s} {kind:>6s} {nc:8d} {reason:>15s} {its:7d} {t:9.4f} {err:12.3e}")
    path = os.path.join(FCLIB, a.tolerance_problem)
    print(f"\nsweeps against the tolerance, {a.tolerance_problem}\n")
    print(f"{'rtol':>8s} {'sweeps':>7s} {'time [s]':>9s} {'FCLIB error':>12s}")
    for tol in (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        _, _, reason, its, t, err = solve(path, "-mbc_pgs_rtol", tol, "-mbc_pgs_max_it", a.max_it)
        print(f"{tol:8.0e} {its:7d} {t:9.4f} {err:12.3e}" + ("" if reason.startswith("CONVERGED") else f"  {reason}"))


if __name__ == "__main__":
    main()
