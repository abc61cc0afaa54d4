"""Per body of the dam (meshes/dam/build.py, water 0.8 H, mu_base 1) at any size, from
build.layout only (no mesh arrays, so 1e8 DOFs takes a second): DOFs N_b, contact DOFs |C_b| (3 x
the vertices of the body's contact surfaces: what BodySchurInverse's -info line prints), contact
points touching the body p_b (its multiplier columns m_b = 3 p_b), the multipliers m and the
nonzeros of W (3 x 3 blocks for every pair of points that share a body). Checked against the
solver's -info and -mbc_monitor at 2e4 ... 4e5 DOFs (docs/performance-model.md).

  bench/results/dam_sizes.py joints|nojoints 2e4 1e6 1e8
"""
import os
import sys
from dataclasses import replace
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "meshes", "dam"))
import numpy as np
import build
def sizes(target, joints, monoliths=4):
    p = build.Dam(level=80.0, mu_base=1.0, joints=joints, monoliths=monoliths)
    p = replace(p, h=build.size_for_dofs(p, target))
    a = build.layout(p)
    rows = max(p.joint_base_rows, 0)
    bodies, base, jpts = {}, [], []
    for k, mo in enumerate(a["mono"], start=1):
        nx, ny, nz = mo["nx"], mo["ny"], len(mo["z"]) - 1
        N = 3 * (nx + 1) * (ny + 1) * (nz + 1)
        nb = (nx + 1) * (ny + 1)
        base.append(nb)
        # joint faces: all face rows from z-row `rows` up (slave / even: full x, to the top; master / odd: x 1..nx-1, z up to nz-1)
        full = (nx + 1) * (nz + 1 - rows)
        inner = (nx - 1) * (nz - rows)
        faces = [] if not joints else [s for s in ("ymin", "ymax") if not (k == 1 and s == "ymin") and not (k == p.monoliths and s == "ymax")]
        nodes_j = sum(inner if k % 2 else full for s in faces)
        # C: base nodes + joint face nodes (the lowest joint row's nodes at z-row `rows` are base-free: no overlap with z = 0 for rows >= 1)
        bodies[f"m{k}"] = dict(N=N, C=3 * (nb + nodes_j), base=nb)
    if joints:
        for k in range(1, p.monoliths):  # joint k: master = odd one; its inner face nodes are the points
            mk = a["mono"][(k if k % 2 else k + 1) - 1]
            jpts.append((mk["nx"] - 1) * (len(mk["z"]) - 1 - rows))
    fx, fy, fz = a["fx"], a["fy"], a["fz"]
    def beyond(axis, lo, hi):
        i, j = np.searchsorted(axis, lo - 1e-9 * abs(hi - lo)), np.searchsorted(axis, hi - 1e-9 * abs(hi - lo))
        return max(i - p.ring, 0), min(j + p.ring, len(axis) - 1)
    i0, i1 = beyond(fx, 0.0, p.base); j0, j1 = beyond(fy, 0.0, p.monoliths * p.width)
    bodies["foundation"] = dict(N=3 * len(fx) * len(fy) * len(fz), C=3 * (i1 - i0 + 1) * (j1 - j0 + 1), base=0)
    # points touching each body
    for k in range(1, p.monoliths + 1):
        pts = base[k - 1]
        if joints:
            if k > 1: pts += jpts[k - 2]
            if k < p.monoliths: pts += jpts[k - 1]
        bodies[f"m{k}"]["p"] = pts
    bodies["foundation"]["p"] = sum(base)
    # rows of W: a point's 3 rows live on the ranks of its master body (base: the monolith; joint k:
    # the odd monolith of the two), each row 3 x (points of the two bodies, less those of the pair)
    for b in bodies.values():
        b["rows"], b["row_nnz"] = 0, 0
    for k in range(1, p.monoliths + 1):
        b = bodies[f"m{k}"]
        b["rows"] += 3 * base[k - 1]
        b["row_nnz"] += 3 * base[k - 1] * 3 * (b["p"] + bodies["foundation"]["p"] - base[k - 1])
    for k in range(1, p.monoliths if joints else 1):
        mk, sk = (k, k + 1) if k % 2 else (k + 1, k)
        b, o = bodies[f"m{mk}"], bodies[f"m{sk}"]
        b["rows"] += 3 * jpts[k - 1]
        b["row_nnz"] += 3 * jpts[k - 1] * 3 * (b["p"] + o["p"] - jpts[k - 1])
    npts = sum(base) + sum(jpts)
    # nnz(W) in points: pairs sharing a body, minus pairs counted twice (same interface: both bodies shared)
    pairs = sum(b["p"] ** 2 for b in bodies.values()) - sum(x ** 2 for x in base) - sum(x ** 2 for x in jpts)
    return dict(h=p.h, N=build.count_dofs(p), bodies=bodies, points=npts, m=3 * npts, nnzW=9 * pairs)
if __name__ == "__main__":
    joints = sys.argv[1] == "joints"
    for t in map(float, sys.argv[2:]):
        s = sizes(t, joints)
        print(f"{t:.0e}: N {s['N']} h {s['h']:.3f} points {s['points']} m {s['m']} nnzW {s['nnzW']:.3e} ({s['nnzW'] / s['m'] ** 2:.2f} of m^2)")
        for b, v in s["bodies"].items():
            print(f"     {b:10s} N {v['N']:10d} |C| {v['C']:8d} points {v['p']:7d} (m_b {3 * v['p']}), rows of W {v['rows']}, their nonzeros {v['row_nnz']:.3e}")
