"""FCLIB's merit in Python (mbcontact.fclib, used by bench/fclib.py) against values worked by hand
from fcmer.c's definition, its reading of the three matrix layouts, and (when python3-siconos is
installed) Siconos's own natural-map residual, which has the same numerator."""
import h5py
import numpy as np
import pytest
import scipy.sparse as sp

from mbcontact import fclib


def one(W, q, mu, r):
    return fclib.merit_local(sp.csr_matrix(np.asarray(W, float)), np.array(q, float), np.array([mu], float), np.array(r, float))


def test_merit_by_hand():
    # separated (r = 0, u_n + mu |u_t| >= 0) and closed with r inside the cone: exact solutions
    assert one(np.eye(3), [1, 3, 4], 0.5, [0, 0, 0]) == 0.0
    assert one(np.eye(3), [-1, 0, 0], 0.5, [1, 0, 0]) == 0.0
    # W = 0, q = (16, 0, 0), r = (1, 0, 0): x = r - u = (-15, 0, 0) projects to 0, |r - 0| = 1, and
    # the scale is 1 + sqrt(|q|) = 5 (mbcontact's PGS divides by 1 + |q| = 17)
    assert one(np.zeros((3, 3)), [16, 0, 0], 0.5, [1, 0, 0]) == pytest.approx(0.2, rel=1e-15)
    # the De Saxce term: W = 0, q = (0, 0.6, 0.8), mu = 0.5, r = (1, 0, 0): x = (1 - 0.5, -0.6, -0.8),
    # |x_t| = 1 lies between the cone and its polar: proj = (0.8, -0.24, -0.32), |r - proj|^2 = 0.2
    assert one(np.zeros((3, 3)), [0, 0.6, 0.8], 0.5, [1, 0, 0]) == pytest.approx(np.sqrt(0.2) / 2, rel=1e-15)
    # mu = 0 with x on the negative normal axis: fcmer.c takes the polar branch (the origin) first
    assert one(np.zeros((3, 3)), [2, 0, 0], 0.0, [1, 0, 0]) == pytest.approx(1 / (1 + np.sqrt(2)), rel=1e-15)


def test_matrix_layouts(tmp_path):
    """nz = -2 (rows), -1 (columns) and triplets (duplicates add) give the same W."""
    W = np.array([[4.0, 1, 0], [5, 3, 0], [0, 0, 2]])  # not symmetric: rows and columns must not swap
    path = tmp_path / "layouts.hdf5"
    csr, csc = sp.csr_matrix(W), sp.csc_matrix(W)
    with h5py.File(path, "w") as f:
        for name, nz, p, i, x in (("rows", -2, csr.indptr, csr.indices, csr.data),
                                  ("cols", -1, csc.indptr, csc.indices, csc.data),
                                  ("trip", 6, [0, 0, 0, 1, 1, 2], [0, 0, 1, 0, 1, 2], [3.0, 1, 5, 1, 3, 2])):
            g = f.create_group(name)
            g["m"], g["n"], g["nz"] = [3], [3], [nz]
            g["p"], g["i"], g["x"] = np.asarray(p), np.asarray(i), np.asarray(x)
    with h5py.File(path, "r") as f:
        for name in ("rows", "cols", "trip"):
            assert np.array_equal(fclib.matrix(f[name]).toarray(), W), name


def test_numerator_is_siconos_residual():
    """Siconos 4.4's fc3d_compute_error sums the same per-contact natural map and divides by
    max(norm, |r|, |u|); scaled back, the two agree to rounding on arbitrary r."""
    sn = pytest.importorskip("siconos.numerics")
    rng = np.random.default_rng(7)
    nc = 6
    B = rng.standard_normal((3 * nc, 3 * nc))
    W = sp.csc_matrix(B @ B.T + np.eye(3 * nc))
    W.indices, W.indptr = W.indices.astype(np.int64), W.indptr.astype(np.int64)
    q, mu = rng.standard_normal(3 * nc), rng.uniform(0.1, 1.0, nc)
    problem = sn.FrictionContactProblem(3, W, q, mu)
    for _ in range(5):
        r = rng.standard_normal(3 * nc)
        u = W @ r + q
        norm = 1 + np.sqrt(np.linalg.norm(q))
        info, err = sn.fc3d_compute_error(problem, r, u.copy(), 1e-8, sn.SolverOptions(sn.SICONOS_FRICTION_3D_NSGS), norm)
        ours = fclib.merit_local(W, q, mu, r) * norm / max(norm, np.linalg.norm(r), np.linalg.norm(u))
        assert ours == pytest.approx(err, rel=1e-12)
