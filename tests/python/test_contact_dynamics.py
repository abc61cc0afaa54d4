"""Contact dynamics against exact solutions: a block sliding or sticking on an inclined plane
(Coulomb friction), the energy balance of an undamped impact, and the same slide on several
ranks. Small meshes (a few hundred DOFs per body), a few seconds in all."""
import math
import re

import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import output_cuts, read_contact, read_csv

G = 9.81
RHO, E = 2000.0, 1.0e9  # kg/m3, Pa: a stiff block, elastic displacements ~ rho g h^2 / E ~ 1e-6 m

# Newmark variants: the scene default (trapezoidal rule) and the dissipative one the two-block
# tests use (it damps the high modes the step does not resolve; both integrate a constant
# acceleration exactly, so neither damps the rigid slide).
TRAPEZOIDAL = {"beta": 0.25, "gamma": 0.5}
DISSIPATIVE = {"beta": 0.3025, "gamma": 0.6}


def contact_state(stdout, step=None):
    """The monitor's "contact: <type> ... iterations" line of a step (default: the last) and its counts
    {"separated": n, "stick": n, "slip": n, "converged": bool}."""
    lines = [l for l in stdout.splitlines() if "contact: " in l and " in " in l and "iterations (merit" in l and (step is None or l.startswith(f"step {step:5d} "))]
    line = lines[-1]
    state = {k: int(v) for k, v in re.findall(r"(separated|stick|slip) (\d+)", line)}
    state["converged"] = "CONVERGED" in line
    return line, state


# ---------------------------------------------------------------------------------------------
# 1. Block on an inclined plane, realised by tilting gravity
# ---------------------------------------------------------------------------------------------

MU = 0.3
BLOCK_H = 0.5   # block 1 x 1 x 0.5 m, mass 1000 kg
DT, T_END = 1.0e-3, 0.5


def incline_scene(tmp_path, theta_deg, newmark):
    """Block [0,1]x[0,1]x[0,0.5] (hex8 4x4x2, 75 vertices) resting with zero gap on a base
    [-0.5,2.5]x[-0.5,1.5]x[-1,0] (hex8 3x2x2) whose top (the slave face) and bottom are prescribed
    in all components: a rigid plane. Gravity g (sin t, 0, -cos t) on the block, applied suddenly.
    rayleigh_beta = 8e-4 s on the block: its lowest elastic modes on the base (shear c_s / 4h
    ~ 224 Hz, compression c_p / 4h ~ 390 Hz) get damping ratios beta w / 2 ~ 0.56 and 0.97, so the
    vibration the sudden load excites dies out within ~0.01 s; C = beta K is zero on rigid motion,
    so the slide itself is not damped (mass damping would be)."""
    meshgen.boxes(str(tmp_path / "incline.msh"),
                  [dict(lo=(-0.5, -0.5, -1.0), hi=(2.5, 1.5, 0.0), n=(3, 2, 2), name="base"),
                   dict(lo=(0, 0, 0), hi=(1, 1, BLOCK_H), n=(4, 4, 2), name="block")])
    th = math.radians(theta_deg)
    scene = {
        "title": f"block on a {theta_deg} degree incline",
        "meshes": {"m": "incline.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": E, "nu": 0.25, "density": RHO}},
                   "block": {"mesh": "m", "regions": "block",
                             "material": {"E": E, "nu": 0.25, "density": RHO, "rayleigh_beta": 8.0e-4}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": MU}],
        "dirichlet": [{"surface": "base_zmin", "components": "all"}, {"surface": "base_zmax", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [G * math.sin(th), 0.0, -G * math.cos(th)], "time": "sudden", "bodies": ["block"]}],
        "analysis": {"type": "dynamic", "dt": DT, "final_time": T_END, "newmark": dict(newmark)},
        "output": {"every": 1000000, "fields": ["displacement"], "energy": True,
                   "points": {"top": {"x": [0.5, 0.5, BLOCK_H], "body": "block"},
                              "bottom": {"x": [0.5, 0.5, 0.0], "body": "block"},
                              "corner": {"x": [0.0, 0.0, 0.0], "body": "block"}}},
    }
    return prep(tmp_path, scene, name="incline")


POINTS = ("top", "bottom", "corner")


@pytest.mark.parametrize("newmark", [TRAPEZOIDAL, DISSIPATIVE], ids=["trapezoidal", "dissipative"])
def test_block_slides_down_incline(tmp_path, newmark):
    """theta = 30 deg > atan(0.3) = 16.7 deg: the block slides with a = g (sin t - mu cos t)
    = 2.3563 m/s2 (every base point slips, friction mu N in total, N = m g cos t). a is the
    second derivative of a least-squares parabola through u_x(t) of three block points over
    t in [0.1, 0.5] s (400 steps, a slide of 0.29 m), after the initial transient. Tolerance
    1e-3 relative (the target is 1 %): Newmark integrates a constant acceleration exactly
    whatever beta and gamma, so the fit can only see the leftover elastic vibration (amplitude
    ~1e-6 m, decaying as exp(-beta w^2 t / 2) with beta w^2 / 2 > 700 /s) against a t^2/2 ~
    0.1 m, and the PGS tolerance 1e-8: measured errors are ~1e-8. The sliding block has no
    sticking contact point at the end, and it stays on the plane (|u_z| at the bottom < 1e-6 m;
    the resultant of the base pressure lies mu h / 2 = 0.075 m ahead of the centre, inside the
    middle third, so no edge lifts off).

    Energy: the frictional dissipation is mu N times the slide (within 1e-3: the initial elastic
    transient) and total = kinetic + strain - work + damped + friction + normal contact stays at 0:
    within 1e-8 of the external work (1445 J) for the trapezoidal rule, whose balance is exact with
    the step's mean force up to the PGS tolerance 1e-8 (measured 1.4e-8 J, 1e-11 of the work;
    without the friction term the total drifted to -751 J). The dissipative variant loses energy
    to its numerical damping of the vibration the sudden load excites: negative, and less than
    twice the static strain energy (measured -7.5e-4 J against 6.9e-3 J)."""
    h5 = incline_scene(tmp_path, 30.0, newmark)
    r = solve(h5, "-mbc_monitor")
    p = read_csv(result(h5, "_points.csv"))
    th = math.radians(30.0)
    exact = G * (math.sin(th) - MU * math.cos(th))
    window = p["t"] >= 0.1 - 1e-12
    errors = {}
    for name in POINTS:
        c = np.polyfit(p["t"][window], p[f"{name}_ux"][window], 2)
        errors[name] = 2 * c[0] / exact - 1
    print(f"\nincline 30 deg, {newmark}: a exact {exact:.6f} m/s2, relative errors of the fits {errors}")
    assert all(abs(e) < 1e-3 for e in errors.values()), errors
    # the slide: 1/2 a t^2 at the end, within the same tolerance (starts at rest at t = 0)
    assert abs(p["bottom_ux"][-1] / (0.5 * exact * T_END**2) - 1) < 1e-2
    assert np.abs(p["bottom_uz"]).max() < 1e-6
    last, state = contact_state(r.stdout)
    assert state["converged"] and state["stick"] == 0 and state["slip"] > 0, last
    # the reported slip (sum of the steps' tangential relative displacements) is the slide
    cc = read_csv(result(h5, "_contact.csv"))
    assert abs(cc["max_slip"][-1] / p["bottom_ux"][-1] - 1) < 1e-4, (cc["max_slip"][-1], p["bottom_ux"][-1])
    # energy: friction dissipates mu N per metre of slide, and with it the balance closes
    en = read_csv(result(h5, "_energy.csv"))
    friction = MU * RHO * BLOCK_H * G * math.cos(th) * p["bottom_ux"][-1]
    work = en["external_work"][-1]
    print(f"energy: work {work:.3f} J, friction {en['friction_dissipation'][-1]:.3f} J (mu N s {friction:.3f}), "
          f"normal contact {en['contact_dissipation'][-1]:.3g} J, max |total| {np.abs(en['total']).max():.3g} J")
    assert abs(en["friction_dissipation"][-1] / friction - 1) < 1e-3
    if newmark == TRAPEZOIDAL:
        assert np.abs(en["total"]).max() < 1e-8 * work
    else:
        assert np.all(en["total"] <= 1e-8 * work) and en["total"].min() > -2 * en["strain"][-1]


@pytest.mark.parametrize("newmark", [TRAPEZOIDAL, DISSIPATIVE], ids=["trapezoidal", "dissipative"])
def test_block_sticks_on_incline(tmp_path, newmark):
    """theta = 10 deg < atan(0.3): the block stays put. Its displacements stay at the elastic
    level: the shear of the block under its weight along the slope, rho g sin t h^2 / (2 G)
    ~ 1e-6 m, and its compression ~ rho g h^2 / (2 E) ~ 2.5e-6 m, at most doubled by the sudden
    load: every |u| < 1e-5 m over the whole run, 2e4 times below the free slide 1/2 g sin t T^2
    = 0.21 m (and 5e3 times below the frictional slide at mu = 0.1). The base carries the weight:
    the contact resultant (contact CSV) balances m g (sin t, 0, -cos t) within 0.5 % (the
    vibration the sudden load excited is damped out by 0.4 s). The resultant of the base pressure
    is (h/2) tan t = 0.044 m off centre, inside the middle third, so no point separates.
    With the dissipative Newmark every point sticks. With the trapezoidal rule the contact forces
    of a constrained point keep a period-2 oscillation (the rule's amplification is -1 for the
    infinitely stiff constraint mode, and damping proportional to K or M does not reach it): the
    two-step mean is exact, and a corner point whose traction ratio is within a few percent of mu
    (edge concentration of the shear traction under an elastic block) may flip to slip every other
    step; at most the 4 corners may slip there."""
    h5 = incline_scene(tmp_path, 10.0, newmark)
    r = solve(h5, "-mbc_monitor")
    p = read_csv(result(h5, "_points.csv"))
    th = math.radians(10.0)
    free_slide = 0.5 * G * math.sin(th) * T_END**2
    umax = max(np.abs(p[f"{n}_u{c}"]).max() for n in POINTS for c in "xyz")
    last, state = contact_state(r.stdout)
    c = read_csv(result(h5, "_contact.csv"))
    late = c["t"] >= 0.4 - 1e-9
    weight = RHO * BLOCK_H * G
    fx, fz = c["fx"][late], c["fz"][late]
    mean2 = lambda f: 0.5 * (f[1:] + f[:-1])  # noqa: E731  (two-step mean)
    print(f"\nincline 10 deg, {newmark}: max |u| {umax:.3e} m (free slide {free_slide:.3f} m); last: {last}; "
          f"resultant ({mean2(fx)[-1]:.2f}, {mean2(fz)[-1]:.2f}) N vs ({-weight * math.sin(th):.2f}, {weight * math.cos(th):.2f})")
    assert umax < 1e-5, umax
    assert np.abs(mean2(fx) / (-weight * math.sin(th)) - 1).max() < 5e-3
    assert np.abs(mean2(fz) / (weight * math.cos(th)) - 1).max() < 5e-3
    assert state["converged"] and state["separated"] == 0, last
    assert state["slip"] == 0 if newmark == DISSIPATIVE else state["slip"] <= 4, last


# ---------------------------------------------------------------------------------------------
# 2. Energy in an undamped impact
# ---------------------------------------------------------------------------------------------

def test_impact_gains_no_energy(tmp_path):
    """An upper block 1 x 1 x 0.5 m (hex8 4x4x2, mass m = 1000 kg) starts delta = 1 mm above a
    lower block 1 x 1 x 1 m (hex8 4x4x4, base fixed), frictionless couple, no damping, gravity
    on the upper block applied suddenly, trapezoidal rule (beta 1/4, gamma 1/2), dt = 1e-4 s:
    the impact (the wave crosses the upper block and back in 2 * 0.5 m / 707 m/s = 1.4 ms) takes
    ~14 steps, so the step resolves it. Impact at t_i = sqrt(2 delta / g) = 14.28 ms with
    kinetic energy K_i = m g delta = 9.81 J; the run goes on to 30 ms.

    * Before the impact the upper block falls freely: u_z = -g t^2 / 2 to 1e-10 relative (the
      trapezoidal rule is exact for a constant acceleration, K times a translation is zero up to
      rounding; measured ~4e-14), and the lower block does not move.
    * The mechanical energy kinetic + strain - external work is exact for the trapezoidal
      rule up to the work of the contact forces; before contact it stays within 1e-10 K_i of 0
      (rounding only). The energy CSV's total adds what the contact took (the step's mean force
      times the gap increments): it stays within 1e-6 K_i of 0 all along.
    * At the first step after t_i the gap (delta + u_z of the upper block's bottom centre - u_z of
      the lower block's top centre, node on node) is closed: |gap| < 1e-6 delta (PGS tolerance).
    * Contact may only dissipate: total <= 1e-6 K_i at every step. 1e-6 covers the rounding of
      the energy sums (terms of order K_i, errors ~1e-12 K_i) and the inexact complementarity of
      the multipliers (PGS to 1e-8), each many orders below it, while any spurious work of the
      multipliers shows up at the scale of K_i. Losing energy at impact is allowed (Lagrange
      multipliers with the trapezoidal rule do); how much is printed."""
    delta = 1.0e-3
    meshgen.boxes(str(tmp_path / "impact.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(4, 4, 4), name="lower"),
                   dict(lo=(0, 0, 1 + delta), hi=(1, 1, 1.5 + delta), n=(4, 4, 2), name="upper")])
    material = {"E": E, "nu": 0.0, "density": RHO}
    dt, final_time = 1.0e-4, 0.03
    scene = {
        "title": "undamped impact",
        "meshes": {"m": "impact.msh"},
        "bodies": {"lower": {"mesh": "m", "regions": "lower", "material": material},
                   "upper": {"mesh": "m", "regions": "upper", "material": material}},
        "couples": [{"master": "upper_zmin", "slave": "lower_zmax", "mu": 0.0}],
        "dirichlet": [{"surface": "lower_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G], "time": "sudden", "bodies": ["upper"]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": final_time, "newmark": dict(TRAPEZOIDAL)},
        "output": {"every": 1000000, "fields": ["displacement"], "energy": True,
                   "points": {"top": {"x": [0.5, 0.5, 1.5 + delta], "body": "upper"},
                              "face": {"x": [0.5, 0.5, 1 + delta], "body": "upper"},
                              "support": {"x": [0.5, 0.5, 1.0], "body": "lower"}}},
    }
    h5 = prep(tmp_path, scene, name="impact")
    r = solve(h5, "-mbc_monitor")
    p = read_csv(result(h5, "_points.csv"))
    en = read_csv(result(h5, "_energy.csv"))
    t = p["t"]
    total = en["kinetic"] + en["strain"] - en["external_work"] + en["damping_dissipation"]  # mechanical
    assert np.array_equal(en["t"], t)
    t_i = math.sqrt(2 * delta / G)
    k_i = 0.5 * RHO * G * delta  # m g delta, m = rho * 0.5 m3
    before = (t > 0) & (t < t_i)
    after = np.argmax(t >= t_i)
    gap = delta + p["face_uz"] - p["support_uz"]
    print(f"\nimpact: K_i {k_i:.4f} J; total energy: max {total.max():.6g} J ({total.max() / k_i:.3g} K_i) at t = "
          f"{t[np.argmax(total)]:.4f} s, after the first contact step {total[after]:.6g} J, end {total[-1]:.6g} J; "
          f"taken by the contact {en['contact_dissipation'][-1]:.6g} J, balance max |total| {np.abs(en['total']).max():.3g} J; "
          f"gap after impact {gap[after]:.3e} m, min gap {gap[after:].min():.3e} m")

    # free fall, exact
    assert before.sum() > 100
    assert np.abs(p["top_uz"][before] / (-0.5 * G * t[before] ** 2) - 1).max() < 1e-10
    assert np.abs(p["face_uz"][before] / (-0.5 * G * t[before] ** 2) - 1).max() < 1e-10
    assert np.all(p["support_uz"][before] == 0)
    assert np.abs(total[t < t_i]).max() < 1e-10 * k_i
    # the gap closes at impact, without penetration
    assert abs(gap[after]) < 1e-6 * delta, gap[after]
    line, state = contact_state(r.stdout, step=after)
    assert state["separated"] == 0 and state["slip"] == 25, line  # frictionless: every point "slips"
    # the balance with the contact's share closes; the contact only takes energy
    assert np.abs(en["total"]).max() < 1e-6 * k_i, np.abs(en["total"]).max()
    assert en["contact_dissipation"].min() > -1e-6 * k_i and np.all(en["friction_dissipation"] == 0)
    # contact never adds energy
    assert total.max() <= 1e-6 * k_i, (f"total energy rises to {total.max():.6g} J = {total.max() / k_i:.3g} x the "
                                       f"kinetic energy at impact, at t = {t[np.argmax(total)]:.5f} s")


# ---------------------------------------------------------------------------------------------
# 3. The slide on several ranks
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("nproc", [2, 3])
def test_incline_slide_parallel(tmp_path, nproc):
    """The 30 deg slide (dissipative Newmark) on nproc ranks gives the 1-rank histories to 1e-8
    relative (max over time of |u_parallel - u_serial| over max over time of |u_serial|, per
    point). On 2 ranks each body has its own rank (the contact data cross ranks); on 3 the block
    (75 vertices against the base's 36) is split over 2 ranks, so its factorization, H and the
    output point are distributed too. Only the summation order of reductions differs: differences
    are rounding (measured: 0 on 2 ranks, ~1e-12 on 3)."""
    serial_dir, parallel_dir = tmp_path / "serial", tmp_path / "parallel"
    serial_dir.mkdir()
    parallel_dir.mkdir()
    histories = []
    for d, n in ((serial_dir, 1), (parallel_dir, nproc)):
        h5 = incline_scene(d, 30.0, DISSIPATIVE)
        solve(h5, nproc=n)
        histories.append(read_csv(result(h5, "_points.csv")))
    serial, parallel = histories
    assert np.array_equal(serial["t"], parallel["t"])
    for name in POINTS:
        us = np.stack([serial[f"{name}_u{c}"] for c in "xyz"], 1)
        up = np.stack([parallel[f"{name}_u{c}"] for c in "xyz"], 1)
        rel = np.linalg.norm(up - us, axis=1).max() / np.linalg.norm(us, axis=1).max()
        assert rel < 1e-8, (name, rel)


# ---------------------------------------------------------------------------------------------
# 4. The reported force of sticking points on a deforming base
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("analysis", ["dynamic", "static"])
def test_stick_force_reported_in_the_frames_of_the_multipliers(tmp_path, analysis):
    """Block 1 x 1 x 0.5 m (hex8 4x4x2, 1000 kg) on a base [-0.5,1.5]^2 x [-1,0] (hex8 2x2x2) fixed
    at its bottom only, so its top (the slave face) deforms and the contact normals tilt by ~1e-6:
    enough to swap the tangent axes the search picks (t1 = e x n, e the axis least aligned with n).
    Gravity and a traction of 2400 N along x on the block's top, mu = 0.6 (mu m g = 5886 N): every
    point sticks. The contact output (the per-point force of the result file, summed, and the CSV
    resultant) must carry the applied loads: -2400 N along x, 0 along y, m g along z. It used to
    rotate each point's multipliers by the tangents of the search after the step instead of those
    D was built with: -1520 / -880 N. Dynamic: Newmark trapezoidal, the traction ramped over 0.05 s,
    Rayleigh beta 8e-4 s on both bodies, 0.2 s; the block's inertia leaves the resultant off by
    m |a|, and the two-step mean (the trapezoidal rule's period-2 constraint mode, see
    test_block_sticks_on_incline) is within 0.5 % of the loads at 0.15-0.2 s. Static: to 1e-6 (the
    equilibrium tolerance). y: below 1e-6 of the load in both."""
    meshgen.boxes(str(tmp_path / "stick.msh"),
                  [dict(lo=(-0.5, -0.5, -1.0), hi=(1.5, 1.5, 0.0), n=(2, 2, 2), name="base"),
                   dict(lo=(0, 0, 0), hi=(1, 1, BLOCK_H), n=(4, 4, 2), name="block")])
    material = {"E": E, "nu": 0.25, "density": RHO, "rayleigh_beta": 8.0e-4}
    load = 2400.0
    scene = {
        "meshes": {"m": "stick.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": material},
                   "block": {"mesh": "m", "regions": "block", "material": material}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.6}],
        "dirichlet": [{"surface": "base_zmin"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G], "time": "sudden", "bodies": ["block"]},
                  {"kind": "traction", "surface": "block_zmax", "vector": [load, 0, 0],
                   "time": {"table": [[0, 0], [0.05, 1], [1, 1]]}}],
        "analysis": {"type": "dynamic", "dt": DT, "final_time": 0.2, "newmark": dict(TRAPEZOIDAL)}
        if analysis == "dynamic" else {"type": "static"},
        "output": {"every": 50, "fields": ["displacement"]},
    }
    h5 = prep(tmp_path, scene, name="stick")
    r = solve(h5, "-mbc_monitor")
    last, state = contact_state(r.stdout)
    assert state["stick"] == 25 and state["slip"] == 0, last
    weight = RHO * BLOCK_H * G
    c = read_csv(result(h5, "_contact.csv"))
    pts = read_contact(result(h5, ".h5"))
    total = pts["force"].sum(axis=0)
    print(f"\nstick {analysis}: point forces summed {total}, CSV ({c['fx'][-1]:.3f}, {c['fy'][-1]:.3g}, {c['fz'][-1]:.3f}) N")
    assert np.allclose(total, [c["fx"][-1], c["fy"][-1], c["fz"][-1]], rtol=1e-12, atol=1e-9 * weight)
    assert np.abs(c["fy"]).max() < 1e-6 * load
    if analysis == "static":
        assert abs(total[0] / -load - 1) < 1e-6 and abs(total[2] / weight - 1) < 1e-6
    else:
        late = c["t"] >= 0.15 - 1e-9
        mean2 = lambda f: 0.5 * (f[1:] + f[:-1])  # noqa: E731
        assert np.abs(mean2(c["fx"][late]) / -load - 1).max() < 5e-3
        assert np.abs(mean2(c["fz"][late]) / weight - 1).max() < 5e-3


def test_failed_contact_solve_cuts_the_step(tmp_path):
    """Step control: with the projected Gauss-Seidel limited to 10 sweeps (no active-set step) the
    contact solve of the first step of the sliding block fails (measured: 1 of 200; 4 when each next step went straight back to dt), while at dt/2 the
    flexibility D is more diagonal (the mass term grows as 1/dt^2) and 10 sweeps suffice; each
    failed step is done again as two steps of dt/2 (recursively, down to -mbc_dt_min), said in
    the monitor and the result file's /cuts; the next 3 steps stay at dt/2 (as two steps each), then
    the step grows back to dt; and the physics is unchanged: the fitted acceleration is g (sin t - mu cos t) within 1e-3 (the tolerance of the
    uncut test above) and the slide at the end matches 1/2 a t^2 within 1e-2. With -mbc_dt_cut 0
    the same run stops with the contact solve's message, as before."""
    h5 = incline_scene(tmp_path, 30.0, TRAPEZOIDAL)
    limited = ("-mbc_multiplier_type", "pgs", "-mbc_pgs_active_set", "0", "-mbc_multiplier_max_it", "10", "-mbc_final_time", "0.2")
    r = solve(h5, *limited, "-mbc_monitor")
    cuts = r.stdout.count("the step is cut to two")
    assert cuts > 0, r.stdout[-2000:]
    solves = {}  # contact solves per step: the steps after a cut stay at dt/2, then grow back
    for m in re.finditer(r"step +(\d+) t \S+ +contact: pgs CONVERGED", r.stdout):
        solves[int(m.group(1))] = solves.get(int(m.group(1)), 0) + 1
    first = int(re.search(r"step +(\d+) t \S+ +contact: pgs solve DIVERGED_ITS", r.stdout).group(1))
    assert [solves[first + k] for k in range(1, 5)] == [2, 2, 2, 1], solves
    assert output_cuts(result(h5, ".h5")).sum() == cuts  # the result file says which steps were cut
    p = read_csv(result(h5, "_points.csv"))
    th = math.radians(30.0)
    exact = G * (math.sin(th) - MU * math.cos(th))
    window = p["t"] >= 0.1 - 1e-12
    c = np.polyfit(p["t"][window], p["bottom_ux"][window], 2)
    assert abs(2 * c[0] / exact - 1) < 1e-3, (2 * c[0], exact, cuts)
    assert abs(p["bottom_ux"][-1] / (0.5 * exact * 0.2**2) - 1) < 1e-2
    r = solve(h5, *limited, "-mbc_dt_cut", "0", check=False)
    assert r.returncode != 0 and "Contact multipliers at step" in r.stderr, r.stderr


@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_block_bounces_off_with_a_tangential_velocity(tmp_path, mu):
    """A 0.4 m block thrown at (0.3, 0.2, -1) m/s onto a fixed 1 x 1 x 0.5 m one (E 100 Pa,
    rho 1: c ~ 10 m/s), Newmark's default trapezoidal rule, 100 steps: it strikes, slides and
    bounces off; its points are separated and re-paired (their slave faces change) as it leaves.
    Kinetic plus strain energy never above the start's (the contact and friction only take
    energy; measured 0 above it). Before the released points went on as separated ones
    (src/interface/interfacerelease.c) the bodies left with 7 % (mu 0) and 64 % (mu 0.3) more
    than they had. With friction the energy balance closes to 1e-10 of the start's (measured
    4e-16); frictionless, the points that press while their pairs change keep H_old lambda_n in the
    acceleration (docs/design.md) and the balance is off by 6 % of it, not checked here."""
    d = 0.01
    meshgen.boxes(str(tmp_path / "b.msh"), [dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(3, 3, 2), name="lower"),
                                            dict(lo=(0.3, 0.3, 0.5 + d), hi=(0.7, 0.7, 0.9 + d), n=(2, 2, 2), name="upper")])
    material = {"E": 100.0, "nu": 0.25, "density": 1.0}
    h5 = prep(tmp_path, {
        "meshes": {"m": "b.msh"},
        "bodies": {b: {"mesh": "m", "regions": b, "material": material} for b in ("lower", "upper")},
        "couples": [{"master": "upper_zmin", "slave": "lower_zmax", "mu": mu}],
        "dirichlet": [{"surface": "lower_zmin", "components": "all"}],
        "initial": [{"body": "upper", "velocity": [0.3, 0.2, -1.0]}],
        "analysis": {"type": "dynamic", "dt": 0.005, "final_time": 0.5},
        "output": {"every": 1000000, "fields": ["displacement"], "energy": True}})
    r = solve(h5, "-mbc_monitor")
    assert r.stdout.count("flexibility matrix rebuilt") > 1  # re-paired on the way
    assert re.findall(r"contact: .*separated (\d+), stick", r.stdout)[-1] == "9"  # it left
    e = read_csv(result(h5, "_energy.csv"))
    e0 = 0.5 * 0.4 ** 3 * (0.3 ** 2 + 0.2 ** 2 + 1.0)
    mech = e["kinetic"] + e["strain"]
    assert abs(mech[0] / e0 - 1) < 1e-12
    assert mech.max() <= e0 * (1 + 1e-12), mech.max() / e0
    if mu > 0:
        assert np.abs(e["total"]).max() < 1e-10 * e0
