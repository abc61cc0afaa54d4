#!/usr/bin/python3
"""Error against run time on the paper's Hertz example (meshes/hertz): two parallel cylinders,
R = 5 mm, E = 210 GPa, nu = 0.3, frictionless, -0.03 mm imposed, static, a quarter of each.

For each mesh level (element edge hc at the contact; uniform over 0.75 mm, then growing by 1.15
up to 0.5 mm): DOFs, contact points, run time split by phase (-log_view events: assembly,
factorization, D = H^T A^-1 H, PGS, solves, search, output), peak RSS of the solver, and the
errors of b (edge extrapolated from the last two loaded nodes, and "b fit": the least-squares
line of p^2 against x^2) and p_max against Hertz for the computed load P and of the surface
displacements against the paper's ANSYS column; for each of --elements (hex8, hex8i; tet10, tet4:
each hex cut into 6 tets, tet10's midside nodes on the arcs, contact on its 6-node faces) and, beside
them on each level, CalculiX (meshes/hertz/ccx.py: the same hex meshes, boundary conditions and
approach, --ccx-element C3D8I, face-to-face frictionless contact with a linear pressure-overclosure
of slope --penalty, one *STATIC step; Debian calculix-ccx, installed with apt when missing unless
--no-ccx or --smoke: the smoke run never runs ccx). Each code's rows end with the first level where
both b and p_max are within 0.5 % and within 1 % of Hertz, and its run time. Then the
PGS tolerance on one level (only Q1 elements exist, so the element order is not a parameter yet;
these and the rest run with the solver's default element), the same finest-but-one level at a quarter of the
approach (b / R halves: the departure from Hertz's half-spaces), the paper's dynamic route on
one level, and the sphere on a half-space (Hertz point contact) at two levels. Prints tables
and writes docs/hertz_convergence.png (error against run time).

  bench/hertz_convergence.py [--quick | --smoke] [--levels 0.04 0.02 0.01 0.0075 0.005] [--no-ccx] [--penalty 1e8]
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "meshes", "hertz"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import build  # noqa: E402  (meshes/hertz/build.py)
import ccx  # noqa: E402  (meshes/hertz/ccx.py)
import plot  # noqa: E402  (bench/plot.py)
import report  # noqa: E402  (meshes/hertz/report.py)
from mbcontact.prep import prepare  # noqa: E402
from mbcontact.results import log_view_times  # noqa: E402

SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")
EVENTS = {"assemble": "MBCBodyAssemble", "factor": "MBCBodyFactor", "D": "MBCFlexibilityAssemble", "PGS": "MBCMultiplierSolve",
          "solves": "MBCBodySolve", "search": ("MBCContactGather", "MBCGlobalSearch", "MBCLocalSearch"), "output": "MBCOutput"}
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def solve(h5, *options):
    """Runs the solver; returns (wall s, peak RSS MiB of the child (os.wait4), {phase: s}, DOFs, stdout);
    the child's CPU time (user + system, os.wait4) is left in solve.cpu."""
    t0 = time.perf_counter()
    p = subprocess.Popen([SOLVER, "-scene", h5, "-log_view", "-mbc_view", *options], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
    out = p.stdout.read().decode()
    err = p.stderr.read().decode()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    solve.cpu = usage.ru_utime + usage.ru_stime
    if p.returncode:
        sys.exit(f"solver failed on {h5}:\n{err}")
    phases = log_view_times(out, EVENTS)
    dofs = sum(int(d) for d in re.findall(r"(\d+) DOFs", out))
    return wall, usage.ru_maxrss / 1024.0, phases, dofs, out


def cylinder_level(work, hc, analysis="static", delta=None, element=None):
    h5 = build.build(work, hc, analysis=analysis, cell=element if element in ("tet4", "tet10") else "hex8")
    if delta is not None:  # another approach
        scene = build.cylinders_scene(analysis)
        scene["dirichlet"][-1]["value"] = -delta
        h5 = prepare(work, "hertz", scene)
    wall, rss, ph, dofs, _ = solve(h5, *(("-body_element", element) if element in ("hex8", "hex8i") else ()))
    res = report.cylinder_results(os.path.join(work, "hertz_result"))
    return dict(hc=hc, element=element, wall=wall, cpu=solve.cpu, rss=rss, dofs=dofs, res=res, err=report.errors(res), **ph)


def ensure_ccx(install):
    """True when CalculiX's ccx is on PATH, after installing Debian's calculix-ccx with apt when
    it is missing and install is set."""
    if ccx.CCX or not install:
        return bool(ccx.CCX)
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    print("CalculiX (ccx) is missing: installing calculix-ccx with apt-get", flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    try:
        rc = subprocess.run([*sudo, "apt-get", "install", "-y", "-qq", "--no-install-recommends", "calculix-ccx"], env=env).returncode
    except OSError as e:
        rc = str(e)
    ccx.CCX = shutil.which("ccx")
    if not ccx.CCX:
        print(f"apt-get install calculix-ccx failed ({rc}): mbcontact only", flush=True)
    return bool(ccx.CCX)


def first_within(rows, tol):
    """The first row (coarsest first) with both b and p_max within tol of Hertz, or None."""
    for r in sorted(rows, key=lambda r: -r["hc"]):
        if abs(r["err"]["b"]) < tol and abs(r["err"]["p_max"]) < tol:
            return r
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="two coarse levels, no dynamic route, one sphere level")
    ap.add_argument("--smoke", action="store_true", help="one coarse cylinder level and a 13k-DOF sphere (25 s at load 10: does the bench still run)")
    ap.add_argument("--levels", type=float, nargs="+", default=[0.04, 0.02, 0.01, 0.0075, 0.005])
    ap.add_argument("--elements", nargs="+", default=["hex8", "hex8i"], help="elements of the cylinder table: hex8, hex8i (-body_element), tet10, tet4 (each hex as 6 tets, build.py's tet10_part)")
    ap.add_argument("--cylinders-only", action="store_true", help="the cylinder table only (no PGS tolerance, quarter approach, dynamic route, sphere)")
    ap.add_argument("--no-ccx", action="store_true", help="mbcontact only (never installs or runs CalculiX)")
    ap.add_argument("--ccx-element", default="C3D8I", help="CalculiX element of its rows (C3D8I, C3D8)")
    ap.add_argument("--ccx-min-hc", type=float, default=0.0075,
                    help="CalculiX only on levels with hc >= this (hc 0.01: 42 s CPU, 0.6 GB; the finer ones grow to minutes)")
    ap.add_argument("--penalty", type=float, default=3e8, help="CalculiX's linear pressure-overclosure slope [MPa/mm] (hc 0.01: p_max moves 0.01 % from 3e8 to 1e9, 0.15 % from 1e8 to 3e8)")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "hertz_convergence.png"))
    a = ap.parse_args()
    levels = [0.04] if a.smoke else [0.04, 0.02] if a.quick else a.levels
    work = tempfile.mkdtemp(prefix="mbc_hertz_")

    use_ccx = not (a.no_ccx or a.smoke) and ensure_ccx(install=True)
    print("Hertz cylinders, static: errors against Hertz for the computed P (b, p_max) and against the paper's ANSYS column (surface u_y); "
          "wall and CPU (user + system) of the solver process")
    if use_ccx:
        print(f"CalculiX {ccx.version()} ({ccx.CCX}): {a.ccx_element}, face-to-face frictionless contact, linear pressure-overclosure "
              f"{a.penalty:g} MPa/mm, one *STATIC step, one thread (OMP_NUM_THREADS=1), SPOOLES; DOFs 3 per node, constrained ones included")
    head = (f"{'code':>9} {'element':>7} {'hc [mm]':>8} {'DOFs':>7} {'points':>6} {'P [N/mm]':>9} {'b err':>8} {'b fit':>8} {'p_max err':>9} {'u_y err':>8} "
            f"{'assemble':>8} {'factor':>7} {'D':>7} {'PGS':>6} {'solves':>6} {'search':>6} {'output':>6} {'wall':>7} {'RSS MiB':>8} {'CPU':>7}")
    print(head, flush=True)
    rows, by_element, ccx_rows = [], {}, []
    for hc in levels:
        for element in a.elements:
            r = cylinder_level(os.path.join(work, f"c{element}{hc}"), hc, element=element)
            by_element.setdefault(element, []).append(r)
            e = r["err"]
            print(f"{'mbcontact':>9} {element:>7} {hc:8.4f} {r['dofs']:7d} {r['res']['points']:6d} {r['res']['P']:9.2f} {e['b']:8.2%} {e['b_fit']:8.2%} {e['p_max']:9.2%} {max(e['upper'], e['lower']):8.2%} "
                  f"{r['assemble']:8.2f} {r['factor']:7.2f} {r['D']:7.2f} {r['PGS']:6.3f} {r['solves']:6.2f} {r['search']:6.3f} {r['output']:6.2f} {r['wall']:7.2f} {r['rss']:8.0f} {r['cpu']:7.2f}", flush=True)
        if use_ccx and hc < a.ccx_min_hc - 1e-12:
            print(f"{'ccx':>9} {a.ccx_element:>7} {hc:8.4f} not run (below --ccx-min-hc {a.ccx_min_hc:g})", flush=True)
        elif use_ccx:
            try:
                r = ccx.run(os.path.join(work, f"ccx{hc}"), hc, a.ccx_element, a.penalty)
            except RuntimeError as exc:
                print(f"{'ccx':>9} {a.ccx_element:>7} {hc:8.4f} failed: {str(exc).splitlines()[0]}", flush=True)
                continue
            ccx_rows.append(r)
            e, dash = r["err"], "-"
            print(f"{'ccx':>9} {a.ccx_element:>7} {hc:8.4f} {r['dofs']:7d} {r['res']['points']:6d} {r['res']['P']:9.2f} {e['b']:8.2%} {e['b_fit']:8.2%} {e['p_max']:9.2%} {dash:>8} "
                  f"{dash:>8} {dash:>7} {dash:>7} {dash:>6} {dash:>6} {dash:>6} {dash:>6} {r['wall']:7.2f} {r['rss']:8.0f} {r['cpu']:7.2f}", flush=True)
    series_rows = [(f"mbcontact {element}", erows) for element, erows in by_element.items()] + ([(f"ccx {a.ccx_element}", ccx_rows)] if ccx_rows else [])
    for tol in (0.005, 0.01):
        for name, erows in series_rows:
            r = first_within(erows, tol)
            print(f"both b and p_max within {tol:.1%} of Hertz, {name}: "
                  + (f"from hc {r['hc']:g} ({r['dofs']} DOFs): wall {r['wall']:.2f} s, CPU {r['cpu']:.2f} s" if r else
                     f"not on these levels (finest hc {min(x['hc'] for x in erows):g})" if erows else "no rows"), flush=True)
    if not use_ccx:
        print("CalculiX: " + ("not run (--smoke)" if a.smoke else "not run (--no-ccx)" if a.no_ccx else "not installed and could not be installed"))
    rows = by_element[a.elements[0]]  # the rest of the bench: the first element only
    print(f"(the paper, 0.1 mm elements: b {report.PAPER['b'] / report.HERTZ_PAPER['b'] - 1:+.2%}, p_max {report.PAPER['p_max'] / report.HERTZ_PAPER['p_max'] - 1:+.2%})")

    sphere_rows, quarter = [], None
    if not (a.quick or a.smoke or a.cylinders_only):
        hc = 0.01 if 0.01 in levels else levels[-1]
        h5 = build.build(os.path.join(work, "tol"), hc)
        print(f"\nPGS tolerance (hc {hc}): {'rtol':>7} {'b err':>8} {'p_max err':>9} {'PGS [s]':>8} {'wall':>7}")
        for rtol in (1e-3, 1e-4, 1e-6, 1e-8, 1e-10):
            # the equilibrium iterations cannot be tighter than the multipliers they balance
            try:
                wall, rss, ph, dofs, _ = solve(h5, "-mbc_multiplier_rtol", f"{rtol:g}", "-mbc_static_rtol", f"{max(rtol, 1e-6):g}")
            except SystemExit:  # the equilibrium iterations may not converge on loose multipliers
                print(f"{'':30s} {rtol:7.0e}  no static equilibrium within 50 iterations", flush=True)
                continue
            e = report.errors(report.cylinder_results(os.path.join(work, "tol", "hertz_result")))
            print(f"{'':30s} {rtol:7.0e} {e['b']:8.2%} {e['p_max']:9.2%} {ph['PGS']:8.3f} {wall:7.2f}", flush=True)
        hc = sorted(levels)[1] if len(levels) > 1 else levels[0]
        quarter = cylinder_level(os.path.join(work, "quarter"), hc, delta=build.DELTA / 4)
        print(f"\nsame mesh (hc {hc}), a quarter of the approach (0.0075 mm): P {quarter['res']['P']:.2f} N/mm, "
              f"b/R {quarter['res']['b'] / build.R:.4f}: b err {quarter['err']['b']:+.2%}, p_max err {quarter['err']['p_max']:+.2%} "
              f"(full approach: b/R {rows[-2]['res']['b'] / build.R:.4f})")
        dyn = cylinder_level(os.path.join(work, "dyn"), 0.02, analysis="dynamic")
        print(f"dynamic route (hc 0.02, rho 7.85e-9 t/mm3, damping 200, dt 0.01 s, 300 steps, load ramped over 1 s): "
              f"b err {dyn['err']['b']:+.2%}, p_max err {dyn['err']['p_max']:+.2%}, u_y err {max(dyn['err']['upper'], dyn['err']['lower']):.2%}, "
              f"wall {dyn['wall']:.1f} s (D {dyn['D']:.1f} s, solves {dyn['solves']:.1f} s, PGS {dyn['PGS']:.2f} s)")

    if not a.cylinders_only:
        print("\nsphere on a half-space (R = 10 mm, an eighth on a quarter block, -0.02 mm imposed): a and p0 against Hertz for the computed P")
        print(f"{'hc [mm]':>8} {'DOFs':>7} {'P [N]':>8} {'a err':>8} {'p0 err':>8} {'factor':>7} {'D':>7} {'wall':>7} {'RSS MiB':>8}", flush=True)
    for hc in ([] if a.cylinders_only else [0.4] if a.smoke else [0.09] if a.quick else [0.09, 0.06]):
        d = os.path.join(work, f"s{hc}")
        h5 = build.build_sphere(d, hc, 0.8)
        wall, rss, ph, dofs, _ = solve(h5)
        res = report.sphere_results(os.path.join(d, "sphere_result"))
        ah, ph0 = report.hertz_point(res["P"], build.SPHERE_R)
        sphere_rows.append(dict(hc=hc, wall=wall, a=res["a"] / ah - 1, p0=res["p0"] / ph0 - 1))
        print(f"{hc:8.3f} {dofs:7d} {res['P']:8.1f} {res['a'] / ah - 1:8.2%} {res['p0'] / ph0 - 1:8.2%} {ph['factor']:7.2f} {ph['D']:7.2f} {wall:7.2f} {rss:8.0f}", flush=True)

    series = []
    for element, erows in by_element.items():
        walls, dash = np.array([r["wall"] for r in erows]), "-" if element == a.elements[0] else ":"
        series += [(walls, np.abs([r["err"]["b"] for r in erows]), "o" + dash, f"cylinders {element}: |error of b|"),
                   (walls, np.abs([r["err"]["p_max"] for r in erows]), "s" + dash, f"cylinders {element}: |error of p_max|"),
                   (walls, np.array([max(r["err"]["upper"], r["err"]["lower"]) for r in erows]), "^" + dash, f"cylinders {element}: surface u_y vs ANSYS")]
    if ccx_rows:
        walls = np.array([r["wall"] for r in ccx_rows])
        series += [(walls, np.abs([r["err"]["b"] for r in ccx_rows]), "o--", f"CalculiX {a.ccx_element}: |error of b|"),
                   (walls, np.abs([r["err"]["p_max"] for r in ccx_rows]), "s--", f"CalculiX {a.ccx_element}: |error of p_max|")]
    if sphere_rows:
        series.append((np.array([s["wall"] for s in sphere_rows]), np.abs([s["p0"] for s in sphere_rows]), "d--", "sphere: |error of p0|"))
    plot.loglog(a.plot, "Hertz: error against run time (2 cores, one rank)", "run time [s]", series, ylabel="relative error")


if __name__ == "__main__":
    main()
