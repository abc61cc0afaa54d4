"""The same answer at 1, 2 and 4 ranks with default options (issues 6, 12): the Hertz cylinders
(two bodies; at 4 ranks each spans two ranks, its DMPlex distributed and its factorization
parallel) and a small dam (three monoliths and the foundation: METIS puts the small bodies on
shared ranks). The contact rows of W live on the ranks of their master bodies; the default
semismooth Newton type solves its system redundantly (PCREDUNDANT, MUMPS) on every rank, so its
iterates are the serial ones up to rounding and each solve ends far below its tolerance
(quadratic convergence): measured differences 1.6e-13 of the field's scale and below (the dam at
4 ranks; 0 at 2 ranks), asserted 1e-10. With the projected Gauss-Seidel type the parallel sweep
differs from the serial one and the fields agree only to its tolerance (-mbc_multiplier_rtol).
(The two-block example is compared dataset by dataset in test_output.py.)"""
import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import body_names, read_body, read_contact

hertz = load_script("meshes/hertz/build.py", "hertz_build_parallel")
dam = load_script("meshes/dam/build.py", "dam_build_parallel")

RANKS = (1, 2, 4)


def fields(prefix):
    """Per body the displacement, and the contact multipliers, of the last output."""
    h5 = prefix + ".h5"
    out = {b: read_body(h5, b)["displacement"] for b in body_names(h5)}
    c = read_contact(h5)
    out["multiplier"], out["gap"] = c["multiplier"], c["gap"]
    return out


def compare(runs, tol=1e-10):
    ref = runs[RANKS[0]]
    ulen = max(np.abs(a).max() for k, a in ref.items() if k not in ("multiplier", "gap"))
    for n in RANKS[1:]:
        for key, a in ref.items():
            b = runs[n][key]
            assert a.shape == b.shape, (key, n)
            scale = np.abs(a).max()
            if key == "gap":  # closed contacts have gaps ~1e-9 of roundoff: measured against the displacements
                scale = max(scale, ulen)
            assert scale > 0, key
            err = np.abs(a - b).max() / scale
            print(f"  {n} ranks, {key}: max difference {err:.2e} of {scale:.3e}")
            assert err < tol, (key, n, err)


def run(h5, tmp_path, options=()):
    runs = {}
    for n in RANKS:
        prefix = str(tmp_path / f"np{n}")
        r = solve(h5, "-mbc_output", prefix, "-mbc_view", *options, nproc=n)
        runs[n] = fields(prefix)
        if n == 4:
            runs["view"] = r.stdout
    view = runs.pop("view")
    return runs, view


def test_hertz_same_at_1_2_4_ranks(tmp_path):
    """Hertz cylinders at hc 0.04 mm (22k DOFs): at 4 ranks each cylinder spans two ranks."""
    h5 = hertz.build(str(tmp_path), hc=0.04)
    runs, view = run(h5, tmp_path)
    assert "ranks 0-1" in view and "ranks 2-3" in view, view
    compare(runs)
    assert runs[1]["multiplier"][:, 0].max() > 0


SMALL = dict(h=15.0, monoliths=3, level=80.0, mu_base=1.0)  # as tests/python/test_dam.py: every base point sticks


def test_dam_static_same_at_1_2_4_ranks(tmp_path):
    """The small static dam (3 monoliths on the foundation, no joints, 3.8k DOFs)."""
    h5 = dam.build(str(tmp_path), joints=False, **SMALL)
    runs, view = run(h5, tmp_path)
    assert "decomposition (METIS" in view
    compare(runs)


def test_dam_dynamic_joints_same_at_1_2_4_ranks(tmp_path):
    """The small dam with its contraction joints, dynamic: the loads ramped over 0.2 s, then 0.2 s
    of the record's strong phase (25 steps). Joint rows couple monoliths that METIS may put on
    different ranks."""
    h5 = dam.build(str(tmp_path), "dynamic", dt=0.02, ramp=0.2, eq_start=0.3, eq_duration=0.2, record_from=3.0,
                   mu_joint=1.0, **SMALL)
    runs, view = run(h5, tmp_path)
    compare(runs)
