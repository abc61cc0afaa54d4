"""FCLIB problems in Python (h5py, numpy, scipy): read a local or global problem, condense a global
one to local form, and FCLIB's merit exactly as its reference implementation computes it.

The merit is fclib_merit_local (MERIT_1) of FCLIB's src/fcmer.c (now in fclib.h, unchanged):
per contact, with u = W r + q recomputed from r (a stored u is not used),
    x = r - (u_n + mu |u_t|, u_t)      (De Saxce's modified velocity)
    e_c = | r - proj_K_mu(x) |_2^2     (K_mu: |r_t| <= mu r_n, mu of that contact, no other scaling)
and merit = sqrt(sum_c e_c) / (1 + sqrt(|q|_2)): the square root of the 2-norm of q, not the
norm itself (mbcontact's PGS divides by 1 + |q|_2). The equality-constraint term of fcmer.c
(V, R, s) is absent from every problem here. One quirk of the reference: it forms W r with CSparse's
cs_gaxpy, which silently does nothing unless W is stored in compressed columns (nz = -1); for a
W in compressed rows or triplets it would use u = q. This module reads W in any of the three
layouts and computes the definition, not the quirk.
"""
import h5py
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def matrix(g):
    """An FCLIB matrix group (m, n, nz, p, i, x) as a CSR matrix: nz = -2 compressed rows,
    -1 compressed columns, >= 0 triplets (i row, p column; duplicates add)."""
    m, n, nz = (int(np.ravel(g[k][...])[0]) for k in ("m", "n", "nz"))
    p, i, x = g["p"][...], g["i"][...], g["x"][...]
    if nz == -2:
        return sp.csr_matrix((x[:p[-1]], i[:p[-1]], p), shape=(m, n))
    if nz == -1:
        return sp.csc_matrix((x[:p[-1]], i[:p[-1]], p), shape=(m, n)).tocsr()
    return sp.coo_matrix((x[:nz], (i[:nz], p[:nz])), shape=(m, n)).tocsr()


def read(path):
    """(kind, W, q, mu) of an FCLIB file, kind "local" or "global"; a global problem
    M v = H r + f, u = H^T v + w is condensed as mbcontact does: W = H^T M^-1 H, q = H^T M^-1 f + w."""
    with h5py.File(path, "r") as f:
        if "fclib_local" in f:
            g = f["fclib_local"]
            return "local", matrix(g["W"]), g["vectors/q"][...], g["vectors/mu"][...]
        if "fclib_global" not in f:
            raise ValueError(f"FCLIB file {path} has neither /fclib_local nor /fclib_global")
        g = f["fclib_global"]
        M, H = matrix(g["M"]).tocsc(), matrix(g["H"]).toarray()
        lu = spla.splu(M)
        W = H.T @ lu.solve(H)
        return "global", sp.csr_matrix(W), H.T @ lu.solve(g["vectors/f"][...]) + g["vectors/w"][...], g["vectors/mu"][...]


def read_solution(path):
    """/solution/r of an FCLIB file."""
    with h5py.File(path, "r") as f:
        return f["solution/r"][...]


def project_cone(x, mu):
    """Rows of x (n x 3: normal, tangent, tangent) projected onto their cones |t| <= mu n, with
    fcmer.c's branches (the origin when mu |x_t| <= -x_n, x itself when |x_t| <= mu x_n)."""
    t = np.hypot(x[:, 1], x[:, 2])
    p = np.zeros_like(x)
    polar = mu * t <= -x[:, 0]
    inside = (t <= mu * x[:, 0]) & ~polar  # fcmer.c tests the polar cone first (matters for mu = 0)
    side = ~inside & ~polar  # here t > 0, so the division below is safe
    p[inside] = x[inside]
    a = (mu[side] * t[side] + x[side, 0]) / (mu[side] ** 2 + 1.0)
    p[side, 0] = a
    p[side, 1] = mu[side] * a * x[side, 1] / t[side]
    p[side, 2] = mu[side] * a * x[side, 2] / t[side]
    return p


def merit_local(W, q, mu, r):
    """FCLIB's merit (fcmer.c fclib_merit_local, MERIT_1) of r for u = W r + q."""
    q, r, mu = np.asarray(q, float), np.asarray(r, float), np.asarray(mu, float)
    u = (W @ r + q).reshape(-1, 3)
    R = r.reshape(-1, 3)
    x = R - np.column_stack([u[:, 0] + mu * np.hypot(u[:, 1], u[:, 2]), u[:, 1], u[:, 2]])
    e = ((R - project_cone(x, mu)) ** 2).sum()
    return np.sqrt(e) / (1.0 + np.sqrt(np.linalg.norm(q)))
