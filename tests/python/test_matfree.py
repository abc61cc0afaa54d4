"""The matrix-free flexibility matrix (-mbc_d_route matfree, docs/multiplier.md): W a shell, a
solve per body per product, the Newton steps by GMRES with FETI's lumped preconditioner. It must
give the multipliers of the dense routes (multi-right-hand-side solves, Schur complement) to the
solve's tolerance: on the small static dam (free monoliths: the rigid-mode constraints in the
Krylov steps), the paper's two blocks, the small dynamic dam with its joints (slip, separation), at
1, 2 and 4 ranks; auto takes it beyond the dense budget; what needs D's entries is refused."""
import re

import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import read_contact
from test_d_route import STATIC, dam, final  # the small static dam and its final state, as the Schur route's tests

blocks = load_script("meshes/blocks/build.py", "blocks_build")


# Tight tolerances for the route comparisons: the routes solve the same problem, so their answers
# differ by the solves' tolerance; at 1e-12 (FCLIB merit and equilibrium) the differences measured
# 1e-11 (small static dam, 1/2/4 ranks), 1e-11 (small dynamic dam), 3e-10 (49k-DOF dam).
TIGHT = ("-mbc_multiplier_rtol", "1e-12", "-mbc_static_rtol", "1e-12")


@pytest.mark.parametrize("nproc", [1, 2, 4])
def test_matfree_route_gives_the_same_multipliers_static_dam(tmp_path, nproc):
    """The small static dam: free monoliths (the Newton steps carry the rigid-mode constraints,
    solved by the constraint preconditioner), at 1, 2 and 4 ranks, against the multi-right-hand-side
    route on one rank."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_d_route", "multirhs", *TIGHT)
    r = solve(h5, "-mbc_output", str(tmp_path / "mf"), "-mbc_d_route", "matfree", "-info", *TIGHT, nproc=nproc)
    assert "Matrix-free D:" in r.stdout and "Krylov Newton step" in r.stdout
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "mf.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


def test_matfree_sample_is_the_same_on_any_number_of_ranks(tmp_path):
    """dscale comes from a sample of D's diagonal at points evenly spaced in couple order: the same
    points, so the same dscale and stopping test, on 1 and 4 ranks (the foundation then spans two
    ranks, and the sample's H columns are not in couple order: a binary search on them unsorted
    found none of the foundation's, and dscale came out 5 % smaller on 4 ranks than on 1), and the
    answers agree as the default route's do (test_parallel.py: 1e-10)."""
    h5 = dam.build(tmp_path, **STATIC)
    lines = {}
    for n in (1, 4):
        r = solve(h5, "-mbc_output", str(tmp_path / f"r{n}"), "-mbc_d_route", "matfree", "-info", ":sys", nproc=n)
        lines[n] = sorted({m.group(0) for m in re.finditer(r"Matrix-free D: .*", r.stdout)})
    assert lines[1] and lines[1] == lines[4], lines
    u0, f0 = final(str(tmp_path / "r1.h5"))
    u1, f1 = final(str(tmp_path / "r4.h5"))
    assert np.abs(u1 - u0).max() <= 1e-10 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-10 * np.abs(f0).max()


def test_matfree_route_default_tolerance(tmp_path):
    """At the default tolerances the matrix-free route lands where the dense one does: the FCLIB
    merit weighs r = dscale lambda against u, and dscale is sampled from 32 columns of D (the lumped
    1 / Kl_dd alone was 15 times too small on this dam, a 15 times looser stop: 7e-5 off on the
    49k dam). Measured 7e-7 (forces) here; 1e-5 allows the sample's error in dscale."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "ref"), "-mbc_d_route", "multirhs", *TIGHT)
    solve(h5, "-mbc_output", str(tmp_path / "mf"), "-mbc_d_route", "matfree")
    u0, f0 = final(str(tmp_path / "ref.h5"))
    u1, f1 = final(str(tmp_path / "mf.h5"))
    assert np.abs(u1 - u0).max() <= 1e-5 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-5 * np.abs(f0).max()


@pytest.mark.parametrize("nproc", [1, 2, 4])
def test_every_route_gives_the_same_multipliers_two_blocks(tmp_path, nproc):
    """The paper's two blocks (dynamic, 441 contact points, mu 0.6), 1 step: multi-right-hand-side,
    Schur (on 4 ranks each block over 2: the inverse's entries by parallel MUMPS) and matrix-free
    give the same contact forces, to 1e-8 of the largest (measured 2e-9 after 5 steps at a merit of
    1e-12 each, on 1, 2 and 4 ranks; one step here)."""
    h5 = blocks.build(str(tmp_path), final_time=0.01)
    out = {}
    for route in ("multirhs", "schur", "matfree"):
        out[route] = str(tmp_path / route)
        solve(h5, "-mbc_output", out[route], "-mbc_d_route", route, "-mbc_multiplier_rtol", "1e-12", nproc=nproc)
    f0 = read_contact(out["multirhs"] + ".h5", step=-1)["force"]
    assert np.abs(f0).max() > 0
    for route in out:
        f = read_contact(out[route] + ".h5", step=-1)["force"]
        assert np.abs(f - f0).max() <= 1e-8 * np.abs(f0).max(), route


def test_watchdog_without_sweeps_changes_the_augmentations(tmp_path):
    """With W a shell there are no Gauss-Seidel sweeps: the watchdog went back to the best iterate
    and Newton took the same steps from it again (the 100k dynamic dam's second step: 59 iterations
    at a merit of ~2e-3). Now it restarts with rho x 2, / 2, x 4, ... (18 there, from rho 0.5). Forced here by a
    watchdog of one iteration on the two blocks (5 steps): the restart happens, the next solves
    start from the default rho again, and the answer is the dense route's to 1e-8."""
    h5 = blocks.build(str(tmp_path), final_time=0.05)
    solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_d_route", "schur", "-mbc_multiplier_rtol", "1e-12")
    r = solve(h5, "-mbc_output", str(tmp_path / "mf"), "-mbc_d_route", "matfree", "-mbc_multiplier_rtol", "1e-12",
              "-mbc_newton_watchdog", "1", "-mbc_multiplier_monitor")
    assert "newton watchdog: back to the best iterate" in r.stdout and "rho 1. / diag(W)" in r.stdout  # twice the default 0.5 of a matrix-free W
    for k in (0, -1):  # the steps written
        f0 = read_contact(str(tmp_path / "rhs.h5"), step=k)["force"]
        f1 = read_contact(str(tmp_path / "mf.h5"), step=k)["force"]
        assert np.abs(f1 - f0).max() <= 1e-8 * np.abs(f0).max(), k


def test_matfree_route_dynamic_dam_with_joints(tmp_path):
    """The small dynamic dam with its joints (75 steps: points separate and slip in the joints,
    D rebuilt for new pairs 12 times): the matrix-free route's answer is the dense one's to 1e-9."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0, h=15.0, monoliths=3)
    ref = solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_monitor", "-mbc_multiplier_rtol", "1e-12")
    r = solve(h5, "-mbc_output", str(tmp_path / "mf"), "-mbc_monitor", "-mbc_d_route", "matfree", "-mbc_multiplier_rtol", "1e-12")
    assert " slip " in r.stdout and r.stdout.count("flexibility matrix rebuilt") == ref.stdout.count("flexibility matrix rebuilt")
    assert any(int(s) > 0 for s in re.findall(r"slip (\d+)", r.stdout))
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "mf.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


def test_auto_route_goes_matrix_free_beyond_the_dense_budget(tmp_path):
    """-mbc_d_route auto (default) keeps D dense while it and the Newton matrix fit in
    -mbc_d_dense_max_mb and goes matrix-free beyond (here forced with a 0.01 MB budget): the same
    answer, and no body's Schur route is weighed (stop 26: the 1M dam's five Schur analyses, made to
    weigh it, were kept for a route it did not take: 4.3 GB beside the factors); with the pgs type,
    which needs W's rows, it stays dense and says so."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "ref"), "-mbc_d_route", "multirhs", *TIGHT)
    r = solve(h5, "-mbc_output", str(tmp_path / "auto"), "-mbc_d_dense_max_mb", "0.01", "-info", *TIGHT)
    assert re.search(r"D dense would take [\d.]+ MB \(-mbc_d_dense_max_mb 0.01\).*: matrix-free", r.stdout)
    assert "Schur route onto" not in r.stdout, r.stdout[-3000:]
    dflt = solve(h5, "-mbc_output", str(tmp_path / "dflt"), "-info")
    assert "Matrix-free D" not in dflt.stdout
    u0, f0 = final(str(tmp_path / "ref.h5"))
    u1, f1 = final(str(tmp_path / "auto.h5"))
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
    pgs = solve(h5, "-mbc_output", str(tmp_path / "pgs"), "-mbc_d_dense_max_mb", "0.01", "-mbc_multiplier_type", "pgs", "-info", check=False)
    assert "dense all the same" in pgs.stdout
    bad = solve(h5, "-mbc_d_dense_max_mb", "-1", check=False)
    assert bad.returncode != 0 and "-mbc_d_dense_max_mb" in bad.stdout + bad.stderr


def test_auto_route_counts_the_schur_workspace_and_the_solves(tmp_path):
    """auto's Schur route must fit in -mbc_d_schur_max_mb with S^-1 and the pattern of the inverse's
    entries asked of MUMPS at once, not S^-1 alone: at 1 MB the foundation (360 contact DOFs: S^-1
    0.99 MB, the entries asked 1.48 MB) takes the solves and a 36-DOF monolith keeps the Schur
    route; the dense D then needs 156 solves, and beyond -mbc_d_solves_max 100 auto goes
    matrix-free. The answers stay the solves' ones."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "ref"), "-mbc_d_route", "multirhs", *TIGHT)
    r = solve(h5, "-mbc_output", str(tmp_path / "a"), "-mbc_d_schur_max_mb", "1", "-info", ":sys", *TIGHT)
    assert "Body foundation: the Schur route onto 360 contact DOFs would take 2.47192 MB (S^-1 0.98877, the inverse's entries asked 1.48315): beyond" in r.stdout
    assert re.search(r"Body m1: the Schur route .*: within", r.stdout)
    assert "Matrix-free D" not in r.stdout and "D through the Schur complement onto" in r.stdout
    r = solve(h5, "-mbc_output", str(tmp_path / "b"), "-mbc_d_schur_max_mb", "1", "-mbc_d_solves_max", "100", "-info", ":sys", *TIGHT)
    assert "solves to build (-mbc_d_solves_max 100.): matrix-free" in r.stdout and "Matrix-free D" in r.stdout
    u0, f0 = final(str(tmp_path / "ref.h5"))
    for out in ("a", "b"):
        u1, f1 = final(str(tmp_path / f"{out}.h5"))
        assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max(), out
    bad = solve(h5, "-mbc_d_solves_max", "-1", check=False)
    assert bad.returncode != 0 and "-mbc_d_solves_max" in bad.stdout + bad.stderr


def test_matfree_route_refuses_what_needs_d_entries(tmp_path):
    """The pgs type sweeps W's rows and -mbc_fclib_write writes W's entries: with -mbc_d_route
    matfree both are refused with a message naming the options, never a crash."""
    h5 = blocks.build(str(tmp_path), final_time=0.02)
    r = solve(h5, "-mbc_output", str(tmp_path / "a"), "-mbc_d_route", "matfree", "-mbc_multiplier_type", "pgs", check=False)
    assert r.returncode != 0 and "-mbc_d_route matfree" in r.stdout + r.stderr and "newton" in r.stdout + r.stderr
    r = solve(h5, "-mbc_output", str(tmp_path / "b"), "-mbc_d_route", "matfree", "-mbc_fclib_write", str(tmp_path / "p.hdf5"), check=False)
    assert r.returncode != 0 and "-mbc_fclib_write" in r.stdout + r.stderr


def test_matfree_restart_equals_uninterrupted(tmp_path):
    """dscale's sample is fixed by the pairs (evenly spaced columns), so a restart rebuilds the same
    shell and the same preconditioner: the last step as the uninterrupted run's."""
    h5 = blocks.build(str(tmp_path), final_time=0.02)
    opt = ("-mbc_d_route", "matfree")
    solve(h5, *opt, "-mbc_output", str(tmp_path / "full"))
    part = str(tmp_path / "part")
    solve(h5, *opt, "-mbc_output", part, "-mbc_checkpoint_every", "1", "-mbc_final_time", "0.01")
    r = solve(h5, *opt, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor")
    assert "restarted from" in r.stdout
    fa = read_contact(str(tmp_path / "full.h5"), step=-1)["force"]
    fb = read_contact(part + "_restart.h5", step=-1)["force"]
    assert np.abs(fa - fb).max() <= 1e-12 * np.abs(fa).max()


def krylov_iterations(stdout):
    return [int(n) for n in re.findall(r"Krylov Newton step: (\d+) iterations", stdout)]


@pytest.mark.parametrize("nproc", [1, 2, 4])
def test_coarse_space_of_single_points_is_exact(tmp_path, nproc):
    """-mbc_d_coarse_points 1: every point its own patch, so span(Phi) is the whole space and the
    coarse matrix E = R^T J R is the Newton matrix itself (with the free monoliths' rigid modes):
    the preconditioner is J^-1 and every Krylov step takes one iteration. This checks W Phi (built
    by block solves per body; on 4 ranks the foundation spans two), J Phi (from W Phi, without a
    product), E and its distribution over ranks; the answer is the dense route's."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_d_route", "multirhs", *TIGHT)
    r = solve(h5, "-mbc_output", str(tmp_path / "mf"), "-mbc_d_route", "matfree", "-mbc_d_coarse_points", "1", "-info", *TIGHT, nproc=nproc)
    its = krylov_iterations(r.stdout)
    assert its and set(its) == {1}, its
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "mf.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


def test_coarse_space_cuts_the_krylov_iterations_dynamic_dam(tmp_path):
    """The small dynamic dam with its joints (no rigid modes; D rebuilt 12 times, so W Phi too):
    patches of 4 points cut the Krylov iterations (measured 5 025 -> 4 276 over 186 Newton steps)
    and leave the Newton iterates alone (the same number of steps); without coarse space and with
    it the answers agree to the solve's tolerance."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0, h=15.0, monoliths=3)
    opt = ("-mbc_d_route", "matfree", "-mbc_multiplier_rtol", "1e-12", "-info", ":mbcmultiplier")
    none = solve(h5, "-mbc_output", str(tmp_path / "none"), *opt, "-mbc_d_coarse_points", "0")
    four = solve(h5, "-mbc_output", str(tmp_path / "four"), *opt, "-mbc_d_coarse_points", "4")
    k0, k4 = krylov_iterations(none.stdout), krylov_iterations(four.stdout)
    assert len(k0) == len(k4) > 100 and sum(k4) < 0.9 * sum(k0), (sum(k0), sum(k4))
    u0, f0 = final(str(tmp_path / "none.h5"))
    u1, f1 = final(str(tmp_path / "four.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


def test_coarse_space_memory_bound_and_options(tmp_path):
    """W Phi is held within -mbc_d_coarse_max_mb by larger patches (the small static dam's 38 points,
    114 multipliers: 4 patches of <= 16 by default; a bound of 2 kB, room for 2 columns, takes one
    patch of all 38); bad values are refused naming the option."""
    h5 = dam.build(tmp_path, **STATIC)
    r = solve(h5, "-mbc_d_route", "matfree", "-info", ":sys")
    assert "coarse space of 12 columns (4 patches of <= 16 points)" in r.stdout
    r = solve(h5, "-mbc_d_route", "matfree", "-mbc_d_coarse_max_mb", "0.002", "-info", ":sys")
    assert "coarse space of 3 columns (1 patches of <= 114 points)" in r.stdout
    for opt, val in (("-mbc_d_coarse_points", "-2"), ("-mbc_d_coarse_max_mb", "0")):
        bad = solve(h5, opt, val, check=False)
        assert bad.returncode != 0 and opt in bad.stdout + bad.stderr
