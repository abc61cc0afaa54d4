"""-mbc_d_route schur (docs/performance-d.md): D_i = H_C^T S^-1 H_C with S the Schur complement of
the body's operator onto its contact DOFs (MUMPS), against the multi-right-hand-side solves: the
same D, so the same answer to rounding, on the small static dam (3 free monoliths: their operators
are K with the fixing rows of K^+) and on the two-rank run (a body on one rank each)."""
import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import read_body, read_contact

dam = load_script("meshes/dam/build.py", "dam_build")

STATIC = dict(h=15.0, monoliths=3, level=80.0, mu_base=1.0, joints=False)
BODIES = ("foundation", "m1", "m2", "m3")


def final(h5file):
    u = np.concatenate([read_body(h5file, b, step=-1)["displacement"].ravel() for b in BODIES])
    return u, read_contact(h5file, step=-1)["force"]


@pytest.mark.parametrize("nproc", [1, 2])
def test_schur_route_gives_the_same_answer(tmp_path, nproc):
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "rhs"), nproc=nproc)
    r = solve(h5, "-mbc_output", str(tmp_path / "schur"), "-mbc_d_route", "schur", "-info", nproc=nproc)
    assert r.stdout.count("D through the Schur complement onto") == 4 * 2, r.stdout[-2000:]  # 4 bodies, 2 builds
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "schur.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
