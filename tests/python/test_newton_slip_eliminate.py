"""The direct Newton step eliminates each slipping contact's tangential row along its slip
direction nu: that row less mu times the contact's normal row is free of W (dr_nu - mu dr_n = c),
so the contact keeps two rows and unknowns (normal, and tangential across the slip) instead of
three (-mbc_newton_slip_eliminate, default on). It is an exact reduction of the same step, so the
solve goes through the same Newton iterates as the full system to the factors' rounding: the same
step systems, each smaller by its eliminated rows, and the same answer to the 1e-9 that the dense
and sparse storages agree to (test_newton_dense.py). The small static dam with joints slips along
its joints and has free monoliths (the bordered system [A + B W, B G^T; G, 0], whose G columns
the reduction transforms too)."""
import re

import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import read_body, read_contact

dam = load_script("meshes/dam/build.py", "dam_build_slip_eliminate")

STATIC = dict(h=15.0, monoliths=3, level=80.0, mu_base=1.0)
DYNAMIC = dict(h=15.0, monoliths=3, dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0)
BODIES = ("foundation", "m1", "m2", "m3")
STEP = re.compile(r"Newton matrix (\d+): [0-9.e+-]+ of its entries nonzero, [^,]+, (\d+) slip rows eliminated")


def final(h5file, step=-1):
    u = np.concatenate([read_body(h5file, b, step=step)["displacement"].ravel() for b in BODIES])
    return u, read_contact(h5file, step=step)["force"]


@pytest.mark.parametrize("nproc", [1, 2, 4])
@pytest.mark.parametrize("storage", ["dense", "sparse"])
def test_eliminated_slip_rows_give_the_full_step(tmp_path, storage, nproc):
    h5 = dam.build(tmp_path, **STATIC, joints=True)
    extra = ["-info", "-mbc_newton_dense_fill", "0.5" if storage == "dense" else "2"]
    e = solve(h5, "-mbc_output", str(tmp_path / "elim"), *extra, nproc=nproc)
    f = solve(h5, "-mbc_output", str(tmp_path / "full"), "-mbc_newton_slip_eliminate", "0", *extra, nproc=nproc)
    se = [(int(n), int(k)) for n, k in STEP.findall(e.stdout)]
    sf = [(int(n), int(k)) for n, k in STEP.findall(f.stdout)]
    assert se and sf, e.stdout[-2000:]
    assert all(k == 0 for _, k in sf)
    # the same step systems iteration by iteration, each smaller by one row per slipping contact
    assert len(se) == len(sf), (se, sf)
    assert [n + k for n, k in se] == [n for n, _ in sf]
    assert sum(k for _, k in se) >= 20  # the joints slip at 2 to 7 contacts an iteration
    u0, f0 = final(str(tmp_path / "full.h5"))
    u1, f1 = final(str(tmp_path / "elim.h5"))
    assert np.abs(f0).max() > 1e6 and np.abs(u0).max() > 1e-4
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


@pytest.mark.parametrize("nproc", [1, 2])
def test_eliminated_slip_rows_in_an_earthquake(tmp_path, nproc):
    """The small dam shaken: the Newton iterations of 75 dynamic steps, where the joints slip back
    and forth, with the full steps' answers at every output step. Every Newton step direct
    (-mbc_newton_lowrank 0): the elimination is the direct step's, and the kept inverse would take
    most of these steps."""
    h5 = dam.build(tmp_path, "dynamic", **DYNAMIC)
    e = solve(h5, "-mbc_output", str(tmp_path / "elim"), "-info", "-mbc_newton_lowrank", "0", nproc=nproc)
    f = solve(h5, "-mbc_output", str(tmp_path / "full"), "-mbc_newton_slip_eliminate", "0", "-info", "-mbc_newton_lowrank", "0", nproc=nproc)
    se = [(int(n), int(k)) for n, k in STEP.findall(e.stdout)]
    sf = [(int(n), int(k)) for n, k in STEP.findall(f.stdout)]
    assert [n + k for n, k in se] == [n for n, _ in sf]
    assert sum(k for _, k in se) >= 100
    for step in range(1, 9):
        u0, f0 = final(str(tmp_path / "full.h5"), step)
        u1, f1 = final(str(tmp_path / "elim.h5"), step)
        assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max(), step
        assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max(), step
