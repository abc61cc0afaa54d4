"""Stable contact pairing (-mbc_contact_stable_normal, docs/performance.md): a master node whose
projection sits on the common edge of two slave faces keeps the face of the pairs D was built
for while the two faces' normals agree within the tolerance, so D is not rebuilt for a face that
flips with motions far below the mesh size. The default (1e-12) changes no answer beyond
rounding; at 1e-4 the small dams build D once instead of twice (static) and twice instead of 12
times (dynamic), and the answers move by the faces' kink angles (1e-5..1e-4). A restart builds
the same pairs with the same preference, bitwise."""
import re

import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import read_body, read_contact

dam = load_script("meshes/dam/build.py", "dam_build")
report = load_script("meshes/dam/report.py", "dam_report")

SMALL = dict(h=15.0, monoliths=3)
STATIC = dict(SMALL, level=80.0, mu_base=1.0, joints=False)
BODIES = ("foundation", "m1", "m2", "m3")


def builds(out):
    return len(re.findall(r"flexibility matrix rebuilt", out))


def final(h5file):
    u = np.concatenate([read_body(h5file, b, step=-1)["displacement"].ravel() for b in BODIES])
    return read_body(h5file, "m1", step=-1)["time"], u, read_contact(h5file, step=-1)["force"]


def test_static_dam_builds_D_once(tmp_path):
    """The small static dam: the first solve moves 12 base nodes across an edge of the foundation's
    faces (kink 1e-5), which rebuilt D; kept, D is built once and the base still carries W and T to
    the equilibrium tolerance (1e-6); displacements within 1e-4 of the default run."""
    h5 = dam.build(tmp_path, **STATIC)
    ref = solve(h5, "-mbc_monitor", "-mbc_output", str(tmp_path / "ref"))
    r = solve(h5, "-mbc_monitor", "-mbc_contact_stable_normal", "1e-4", "-mbc_output", str(tmp_path / "stable"))
    assert builds(ref.stdout) == 2 and builds(r.stdout) == 1, (ref.stdout, r.stdout)
    base = report.summarize(str(tmp_path / "stable"))["couples"][1]
    assert abs(base["vertical_over_weight"] - 1) < 1e-6 and abs(base["horizontal_over_thrust"] - 1) < 1e-6
    _, u0, f0 = final(str(tmp_path / "ref.h5"))
    _, u1, f1 = final(str(tmp_path / "stable.h5"))
    assert 0 < np.abs(u1 - u0).max() <= 1e-4 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-3 * np.abs(f0).max()


@pytest.mark.parametrize("save, load", [(1, 1), (2, 1)])
def test_restart_keeps_the_stable_faces(tmp_path, save, load):
    """The small dynamic dam (75 steps) with -mbc_contact_stable_normal 3e-5: D built 10 times
    instead of 12 (twice at 1e-4), the last build before step 30 with kept faces; a checkpoint at step
    30 restarts (the build's search replayed with the built pairs' faces preferred, as the run
    searched; without it the replayed search finds other faces and the restart stops) and ends
    where the uninterrupted run ends: to 1e-12 on the same ranks, to 1e-10 from 2 ranks to 1, where
    the Newton step's dense LU changes from ScaLAPACK's to LAPACK's (their rounding: 2.2e-12 of the
    largest force, measured; test_d_route.py's restart)."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0, **SMALL)
    opt = ("-mbc_contact_stable_normal", "3e-5", "-mbc_monitor")
    full = solve(h5, *opt, "-mbc_output", str(tmp_path / "full"), nproc=save)
    assert builds(full.stdout) < 12, full.stdout
    part = str(tmp_path / "part")
    solve(h5, *opt, "-mbc_output", part, "-mbc_checkpoint_every", "30", "-mbc_final_time", "0.7", nproc=save)
    r = solve(h5, *opt, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", nproc=load)
    assert "restarted from" in r.stdout
    ta, ua, fa = final(str(tmp_path / "full.h5"))
    tb, ub, fb = final(part + "_restart.h5")
    assert ta == tb and np.abs(ua).max() > 1e-3
    tol = 1e-12 if save == load else 1e-10
    assert np.abs(ua - ub).max() <= tol * np.abs(ua).max()
    assert np.abs(fa - fb).max() <= tol * np.abs(fa).max()
