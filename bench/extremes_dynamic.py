#!/usr/bin/python3
"""Numerical stability of the dynamic contact step (issue 17, dynamic part), each case against an
exact or analytic reference.

timestep  dt = 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1 s on one scene to T = 1 s (dt = 1 s: one step).
          A block 1 x 1 x 0.5 m (E 1e10 Pa, nu 0, rho 2000, 2 hex cells) on a rigid plane (a base
          whose top and bottom are prescribed), mu = 0.3, trapezoidal rule, no damping. Gravity
          (0, 0, -g) and a horizontal body force mu g, both ramped over 0.1 s with the same table,
          plus a horizontal j t (j = g). Friction mu N balances the mu g part at every instant, so
          the rigid-body Coulomb answer is a slide from t = 0 with a = j t: x(t) = j t^3 / 6.
          The trapezoidal rule applied to that motion gives x_n = j t^3 / 6 + j t dt^2 / 12
          exactly (per step it integrates the linear acceleration's t^3 term with dt^3 j / 4
          instead of dt^3 j / 6), so the expected relative error at T is dt^2 / (2 T^2): order 2,
          from 5e-11 to 0.5. The elastic block departs from the rigid one by its elastic
          deformation and the vibration the start excites (measured below 1e-6). The elastic
          periods are ~1e-3 s: dt spans 1e-2 to 1e3 of them, and the reference holds at both ends.
          Pass: every multiplier solve CONVERGED, |error - dt^2 / (2 T^2)| < 1e-5, and the
          mechanical energy plus what friction took never above 0 by more than 1e-6 of the
          reference kinetic energy at T (m (j T^2 / 2)^2 / 2 = 12 kJ).
bounce    An upper block 1 x 1 x 0.5 m (one hex8i cell, E 1e9, nu 0, rho 2000) dropped delta = 25 um
          onto a lower block 1 x 1 x 1 m (one cell, fixed bottom), frictionless, no damping,
          trapezoidal rule, dt = 1e-4 s, run for P = 10, 100, 1000 periods of the first bounce
          (2 sqrt(2 delta / g) = 4.5 ms, so 1000 periods = 4.5 s = 45 150 steps). Reference:
          undamped, the mechanical energy kinetic + strain - external work stays 0; impacts
          with Lagrange multipliers may lose energy (docs/design.md), never gain. error: the
          energy lost at the end / K_i (K_i = m g delta, the kinetic energy at the first impact);
          drift: its largest gain / K_i. Pass: every solve CONVERGED and drift < 1e-6 (the
          rounding of energy sums of order K_i, ~1e-12, and the multiplier tolerance 1e-8).
          Also reported: impacts (landings after a flight with every contact point open) and the
          deepest penetration at a corner.
          A listed, uncounted row repeats 100 periods with -mbc_contact_push_out (the step closes
          a penetration it starts from, the behaviour before the fix): it gained 120 K_i.

Every case returns a dict (cases()); main() prints the table and writes docs/extremes_dynamic.png.

  bench/extremes_dynamic.py [--smoke] [--plot PNG]
"""
import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402
from mbcontact.results import read_csv  # noqa: E402

SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
G = 9.81
RHO = 2000.0
TRAPEZOIDAL = {"beta": 0.25, "gamma": 0.5}

# timestep sweep
MU, J, T_SLIDE, RAMP = 0.3, G, 1.0, 0.1
E_SLIDE = 1.0e10
FLOOR = 1e-5        # |error - dt^2 / (2 T^2)|: the elastic block against the rigid one (measured < 1e-6)
DRIFT_TOL = 1e-6    # energy gain / reference energy: rounding and the multiplier tolerance 1e-8
TIMESTEPS = [1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0]

# bounces
DELTA, E_BOUNCE, DT_BOUNCE = 25e-6, 1.0e9, 1e-4
PERIODS = [10, 100, 1000]


def run(h5, *options):
    """The solver with -mbc_monitor; returns (returncode, stdout + stderr, wall s)."""
    t0 = time.perf_counter()
    r = subprocess.run([SOLVER, "-scene", h5, "-mbc_monitor", *options], capture_output=True, text=True, env=ENV)
    return r.returncode, r.stdout + r.stderr, time.perf_counter() - t0


def monitor(out):
    """Converged reasons of the multiplier solves, their iterations, static iterations, step cuts
    (the dynamic monitor prints "contact: newton CONVERGED_RTOL in 2 iterations (merit ...)" per
    solve, a failed one "contact: newton solve DIVERGED_ITS ...", bench/extremes.py's row())."""
    reasons = sorted(set(re.findall(r"contact: \w+ (\w+) in", out)) | set(re.findall(r"contact: \w+ solve (\w+)", out))) or ["(none)"]
    its = sum(int(i) for i in re.findall(r" in (\d+) iterations", out))
    static_its = len(re.findall(r"static iteration", out))
    cuts = out.count("the step is cut to two")
    return reasons, its, static_its, cuts


def converged(reasons):
    return bool(reasons) and all(r.startswith("CONVERGED") for r in reasons)


def slide_case(work, dt, T=T_SLIDE):
    """The block on the rigid plane at time step dt (module docstring); a case dict."""
    name = f"slide_{dt:g}"
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(-0.5, -0.5, -1.0), hi=(3.5, 1.5, 0.0), n=(4, 2, 2), name="base"),
                   dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(1, 1, 2), name="block")])
    material = {"E": E_SLIDE, "nu": 0.0, "density": RHO}
    ramp = {"table": [[0, 0], [RAMP, 1], [T, 1]]}
    scene = {
        "title": f"block sliding under a ramped push, dt = {dt:g} s",
        "meshes": {"m": f"{name}.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": material},
                   "block": {"mesh": "m", "regions": "block", "material": material}},
        # the block's bottom nodes are the contact points: they stay paired while it slides 1.6 m
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": MU}],
        "dirichlet": [{"surface": "base_zmin", "components": "all"}, {"surface": "base_zmax", "components": "all"}],
        # N = m g f(t) and the push mu m g f(t) share the ramp f: friction balances it at every instant
        "loads": [{"kind": "gravity", "vector": [MU * G, 0, -G], "time": ramp, "bodies": ["block"]},
                  {"kind": "gravity", "vector": [J * T, 0, 0], "time": {"table": [[0, 0], [T, 1]]}, "bodies": ["block"]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": T, "newmark": dict(TRAPEZOIDAL)},
        "output": {"every": 1000000000, "fields": ["displacement"], "energy": True,
                   "points": {"mid": {"x": [0.5, 0.5, 0.25], "body": "block"}}},
    }
    h5 = prepare(work, name, scene)
    rc, out, wall = run(h5)
    reasons, its, static_its, cuts = monitor(out)
    x_ref = J * T**3 / 6
    expected = dt**2 / (2 * T**2)
    e_ref = 0.5 * RHO * 0.5 * (J * T**2 / 2) ** 2
    error = drift = float("inf")
    if rc == 0:
        p = read_csv(h5[:-3] + "_result_points.csv")
        en = read_csv(h5[:-3] + "_result_energy.csv")
        error = abs(p["mid_ux"][-1] / x_ref - 1)
        gain = en["kinetic"] + en["strain"] - en["external_work"] + en["damping_dissipation"] + en["friction_dissipation"]
        drift = max(float(gain.max()), 0.0) / e_ref
    ok = rc == 0 and converged(reasons) and abs(error - expected) < FLOOR and drift < DRIFT_TOL
    return dict(category="timestep", value=f"dt {dt:g} s", x=dt, reasons=reasons, mult_its=its, static_its=static_its,
                error=error, drift=drift, wall=wall, ok=ok, cuts=cuts, expected=expected,
                ref=f"rigid Coulomb slide x = j T^3/6 = {x_ref:.4g} m; trapezoidal error dt^2/(2T^2) = {expected:.2g}",
                note="" if rc == 0 else out.strip().splitlines()[-1])


def bounce_case(work, periods, dt=DT_BOUNCE, push_out=False):
    """The block dropped on the elastic block, run for `periods` periods of the first bounce; a case dict."""
    name = f"bounce_{periods}{'_push' if push_out else ''}"
    t_i = math.sqrt(2 * DELTA / G)
    steps = int(round(periods * 2 * t_i / dt))
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), name="lower"),
                   dict(lo=(0, 0, 1 + DELTA), hi=(1, 1, 1.5 + DELTA), n=(1, 1, 1), name="upper")])
    material = {"E": E_BOUNCE, "nu": 0.0, "density": RHO}
    scene = {
        "title": f"undamped bounces, {periods} periods",
        "meshes": {"m": f"{name}.msh"},
        "bodies": {"lower": {"mesh": "m", "regions": "lower", "material": material},
                   "upper": {"mesh": "m", "regions": "upper", "material": material}},
        "couples": [{"master": "upper_zmin", "slave": "lower_zmax", "mu": 0.0}],
        "dirichlet": [{"surface": "lower_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G], "time": "sudden", "bodies": ["upper"]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": steps * dt, "newmark": dict(TRAPEZOIDAL)},
        "output": {"every": 1000000000, "fields": ["displacement"], "energy": True,
                   # a corner node on a corner node: the gap there is delta + the difference of u_z
                   "points": {"face": {"x": [0, 0, 1 + DELTA], "body": "upper"},
                              "support": {"x": [0, 0, 1], "body": "lower"}}},
    }
    h5 = prepare(work, name, scene)
    rc, out, wall = run(h5, *(["-mbc_contact_push_out"] if push_out else []))
    reasons, its, static_its, cuts = monitor(out)
    k_i = RHO * 0.5 * G * DELTA
    error = drift = float("inf")
    impacts, penetration = 0, float("nan")
    if rc == 0:
        en = read_csv(h5[:-3] + "_result_energy.csv")
        c = read_csv(h5[:-3] + "_result_contact.csv")
        p = read_csv(h5[:-3] + "_result_points.csv")
        mech = en["kinetic"] + en["strain"] - en["external_work"] + en["damping_dissipation"]
        error = abs(mech[-1]) / k_i
        drift = max(float(mech.max()), 0.0) / k_i
        flying = c["separated"] == c["points"]
        impacts = int(np.sum(flying[:-1] & ~flying[1:]))
        gap = DELTA + p["face_uz"] - p["support_uz"]
        penetration = max(0.0, -float(gap.min()))
    ok = rc == 0 and converged(reasons) and drift < DRIFT_TOL
    return dict(category="bounce", value=f"{periods} periods" + (" push_out" if push_out else ""), x=float(periods),
                reasons=reasons, mult_its=its, static_its=static_its, error=error, drift=drift, wall=wall, ok=ok,
                cuts=cuts, impacts=impacts, penetration=penetration, steps=steps, counted=not push_out,
                ref=f"undamped: mechanical energy stays 0 (K_i = {k_i:.4g} J); error = energy lost / K_i",
                note="" if rc == 0 else out.strip().splitlines()[-1])


def cases(work, smoke):
    """Every case of both categories (smoke: one each), as dicts: category, value, x, reasons,
    mult_its, static_its, error, drift, wall, ok, ref (and cuts, expected / impacts, penetration)."""
    rows = [slide_case(work, dt) for dt in ([1e-2] if smoke else TIMESTEPS)]
    rows += [bounce_case(work, n) for n in ([100] if smoke else PERIODS)]
    if not smoke:  # the behaviour before the fix, listed, not counted (docs/stability-dynamic.md)
        rows.append(bounce_case(work, 100, push_out=True))
    return rows


def print_row(r):
    extra = (f"expected {r['expected']:.1e}" if r["category"] == "timestep"
             else f"impacts {r['impacts']} pen {r['penetration']:.1e} m")
    mark = ("pass" if r["ok"] else "FAIL") if r.get("counted", True) else ("(ok)" if r["ok"] else "(fail)")
    print(f"{r['category']:>9} {r['value']:>22} {','.join(r['reasons']):>16} {r['mult_its']:>7} {r['static_its']:>6} "
          f"{r['error']:10.2e} {r['drift']:10.2e} {r['cuts']:>4} {r['wall']:8.2f} {mark:>6}  {extra}"
          + (f"  [{r['note']}]" if r["note"] else ""), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--smoke", action="store_true", help="one case per category")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "extremes_dynamic.png"))
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="mbc_extremes_dynamic_")
    print(f"{'category':>9} {'value':>22} {'reasons':>16} {'mult':>7} {'static':>6} {'error':>10} {'drift':>10} {'cuts':>4} {'wall':>8}")
    rows = []
    for dt in ([1e-2] if a.smoke else TIMESTEPS):
        rows.append(slide_case(work, dt))
        print_row(rows[-1])
    for n in ([100] if a.smoke else PERIODS):
        rows.append(bounce_case(work, n))
        print_row(rows[-1])
    if not a.smoke:
        rows.append(bounce_case(work, 100, push_out=True))
        print_row(rows[-1])
    counted = [r for r in rows if r.get("counted", True)]
    failed = [r for r in counted if not r["ok"]]
    print(f"\n{len(counted) - len(failed)} of {len(counted)} cases pass" + (": failing " + ", ".join(f"{r['category']} {r['value']}" for r in failed) if failed else "")
          + f"; {sum(r['wall'] for r in rows):.1f} s of solver wall time")
    import plot  # noqa: E402  (bench/plot.py)
    floor = 1e-17  # a log plot of an exact zero
    ts = [r for r in rows if r["category"] == "timestep"]
    bs = [r for r in counted if r["category"] == "bounce"]
    plot.loglog(a.plot, "dynamic contact: error and energy gain", "dt [s] (timestep) / bounce periods (bounce)",
                [([r["x"] for r in ts], [max(r["error"], floor) for r in ts], "o-", "timestep: slide error"),
                 ([r["x"] for r in ts], [r["expected"] for r in ts], "k--", "timestep: dt^2/(2T^2)"),
                 ([r["x"] for r in ts], [max(r["drift"], floor) for r in ts], "v:", "timestep: energy gain / E_ref"),
                 ([r["x"] for r in bs], [max(r["error"], floor) for r in bs], "s-", "bounce: energy lost / K_i"),
                 ([r["x"] for r in bs], [max(r["drift"], floor) for r in bs], "^:", "bounce: energy gain / K_i")],
                ylabel="relative")


if __name__ == "__main__":
    main()
