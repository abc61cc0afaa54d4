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
bounce    An upper block 1 x 1 x 0.5 m (one hex8i cell, E 1e11 Pa, nu 0, rho 2000: m = 1000 kg, nearly
          rigid) dropped delta = 10 um onto a pad 1 x 1 x 1 m (one cell, E 4e9, rho 2: a light spring
          k = E A / h), fixed at its bottom; frictionless, no damping, trapezoidal rule, dt = 1e-4 s,
          run for P = 10, 100, 1000 periods of the first bounce (analytic: 4.785 ms = 1.91 ms on the
          pad + 2.86 ms in flight, so 1000 periods = 4.79 s = 47 854 steps). References: the rigid
          block on the pad's spring (in series with the block's own E A / h) gives the pad's
          deepest compression in the first contact, 9.808 um (error, relative; expected within the
          sampling of the peak by the steps, (w dt)^2 / 8 = 5e-3, and the pad's mass, 2e-3 of the
          block's); undamped, the mechanical energy kinetic + strain - external work stays 0:
          impacts with Lagrange multipliers may lose energy (each landing stops the pad's top
          nodes: docs/design.md), never gain. drift: its largest gain / K_i (K_i = m g delta).
          Pass: every solve CONVERGED and drift < 1e-6 (the rounding of energy sums of order K_i,
          ~1e-12, and the multiplier tolerance 1e-8). Also reported: impacts (landings after a
          flight with every contact point open), the last flight, the energy lost / K_i, and the
          deepest penetration at a corner node (on a corner node).
          A last row repeats 100 periods with -mbc_contact_keep_penetration (a dynamic step starts
          from max(gap, 0)). Before the fix of the gap to warped slave quads (MBCCoupleProjectOnFace)
          the 100 periods gained 2600 K_i (docs/stability.md).

Every case returns a dict (cases()); main() prints the table and writes docs/extremes_dynamic.png.

  bench/extremes_dynamic.py [--smoke] [--plot PNG]
"""
import argparse
import math
import os
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import monitor  # noqa: E402  (bench/monitor.py)
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402
from mbcontact.results import read_csv  # noqa: E402

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
DELTA, DT_BOUNCE = 10e-6, 1e-4
E_BOUNCE = 1.0e11             # the upper block: stiff, it bounces nearly as a rigid body
E_PAD, RHO_PAD = 4.0e9, 2.0   # the lower block: a light spring (its top nodes' mass is what a landing loses)
PERIODS = [10, 100, 1000]


def run(h5, *options):
    """The solver with -mbc_monitor: (returncode, stdout + stderr, wall s, monitor.stats + the step
    cuts)."""
    r, wall = monitor.run(h5, options)
    out = r.stdout + r.stderr
    return r.returncode, out, wall, (*monitor.stats(out), out.count("the step is cut to two"))


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
    rc, out, wall, (reasons, its, static_its, cuts) = run(h5)
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
    ok = rc == 0 and monitor.converged(reasons) and abs(error - expected) < FLOOR and drift < DRIFT_TOL
    return dict(category="timestep", value=f"dt {dt:g} s", x=dt, reasons=reasons, mult_its=its, static_its=static_its,
                error=error, drift=drift, wall=wall, ok=ok, cuts=cuts, expected=expected,
                ref=f"rigid Coulomb slide x = j T^3/6 = {x_ref:.4g} m; trapezoidal error dt^2/(2T^2) = {expected:.2g}",
                note="" if rc == 0 else out.strip().splitlines()[-1])


def bounce_reference():
    """The rigid upper block on the pad as a spring: (K_i, first bounce period, peak pad compression).
    k: the pad (E A / h, uniaxial, nu = 0: exact for hex8i) in series with the upper block's
    compression (its E A / h), the pad's 2 kg neglected (2e-3 of the block)."""
    m = RHO * 0.5
    k = 1.0 / (1.0 / E_PAD + 0.5 / E_BOUNCE)
    w, v = math.sqrt(k / m), math.sqrt(2 * G * DELTA)
    period = (math.pi + 2 * math.atan(G / (w * v))) / w + 2 * v / G  # in contact, then in flight
    xs = m * G / k
    peak = (xs + math.sqrt(xs * xs + 2 * xs * DELTA)) * k / E_PAD  # the pad's share of the compression
    return m * G * DELTA, period, peak


def bounce_case(work, periods, dt=DT_BOUNCE, keep=False):
    """The block dropped on the pad, run for `periods` periods of the first bounce; a case dict."""
    name = f"bounce_{periods}{'_keep' if keep else ''}"
    k_i, period, peak = bounce_reference()
    steps = int(round(periods * period / dt))
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), name="pad"),
                   dict(lo=(0, 0, 1 + DELTA), hi=(1, 1, 1.5 + DELTA), n=(1, 1, 1), name="upper")])
    scene = {
        "title": f"undamped bounces, {periods} periods",
        "meshes": {"m": f"{name}.msh"},
        "bodies": {"pad": {"mesh": "m", "regions": "pad", "material": {"E": E_PAD, "nu": 0.0, "density": RHO_PAD}},
                   "upper": {"mesh": "m", "regions": "upper", "material": {"E": E_BOUNCE, "nu": 0.0, "density": RHO}}},
        "couples": [{"master": "upper_zmin", "slave": "pad_zmax", "mu": 0.0}],
        "dirichlet": [{"surface": "pad_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G], "time": "sudden", "bodies": ["upper"]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": steps * dt, "newmark": dict(TRAPEZOIDAL)},
        "output": {"every": 1000000000, "fields": ["displacement"], "energy": True,
                   # a corner node on a corner node: the gap there is delta + the difference of u_z
                   "points": {"face": {"x": [0, 0, 1 + DELTA], "body": "upper"},
                              "support": {"x": [0, 0, 1], "body": "pad"}}},
    }
    h5 = prepare(work, name, scene)
    rc, out, wall, (reasons, its, static_its, cuts) = run(h5, *(["-mbc_contact_keep_penetration"] if keep else []))
    error = drift = loss = float("inf")
    impacts, penetration, rest = 0, float("nan"), float("nan")
    if rc == 0:
        en = read_csv(h5[:-3] + "_result_energy.csv")
        c = read_csv(h5[:-3] + "_result_contact.csv")
        p = read_csv(h5[:-3] + "_result_points.csv")
        mech = en["kinetic"] + en["strain"] - en["external_work"] + en["damping_dissipation"]
        loss = -mech[-1] / k_i
        drift = max(float(mech.max()), 0.0) / k_i
        flying = c["separated"] == c["points"]
        landings = np.flatnonzero(flying[:-1] & ~flying[1:]) + 1
        impacts = len(landings)
        rest = float(c["t"][np.flatnonzero(flying)[-1]]) if flying.any() else 0.0  # the last flight
        gap = DELTA + p["face_uz"] - p["support_uz"]
        penetration = max(0.0, -float(gap.min()))
        if impacts >= 2:  # the pad's deepest compression between the first two landings
            error = abs(-p["support_uz"][landings[0]:landings[1]].min() / peak - 1)
    ok = rc == 0 and monitor.converged(reasons) and drift < DRIFT_TOL
    return dict(category="bounce", value=f"{periods} periods" + (" keep_pen" if keep else ""), x=float(periods),
                reasons=reasons, mult_its=its, static_its=static_its, error=error, drift=drift, wall=wall, ok=ok,
                cuts=cuts, impacts=impacts, rest=rest, loss=loss, penetration=penetration, steps=steps,
                ref=f"rigid block on the pad's spring: first period {period * 1e3:.4g} ms, peak pad compression "
                    f"{peak:.4g} m (error); undamped: no energy gain over K_i = {k_i:.4g} J (drift)",
                note="" if rc == 0 else out.strip().splitlines()[-1])


def cases(work, smoke):
    """Every case of both categories (smoke: one each), as dicts: category, value, x, reasons,
    mult_its, static_its, error, drift, wall, ok, ref (and cuts, expected / impacts, penetration)."""
    rows = [slide_case(work, dt) for dt in ([1e-2] if smoke else TIMESTEPS)]
    rows += [bounce_case(work, n) for n in ([100] if smoke else PERIODS)]
    if not smoke:  # the same with a dynamic step starting from max(gap, 0)
        rows.append(bounce_case(work, 100, keep=True))
    return rows


def print_row(r):
    extra = (f"expected {r['expected']:.1e}" if r["category"] == "timestep"
             else f"impacts {r['impacts']} last flight {r['rest']:.3f} s lost {r['loss']:.3f} K_i pen {r['penetration']:.1e} m")
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
        rows.append(bounce_case(work, 100, keep=True))
        print_row(rows[-1])
    counted = [r for r in rows if r.get("counted", True)]
    failed = [r for r in counted if not r["ok"]]
    print(f"\n{len(counted) - len(failed)} of {len(counted)} cases pass" + (": failing " + ", ".join(f"{r['category']} {r['value']}" for r in failed) if failed else "")
          + f"; {sum(r['wall'] for r in rows):.1f} s of solver wall time")
    import plot  # noqa: E402  (bench/plot.py)
    floor = 1e-17  # a log plot of an exact zero
    ts = [r for r in rows if r["category"] == "timestep"]
    bs = [r for r in counted if r["category"] == "bounce" and "keep" not in r["value"]]
    plot.loglog(a.plot, "dynamic contact: error and energy gain", "dt [s] (timestep) / bounce periods (bounce)",
                [([r["x"] for r in ts], [max(r["error"], floor) for r in ts], "o-", "timestep: slide error"),
                 ([r["x"] for r in ts], [r["expected"] for r in ts], "k--", "timestep: dt^2/(2T^2)"),
                 ([r["x"] for r in ts], [max(r["drift"], floor) for r in ts], "v:", "timestep: energy gain / E_ref"),
                 ([r["x"] for r in bs], [max(r["error"], floor) for r in bs], "s-", "bounce: peak pad compression error"),
                 ([r["x"] for r in bs], [max(r["loss"], floor) for r in bs], "D-", "bounce: energy lost / K_i"),
                 ([r["x"] for r in bs], [max(r["drift"], floor) for r in bs], "^:", "bounce: energy gain / K_i")],
                ylabel="relative")


if __name__ == "__main__":
    main()
