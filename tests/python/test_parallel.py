"""The same answer at 1, 2 and 4 ranks with default options (issues 6, 12): the Hertz cylinders
(two bodies; at 4 ranks each spans two ranks, its DMPlex distributed and its factorization
parallel) and a small dam (three monoliths and the foundation: the small bodies share ranks, the
foundation, most of the work, spans ranks of its own). The contact rows of W live on the ranks of their master bodies; the default
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
    ranks = sorted(runs)
    ref = runs[ranks[0]]
    ulen = max(np.abs(a).max() for k, a in ref.items() if k not in ("multiplier", "gap"))
    for n in ranks[1:]:
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
    of the record's strong phase (25 steps). The foundation carries 86 % of the work (DOFs^(4/3)):
    it spans ranks 0-2 at 4 ranks, the monoliths share rank 3 (couples across single-rank bodies
    on different ranks: the two blocks of test_output.py)."""
    h5 = dam.build(str(tmp_path), "dynamic", dt=0.02, ramp=0.2, eq_start=0.3, eq_duration=0.2, record_from=3.0,
                   mu_joint=1.0, **SMALL)
    runs, view = run(h5, tmp_path)
    compare(runs)


def view_layout(view):
    """{body: (first rank, last rank, DOFs)} and the printed largest rank work over the mean."""
    import re
    bodies = {m[0]: (int(m[1]), int(m[2]), int(m[3])) for m in re.findall(r"  body (\S+): ranks (\d+)-(\d+), (\d+) DOFs", view)}
    imbalance = float(re.search(r"largest rank work \(DOFs\^4/3, the factor's entries\) ([0-9.]+) of the mean", view)[1])
    return bodies, imbalance


def test_decomposition_by_work(tmp_path):
    """Bodies onto ranks by their work, DOFs^(4/3) (the factor's entries: every solve with it), not
    their DOFs. A small dam on a small foundation (3 monoliths of 288-378 DOFs, the foundation 1 170
    DOFs: 55 % of the DOFs, 65 % of the work; the foundation so short upstream that no reservoir floor
    is left beyond the contact ring). On 2 ranks the foundation is alone on one. On 3 it
    gets two ranks of its own (alone on one it would carry 1.96 of the mean work, on two 0.98 while
    the monoliths' rank carries 1.04); by DOFs it had one (1.65 of the mean) and the monoliths two.
    The printed balance is the largest rank's work over the mean, recomputed here from the
    printed layout, and the 3-rank answer is the 1-rank one."""
    h5 = dam.build(str(tmp_path), joints=False, h=15.0, monoliths=3, level=80.0, mu_base=1.0,
                   upstream=0.3, downstream=0.5, depth=0.3)
    runs, views = {}, {}
    for n in (1, 2, 3):
        prefix = str(tmp_path / f"np{n}")
        views[n] = solve(h5, "-mbc_output", prefix, "-mbc_view", nproc=n).stdout
        runs[n] = fields(prefix)
    for n in (2, 3):
        bodies, imbalance = view_layout(views[n])
        assert sorted(bodies) == ["foundation", "m1", "m2", "m3"], views[n]
        load = np.zeros(n)
        for first, last, ndof in bodies.values():
            load[first:last + 1] += ndof ** (4 / 3) / (last - first + 1)
        assert abs(imbalance - load.max() / load.mean()) < 1.5e-3, (n, imbalance, load)
        f0, f1, _ = bodies["foundation"]
        ranks_m = {bodies[m][:2] for m in ("m1", "m2", "m3")}
        assert len(ranks_m) == 1, views[n]  # the monoliths share one rank
        (m0, m1), = ranks_m
        assert m0 == m1 and not f0 <= m0 <= f1, views[n]
        assert f1 - f0 + 1 == n - 1, (n, views[n])
    compare(runs)
