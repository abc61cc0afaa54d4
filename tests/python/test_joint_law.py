"""The joint law of a bonded couple (docs/dam.md, "Bonded joints"): cohesion c, tensile strength
f_t <= c/mu, brittle break point by point to residual friction mu_r.

The scenes are a block of one hex8 cell (1 x 1 x 0.5, nu = 0) on a larger base (3 x 3, one
cell) held at every node. The block is the master side, so its four bottom corners are the contact
points, each of area 1/4; the loads act on those nodes (the push, the pull) and as a uniform pressure on its top, so every
point carries the same traction (nu = 0: the pressure reaches the base unchanged, no Poisson
shear): the bond of all four points reaches the cone's boundary at the same load, the resultant's
capacity c A + mu N, and the law can be checked against that number to the solver's tolerance."""
import os
import re
import subprocess

import numpy as np
import pytest

from conftest import BUILD, PREP, ROOT, env, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import output_times, read_contact, read_csv

A, H = 1.0, 0.5          # contact area, block height
C, MU, MU_R = 1.0e6, 0.6, 0.5
P = 1.0e6                # pressure on the block's top: N = P A


def scene(tmp_path, push=0.0, pull=0.0, dynamic=None, joint=None, pressure=P, mu=MU, final_time=1.6):
    """push: the resultant at the end of a load on the block's bottom nodes along x; pull: a uniform
    traction up on its top, resultant `pull` (the block stretched uniformly, nu = 0: its bottom
    nodes carry pull/4 each). Static: both grow linearly over t = 0..1 in steps of 0.1, the pressure
    is constant. dynamic = dt: a static stage (t = 0..1) under the pressure alone, then the push or
    pull growing linearly from 0 at t = 1 to its resultant at t = 2, in dynamic steps of dt."""
    meshgen.boxes(str(tmp_path / "j.msh"),
                  [dict(lo=(-1, -1, -0.5), hi=(2, 2, 0), n=(1, 1, 1), name="base", cell="hex8"),
                   dict(lo=(0, 0, 0), hi=(1, 1, H), n=(1, 1, 1), name="block", cell="hex8")])
    material = {"E": 3.0e10, "nu": 0.0, "density": 2400}
    couple = {"master": "block_zmin", "slave": "base_zmax", "mu": mu}
    couple.update(joint if joint is not None else {"cohesion": C, "mu_residual": MU_R})
    loads = [{"kind": "pressure", "surface": "block_zmax", "value": pressure}] if pressure else []
    ramp = {"table": [[1, 0], [2, 1]] if dynamic else [[0, 0], [1, 1]]}
    growing = []
    if push:
        growing.append({"kind": "nodal_force", "nodes": "bottom", "vector": [push / 4, 0, 0], "time": ramp})
    if pull:
        growing.append({"kind": "traction", "surface": "block_zmax", "vector": [0, 0, pull / A], "time": ramp})
    sc = {"meshes": {"m": "j.msh"},
          "bodies": {b: {"mesh": "m", "regions": b, "material": material} for b in ("base", "block")},
          "node_sets": {"bottom": {"box": {"lo": [0, 0, 0], "hi": [1, 1, 0]}, "bodies": ["block"]}},
          "couples": [couple],
          "dirichlet": [{"body": "base", "components": "all"}],
          "loads": loads}
    if dynamic:
        sc["stages"] = [{"name": "weight", "analysis": {"type": "static"}},
                        {"name": "push", "analysis": {"type": "dynamic", "dt": dynamic, "final_time": final_time}, "loads": growing}]
    else:
        sc["loads"] = loads + growing
        sc["analysis"] = {"type": "static", "dt": 0.1, "final_time": 1.0}
    return sc


def steps(h5):
    return [read_contact(result(h5, ".h5"), step=k) for k in range(len(output_times(result(h5, ".h5"))))]


@pytest.mark.parametrize("nproc", [1, 2])
def test_bonded_block_pushed_holds_below_capacity(tmp_path, nproc):
    """Static, pushed up to T = 0.95 (c A + mu N) = 1.52 MN (mu N alone is 0.6 MN: unbonded it would
    slide from T = 0.375 of this): every point stays bonded, sticks, and carries T/4 and N/4, in every
    load step; the monitor and the CSV count the bonded points."""
    cap = C * A + MU * P * A
    h5 = prep(tmp_path, scene(tmp_path, push=0.95 * cap))
    r = solve(h5, "-mbc_monitor", "-mbc_multiplier_rtol", "1e-10", nproc=nproc)  # static, free block: newton
    assert "bonded 4" in r.stdout
    c = read_csv(result(h5, "_contact.csv"))
    assert np.all(c["bonded"] == 4)
    for q in steps(h5):
        T = 0.95 * cap * q["time"]
        assert np.all(q["bonded"] == 1) and np.all(np.isnan(q["break_time"]))
        assert np.all(q["state"] == 1), q["state"]
        assert np.allclose(q["pressure"], P, rtol=1e-6)
        assert np.allclose(q["traction"][:, 0], -T / A, rtol=1e-6, atol=1e-6 * P), (q["time"], q["traction"])


def test_bonded_block_pushed_beyond_capacity_has_no_static_state(tmp_path):
    """Static: at the load step where T passes c A + mu N every bond breaks (in that step), and
    mu_r N cannot hold the block: no static equilibrium, a clear error."""
    cap = C * A + MU * P * A
    h5 = prep(tmp_path, scene(tmp_path, push=1.05 * cap))
    r = solve(h5, check=False)
    assert r.returncode != 0
    assert "no static equilibrium" in r.stderr + r.stdout


@pytest.mark.parametrize("nproc,options", [(1, ()), (2, ()), (1, ("-mbc_d_route", "matfree")),
                                            (1, ("-mbc_contact_sliding", "small"))])
def test_bonded_block_pushed_breaks_at_capacity_then_slides(tmp_path, nproc, options):
    """Dynamic (trapezoidal Newmark, dt 0.01 s) after a static stage under the pressure, the push
    growing from t = 1 so that T reaches c A + mu N at t* = 1.505 s (between steps): the
    complementarity holds on the step's mean force, T at mid-step, so the bonds hold up to the step
    ending at 1.51 and break in it (all four: one step); from there every point slides with
    |t| = mu_r p (the residual friction), in the four steps to 1.54 s (it has slid 0.3 m by then:
    (T - mu_r N)/m is 900 m/s^2). The same with the matrix-free D (the shift's
    product W s through the bodies' solves) and with small sliding."""
    cap = C * A + MU * P * A
    tstar = 0.505
    h5 = prep(tmp_path, scene(tmp_path, push=cap / tstar, dynamic=0.01, final_time=1.54))
    r = solve(h5, "-mbc_monitor", "-mbc_multiplier_rtol", "1e-10", *options, nproc=nproc)
    seen_break, sliding = None, 0
    for q in steps(h5)[2:]:  # the static stage's step, the dynamic stage's initial state
        t = q["time"]
        mid = t - 1.005
        if mid < tstar:
            assert np.all(q["bonded"] == 1), (t, q["bonded"])
            assert np.allclose(q["traction"][:, 0], -cap / tstar * mid / A, rtol=1e-6), (t, q["traction"])
        else:
            assert np.all(q["bonded"] == 0), (t, q["bonded"])
            seen_break = seen_break or t
            assert np.allclose(q["break_time"], seen_break)
            assert np.all(q["state"] == 2), (t, q["state"])
            ratio = np.linalg.norm(q["traction"], axis=1) / q["pressure"]
            assert len(ratio) == 4 and np.allclose(ratio, MU_R, rtol=1e-6), (t, ratio)
            sliding += 1
    assert seen_break is not None and abs(seen_break - 1.51) < 1e-9 and sliding == 4
    assert "bonded 0" in r.stdout and re.search(r"step +\d+ t 1.51 .*, 4 bonds broke \(2 solves\); .*bonded 0", r.stdout), r.stdout


@pytest.mark.parametrize("mtype", ["newton", "pgs"])
def test_bonded_block_pushed_without_pressure_dynamic(tmp_path, mtype):
    """Both multiplier types, dynamic from rest (the projected Gauss-Seidel cannot hold a free body in
    a static stage): no pressure, the push reaches the capacity c A at t = 0.505 s; bonded (t = T/A
    at mid-step) before, broken in the step ending at 0.51 s, then no friction holds the block
    (mu_r N = 0 at rest): it moves off along +x, tipping onto its front edge under its own
    inertia, whose points slide with |t| = mu_r p."""
    tstar = 0.505
    sc = scene(tmp_path, push=C * A / tstar, pressure=0.0)
    sc["analysis"] = {"type": "dynamic", "dt": 0.01, "final_time": 0.6}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_type", mtype, "-mbc_multiplier_rtol", "1e-10")
    for q in steps(h5)[1:]:
        t, mid = q["time"], q["time"] - 0.005
        if mid < tstar:
            assert np.all(q["bonded"] == 1), t
            assert np.allclose(q["traction"][:, 0], -C / tstar * mid, rtol=1e-6), (t, q["traction"])
        elif len(q["bonded"]):
            assert np.all(q["bonded"] == 0) and np.allclose(q["break_time"], 0.51), (t, q["break_time"])
            tn = np.linalg.norm(q["traction"], axis=1)
            assert np.allclose(tn, MU_R * np.maximum(q["pressure"], 0), rtol=1e-6, atol=1e-6 * C), (t, tn, q["pressure"])


@pytest.mark.parametrize("nproc", [1, 2])
def test_bonded_block_pulled_holds_below_tensile_strength(tmp_path, nproc):
    """Static, no pressure, pulled up to F = 0.9 f_t A with f_t = c/(2 mu), half the cone's apex (the
    cut-off is judged after the solve of the shifted cone): every bond holds in tension, p = -F/A,
    and the points are "stick" (a bond in tension is not a separated point)."""
    ft = 0.5 * C / MU
    h5 = prep(tmp_path, scene(tmp_path, pull=0.9 * ft * A, pressure=0.0,
                              joint={"cohesion": C, "tensile_strength": ft}))
    solve(h5, "-mbc_multiplier_rtol", "1e-10", nproc=nproc)
    for q in steps(h5):
        assert np.all(q["bonded"] == 1) and np.all(q["state"] == 1)  # held in tension: stick, not separated
        assert np.allclose(q["pressure"], -0.9 * ft * q["time"], rtol=1e-6, atol=1e-3), (q["time"], q["pressure"])


@pytest.mark.parametrize("nproc", [1, 2])
def test_bonded_block_pulled_separates_beyond_tensile_strength(tmp_path, nproc):
    """Dynamic: the pull reaches f_t A at t* = 0.505 s; the bonds hold (p = -F/A at mid-step) before,
    break in the step ending at 0.51 s, and the block separates: no normal force, the gap opens."""
    ft = 0.5 * C / MU
    tstar = 0.505
    h5 = prep(tmp_path, scene(tmp_path, pull=ft * A / tstar, pressure=0.0,
                              joint={"cohesion": C, "tensile_strength": ft}, dynamic=0.01))
    solve(h5, "-mbc_multiplier_rtol", "1e-10", nproc=nproc)
    gaps = []
    for q in steps(h5)[2:]:
        t, mid = q["time"], q["time"] - 1.005
        if not len(q["bonded"]):  # the block has left the search's reach
            break
        if mid < tstar:
            assert np.all(q["bonded"] == 1), t
            # the traction acts on the top: the block's inertia (the elastic oscillation the ramp
            # starts, undamped by the trapezoidal rule) puts the bottom's force off it by ~1e-4
            assert np.allclose(q["pressure"], -ft / tstar * mid, rtol=2e-3), (t, q["pressure"])
        else:
            assert np.all(q["bonded"] == 0) and np.allclose(q["break_time"], 1.51), (t, q["break_time"])
            assert np.all(q["state"] == 0), (t, q["state"])
            gaps.append(q["gap"].min())
    assert gaps and gaps[0] >= 0 and np.all(np.diff(gaps) > 0), gaps


def test_unbonded_couple_unchanged(tmp_path):
    """Cohesion 0 (the default) takes today's path: no bonded/break_time datasets, no CSV column. (That
    the results stay bitwise those of the code before the joint law was checked against its build on
    a dragged block, dynamic with both multiplier types, and a static block held by friction alone:
    every dataset of the result files and the contact CSVs equal, docs/design.md.)"""
    sc = scene(tmp_path, push=0.3 * MU * P, joint={})
    h5 = prep(tmp_path, sc)
    solve(h5)
    q = read_contact(result(h5, ".h5"))
    assert "bonded" not in q and "break_time" not in q
    assert "bonded" not in read_csv(result(h5, "_contact.csv"))


@pytest.mark.parametrize("joint,message", [
    ({"cohesion": -1.0}, "couples[0].cohesion (couple k=1): must be >= 0"),
    ({"cohesion": "nan"}, "couples[0].cohesion (couple k=1): must be a finite number"),
    ({"cohesion": 1.0e6, "tensile_strength": 2.0e6}, "couples[0].tensile_strength (couple k=1): 2e+06 exceeds cohesion / mu"),
    ({"cohesion": 1.0e6, "tensile_strength": -1.0}, "couples[0].tensile_strength (couple k=1): must be >= 0"),
    ({"cohesion": 1.0e6, "mu_residual": -0.1}, "couples[0].mu_residual (couple k=1): must be >= 0"),
    ({"tensile_strength": 1.0}, "couples[0].tensile_strength (couple k=1): a joint law's key needs cohesion"),
    ({"cohesion": 0, "mu_residual": 0.3}, "couples[0] (couple k=1): tensile_strength, mu_residual and softening_displacement belong to a bonded joint"),
    ({"cohesion": 1.0e6, "softening_displacement": -1e-3}, "couples[0].softening_displacement (couple k=1): must be >= 0"),
])
def test_joint_input_errors(tmp_path, joint, message):
    """Bad joint keys stop the prep with a message naming the couple and the key, non-zero exit."""
    sc = scene(tmp_path, joint=joint, mu=0.6 if "mu0" not in joint else 0.0)
    (tmp_path / "s.yaml").write_text(__import__("yaml").safe_dump(sc, sort_keys=False))
    r = subprocess.run([PREP, str(tmp_path / "s.yaml"), "-o", str(tmp_path / "s.h5")], capture_output=True, text=True, env=env())
    assert r.returncode != 0
    assert message in r.stderr, r.stderr


def test_joint_cohesion_needs_friction(tmp_path):
    sc = scene(tmp_path, joint={"cohesion": 1.0e6}, mu=0.0)
    (tmp_path / "s.yaml").write_text(__import__("yaml").safe_dump(sc, sort_keys=False))
    r = subprocess.run([PREP, str(tmp_path / "s.yaml"), "-o", str(tmp_path / "s.h5")], capture_output=True, text=True, env=env())
    assert r.returncode != 0
    assert "couples[0].cohesion (couple k=1): a bonded joint needs friction mu > 0" in r.stderr, r.stderr


@pytest.mark.parametrize("nproc,softening", [(1, 0.0), (2, 0.0), (1, 0.05)])
def test_broken_points_survive_restart(tmp_path, nproc, softening):
    """The checkpoint keeps the bonds' state (/joints/break_time): the pushed block checkpointed at
    t = 1.53 s, after its bonds broke at 1.51 s, and restarted to 1.6 s goes on sliding with the
    same break times and ends where the uninterrupted run ends (1e-12); a restart that forgot them
    would bond the block again and hold it. With softening (delta_s = 0.05 m) checkpointed at 1.52 s,
    while the bonds soften, the damage and the slip summed are kept too."""
    import h5py
    from mbcontact.results import read_body
    cap = C * A + MU * P * A
    joint = {"cohesion": C, "mu_residual": MU_R, **({"softening_displacement": softening} if softening else {})}
    sc = scene(tmp_path, push=cap / 0.505, dynamic=0.01, joint=joint)
    sc["output"] = {"fields": ["displacement"]}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_output", str(tmp_path / "full"), nproc=nproc)
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "1", "-mbc_final_time", "1.52" if softening else "1.53", nproc=nproc)
    with h5py.File(part + "_checkpoint.h5", "r") as f:
        jt = f["joints/break_time"][:]
        if softening:  # 4 break times (all bonded), then damage and slip summed per master node: mid-softening
            assert len(jt) == 12 and np.all(jt[:4] > 1e300) and np.all((jt[4::2] > 0) & (jt[4::2] < 1)), jt
        else:
            assert np.any(np.abs(jt - 1.51) < 1e-12), jt
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor", nproc=nproc)
    assert "restarted from" in r.stdout
    q = read_contact(part + "_restart.h5")
    full = read_contact(str(tmp_path / "full.h5"))
    assert q["time"] == pytest.approx(1.6) and np.all(q["bonded"] == 0) and np.array_equal(q["break_time"], full["break_time"])
    assert softening or np.allclose(q["break_time"], 1.51)
    a = read_body(str(tmp_path / "full.h5"), "block")
    b = read_body(part + "_restart.h5", "block")
    assert a["time"] == b["time"] == pytest.approx(1.6)
    assert np.abs(a["displacement"] - b["displacement"]).max() <= 1e-12 * np.abs(a["displacement"]).max()


@pytest.mark.parametrize("when,bonded", [("3", True), ("55", False)])
def test_fclib_write_of_a_bonded_step(tmp_path, when, bonded):
    """-mbc_fclib_write at a bonded step writes the shifted problem (r_n' = r_n + s, q' = q - W s,
    the couple's mu; its title says so): the stored r' solves it in the Coulomb cones, each bonded
    point's r_n' exceeds the shift s = dscale (c/mu) A / theta by the (compressive) multiplier, and
    mbcontact -fclib solves the file again. The info group's description says what the rows hold.
    After the break (step 55) it is the plain problem with mu_residual, and no info group."""
    from mbcontact.fclib import merit_local, read
    tstar = 0.505
    sc = scene(tmp_path, push=C * A / tstar, pressure=0.0)
    sc["analysis"] = {"type": "dynamic", "dt": 0.01, "final_time": 0.6}
    h5 = prep(tmp_path, sc)
    out = tmp_path / f"step{when}.hdf5"
    solve(h5, "-mbc_fclib_write", str(out), "-mbc_fclib_write_step", when, "-mbc_multiplier_rtol", "1e-10")
    kind, W, q, mus = read(str(out))
    import h5py
    with h5py.File(out, "r") as f:
        r, u = f["solution/r"][...], f["solution/u"][...]
        title = f["fclib_local/info/description"][()].decode() if "fclib_local/info" in f else ""
    assert np.abs(W @ r + q - u).max() <= 1e-10 * (1 + np.abs(u).max())
    assert merit_local(W, q, mus, r) < 1e-8
    assert np.allclose(mus, MU if bonded else MU_R)
    assert ("bonded points: the shifted cone" in title) == bonded, title
    if bonded:  # at rest, pushed: the normal multipliers of the shifted problem are the shift itself
        rn = r[0::3]
        assert np.all(rn > 0) and np.allclose(rn, rn[0], rtol=1e-8)
    from conftest import SOLVER
    again = subprocess.run([SOLVER, "-fclib", str(out)], capture_output=True, text=True, env=env())
    assert again.returncode == 0 and "CONVERGED" in again.stdout, again.stdout + again.stderr


@pytest.mark.parametrize("nproc,fraction", [(1, "1"), (2, "1"), (1, "0")])
def test_cracked_base_under_a_moment(tmp_path, nproc, fraction):
    """The classical cracked-base analysis of a gravity dam: a stiff block (B = 4 m along x, 2 m
    high, 1 m wide, E = 1e12) bonded (c = 10 MPa, mu = 1, f_t = 0.1 MPa) on a thin elastic layer
    (0.1 m, E = 1e9, nu = 0, held at its bottom: a Winkler foundation, so the base pressure is
    beam theory's linear stress), N = 4 MN from a pressure on top, pushed on its upstream face by T
    growing to 5.33 MN, whose moment T H/2 brings the resultant to e = B/3 (the middle-third rule's
    limit is B/6). Beam theory: sigma = N/A -/+ M (B/2)/I at heel and toe; the heel reaches -f_t at
    t = 0.55. Once it cracks, the bonded length L = B - a carries the linear stress with the
    resultant N at x_N = B/2 + e and the tip at -f_t: N/L (1 - 6 (x_N - (a + B)/2)/L) = -f_t gives
    the crack length a (the no-tension crack 3 e - B/2 when f_t = 0). Measured on 64 cells along x
    (h = 1/16 m): the crack runs from the tension side, in the step's cascade of re-solves (behind
    its tip at most one row of nodes still bonded, where the nodal pressures alternate, and the
    heel's corner nodes, whose pressure the layer's free edge keeps above beam theory's), its
    length within 1.8 h of a (0.11 m of up to 1.95 m; measured 1.55 h, 1.73 h with fraction 0), and before the crack the pressures inside the
    base (the corner nodes aside) within 6 % of the mean pressure N/A of beam theory's (the
    corners' share moves inward). The same with -mbc_joint_break_fraction 0 (the most loaded bond
    first in each solve of the cascade: 42 solves for the whole crack instead of 29)."""
    from scipy.optimize import brentq
    B, Hb, n = 4.0, 2.0, 64
    h = B / n
    p, ft = 1.0e6, 0.1e6
    N = p * B
    Tfin = N * B / 3 / (Hb / 2)
    meshgen.boxes(str(tmp_path / "c.msh"),
                  [dict(lo=(0, 0, -0.1), hi=(B, 1, 0), n=(n, 1, 1), name="base", cell="hex8"),
                   dict(lo=(0, 0, 0), hi=(B, 1, Hb), n=(n, 1, 4), name="block", cell="hex8")])
    sc = {"meshes": {"m": "c.msh"},
          "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 1e9, "nu": 0.0}},
                     "block": {"mesh": "m", "regions": "block", "material": {"E": 1e12, "nu": 0.0}}},
          "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 1.0, "cohesion": 10e6, "tensile_strength": ft}],
          "dirichlet": [{"surface": "base_zmin", "components": "all"}],
          "loads": [{"kind": "pressure", "surface": "block_zmax", "value": p},
                    {"kind": "traction", "surface": "block_xmin", "vector": [Tfin / Hb, 0, 0], "time": {"table": [[0, 0], [1, 1]]}}],
          "analysis": {"type": "static", "dt": 0.05, "final_time": 1.0}}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10", "-mbc_joint_break_fraction", fraction, nproc=nproc)
    cracked, worst = 0, 0.0
    for q in steps(h5):
        x = q["reference"][:, 0]
        M = Tfin * q["time"] * Hb / 2
        xN = B / 2 + M / N

        def tip(a):
            L = B - a
            return N / L * (1 - 6 * (xN - (a + B) / 2) / L) + ft
        a = 0.0 if tip(0) >= 0 else brentq(tip, 0, B - 1e-9)
        broken = q["bonded"] == 0
        crack = x[broken].max() + h / 2 if broken.any() else 0.0
        # the crack runs from the heel; behind its tip at most one row of nodes may hold on besides the
        # heel's corner (the nodal pressures near the tip alternate: the layer's consistent forces)
        behind = ~broken & (x > h / 2) & (x < (x[broken].max() if broken.any() else 0))
        assert len(set(x[behind])) <= 1, (q["time"], sorted(set(x[behind])))
        assert abs(crack - a) <= 1.8 * h, (q["time"], crack, a)
        if not broken.any():
            inner = (x > 1.5 * h) & (x < B - 1.5 * h)
            beam = N / B + M * (x[inner] - B / 2) / (B**3 / 12)
            worst = max(worst, np.abs(q["pressure"][inner] - beam).max() / (N / B))
        cracked = max(cracked, crack)
    assert cracked > 1.8  # the crack ran to about half the base
    assert worst < 0.06, worst  # measured 5.3 %, next to the corners


def test_energy_balance_closes_across_the_break(tmp_path):
    """The pushed block of test_bonded_block_pushed_breaks_at_capacity_then_slides with the energy
    balance: a bonded point does no work (no relative motion: its multiplier holds it), and after
    the break the points' work is the friction and contact dissipation the balance already counts,
    so the brittle break needs no term of its own: the total (work - kinetic - strain -
    dissipations) stays constant through the dynamic stage to 1e-11 of the external work
    (measured 1.1e-12: 1.5e-5 J of 1.3e7 J) while the block goes from rest to 2.8 MJ of kinetic
    energy within 0.05 s of the break, 0.47 MJ dissipated by residual friction."""
    cap = C * A + MU * P * A
    sc = scene(tmp_path, push=cap / 0.505, dynamic=0.01)
    sc["output"] = {"energy": True}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10")
    e = read_csv(result(h5, "_energy.csv"))
    dyn = e["t"] > 1
    tot = e["total"][dyn]
    assert np.abs(tot - tot[0]).max() <= 1e-11 * e["external_work"].max(), (tot - tot[0])
    assert e["kinetic"][-1] > 1e6 and e["friction_dissipation"][-1] > 1e5


@pytest.mark.parametrize("option,value,message", [
    ("-mbc_joint_break_fraction", "2", "must lie in [0, 1]"),
    ("-mbc_joint_break_rtol", "-1", "must lie in [0, 1)"),
])
def test_joint_option_errors(tmp_path, option, value, message):
    h5 = prep(tmp_path, scene(tmp_path, push=1.0))
    r = solve(h5, option, value, check=False)
    assert r.returncode != 0 and option in r.stderr and message in r.stderr, r.stderr


def test_python_api_reports_the_bonds(tmp_path):
    """Solver.getContactPoints() has bonded and break_time with bonded couples (the C API's
    MBCSolverGetContactJoints), as the result file does: the pushed block of
    test_bonded_block_pushed_without_pressure_dynamic stepped from Python to 0.52 s."""
    import sys
    sc = scene(tmp_path, push=C * A / 0.505, pressure=0.0)
    sc["analysis"] = {"type": "dynamic", "dt": 0.01, "final_time": 0.52}
    h5 = prep(tmp_path, sc)
    script = tmp_path / "drive.py"
    script.write_text(f"""
from petsc4py import PETSc
import mbcontact
opts = PETSc.Options()
opts["mbc_output"] = {str(tmp_path / "py")!r}
scene = mbcontact.Scene().load({str(h5)!r})
solver = mbcontact.Solver().create()
solver.setScene(scene)
solver.setFromOptions()
solver.setUp()
rows = []
while not solver.done:
    solver.step()
    cp = solver.getContactPoints()
    rows.append((int(cp["bonded"].sum()), float(cp["break_time"].max()) if (cp["bonded"] == 0).any() else -1))
print("ROWS", rows)
""")
    e = env()
    e["PYTHONPATH"] = os.pathsep.join([os.path.join(ROOT, "python"), os.path.join(BUILD, "python")])
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=e, timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    rows = eval(r.stdout.split("ROWS", 1)[1])
    assert rows[-3][0] == 4 and rows[-2] == (0, pytest.approx(0.51)) and rows[-1] == (0, pytest.approx(0.51)), rows


@pytest.mark.parametrize("scheme", [{"scheme": "generalized_alpha", "rho_inf": 0.8}, {"scheme": "hht", "alpha": -0.1},
                                    {"newmark": {"beta": 0.3025, "gamma": 0.6}}])
def test_break_under_other_time_schemes(tmp_path, scheme):
    """The bonded cone is imposed on the step's mean contact force z = theta lambda_n+1 + (1 - theta)
    lambda_n, whose theta each scheme sets (docs/design.md): the shift in the problem's units is
    (c/mu) A / theta. Under generalized-alpha (rho_inf 0.8), HHT (alpha -0.1) and the dissipative
    Newmark the pushed block holds with all four bonds to 1.50 s, breaks in the step ending at
    1.51 s, and slides with |t| = mu_r p."""
    cap = C * A + MU * P * A
    sc = scene(tmp_path, push=cap / 0.505, dynamic=0.01, final_time=1.54)
    sc["stages"][1]["analysis"].update(scheme)
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10")
    for q in steps(h5)[2:]:
        if q["time"] < 1.505:
            assert np.all(q["bonded"] == 1) and np.all(q["state"] == 1), q["time"]
        else:
            ratio = np.linalg.norm(q["traction"], axis=1) / q["pressure"]
            assert np.all(q["bonded"] == 0) and np.allclose(q["break_time"], 1.51), q["time"]
            assert len(ratio) == 4 and np.allclose(ratio, MU_R, rtol=1e-6), (q["time"], ratio)


def test_softening_bond_dynamic_against_the_equation_of_motion(tmp_path):
    """Linear softening (softening_displacement delta_s = 0.05 m): the pushed block of
    test_bonded_block_pushed_breaks_at_capacity_then_slides (the stiff block moves as a rigid body
    of mass m = 1200 kg) starts to slide where T passes c A + mu N, and from there every point's
    traction is the softened cone's, |t| = (1 - D) c + mu(D) p with mu(D) = mu + D (mu_r - mu), to
    1e-6, its damage D = slip / delta_s; at D = 1 the bond breaks (then mu_r). The slip follows the
    equation of motion m x'' = T(t) - [(1 - D) c A + mu(D) N], D = x / delta_s (integrated to 1e-10),
    within 15 % at dt = 1 ms from 1 mm of slip on: first order in dt, as the mean force's half step
    (the largest error measured 25 %, 11.7 %, 5.5 % at dt = 2, 1, 0.5 ms; the slip at 1.56 s 0.475,
    0.448, 0.435 m against 0.422 m),
    an unstable softening (its slope, 2.2e7 N/m, e-folds the slip in 7 ms)."""
    from scipy.integrate import solve_ivp
    ds, dt = 0.05, 0.001
    cap = C * A + MU * P * A
    rate = cap / 0.505
    sc = scene(tmp_path, push=rate, dynamic=dt, final_time=1.56,
               joint={"cohesion": C, "mu_residual": MU_R, "softening_displacement": ds})
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10")
    m = 2400 * A * H

    def rhs(t, y):
        x, v = y
        F = rate * (t - 1)
        if x <= 0 and v <= 0 and F < cap:
            return [0, 0]
        D = min(1.0, max(x, 0) / ds)
        return [v, (F - (1 - D) * C * A - (MU + D * (MU_R - MU)) * P * A) / m]
    ode = solve_ivp(rhs, (1.0, 1.56), [0, 0], max_step=1e-4, rtol=1e-10, atol=1e-12, dense_output=True)
    softened = broken = 0
    for q in steps(h5)[2:]:
        t, D = q["time"], q["damage"]
        slip = np.linalg.norm(q["slip"], axis=1)
        tn = np.linalg.norm(q["traction"], axis=1)
        if np.all(q["bonded"] == 1) and D.max() > 1e-6:
            softened += 1
            assert np.allclose(D, slip / ds, rtol=1e-6, atol=1e-9), (t, D, slip)
            assert np.allclose(tn, (1 - D) * C + (MU + D * (MU_R - MU)) * q["pressure"], rtol=1e-6), (t, tn)
        if np.all(q["bonded"] == 0):
            broken += 1
            assert np.all(D == 1) and np.allclose(tn, MU_R * q["pressure"], rtol=1e-6), t
        x = ode.sol(t)[0]
        if x > 1e-3:
            assert abs(slip.mean() / x - 1) < 0.15, (t, slip.mean(), x)
    assert softened > 10 and broken > 10, (softened, broken)


@pytest.mark.parametrize("nproc", [1, 2])
def test_softening_bond_static_displacement_driven(tmp_path, nproc):
    """Static, the block's top driven along x by 0.08 m in 40 load steps (displacement control: the
    block's shear stiffness, 3e10 N/m, is far above the softening's 2.2e7 N/m, so every state is
    stable): the base holds to the peak, then every point's traction follows its softened cone
    (1 - D) c + mu(D) p with D = slip / delta_s to 1e-6 in every load step (the damage counted from
    each load step's start over its equilibrium iterations; the points' slips differ by the block's
    shear under the drive's moment), reaching mu_r p once the bonds break at a slip of delta_s =
    0.05 m. p = 4 MPa keeps the whole base pressed against that moment (an opening adds to D)."""
    ds = 0.05
    sc = scene(tmp_path, joint={"cohesion": C, "mu_residual": MU_R, "softening_displacement": ds}, pressure=4 * P)
    sc["dirichlet"] += [{"surface": "block_zmax", "components": ["x"], "value": 0.08, "time": {"table": [[0, 0], [1, 1]]}},
                        {"surface": "block_zmax", "components": ["y"]}]
    sc["analysis"] = {"type": "static", "dt": 0.025, "final_time": 1.0}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10", nproc=nproc)
    seen = set()
    for q in steps(h5):
        D = q["damage"]
        slip = np.linalg.norm(q["slip"], axis=1)
        tn = np.linalg.norm(q["traction"], axis=1)
        assert np.allclose(D, np.minimum(1, slip / ds), rtol=1e-6, atol=1e-9), (q["time"], D, slip)
        if slip.min() > 1e-6:  # every point slides: on its softened cone
            assert np.allclose(tn, (1 - D) * C + (MU + D * (MU_R - MU)) * q["pressure"], rtol=1e-6), (q["time"], tn)
            seen.add("softening" if D.max() < 1 else "broken")
    assert seen == {"softening", "broken"}


@pytest.mark.parametrize("bonded", [True, False])
def test_intact_bond_keeps_the_water_out(tmp_path, bonded):
    """Uplift with penetration (docs/scene.md, couples' uplift) on the base of the cracked-base
    scene: the reservoir's water enters the joint from the heel up to the first point in
    compression, or still bonded. Bonded strongly (c = 10 MPa, f_t = c/mu = 5 MPa: nothing breaks) the heel
    holds in tension under the moment (p down to -0.9 MPa at t = 1) and the joint stays dry (wet
    length 0 in every step); unbonded the heel opens and the water runs in (wet length > 0)."""
    B, Hb, n = 4.0, 2.0, 32
    p = 1.0e6
    N = p * B
    Tfin = N * B / 3 / (Hb / 2)
    meshgen.boxes(str(tmp_path / "c.msh"),
                  [dict(lo=(0, 0, -0.1), hi=(B, 1, 0), n=(n, 1, 1), name="base", cell="hex8"),
                   dict(lo=(0, 0, 0), hi=(B, 1, Hb), n=(n, 1, 4), name="block", cell="hex8")])
    couple = {"master": "block_zmin", "slave": "base_zmax", "mu": 2.0,  # the unbonded block, its N lowered by the uplift, holds
              "uplift": {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": B, "heel_head": 20.0,
                         "unit_weight": 9810.0, "level": 20.0, "penetration": True}}
    if bonded:
        couple["cohesion"] = 10e6
    sc = {"meshes": {"m": "c.msh"},
          "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 1e9, "nu": 0.0}},
                     "block": {"mesh": "m", "regions": "block", "material": {"E": 1e12, "nu": 0.0}}},
          "couples": [couple],
          "dirichlet": [{"surface": "base_zmin", "components": "all"}],
          "loads": [{"kind": "pressure", "surface": "block_zmax", "value": p},
                    {"kind": "traction", "surface": "block_xmin", "vector": [Tfin / Hb, 0, 0], "time": {"table": [[0, 0], [1, 1]]}}],
          "analysis": {"type": "static", "dt": 0.1, "final_time": 1.0}}
    h5 = prep(tmp_path, sc)
    solve(h5, "-mbc_multiplier_rtol", "1e-10")
    wet = read_csv(result(h5, "_contact.csv"))["wet_length"]
    q = read_contact(result(h5, ".h5"))
    if bonded:
        assert np.all(q["bonded"] == 1) and q["pressure"].min() < -0.5e6, q["pressure"].min()
        assert np.all(wet == 0), wet
    else:
        assert wet[-1] > 0.5, wet


@pytest.mark.parametrize("cohesion", [0.0, 1e6], ids=["unbonded", "bonded"])
def test_static_dam_with_a_lift_joint(tmp_path, cohesion):
    """The builder's static dam with a lift joint at 40 m, bonded (c = 1 MPa) or not: each lift a
    free body on the one below, every monolith held by contact only. Bonded, the multiplier solve
    starts from r' = 0 (the warm start r + s only from a nonzero r), so the Newton type takes its
    all-stick predictor; it stalled at a merit of 6e-2 before (every load step cut). The base
    carries the four monoliths' weight W and the water's thrust T to 1e-6 (the builder's analytic
    values), and a bonded lift joint stays bonded at this load."""
    from conftest import load_script
    dam = load_script("meshes/dam/build.py", "dam_build")
    h5 = dam.build(tmp_path, "static", h=10.0, lift_joints=(40.0,), cohesion_lift=cohesion, quiet=True)
    solve(h5)
    info = dam.build.info
    c = read_csv(result(h5, "_contact.csv"))
    base = c["couple"] == 1
    n = info["params"]["monoliths"]
    assert abs(c["fz"][base][-1] - n * info["weight"]) < 1e-6 * n * info["weight"], c["fz"][base]
    assert abs(abs(c["fx"][base][-1]) - n * info["thrust"]) < 1e-6 * n * info["weight"], c["fx"][base]
    lift = c["couple"] != 1
    if cohesion:
        assert np.all(c["bonded"][lift] == c["points"][lift]), (c["bonded"][lift], c["points"][lift])
