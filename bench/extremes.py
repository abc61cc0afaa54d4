#!/usr/bin/python3
"""Numerical stability on extreme cases (issue 17), first part: static scenes with an exact answer.

A block [0,L]^2 x [L,1.5L] pressed by p on its top onto a base [0,L]^3 fixed at its bottom,
frictionless, nu = 0: uniaxial stress, so every hex8i mesh gives the exact field. Reference:
the block's top moves u_z = -p (L/E_base + L/(2 E_block)); the contact normal force is p L^2.
Swept, each from one scene builder with the solver's default options (Poisson's ratio, time steps
and bounces come from bench/extremes_poisson.py and bench/extremes_dynamic.py):
  contrast  E_block / E_base from 1e-6 to 1e6 (soft under stiff and the reverse)
  size      L from 1e-3 m to 1e4 m
  units     the same scene in m/kg/s and in mm/t/s (u in mm = 1e3 u in m, forces N vs N)
  friction  mu = 0, 0.01, 0.3, 1, 10 with a shear min(mu/2, 1/2) p on the block (held only by contact:
            the friction resultant must carry it exactly; "u_z err" is then the error of fx)
  gap       initial gap 0 .. 10 element sizes, the block's top pushed by gap + delta in 1 or 10
            static load steps (F err: the contact force against delta E L / 1.5)
  ratio     element size ratio across the couple 1:1 to 1:20, either side fine
For each case: the multiplier solves' converged reasons and iterations, the static iterations,
the errors of u_z and of the normal force, wall time; a pass/fail column (errors < 1e-8).
Writes docs/extremes.png (error against the swept parameter).

  bench/extremes.py [--smoke] [--plot PNG]
"""
import argparse
import os
import re
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import monitor  # noqa: E402  (bench/monitor.py)
import plot  # noqa: E402  (bench/plot.py)
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402
from mbcontact.results import read_csv  # noqa: E402

import extremes_dynamic  # noqa: E402  (bench/extremes_dynamic.py)
import extremes_poisson  # noqa: E402  (bench/extremes_poisson.py)

CATEGORY_MODULES = [extremes_poisson, extremes_dynamic]  # the categories of other files (bench/extremes_*.py): cases(work, smoke) -> rows
TOL = 1e-8  # exact answer: only rounding and the multiplier tolerance (1e-8 relative) remain
STATIC_RTOL = 1e-6  # the solver's default -mbc_static_rtol: what a step that iterates promises


def run(work, name, scene, nproc=1):
    """Prepares the scene and runs the solver with -mbc_monitor on nproc ranks: (h5, the
    CompletedProcess, wall s)."""
    h5 = prepare(work, name, scene)
    return (h5, *monitor.run(h5, nproc=nproc))


def stack(work, name, L=1.0, E_base=2e10, E_block=2e10, p=1e6, n_base=2, n_block=3, mu=0.0, tau=0.0, block_master=True, nproc=1):
    """The block on the base; returns (u_z of the block's top centre, normal force, exact u_z,
    exact force, monitor output, wall s)."""
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(L, L, L), n=(n_base, n_base, 2), name="base"),
                   dict(lo=(0, 0, L), hi=(L, L, 1.5 * L), n=(n_block, n_block, 1), name="block")])
    scene = {"meshes": {"m": f"{name}.msh"},
             "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": E_base, "nu": 0.0}},
                        "block": {"mesh": "m", "regions": "block", "material": {"E": E_block, "nu": 0.0}}},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": mu} if block_master
                         else {"master": "base_zmax", "slave": "block_zmin", "mu": mu}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"}],
             "loads": [{"kind": "pressure", "surface": "block_zmax", "value": p}]
             + ([{"kind": "traction", "surface": "block_zmax", "vector": [tau, 0, 0]}] if tau else []),
             "analysis": {"type": "static"},
             "output": {"points": {"top": {"x": [L / 2, L / 2, 1.5 * L], "body": "block"}}}}
    h5, r, wall = run(work, name, scene, nproc)
    if r.returncode:
        return None, None, -p * (L / E_base + 0.5 * L / E_block), p * L * L, r.stdout + r.stderr, wall
    pts = read_csv(h5[:-3] + "_result_points.csv")
    c = read_csv(h5[:-3] + "_result_contact.csv")
    if tau:  # friction: the tangential resultant carries the shear exactly (the block is held only by contact)
        sign = 1 if block_master else -1  # the CSV's resultant acts on the master side
        return c["fx"][-1], c["fz"][-1], -sign * tau * L * L, sign * p * L * L, r.stdout, wall
    return pts["top_uz"][-1], c["fz"][-1], -p * (L / E_base + 0.5 * L / E_block), p * L * L, r.stdout, wall


def gap_case(work, name, gap, steps, hold=True, L=1.0, E=2e10, delta=1e-4, nproc=1):
    """The block starts gap above the base and its top is pushed down by gap + delta (u_z
    prescribed; x and y held on the block's xmin/ymin faces, or free with hold=False) in one
    static load step or ramped over steps: the contact force is delta E L^2 / (1.5 L) exactly
    (both bodies uniaxial, nu = 0)."""
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(L, L, L), n=(2, 2, 2), name="base"),
                   dict(lo=(0, 0, L + gap), hi=(L, L, 1.5 * L + gap), n=(3, 3, 1), name="block")])
    scene = {"meshes": {"m": f"{name}.msh"},
             "bodies": {b: {"mesh": "m", "regions": b, "material": {"E": E, "nu": 0.0}} for b in ("base", "block")},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.0}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"},
                           {"surface": "block_zmax", "components": ["z"], "value": -(gap + delta),
                            "time": {"table": [[0, 0], [1, 1]]}}]
             + ([{"surface": "block_xmin", "components": ["x"]}, {"surface": "block_ymin", "components": ["y"]}] if hold else []),
             "analysis": {"type": "static", "dt": 1.0 / steps, "final_time": 1.0}}
    h5, r, wall = run(work, name, scene, nproc)
    f_ex = delta * E * L * L / (1.5 * L)
    if r.returncode:
        return None, None, 1.0, f_ex, r.stdout + r.stderr, wall
    c = read_csv(h5[:-3] + "_result_contact.csv")
    return 1.0, c["fz"][-1], 1.0, f_ex, r.stdout, wall


def stack3(work, name, E=(2e10, 2e10, 2e10), p=None, L=1.0, nproc=1):
    """Three bodies: the base [0,L]^3 (E[0], fixed at its bottom), a middle block [L, 1.5L] (E[1])
    and a top block [1.5L, 2L] (E[2]), frictionless couples, nu = 0, p on the top: uniaxial in
    all three, the middle and top blocks held only by contact. Top u_z = -p L (1/E0 + 1/(2 E1) +
    1/(2 E2)); each couple carries p L^2. p defaults to 1e-4 of the softest E (small strain)."""
    p = 1e-4 * min(E) if p is None else p
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(L, L, L), n=(2, 2, 2), name="base"),
                   dict(lo=(0, 0, L), hi=(L, L, 1.5 * L), n=(3, 3, 1), name="mid"),
                   dict(lo=(0, 0, 1.5 * L), hi=(L, L, 2 * L), n=(2, 2, 1), name="top")])
    scene = {"meshes": {"m": f"{name}.msh"},
             "bodies": {b: {"mesh": "m", "regions": b, "material": {"E": e, "nu": 0.0}} for b, e in zip(("base", "mid", "top"), E)},
             "couples": [{"master": "mid_zmin", "slave": "base_zmax", "mu": 0.0},
                         {"master": "top_zmin", "slave": "mid_zmax", "mu": 0.0}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"}],
             "loads": [{"kind": "pressure", "surface": "top_zmax", "value": p}],
             "analysis": {"type": "static"},
             "output": {"points": {"top": {"x": [L / 2, L / 2, 2 * L], "body": "top"}}}}
    h5, r, wall = run(work, name, scene, nproc)
    uz_ex = -p * L * (1 / E[0] + 0.5 / E[1] + 0.5 / E[2])
    if r.returncode:
        return None, None, uz_ex, p * L * L, r.stdout + r.stderr, wall
    pts = read_csv(h5[:-3] + "_result_points.csv")
    c = read_csv(h5[:-3] + "_result_contact.csv")
    # the worse of the two couples' normal forces
    fz = [f for f in c["fz"][-2:]] if c["fz"].size >= 2 else [c["fz"][-1]]
    worst = max(fz, key=lambda f: abs(f / (p * L * L) - 1))
    return pts["top_uz"][-1], worst, uz_ex, p * L * L, r.stdout, wall


HEADER = f"{'category':>9} {'value':>20} {'reasons':>16} {'mult':>6} {'static':>6} {'error':>9} {'drift':>9} {'wall':>7} {'':>5}"


solve_stats = monitor.stats


def show(r):
    """Prints one case of any category (the dicts of the category modules too)."""
    drift = "" if r.get("drift") is None else f"{r['drift']:9.2e}"
    print(f"{r['category']:>9} {r['value']:>20} {','.join(r['reasons']):>16} {r['mult_its']:>6} {r['static_its']:>6} "
          f"{r['error']:9.2e} {drift:>9} {r['wall']:7.2f} {'pass' if r['ok'] else 'FAIL':>5}"
          + (f"  {r['note']}" if r.get("note") else ""), flush=True)
    return r


def row(category, value, res, x=None, count=True, series=""):
    """A static case against its exact answer: the error is the worse of u_z and the force."""
    uz, fz, uz_ex, fz_ex, out, wall = res
    reasons, mult_its, static_its = solve_stats(out)
    if uz is None:
        e_u = e_f = float("inf")
    else:
        e_u, e_f = abs(uz / uz_ex - 1), abs(fz / fz_ex - 1)
    # exact where a step's first equilibrium iteration ends it (linear problem, pairs known); a step
    # that iterates stops at -mbc_static_rtol (1e-6 of the force, default): the gap is measured
    # along the current normals, so after a mid-step re-search the iterations contract linearly
    # (docs/stability.md) and the answer is as exact as that tolerance
    iterated = max([int(i) for i in re.findall(r"static iteration (\d+):", out)] or [0]) > 2
    tol = STATIC_RTOL if iterated else TOL
    ok = e_u < tol and e_f < tol and monitor.converged(reasons)
    return show(dict(category=category, value=value, x=x, reasons=reasons, mult_its=mult_its, static_its=static_its,
                     error=max(e_u, e_f), e_u=e_u, e_f=e_f, drift=None, wall=wall, ok=ok, count=count, series=series))


def static_cases(work, smoke):
    """The categories with an exact static answer."""
    rows = []
    contrasts = [1e-6, 1e6] if smoke else [1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6]
    for i, k in enumerate(contrasts):
        # p = 1e-4 of the softer E: a small strain on both sides (the solver refuses motions above ten model sizes)
        rows.append(row("contrast", f"{k:g}", stack(work, f"c{i}", E_block=2e10 * k, p=1e-4 * 2e10 * min(k, 1.0)), x=k))
    # three bodies, the middle one held only by contact: stiff between soft, soft between stiff, graded
    triples = [(1, 1e6, 1)] if smoke else [(1, 1e6, 1), (1e6, 1, 1e6), (1, 1e3, 1e6), (1e6, 1e3, 1)]
    for i, t in enumerate(triples):
        rows.append(row("contrast3", ":".join(f"{k:g}" for k in t), stack3(work, f"t{i}", E=tuple(2e10 * k for k in t)),
                        x=t[1] / t[0]))
    sizes = [1e-3] if smoke else [1e-3, 1e-1, 1.0, 1e2, 1e4]
    for i, L in enumerate(sizes):
        rows.append(row("size", f"{L:g} m", stack(work, f"s{i}", L=L), x=L))
    # units: m/kg/s (E in Pa, p in Pa) against mm/t/s (E in MPa, p in MPa); u in mm = 1e3 u in m
    si = stack(work, "u_si", L=1.0, E_base=2e10, E_block=2e10, p=1e6)
    mm = stack(work, "u_mm", L=1e3, E_base=2e4, E_block=2e4, p=1.0)
    e_u = abs(mm[0] / (1e3 * si[0]) - 1) if si[0] and mm[0] else float("inf")
    e_f = abs(mm[1] / si[1] - 1) if si[1] and mm[1] else float("inf")
    reasons, mult_its, static_its = solve_stats(si[4] + mm[4])
    rows.append(show(dict(category="units", value="mm vs m", x=1.0, reasons=reasons, mult_its=mult_its, static_its=static_its,
                          error=max(e_u, e_f), drift=None, wall=si[5] + mm[5], ok=max(e_u, e_f) < 1e-10, count=True)))
    # friction: a shear tau = min(mu / 2, 1/2) p on the top (stick: fx = -tau L^2 exactly); mu = 0 with no shear.
    # Above tau = p the block (h = L/2) overturns: refused (test_extremes.py)
    mus = [10.0] if smoke else [0.0, 0.01, 0.3, 1.0, 10.0]
    for i, mu in enumerate(mus):
        rows.append(row("friction", f"mu {mu:g}", stack(work, f"f{i}", mu=mu, tau=min(0.5 * mu, 0.5) * 1e6), x=max(mu, 1e-3)))
    # initial gaps 0 .. 10 element sizes (h = L/2 through the block), closed in one load step or in 10;
    # the block's x and y held, or free (its x, y and rotation about z resisted by nothing, unloaded)
    gaps = [(10, 10)] if smoke else [(0, 1), (0.1, 1), (1, 1), (10, 1), (1, 10), (10, 10)]
    for hold in (True, False):
        for i, (g, n) in enumerate(gaps):
            rows.append(row("gap" if hold else "gap free", f"{g:g}h/{n}st", gap_case(work, f"g{i}{hold:d}", g * 0.5, n, hold=hold),
                            x=max(g, 0.01), series=f"{n} load step{'s' if n > 1 else ''}"))
    ratios = [(1, 20)] if smoke else [(2, 2), (1, 5), (5, 1), (1, 20), (20, 1)]
    for nb, nk in ratios:
        rows.append(row("ratio", f"{nb}:{nk}", stack(work, f"r{nb}_{nk}", n_base=nb, n_block=nk), x=nk / nb))
    return rows


XLABEL = {"contrast": "E_block / E_base", "contrast3": "E_middle / E_base", "size": "L [m]", "units": "",
          "friction": "mu", "gap": "gap / h", "gap free": "gap / h", "ratio": "h_base / h_block",
          "poisson": "nu", "timestep": "dt [s]", "bounce": "bounces"}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--smoke", action="store_true", help="one case per category")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "extremes.png"))
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="mbc_extremes_")
    print(HEADER)
    rows = static_cases(work, a.smoke)
    for module in CATEGORY_MODULES:
        rows += [show(r) for r in module.cases(work, a.smoke)]
    counted = [r for r in rows if r.get("count", r.get("counted", True))]
    failed = [r for r in counted if not r["ok"]]
    print(f"\n{len(counted) - len(failed)} of {len(counted)} cases pass" + (": failing " + ", ".join(f"{r['category']} {r['value']}" for r in failed) if failed else ""))
    floor = 1e-17  # a log plot of an exact zero
    panels = []
    for cat in dict.fromkeys(r["category"] for r in rows):
        rs = [r for r in rows if r["category"] == cat and r.get("x") is not None]
        if not rs:
            continue
        series = []
        for name in dict.fromkeys(r.get("series", "") for r in rs):  # a line per series, in x order
            sr = sorted((r for r in rs if r.get("series", "") == name), key=lambda r: r["x"])
            xs = [r["x"] for r in sr]
            series.append((xs, [min(max(r["error"], floor), 1e3) for r in sr], "o-", f"error {name}".strip()))
            if any(r.get("drift") is not None for r in sr):
                series.append((xs, [max(r["drift"] or 0.0, floor) for r in sr], "s--", f"energy drift {name}".strip()))
        xs = [r["x"] for r in rs]
        panels.append((cat, XLABEL.get(cat, ""), "relative error", series, min(xs) > 0 and max(xs) / min(xs) > 50))
    plot.panels(a.plot, "bench/extremes.py: error against the swept parameter", panels)


if __name__ == "__main__":
    main()
