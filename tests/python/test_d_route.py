"""-mbc_d_route schur (docs/performance.md): D_i = H_C^T S^-1 H_C with S the Schur complement of
the body's operator onto its contact DOFs (S^-1 = (A^-1)_CC, MUMPS's entries of the inverse from the
body's own factor), against the multi-right-hand-side solves: the
same D, so the same answer to rounding, on the small static dam (3 free monoliths: their operators
are K with the fixing rows of K^+) and on the two-rank run (a body on one rank each). The
matrix-free route: test_matfree.py."""
import re

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


@pytest.mark.parametrize("nproc", [1, 4])
def test_schur_route_gives_the_same_answer(tmp_path, nproc):
    """On 4 ranks the foundation spans 3 of them: its S^-1 by parallel MUMPS (the inverse's entries
    gathered on its first rank), which before stop 27 fell back to the solves; the monoliths share
    the fourth. (Bodies on one rank each over 2 ranks: the two blocks in test_matfree.py and the
    restarts below.) Without the pairing's hysteresis the static dam builds D twice (its pairs
    change once), which is the path where S^-1 is reused; with it (default) D is built once and
    test_pair_hysteresis.py checks that answer."""
    h5 = dam.build(tmp_path, **STATIC)
    rebuild = ("-mbc_contact_hysteresis", "0")
    solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_d_route", "multirhs", *rebuild, nproc=nproc)
    r = solve(h5, "-mbc_output", str(tmp_path / "schur"), "-mbc_d_route", "schur", "-info", *rebuild, nproc=nproc)
    assert r.stdout.count("D through the Schur complement onto") == 4, r.stdout[-2000:]  # 4 bodies, S^-1 once
    assert r.stdout.count("S^-1 reused") == 4  # the second build
    if nproc == 4:
        assert re.search(r"Body foundation: D through the Schur complement onto \d+ contact DOFs of \d+ \(S\^-1, the inverse's entries from the body's factor, 3 ranks", r.stdout)
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "schur.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


def test_schur_inverse_serves_every_rebuild(tmp_path):
    """The small dynamic dam (75 steps, joints) paired without hysteresis: D is rebuilt 12 times for
    new pairs; S^-1 on each body's contact-surface DOFs is computed once (the operator does not
    change) and every rebuild is two dense products: the answer is the multi-right-hand-side
    route's to 1e-9. (With the default hysteresis the pairs hold and D is built once.)"""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0, h=15.0, monoliths=3)
    rebuild = ("-mbc_contact_hysteresis", "0")
    ref = solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_monitor", "-mbc_d_route", "multirhs", *rebuild)
    r = solve(h5, "-mbc_output", str(tmp_path / "schur"), "-mbc_monitor", "-mbc_d_route", "schur", "-info", *rebuild)
    n = ref.stdout.count("flexibility matrix rebuilt")
    assert n == r.stdout.count("flexibility matrix rebuilt") and n > 2
    assert r.stdout.count("D through the Schur complement onto") == 4
    assert r.stdout.count("S^-1 reused") == 4 * (n - 1)
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "schur.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()


@pytest.mark.parametrize("save, load", [(1, 1), (2, 1)])
def test_schur_restart_equals_uninterrupted(tmp_path, save, load):
    """A restart computes S^-1 from the same operator on the same contact-surface DOFs (a set fixed
    by the scene, not by the pairs), so it builds the same D: the last step as the uninterrupted
    run's to 1e-12 on the same ranks. From 2 ranks to 1 the Newton step's dense LU is ScaLAPACK's
    before the restart and LAPACK's after (docs/performance.md 3d): their rounding differs, and
    the last step's forces differ by 1.8e-12 of the largest (measured); 1e-10 still sees any lost
    state (a replayed search that finds other faces moves forces by 1e-4 and more). Paired without
    hysteresis, so that D is rebuilt after the restart from the restarted S^-1; the default
    pairing's restart: test_pair_hysteresis.py."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0, h=15.0, monoliths=3)
    opt = ("-mbc_d_route", "schur", "-info", "-mbc_contact_hysteresis", "0")
    full = solve(h5, *opt, "-mbc_output", str(tmp_path / "full"), nproc=save)
    assert "S^-1 reused" in full.stdout
    part = str(tmp_path / "part")
    solve(h5, *opt, "-mbc_output", part, "-mbc_checkpoint_every", "30", "-mbc_final_time", "0.7", nproc=save)
    r = solve(h5, *opt, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor", nproc=load)
    assert "restarted from" in r.stdout
    ua, fa = final(str(tmp_path / "full.h5"))
    ub, fb = final(part + "_restart.h5")
    tol = 1e-12 if save == load else 1e-10
    assert np.abs(ua - ub).max() <= tol * np.abs(ua).max() and np.abs(ua).max() > 1e-3
    assert np.abs(fa - fb).max() <= tol * np.abs(fa).max()


def test_auto_route_takes_schur_where_it_fits(tmp_path):
    """-mbc_d_route auto (default): every body of the small static dam is on one rank and its S^-1
    is a few MB, so all four take the Schur route and the answer is the solves' to 1e-9;
    -mbc_d_schur_max_mb 0 sends every body to the solves (no Schur line); a negative budget is
    refused naming the option."""
    h5 = dam.build(tmp_path, **STATIC)
    ref = solve(h5, "-mbc_output", str(tmp_path / "rhs"), "-mbc_d_route", "multirhs", "-info")
    auto = solve(h5, "-mbc_output", str(tmp_path / "auto"), "-info")
    none = solve(h5, "-mbc_output", str(tmp_path / "none"), "-mbc_d_schur_max_mb", "0", "-info")
    assert "Schur complement onto" not in ref.stdout and "Schur complement onto" not in none.stdout
    assert auto.stdout.count("D through the Schur complement onto") == 4, auto.stdout[-2000:]
    u0, f0 = final(str(tmp_path / "rhs.h5"))
    u1, f1 = final(str(tmp_path / "auto.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
    bad = solve(h5, "-mbc_d_schur_max_mb", "-1", check=False)
    assert bad.returncode != 0 and "-mbc_d_schur_max_mb" in bad.stdout + bad.stderr



def test_out_of_core_factors_give_the_same_answer(tmp_path, monkeypatch):
    """-body_mat_mumps_icntl_22 1 (README, docs/performance.md 3d): the bodies' factors on disk,
    in MUMPS_OOC_TMPDIR; the Schur route's entries of the inverse and the body solves read them
    back: the same answer as in core to 1e-9, and nothing left in the directory."""
    h5 = dam.build(tmp_path, **STATIC)
    ooc = tmp_path / "ooc"
    ooc.mkdir()
    monkeypatch.setenv("MUMPS_OOC_TMPDIR", str(ooc))
    solve(h5, "-mbc_output", str(tmp_path / "core"))
    r = solve(h5, "-mbc_output", str(tmp_path / "disk"), "-body_mat_mumps_icntl_22", "1", "-body_foundation_mat_mumps_icntl_4", "2")
    assert re.search(r"ICNTL\(22\) Out-of-core option\s+=\s+1", r.stdout), r.stdout[-2000:]
    u0, f0 = final(str(tmp_path / "core.h5"))
    u1, f1 = final(str(tmp_path / "disk.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
    assert not list(ooc.iterdir())


@pytest.mark.parametrize("nproc", [1, 4])
def test_factors_go_out_of_core_where_memory_is_short(tmp_path, monkeypatch, nproc):
    """-mbc_memory_mb (default: the rank's share of its node's available memory): a body whose MUMPS
    factor would not fit in core in what the rank has left is factored out of core (ICNTL(22) = 1),
    decided from MUMPS's own estimates before the factorization; one that would not fit even out
    of core is refused, naming the body, the estimate and the option, instead of being killed by
    the kernel. The memory a rank holds before its factors differs by machine, so the test reads
    it from the refusal and then aims the budget at the foundation's window from the estimates the
    previous run printed (on 4 ranks the foundation spans 3: the decision is theirs together): the answer is the in-core one. h 6:
    the foundation's factor is ~57 MB in core, 21 out of core, well above the noise of what a rank
    holds (the coarser dam's factors are below 1 MB)."""
    h5 = dam.build(tmp_path, **dict(STATIC, h=6.0))
    ooc = tmp_path / "ooc"
    ooc.mkdir()
    monkeypatch.setenv("MUMPS_OOC_TMPDIR", str(ooc))
    solve(h5, "-mbc_output", str(tmp_path / "core"), nproc=nproc)
    bad = solve(h5, "-mbc_memory_mb", "1", check=False, nproc=nproc)
    msg = bad.stdout + bad.stderr
    m = re.search(r"Body '\w+': MUMPS estimates its factor \(\d+ DOFs\) at \d+ MB on a rank even out of core, and this rank has (-?\d+) MB left of -mbc_memory_mb 1 ", msg)
    assert bad.returncode != 0 and m, msg[-2000:]
    held = 1 - int(m.group(1))  # MB this rank held when its first factor came
    u0, f0 = final(str(tmp_path / "core.h5"))
    # What a rank holds when its factor comes varies from run to run by a few MB (more under a
    # loaded machine), and on 4 ranks the window between "fits in core" and "fits out of core" is
    # ~20 MB wide: aim for its middle from what the previous run printed, not from a fixed list.
    budget = held + 40
    for _ in range(8):
        r = solve(h5, "-mbc_output", str(tmp_path / "disk"), "-mbc_memory_mb", str(budget), "-info", check=False, nproc=nproc)
        out = r.stdout + r.stderr
        if r.returncode == 0 and "out of core (ICNTL(22) = 1)" in r.stdout:
            break
        est = re.findall(r"Body foundation: MUMPS estimates its factor at (\d+) MB in core, (\d+) MB out of core on a rank with (-?\d+) MB left of -mbc_memory_mb (\d+)", out)
        refused = re.search(r"at (\d+) MB on a rank even out of core, and this rank has (-?\d+) MB left of -mbc_memory_mb (\d+)", out)
        if est:  # the foundation in core: aim for the middle of (out-of-core estimate, in-core estimate / (3/4))
            e_in, e_out, left, b = map(int, est[0])
            budget = b - left + int((e_out + e_in / 0.75) / 2)
        elif refused:  # not even out of core: twice the out-of-core estimate left
            e_out, left, b = map(int, refused.groups())
            budget = b - left + 2 * e_out
        else:  # in core without MUMPS's estimates: the cheap bound saw room enough
            assert r.returncode == 0, out[-2000:]
            budget -= 10
    else:
        pytest.fail("no budget sent a factor out of core:\n" + r.stdout[-3000:])
    for est_in, left, where in re.findall(r"MUMPS estimates its factor at (\d+) MB in core, \d+ MB out of core on a rank with (-?\d+) MB left of -mbc_memory_mb \d+: (in core|out of core)", r.stdout):
        # the rule, est_in > 3/4 of what is left, with what is left printed to the nearest MB
        if where == "out of core":
            assert int(est_in) > 0.75 * (int(left) - 0.5)
        else:
            assert int(est_in) <= 0.75 * (int(left) + 0.5)
    u1, f1 = final(str(tmp_path / "disk.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
    assert not list(ooc.iterdir())


@pytest.mark.parametrize("even", [False, True])
def test_contact_rows_live_with_the_body_that_computes_most_of_them(tmp_path, even):
    """Two ranks: the foundation on one, the three monoliths on the other. Every point of the base
    couple touches the foundation (whose D_b spans all of them) and one monolith (a third of
    them), so its row of W lives on the foundation's rank, where that D_b is computed; before,
    every point lived on its master's (a monolith's) rank and the foundation's D_b crossed to it
    in W's assembly (the 198k dam on 2 ranks: 21.6 -> 18.9 s, docs/performance.md 3f). By default
    (-mbc_contact_rows_even) that order is cut into equal shares, so that the multiplier solve's
    row-wise work is split too: one rank then holds its own points and a share of the other's.
    The answer is one rank's either way."""
    h5 = dam.build(tmp_path, **STATIC)
    solve(h5, "-mbc_output", str(tmp_path / "one"))
    r = solve(h5, "-mbc_output", str(tmp_path / "two"), "-info", *([] if even else ["-mbc_contact_rows_even", "0"]), nproc=2)
    found = re.search(r"\[(\d)\] <sys> BodySchurInverse\(\): Body foundation: D through", r.stdout)
    counts = dict(re.findall(r"\[(\d)\] <sys> InterfaceRankOrder\(\): (\d+) of \d+ contact points on this rank", r.stdout))
    assert found and len(counts) == 2, r.stdout[-3000:]
    total = int(re.search(r"\d+ of (\d+) contact points on this rank", r.stdout).group(1))
    if even:
        assert sorted(int(c) for c in counts.values()) == [total // 2, total - total // 2], counts
    else:
        assert int(counts[found.group(1)]) == total > 0
    u0, f0 = final(str(tmp_path / "one.h5"))
    u1, f1 = final(str(tmp_path / "two.h5"))
    assert np.abs(u1 - u0).max() <= 1e-9 * np.abs(u0).max()
    assert np.abs(f1 - f0).max() <= 1e-9 * np.abs(f0).max()
