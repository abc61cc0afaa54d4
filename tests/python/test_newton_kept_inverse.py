"""The Newton step through the kept inverse of a reference state's Newton matrix
(newtonlowrank.c, -mbc_newton_lowrank, the default): it gives the direct solve's answer, it is
taken where it should be (dynamic steps with W assembled), and a restart restores its reference,
so that the restarted run repeats the uninterrupted one bit for bit.

Both paths solve each Newton system to a residual of 1e-12 of its right side (refined), far
below the multiplier solve's own tolerance (1e-8): the answers agree to rounding (measured
4e-15 on the rocking block, 1e-12 on the 49k dam over 30 earthquake steps); asserted 1e-10."""
import math
import re

import h5py
import numpy as np
import pytest

from conftest import load_script, prep, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_contact

dam = load_script("meshes/dam/build.py", "dam_build_kept_inverse")
G = 9.81


def rocking_block(tmp_path, cell, half=False, mu=0.8, push=0.0):
    """A 1 x 1 x 1.5 m block on a clamped base (mu 0.8, non-matching: 4 x 4 on 5 x 5), its
    weight and a top traction ramped to 8 kPa over 0.03 s, which lifts the heel: the contact goes
    from all stuck to 15 of 25 points separated, the states the reference (all stuck: the inverse
    is built after three direct steps, N = active rows) differs from. half: the base cut at the
    block's y = 0 face and both held in y there (a symmetry plane along the traction), so the
    points on that plane have a direction without flexibility (frozen rows). push: gravity tilted
    by push g along x, without the traction (the block slides on its whole base)."""
    meshgen.boxes(str(tmp_path / "rock.msh"),
                  [dict(lo=(-0.5, 0.0 if half else -0.5, -1.0), hi=(1.5, 1.5, 0.0), n=(5, 4 if half else 5, 2), name="base", cell=cell),
                   dict(lo=(0, 0, 0), hi=(1, 1, 1.5), n=(4, 4, 3), name="block", cell=cell)])
    plane = [{"surface": "base_ymin", "components": ["y"]}, {"surface": "block_ymin", "components": ["y"]}] if half else []
    return prep(tmp_path, {
        "meshes": {"m": "rock.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 1e9, "nu": 0.25, "density": 2000}},
                   "block": {"mesh": "m", "regions": "block",
                             "material": {"E": 1e9, "nu": 0.25, "density": 2000, "rayleigh_beta": 1e-3}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": mu}],
        "dirichlet": [{"surface": "base_zmin", "components": "all"}, *plane],
        "loads": [{"kind": "gravity", "vector": [push * G, 0, -G], "time": "sudden", "bodies": ["block"]},
                  {"kind": "traction", "surface": "block_zmax", "vector": [0.0 if push else 8000.0, 0, 0],
                   "time": {"table": [[0, 0], [0.03, 1], [1, 1]]}}],
        "analysis": {"type": "dynamic", "dt": 1e-3, "final_time": 0.06},
        "output": {"every": 5, "fields": ["displacement"]},
    }, name="rock")


def kept_steps(stdout):
    return len(re.findall(r"Newton step by the kept inverse: \d+ rows differ of \d+ active \(\d+ closed since\), residual \S+ of the right side after \d+ refinements\n", stdout))


def final(h5, body):
    return read_body(h5, body, step=-1), read_contact(h5, step=-1)


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
@pytest.mark.parametrize("nproc", [1, 2, 4])
def test_same_answer_as_the_direct_solve(tmp_path, cell, nproc):
    """The rocking block with and without the kept inverse: the same displacements, forces and
    states to 1e-10; the default takes kept-inverse steps (ScaLAPACK's inverse on 2 and 4 ranks),
    and the heel's separated points are among the states it corrects."""
    h5 = rocking_block(tmp_path, cell)
    on = solve(h5, "-mbc_output", str(tmp_path / "on"), "-info", ":mbcmultiplier", nproc=nproc)
    solve(h5, "-mbc_output", str(tmp_path / "off"), "-mbc_newton_lowrank", "0", nproc=nproc)
    assert kept_steps(on.stdout) >= 10, on.stdout[-3000:]
    assert re.search(r"Reference Newton matrix 75 \(0 contacts separated\): inverted", on.stdout), on.stdout[-3000:]
    (ua, ca), (ub, cb) = final(str(tmp_path / "on.h5"), "block"), final(str(tmp_path / "off.h5"), "block")
    assert (ca["state"] == 0).sum() >= 10  # the heel lifted
    assert np.array_equal(ca["state"], cb["state"])
    assert np.abs(ua["displacement"] - ub["displacement"]).max() <= 1e-10 * np.abs(ub["displacement"]).max()
    assert np.abs(ca["force"] - cb["force"]).max() <= 1e-10 * np.abs(cb["force"]).max()


@pytest.mark.parametrize("nproc", [1, 2])
def test_frozen_rows_and_separated_rows_in_the_reference(tmp_path, nproc):
    """The half rocking block: J_ref is diagonal on the rows of its symmetry plane's held
    direction (frozen) and, once the heel has lifted, on the separated points' rows; Z is the
    inverse of the other rows' block (ReferenceBlocks). The first reference is all stuck (75 rows,
    5 frozen); once the heel has lifted a new one is taken (10 points separated: 42 rows not
    diagonal), and the steps through both give the direct solve's answer to 1e-10, with no
    traction across the plane. At -mbc_newton_lowrank_max 0.6: under the default 0.8 the kept
    inverse serves every step of this block from its first reference, and the second reference,
    the one with separated rows, is not taken."""
    h5 = rocking_block(tmp_path, "hex8", half=True)
    on = solve(h5, "-mbc_output", str(tmp_path / "on"), "-info", ":mbcmultiplier", "-mbc_newton_lowrank_max", "0.6", nproc=nproc)
    solve(h5, "-mbc_output", str(tmp_path / "off"), "-mbc_newton_lowrank", "0", nproc=nproc)
    refs = [tuple(map(int, t)) for t in re.findall(r"Reference Newton matrix (\d+) \((\d+) contacts separated\): inverted \(its (\d+) rows not diagonal\)", on.stdout)]
    assert refs and all(n - s > 3 * o for n, o, s in refs), refs  # frozen rows besides the separated ones' 3
    assert any(o > 0 for _, o, _ in refs), refs
    assert kept_steps(on.stdout) >= 40 and set(re.findall(r"after (\d+) refinements", on.stdout)) == {"0"}, on.stdout[-3000:]
    (ua, ca), (ub, cb) = final(str(tmp_path / "on.h5"), "block"), final(str(tmp_path / "off.h5"), "block")
    assert np.array_equal(ca["state"], cb["state"])
    assert np.abs(ua["displacement"] - ub["displacement"]).max() <= 1e-10 * np.abs(ub["displacement"]).max()
    assert np.abs(ca["force"] - cb["force"]).max() <= 1e-10 * np.abs(cb["force"]).max()
    plane = np.abs(ca["reference"][:, 1]) < 1e-12
    assert plane.sum() >= 3 and np.abs(ca["force"][plane, 1]).max() <= 1e-10 * np.abs(ca["force"]).max()


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
@pytest.mark.parametrize("nproc", [1, 2])
def test_sliding_block_two_rows_a_slipping_point(tmp_path, cell, nproc):
    """The rocking block's scene with mu 0.2 pushed by its own weight's 0.3 g along x: after the
    first steps (all stuck: the reference) every point slips and none lifts. A slipping point's
    normal row is the sticking reference's, so only its two tangential rows are corrected: 2/3 of
    the active rows differ, within -mbc_newton_lowrank_max 0.8 (with the three rows of each
    contact counted, every such step went to the direct LU). The same answers as the direct solve
    to 1e-10."""
    h5 = rocking_block(tmp_path, cell, mu=0.2, push=0.3)
    on = solve(h5, "-mbc_output", str(tmp_path / "on"), "-info", ":mbcmultiplier", nproc=nproc)
    solve(h5, "-mbc_output", str(tmp_path / "off"), "-mbc_newton_lowrank", "0", nproc=nproc)
    steps = [tuple(map(int, t)) for t in re.findall(r"Newton step by the kept inverse: (\d+) rows differ of (\d+) active", on.stdout)]
    assert sum(3 * k == 2 * n for k, n in steps) >= 10, steps  # every active point slipping
    (ua, ca), (ub, cb) = final(str(tmp_path / "on.h5"), "block"), final(str(tmp_path / "off.h5"), "block")
    assert (ca["state"] == 2).all(), ca["state"]  # every point slipping at the end
    assert np.array_equal(ca["state"], cb["state"])
    assert np.abs(ua["displacement"] - ub["displacement"]).max() <= 1e-10 * np.abs(ub["displacement"]).max()
    assert np.abs(ca["force"] - cb["force"]).max() <= 1e-10 * np.abs(cb["force"]).max()


def shaken_dam(tmp_path):
    """The small staged dam with its joints (3 monoliths, h 15 m, water at 0.95 H, mu 0.8) under
    0.4 s of the 3-component record's strong phase (dt 0.02): the inverse is built in the fifth
    step, after 12 direct Newton steps (29 joint points separated in its reference), and points open, close and slip from step
    to step."""
    return dam.build(tmp_path, "staged", dt=0.02, eq_duration=0.4, record_from=3.0, joints=True, h=15.0,
                     monoliths=3, components="xyz")


@pytest.mark.parametrize("nproc, dist", [(1, False), (2, False), (2, True), (4, True)])
def test_shaken_dam_same_answer_as_the_direct_solve(tmp_path, nproc, dist):
    """The shaken dam's joints open, close and slip: the kept inverse's steps correct rows closed
    since the reference (their (W Z) rows come from the product kept with Z) and give the direct
    solve's displacements and forces to 1e-10. Both take the same Newton steps, so every solve
    takes as many iterations either way: the kept inverse's step is checked against products with
    W, so an assembled Newton matrix that is not the Jacobian (it is read from W's CSR arrays a
    contact at a time) would slow the direct solves' convergence: one 5 % off fails it on 1 and 2
    ranks. dist: the correction M factored over the ranks (ScaLAPACK) whatever its size (by
    default from k = 1 000 on)."""
    h5 = shaken_dam(tmp_path)
    extra = ["-mbc_newton_lowrank_dist_min", "0"] if dist else []
    on = solve(h5, "-mbc_output", str(tmp_path / "on"), "-info", ":mbcmultiplier", "-mbc_multiplier_converged_reason", *extra, nproc=nproc)
    off = solve(h5, "-mbc_output", str(tmp_path / "off"), "-mbc_newton_lowrank", "0", "-mbc_multiplier_converged_reason", nproc=nproc)
    its = [re.findall(r"multiplier solve \(newton\) \S+ in (\d+) iterations", run.stdout) for run in (on, off)]
    assert len(its[0]) >= 20 and its[0] == its[1], its
    closed = [int(c) for c in re.findall(r"active \((\d+) closed since\), residual \S+ of the right side after \d+ refinements\n", on.stdout)]  # taken steps
    assert kept_steps(on.stdout) >= 20 and max(closed) > 0, on.stdout[-3000:]
    # Z is J_ref's inverse to rounding (cond_1 75), so no step needs a refinement; Z_SD 10 % off
    # (the columns of the rows closed since) needed two in 25 steps and failed in 21
    assert set(re.findall(r"after (\d+) refinements", on.stdout)) == {"0"}, on.stdout[-3000:]
    names = ["foundation", "m1", "m2", "m3"]
    ua = np.concatenate([read_body(str(tmp_path / "on.h5"), b, step=-1)["displacement"].ravel() for b in names])
    ub = np.concatenate([read_body(str(tmp_path / "off.h5"), b, step=-1)["displacement"].ravel() for b in names])
    ca, cb = read_contact(str(tmp_path / "on.h5"), step=-1), read_contact(str(tmp_path / "off.h5"), step=-1)
    assert np.array_equal(ca["state"], cb["state"])
    assert np.abs(ua - ub).max() <= 1e-10 * np.abs(ub).max()
    assert np.abs(ca["force"] - cb["force"]).max() <= 1e-10 * np.abs(cb["force"]).max()


@pytest.mark.parametrize("save, load", [(1, 1), (2, 2), (2, 1)])
def test_restart_restores_the_reference(tmp_path, save, load):
    """A checkpoint at earthquake step 7 holds the kept inverse's reference (the separated points
    when it was built, which differ from step 7's) and the direct steps since; the restart builds
    the same inverse and ends where the uninterrupted run ends: bit for bit on the same ranks, to
    1e-10 from 2 ranks to 1 (ScaLAPACK's rounding against LAPACK's, test_pair_hysteresis.py)."""
    h5 = shaken_dam(tmp_path)
    full = solve(h5, "-mbc_output", str(tmp_path / "full"), "-info", ":mbcmultiplier", nproc=save)
    assert kept_steps(full.stdout) >= 20
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "7", "-mbc_final_time", "1.18", nproc=save)
    with h5py.File(part + "_checkpoint.h5") as f:
        state = f["contact/solve_state"][:]
        m = f.attrs["num_multipliers"]
        assert state.shape == (m + 1,) and set(np.unique(state[:m])) == {0.0, 1.0} and state[m] == 0
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor", nproc=load)
    assert "restarted from" in r.stdout
    names = ["foundation", "m1", "m2", "m3"]
    ua = np.concatenate([read_body(str(tmp_path / "full.h5"), b, step=-1)["displacement"].ravel() for b in names])
    ub = np.concatenate([read_body(part + "_restart.h5", b, step=-1)["displacement"].ravel() for b in names])
    ca, cb = read_contact(str(tmp_path / "full.h5"), step=-1), read_contact(part + "_restart.h5", step=-1)
    if save == load:
        assert np.array_equal(ua, ub) and np.array_equal(ca["force"], cb["force"])
    else:
        assert np.abs(ua - ub).max() <= 1e-10 * np.abs(ua).max()
        assert np.abs(ca["force"] - cb["force"]).max() <= 1e-10 * np.abs(ca["force"]).max()
