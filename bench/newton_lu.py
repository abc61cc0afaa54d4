#!/usr/bin/python3
"""The Newton step's LU: MUMPS on the AIJ matrix against LAPACK on the dense one, against the
matrix's fill -- what -mbc_newton_dense_fill (0.5) chooses between.

The Newton matrix J = A + B W couples two contacts when they share a body (W = sum_b H_b^T A_b^-1
H_b is dense on each body's contacts). Two scenes of `bodies` bodies (contact_bodies): a chain,
whose J is banded (fill about 3 / bodies), and a dam, a foundation under a row of monoliths with
joints, whose base contacts all couple through the foundation (a dam without joints is 0.99
full). The values
are random with a dominant diagonal (the LU's cost, not its pivoting, is measured). Times are the
best of --repeat factorizations (symbolic + numeric for MUMPS, as each Newton step refactors).

  /usr/bin/python3 bench/newton_lu.py --n 3000 --bodies 2 3 5 8 12 20 40 --plot newton_lu.png
"""
import argparse
import sys
import time

import numpy as np
import petsc4py

petsc4py.init(sys.argv[:1])
from petsc4py import PETSc  # noqa: E402


def contact_bodies(n_points, bodies, scene):
    """Per contact point its two bodies. chain: bodies 0, 1, ... in a row, the points spread over
    the bodies - 1 interfaces. dam: body 0 the foundation under bodies - 1 monoliths, half the
    points on the monoliths' bases, half on the joints between neighbours."""
    if scene == "chain":
        groups = [[(i, i + 1) for i in range(bodies - 1)]]
    else:
        groups = [[(0, i) for i in range(1, bodies)], [(i, i + 1) for i in range(1, bodies - 1)]]
        groups = [g for g in groups if g]
    pairs = []
    for g in groups:  # the group's share of the points, spread evenly over its interfaces
        share = n_points // len(groups)
        pairs += [g[k * len(g) // share] for k in range(share)]
    return np.array(pairs)


def newton_matrix(pairs, seed=1):
    """J as a dense array: 3x3 blocks between points on a common body."""
    n = 3 * len(pairs)
    rng = np.random.default_rng(seed)
    a, b = pairs[:, 0], pairs[:, 1]
    share = (a[:, None] == a[None, :]) | (a[:, None] == b[None, :]) | (b[:, None] == a[None, :]) | (b[:, None] == b[None, :])
    mask = np.kron(share, np.ones((3, 3), dtype=bool))
    J = np.where(mask, rng.uniform(-1, 1, (n, n)), 0.0)
    J[np.diag_indices(n)] = np.abs(J).sum(axis=1) + 1.0
    return J, mask.mean()


def factor_time(M, solver, repeat):
    best = np.inf
    b = M.createVecLeft()
    b.set(1.0)
    x = b.duplicate()
    for _ in range(repeat):
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType(solver)
        ksp.setOperators(M)
        t = time.perf_counter()
        ksp.setUp()
        best = min(best, time.perf_counter() - t)
        ksp.solve(b, x)
        ksp.destroy()
    r = M.createVecLeft()
    M.mult(x, r)
    r.axpy(-1.0, b)
    return best, r.norm() / b.norm()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=3000, help="unknowns (3 per contact point)")
    ap.add_argument("--bodies", type=int, nargs="+", default=[2, 3, 5, 8, 12, 20, 40])
    ap.add_argument("--scenes", nargs="+", default=["chain", "dam"], choices=["chain", "dam"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--plot", help="write the ratio against the fill here")
    a = ap.parse_args()
    rows = []
    print(f"{'scene':>6} {'bodies':>6} {'n':>6} {'fill':>6} {'MUMPS [s]':>10} {'LAPACK [s]':>11} {'LAPACK/MUMPS':>13} {'residuals':>19}")
    for scene, nb in [(sc, nb) for sc in a.scenes for nb in a.bodies if sc == "chain" or nb > 2]:
        J, fill = newton_matrix(contact_bodies(a.n // 3, nb, scene))
        n = J.shape[0]
        nz = J != 0
        indptr = np.concatenate([[0], np.cumsum(nz.sum(axis=1))]).astype(PETSc.IntType)
        indices = np.nonzero(nz)[1].astype(PETSc.IntType)
        A = PETSc.Mat().createAIJ([n, n], csr=(indptr, indices, J[nz]), comm=PETSc.COMM_SELF)
        A.assemble()
        D = PETSc.Mat().createDense([n, n], array=J.copy(order="F").ravel(order="F"), comm=PETSc.COMM_SELF)
        D.assemble()
        ts, rs = factor_time(A, "mumps", a.repeat)
        td, rd = factor_time(D, "petsc", a.repeat)
        rows.append((scene, n, fill, ts, td))
        print(f"{scene:>6} {nb:>6} {n:>6} {fill:>6.3f} {ts:>10.4f} {td:>11.4f} {td / ts:>13.2f} {rs:>9.1e} {rd:>9.1e}")
        assert rs < 1e-10 and rd < 1e-10, "a factorization did not solve its system"
    if a.plot:
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(5, 3.5))
        for scene in a.scenes:
            sel = [r for r in rows if r[0] == scene]
            ax.semilogy([r[2] for r in sel], [r[4] / r[3] for r in sel], "o-", label=scene)
        ax.axhline(1.0, color="k", lw=0.5)
        ax.axvline(0.5, color="r", lw=0.5, ls="--", label="-mbc_newton_dense_fill 0.5")
        ax.set_xlabel("fill of the Newton matrix")
        ax.set_ylabel("LAPACK / MUMPS factorization time")
        ax.set_title(f"n = {a.n}")
        ax.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=100)


if __name__ == "__main__":
    main()
