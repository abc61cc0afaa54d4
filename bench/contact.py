#!/usr/bin/python3
"""Contact forces against the number of contact points: building D = sum H^T A^-1 H and the
projected Gauss-Seidel (PGS) solve, on the paper's two-block example (block 2 on block 1,
mu = 0.6, sudden body force of 100 N/m3, dynamic, damping 200 M; meshes/blocks/build.py)
with the contact face refined: block 2 has n x n hex8 on its base (the master surface,
(n+1)^2 contact points, 3 multipliers each), block 1 a coarser non-matching slave grid of
round(0.7 n) x round(0.7 n); both 10 layers high.

1. Against n, a few Newmark steps (--steps, dt = 0.01 s): times from -log_view's events
   MBCFlexibilityAssemble (D, dense, built once as the pairs do not change; split into the
   KSPMatSolve of X = A^-1 H and the product H^T X, H sparse), MBCPGSSolve (per step), sweeps per
   step from -mbc_monitor ("contact: PGS CONVERGED_RTOL in N sweeps"), MBCBodyFactor and
   MBCBodySolve for context, wall time and peak RSS of the solver (--repeat: the fastest of
   several runs). Growth exponents are least-squares slopes of log time against log contact
   points over the larger sizes. The bodies grow with n too (DOFs ~ 50 points).
2. For one size (--tol-size), -mbc_multiplier_rtol from 1e-2 to 1e-10, newton and pgs with the active-set step
   (default, every 20 sweeps) and without (-mbc_pgs_active_set 0), run to a steady state
   (--tol-final-time): sweeps and PGS time per step and the error of the steady displacement
   of block 2's top (mean of top_uz over the last 0.5 s of <scene>_result_points.csv) against
   the exact -1.5e-4 m.

Prints tables and writes docs/contact.png. Exits non-zero if a solver run fails. The whole run
takes about 15 minutes on 2 cores (most of it the loose tolerances of part 2, where block 2
sinks in, the pairs change and D is rebuilt at most steps); --quick about 25 s.

  bench/contact.py [--quick] [--sizes 5 10 15 20 25 30] [--steps 5] [--repeat 1] [--tol-size 15] [--sizes-only]
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.join(ROOT, "meshes", "blocks"))
from mbcontact import meshgen  # noqa: E402
from mbcontact.results import read_csv  # noqa: E402
import build as blocks  # noqa: E402  (meshes/blocks/build.py: the paper's scene)

import plot  # noqa: E402  (bench/plot.py)

BUILD = os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build"))
SOLVER = os.path.join(BUILD, "mbcontact")
PREP = os.path.join(ROOT, "python", "mbcontact-prep")
EVENTS = ("MBCFlexibilityAssemble", "MBCMultiplierSolve", "MBCBodyFactor", "MBCBodySolve",
          "KSPMatSolve", "MatTrnMatMultSym", "MatTrnMatMultNum")
TOP = -1.5e-4  # exact steady displacement of block 2's top [m]
LAYERS = 10
ACTIVE_SET = 20  # the solver's default -mbc_pgs_active_set


def slave_grid(n):
    return max(2, round(0.7 * n))


def make_scene(work, n, dt, final_time):
    """The two-block scene with an n x n master grid; returns the .h5 path."""
    d = os.path.join(work, f"n{n}")
    os.makedirs(d, exist_ok=True)
    ns = slave_grid(n)
    meshgen.boxes(os.path.join(d, "blocks.msh"),
                  [dict(lo=(0, 0, 0), hi=(100, 100, 100), n=(ns, ns, LAYERS), cell="hex8", name="block1"),
                   dict(lo=(0, 0, 100), hi=(100, 100, 200), n=(n, n, LAYERS), cell="hex8", name="block2")])
    with open(os.path.join(d, "blocks.yaml"), "w") as f:
        yaml.safe_dump(blocks.scene(dt, final_time), f, sort_keys=False)
    h5 = os.path.join(d, "blocks.h5")
    subprocess.run([PREP, os.path.join(d, "blocks.yaml"), "-o", h5, "-q"], check=True)
    return h5


def dofs(n):
    ns = slave_grid(n)
    return 3 * (LAYERS + 1) * ((ns + 1) ** 2 + (n + 1) ** 2)


def run(h5, *options):
    """Runs the solver with -mbc_monitor -log_view; returns a dict of what it measured.
    Exits the benchmark if the solver fails."""
    cmd = [SOLVER, "-scene", h5, "-mbc_monitor", "-log_view", *map(str, options)]
    log, err = h5[:-3] + ".log", h5[:-3] + ".err"
    t0 = time.perf_counter()
    with open(log, "w") as fo, open(err, "w") as fe:
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe)
        _, status, usage = os.wait4(p.pid, 0)
        p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    out = open(log).read()
    if p.returncode:
        sys.stderr.write(f"\nsolver failed (exit status {p.returncode}): {' '.join(cmd)}\n"
                         + "".join(out.splitlines(True)[-10:]) + open(err).read())
        sys.exit(1)
    ev = {}
    for line in out.splitlines():
        w = line.split()
        if w and w[0] in EVENTS:
            ev[w[0]] = (int(w[1]), float(w[3]))
    sweeps = [int(s) for s in re.findall(r"contact: \w+ CONVERGED_\w+ in (\d+) iterations", out)]
    points = [int(s) for s in re.findall(r"contact: (\d+) contact points, (?:\d+ multipliers, )?flexibility matrix rebuilt", out)]
    last = re.findall(r"contact: \w+ .*separated (\d+), stick (\d+), slip (\d+)", out)
    steps = len(re.findall(r"^step\s+\d+ t \S+\s+max\|u\|", out, re.M)) - 1  # minus step 0
    if not sweeps or not points or steps < 1:
        sys.stderr.write(f"\nno contact in the run: {' '.join(cmd)}\n")
        sys.exit(1)
    t = {k: v[1] for k, v in ev.items()}
    return {"wall": wall, "rss": usage.ru_maxrss / 1024.0, "events": t, "sweeps": sweeps, "steps": steps,
            "points": points[0], "builds": len(points), "state": tuple(map(int, last[-1])),
            "pgs_calls": ev.get("MBCMultiplierSolve", (1, 0))[0]}


def slope(x, y):
    """Least-squares exponent of y ~ x^p."""
    return np.polyfit(np.log(x), np.log(y), 1)[0]


def against_points(a, work):
    print(f"\ntwo blocks, master grid n x n, slave round(0.7 n)^2, {LAYERS} layers; dt {a.dt} s, {a.steps} Newmark steps, "
          "one rank, MUMPS Cholesky\n")
    head = (f"{'n':>3} {'slave':>5} {'points':>6} {'m':>5} {'DOFs':>6} {'D [s]':>8} {'solves':>8} {'HtX':>8} "
            f"{'mult/step':>9} {'its':>6} {'factor':>7} {'solve/step':>10} {'wall':>7} {'RSS MiB':>8}")
    print(head, flush=True)
    rows = []
    for n in a.sizes:
        h5 = make_scene(work, n, a.dt, a.steps * a.dt)
        runs = [run(h5) for _ in range(a.repeat)]
        r = runs[0]  # the same computation every time: keep the fastest of each time
        r["events"] = e = {k: min(x["events"].get(k, 0) for x in runs) for k in r["events"]}
        r["wall"] = min(x["wall"] for x in runs)
        r.update(n=n, D=e.get("MBCFlexibilityAssemble", 0), solves=e.get("KSPMatSolve", 0),
                 htx=e.get("MatTrnMatMultSym", 0) + e.get("MatTrnMatMultNum", 0),
                 pgs=e.get("MBCMultiplierSolve", 0) / r["pgs_calls"], body_solve=e.get("MBCBodySolve", 0) / r["steps"])
        rows.append(r)
        print(f"{n:3d} {slave_grid(n):5d} {r['points']:6d} {3 * r['points']:5d} {dofs(n):6d} {r['D']:8.3f} {r['solves']:8.3f} "
              f"{r['htx']:8.3f} {r['pgs']:9.4f} {np.mean(r['sweeps']):6.1f} {e.get('MBCBodyFactor', 0):7.3f} "
              f"{r['body_solve']:10.4f} {r['wall']:7.2f} {r['rss']:8.0f}", flush=True)
        if r["builds"] != 1:
            print(f"    D built {r['builds']} times (the pairs changed)")
    print("\npoints: contact points (master nodes); m = 3 points multipliers; D = MBCFlexibilityAssemble, of which")
    print("solves = KSPMatSolve (X = A^-1 H, m right-hand sides per body) and HtX = MatTransposeMatMult (H^T X, H sparse);")
    print("mult/step = MBCMultiplierSolve per call, its = mean multiplier iterations per step (Newton steps; sweeps with pgs); factor = MBCBodyFactor (all factorizations);")
    print("solve/step = MBCBodySolve / steps (both bodies, the initial-state solves included).")
    p = np.array([r["points"] for r in rows], float)
    big = p >= min(200, p[-2]) if len(p) > 2 else p > 0
    fits = {}
    for key, label in (("D", "D assembly"), ("solves", "  KSPMatSolve"), ("htx", "  H^T X"), ("pgs", "solve per step")):
        y = np.array([r[key] for r in rows])
        if big.sum() >= 2 and (y[big] > 0).all():
            fits[key] = slope(p[big], y[big])
            local = ", ".join(f"{slope(p[i:i + 2], y[i:i + 2]):.2f}" for i in range(len(p) - 1) if (y[i:i + 2] > 0).all())
            print(f"{label:15s} ~ points^{fits[key]:.2f} (fit over {int(p[big][0])}..{int(p[big][-1])} points; "
                  f"between successive sizes: {local})")
    return rows, fits


def against_tolerance(a, work):
    n = a.tol_size
    h5 = make_scene(work, n, a.dt, a.tol_final_time)
    print(f"\nMultiplier solve tolerance, n = {n} (slave {slave_grid(n)}), dt {a.dt} s to t = {a.tol_final_time} s "
          f"({round(a.tol_final_time / a.dt)} steps); steady top_uz = mean over the last 0.5 s, exact {TOP:g} m\n")
    print(f"{'rtol':>7} {'solver':>10} {'its/step':>11} {'max':>6} {'mult/step':>9} {'mult tot':>9} "
          f"{'D builds':>8} {'top_uz':>12} {'error':>9} {'wall':>7}  last step (sep/stick/slip)", flush=True)
    rows = []
    variants = (("newton", ()), (f"pgs + AS {ACTIVE_SET}", ("-mbc_multiplier_type", "pgs", "-mbc_pgs_active_set", ACTIVE_SET)),
                ("pgs", ("-mbc_multiplier_type", "pgs", "-mbc_pgs_active_set", 0)))
    for label, opts in variants:
        for tol in a.tols:
            r = run(h5, "-mbc_multiplier_rtol", tol, "-mbc_multiplier_max_it", a.max_it if label != "newton" else 100, *opts)
            pts = read_csv(h5[:-3] + "_result_points.csv")
            late = pts["t"] >= pts["t"][-1] - 0.5 + 1e-9
            top = pts["top_uz"][late].mean()
            r.update(top=top, err=abs(top / TOP - 1), pgs=r["events"].get("MBCMultiplierSolve", 0), tol=tol, act=label)
            rows.append(r)
            print(f"{tol:7.0e} {label:>10} {np.mean(r['sweeps']):11.1f} {max(r['sweeps']):6d} "
                  f"{r['pgs'] / r['pgs_calls']:9.4f} {r['pgs']:9.2f} {r['builds']:8d} {r['top']:12.5e} {r['err']:9.2e} "
                  f"{r['wall']:7.2f}  {'/'.join(map(str, r['state']))}", flush=True)
    print("\nrtol: -mbc_multiplier_rtol, on the FCLIB merit of each step's problem scaled to |q| = 1 (relative); solver:")
    print("newton (the default: semismooth Newton, iterations = Newton steps), pgs with the active-set step every")
    print(f"{ACTIVE_SET} sweeps (-mbc_pgs_active_set) or without it (iterations = sweeps);")
    print("error: |steady top_uz / -1.5e-4 - 1| (discretisation included).")
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the two smallest sizes, tolerance study on the smallest (smoke run)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[5, 10, 15, 20, 25, 30], help="master grids n")
    ap.add_argument("--steps", type=int, default=5, help="Newmark steps of the size runs")
    ap.add_argument("--repeat", type=int, default=1, help="runs per size, the fastest time of each kept")
    ap.add_argument("--dt", type=float, default=0.01)
    ap.add_argument("--tol-size", type=int, default=15, help="master grid of the tolerance study")
    ap.add_argument("--tol-final-time", type=float, default=1.5, help="end of the tolerance runs [s]")
    ap.add_argument("--tols", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10])
    ap.add_argument("--max-it", type=int, default=100000, help="-mbc_multiplier_max_it of the pgs tolerance runs")
    ap.add_argument("--sizes-only", action="store_true", help="part 1 only (the tolerance study takes most of the time)")
    ap.add_argument("--plot", default=None, help="PNG (default docs/contact.png; with --quick, in the temporary directory)")
    a = ap.parse_args()
    if a.quick:
        a.sizes = sorted(a.sizes)[:2]
        a.tol_size = a.sizes[0]
    if not os.access(SOLVER, os.X_OK):
        sys.exit(f"no solver at {SOLVER} (build it, or set MBC_BUILD_DIR)")
    with tempfile.TemporaryDirectory() as work:
        rows, fits = against_points(a, work)
        if not a.sizes_only:
            against_tolerance(a, work)
        p = [r["points"] for r in rows]
        ref = lambda e, y: [y * (x / p[-1]) ** e for x in p]  # noqa: E731  slopes through the largest size
        plot.loglog(a.plot or (os.path.join(work, "contact.png") if a.quick else os.path.join(ROOT, "docs", "contact.png")),
                    f"two blocks, {a.steps} steps, one rank", "contact points",
                    [(p, [r["D"] for r in rows], "o-", "D assembly (once)"),
                     (p, [r["solves"] for r in rows], "o--", "  of which KSPMatSolve"),
                     (p, [r["htx"] for r in rows], "o:", "  of which H^T X"),
                     (p, [r["pgs"] for r in rows], "s-", "multiplier solve per step"),
                     (p, [r["events"].get("MBCBodyFactor", 0) for r in rows], "^-", "body factorizations"),
                     (p, [r["body_solve"] for r in rows], "v-", "body solves per step"),
                     (p, ref(2, rows[-1]["D"]), "k:", "points^2"),
                     (p, ref(3, rows[-1]["D"]), "k--", "points^3")])


if __name__ == "__main__":
    sys.exit(main())
