#!/usr/bin/python3
"""An earthquake on the staged dam with joints (meshes/dam/build.py --staged --joints): the cost of
a dynamic step by phase against DOFs, the interface's work against the bodies' own solves, and
what the joints did. The record (the builder's synthetic one) is cut at --record-from s so that the
earthquake stage starts in its strong phase; the run stops after --steps steps of it.

Per size: DOFs, contact points, the earthquake stage's wall time per step, and per step the
bodies' solves (MBCBodySolve), D (MBCFlexibilityAssemble) with its number of builds in the stage,
the multiplier solve (MBCMultiplierSolve) with its dense LU factorizations (MatLUFactor, MBCMixedLUFactor; the
step time and the multiplier solve leave out the Newton type's kept inverses, MBCNewtonInverse,
shown apart as "inverse": once a stage over a few strong steps, but taken again as the references
go stale over a whole record, 17-46 times in 2 000 steps at 49k DOFs), the
mortar integration and the search (MBCContactIntegrate; MBCContactGather + MBCGlobalSearch +
MBCLocalSearch), "iface/solves" = (D + multiplier with its inverses + integration + search) /
bodies' solves, the
static stage's wall time, the solver's peak RSS (os.wait4; on P ranks the largest process), and
at the last step the largest joint opening and slip. --compare OPTIONS runs every size a second
time with those options added and prints the second run's times against the first's and the
largest difference of the answers (couple resultants, displacements, opening, slip over every
output step), e.g. --compare "-mbc_contact_hysteresis 0". Writes a plot of the phases per step
against DOFs (--plot).

  bench/quake.py [--dofs 2e4 5e4 1e5 2e5] [--steps 30] [--ranks 1] [--options "..."]
                 [--compare "..."] [--record-from 7] [--timeout 3600] [--keep DIR] [--plot PNG]
"""
import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "meshes", "dam"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import build  # noqa: E402  (meshes/dam/build.py)
import plot  # noqa: E402  (bench/plot.py)
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import results  # noqa: E402

SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1")
EVENTS = {"solves": "MBCBodySolve", "D": "MBCFlexibilityAssemble", "mult": "MBCMultiplierSolve", "LU": ("MatLUFactor", "MBCMixedLUFactor"), "inv": "MBCNewtonInverse",
          "integ": "MBCContactIntegrate", "search": ("MBCContactGather", "MBCGlobalSearch", "MBCLocalSearch")}
INTERFACE = ("D", "mult", "integ", "search")
DT = 0.01  # the builder's staged time step


def stage_block(text, name):
    """The -log_view event table of the stage called name (its first listing)."""
    m = re.search(rf"^--- Event Stage \d+: {re.escape(name)}\s*$(.*?)(?=^--- Event Stage|\Z)", text, re.M | re.S)
    return m.group(1) if m else ""


def stage_events(block):
    """Seconds (max over ranks) and counts of EVENTS in one stage's table."""
    out = {}
    for key, ev in EVENTS.items():
        t = n = 0
        for e in ev if isinstance(ev, tuple) else (ev,):
            for c, s in re.findall(rf"^{e}\s+(\d+)\s+\S+\s+(\S+)", block, re.M):
                n += int(c)
                t += float(s)
        out[key], out[key + "_n"] = t, n
    return out


def stage_wall(text, name):
    m = re.search(rf"^\s*\d+:\s+{re.escape(name)}:\s+(\S+)", text, re.M)
    return float(m.group(1)) if m else float("nan")


def run(h5, out, ranks, steps, options, timeout):
    cmd = [SOLVER, "-scene", h5, "-mbc_output", out, "-mbc_final_time", f"{1.0 + steps * DT:.6g}", "-mbc_monitor", "-log_view", *options]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=ENV)
    timer = __import__("threading").Timer(timeout, p.kill)
    timer.start()
    text = p.stdout.read().decode(errors="replace")
    _, status, usage = os.wait4(p.pid, 0)
    timer.cancel()
    r = dict(rc=os.waitstatus_to_exitcode(status), wall=time.perf_counter() - t0, rss=usage.ru_maxrss / 1024.0, text=text)
    eq = stage_block(text, "MBC stage 1 earthquake")
    r.update(stage_events(eq))
    r["eq_wall"] = stage_wall(text, "MBC stage 1 earthquake")
    r["static_wall"] = stage_wall(text, "MBC stage 0 static")
    quake = text.split("stage 1 earthquake:", 1)[-1]
    r["steps"] = len(re.findall(r"^step\s+\d+\s+t\s+\S+\s+contact: newton", quake, re.M))
    r["builds"] = r["D_n"]  # D at the stage's start (its operator K + a0 M) and at every change of pairs
    m = re.search(r"(\d+) contact points", text)
    r["points"] = int(m.group(1)) if m else 0
    r["h5"] = out + ".h5"
    if r["rc"] == 0:
        c = results.read_contact(r["h5"], step=-1)
        r["opening"] = float(np.maximum(c["gap"], 0).max())
        r["slip"] = float(np.linalg.norm(c["slip"], axis=1).max())
    return r


def answers_differ(a, b):
    """Largest differences of b's answers from a's over every output step, relative to a's largest."""
    names = results.body_names(a)
    worst = dict(u=0.0, resultant=0.0, opening=0.0, slip=0.0)
    for s in range(min(len(results.output_times(a)), len(results.output_times(b)))):
        ua = np.concatenate([results.read_body(a, k, step=s)["displacement"].ravel() for k in names])
        ub = np.concatenate([results.read_body(b, k, step=s)["displacement"].ravel() for k in names])
        worst["u"] = max(worst["u"], np.abs(ua - ub).max() / max(np.abs(ua).max(), 1e-300))
        ca, cb = results.read_contact(a, step=s), results.read_contact(b, step=s)
        for k in np.unique(ca["couple"]):
            fa, fb = ca["force"][ca["couple"] == k].sum(0), cb["force"][cb["couple"] == k].sum(0)
            worst["resultant"] = max(worst["resultant"], np.abs(fa - fb).max() / max(np.abs(fa).max(), 1e-300))
        for key, f in (("opening", lambda c: np.maximum(c["gap"], 0).max()), ("slip", lambda c: np.linalg.norm(c["slip"], axis=1).max())):
            va, vb = f(ca), f(cb)
            if va > 0:
                worst[key] = max(worst[key], abs(va - vb) / va)
    return worst


def row(label, r):
    n = max(r["steps"], 1)
    iface = sum(r[k] for k in INTERFACE)  # the inverses too: a record takes them again and again
    return (f"{label:>9} {r['points']:>7} {r['steps']:>5} {(r['eq_wall'] - r['inv']) / n:>8.3f} {r['solves'] / n:>8.3f} {r['D'] / n:>8.3f} {r['builds']:>6} "
            f"{(r['mult'] - r['inv']) / n:>8.3f} {r['LU_n']:>5} {r['inv']:>8.2f} {(r['integ'] + r['search']) / n:>8.3f} {iface / max(r['solves'], 1e-12):>7.1f} "
            f"{r['static_wall']:>8.1f} {r['rss']:>7.0f} {r.get('opening', float('nan')) * 1e3:>8.3f} {r.get('slip', float('nan')) * 1e3:>8.3f}"
            + ("" if r["rc"] == 0 else f"  exit {r['rc']}"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dofs", type=float, nargs="+", default=[2e4, 5e4, 1e5, 2e5])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--options", default="")
    ap.add_argument("--compare", default=None)
    ap.add_argument("--record-from", type=float, default=7.0)
    ap.add_argument("--timeout", type=float, default=3600)
    ap.add_argument("--keep", default=None)
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "quake_bench.png"))
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="mbc_quake_")
    variants = [("A", shlex.split(a.options))] + ([("B", shlex.split(a.options) + shlex.split(a.compare))] if a.compare is not None else [])
    print(f"staged dam with joints, record from {a.record_from:g} s, {a.steps} earthquake steps of {DT:g} s, {a.ranks} rank(s)")
    for v, opts in variants:
        print(f"  {v}: {' '.join(opts) or '(defaults)'}")
    print("\nper earthquake step [s], step and mult without the Newton type's kept inverses (inverse [s], all of the stage); iface/solves:\n"
          "(D + multiplier with its inverses + integration + search) / bodies' solves; opening, slip [mm] at the last step")
    head = f"{'DOFs':>9} {'points':>7} {'steps':>5} {'step':>8} {'solves':>8} {'D':>8} {'builds':>6} {'mult':>8} {'LU':>5} {'inverse':>8} {'integ+s':>8} {'iface/s':>7} {'static':>8} {'MiB':>7} {'opening':>8} {'slip':>8}"
    print(head)
    runs = []
    for dofs in a.dofs:
        d = os.path.join(work, f"dam{int(dofs)}")
        h5 = build.build(d, "staged", target_dofs=dofs, joints=True, record_from=a.record_from)
        rs = {v: run(h5, os.path.join(d, f"out{v}"), a.ranks, a.steps, opts, a.timeout) for v, opts in variants}
        for r in rs.values():
            r["dofs"] = build.build.info["dofs"]
        for v, r in rs.items():
            print(row(f"{r['dofs']}" if v == "A" else "  B", r), flush=True)
        if "B" in rs and rs["A"]["rc"] == 0 and rs["B"]["rc"] == 0:
            A, B = rs["A"], rs["B"]
            diff = answers_differ(A["h5"], B["h5"])
            print(f"{'B/A':>9} step {(B['eq_wall'] - B['inv']) / (A['eq_wall'] - A['inv']):.2f}, D {B['D'] / max(A['D'], 1e-12):.2f}, "
                  f"multiplier {(B['mult'] - B['inv']) / max(A['mult'] - A['inv'], 1e-12):.2f} (inverse {A['inv']:.1f} s, {B['inv']:.1f} s); "
                  "B - A: " + ", ".join(f"{k} {v:.1e}" for k, v in diff.items()), flush=True)
        runs.append(rs["A"])
    ok = [r for r in runs if r["rc"] == 0 and r["steps"]]
    if a.plot and ok:
        x = [r["dofs"] for r in ok]
        series = [([r[k] / r["steps"] for r in ok], style, label) for k, style, label in
                  (("solves", "o-", "bodies' solves"), ("D", "s-", "D"), ("mult", "^-", "multiplier solve"), ("integ", "v-", "integration"))]
        series = [(x, [max(v, 1e-6) for v in y], style, label) for y, style, label in series]
        series.append((x, [r["eq_wall"] / r["steps"] for r in ok], "k--", "whole step"))
        plot.loglog(a.plot, "earthquake step of the staged dam with joints", "DOFs", series, ylabel="time per step [s]")
    return 0 if all(r["rc"] == 0 for r in runs) else 1


if __name__ == "__main__":
    sys.exit(main())
