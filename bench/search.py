#!/usr/bin/python3
"""Contact search time against the number of surface nodes: mbcontact's cell-grid global search +
projection local search (build/bench_search, C), against a brute-force O(N M) nearest-node search
and SciPy's cKDTree on the very same node sets. Prints a table and writes docs/search.png.

  bench/search.py [--sizes 1000 10000 100000 1000000 4000000] [--brute-max 20000]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot  # noqa: E402  (bench/plot.py)


def brute_force(master, slave, chunk=2000):
    """Nearest slave node of every master node by computing all N x M distances."""
    best = np.empty(len(master), dtype=np.int64)
    for i in range(0, len(master), chunk):
        d = ((master[i:i + chunk, None, :] - slave[None, :, :]) ** 2).sum(-1)
        best[i:i + chunk] = d.argmin(axis=1)
    return best


def kdtree(master, slave):
    """Nearest slave node by SciPy's KD-tree (tree build included)."""
    return cKDTree(slave).query(master)[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000, 100000, 1000000, 4000000])
    ap.add_argument("--brute-max", type=int, default=20000, help="largest node count for the O(N M) search")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "search.png"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        prefix = os.path.join(work, "s")
        out = subprocess.run([os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "bench_search"), "-sizes", ",".join(map(str, a.sizes)), "-prefix", prefix],
                             check=True, capture_output=True, text=True).stdout.splitlines()
        rows = []
        for line in out[1:]:
            w = line.split()
            nodes, total = int(w[0]), float(w[5])
            master = np.load(f"{prefix}_master_{nodes}.npy")
            slave = np.load(f"{prefix}_slave_{nodes}.npy")
            t0 = time.perf_counter()
            kd = kdtree(master, slave)
            tkd = time.perf_counter() - t0
            tbf = float("nan")
            if nodes <= a.brute_max:
                t0 = time.perf_counter()
                bf = brute_force(master, slave)
                tbf = time.perf_counter() - t0
                assert (bf == kd).all(), "brute force and KD-tree disagree"
            rows.append((nodes, float(w[3]), float(w[4]), total, tkd, tbf, int(w[7])))
    print("\ncontact search on two non-matching wavy quad surfaces (one couple), one core\n")
    print(f"{'nodes':>9} {'global [s]':>11} {'local [s]':>10} {'mbcontact':>10} {'nodes/s':>10} {'KD-tree [s]':>12} {'brute [s]':>10} {'points':>9}")
    for n, g, l, t, k, b, p in rows:
        print(f"{n:9d} {g:11.4f} {l:10.4f} {t:10.4f} {n / t:10.3e} {k:12.4f} {b:10.4f} {p:9d}")
    print("\nmbcontact = global + local search (the local search projects onto faces: the KD-tree and the")
    print("brute force only find the nearest node). Brute force only up to --brute-max nodes (O(N M)).")
    n = np.array([r[0] for r in rows])
    series = [(n, [r[3] for r in rows], "o-", "mbcontact global + local"),
              (n, [r[4] for r in rows], "s-", "cKDTree (nearest node only)")]
    bf = [(r[0], r[5]) for r in rows if r[5] == r[5]]
    if bf:  # none when every size is above --brute-max: zip(*[]) gave a 2-tuple series, and the plot crashed
        series.append((*zip(*bf), "^-", "brute force O(N M)"))
    plot.loglog(a.plot, None, "surface nodes", series + [(n, n / 2e6, "k:", "linear, 2e6 nodes/s")])


if __name__ == "__main__":
    sys.exit(main())
