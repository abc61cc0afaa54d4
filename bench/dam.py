#!/usr/bin/python3
"""The dam scene (meshes/dam/build.py, static analysis, no joints) against its size: DOFs, contact
points, multipliers, run time split by phase (-log_view events: assembly, factorization, search,
D = H^T A^-1 H, PGS, body solves, output), wall time, peak RSS of the solver (os.wait4 of the
child: on P ranks, the mpirun process tree's largest single process), and the load average;
then a strong-scaling table 1 -> 2 ranks at one size. Writes docs/dam_bench.png (time per phase
against DOFs, log-log).

By default this bench uses the static case of the tests (water at 0.8 H, mu_base 1.0), which
its tables have measured from the start; --defaults runs the builder's defaults (water at 0.95 H,
mu 0.8), which ended in DIVERGED_ITS before the Newton type and the exact free bodies and
converge since (docs/dam.md, "Analyses"; measured at 5k and 20k DOFs: exit 0, 2 D builds in 3
iterations). A run that fails still reports its phases up to the failure when -log_view prints.

  bench/dam.py [--dofs 5e3 2e4 5e4 1e5] [--scaling 5e4] [--ranks 2] [--defaults] [--joints] [--timeout 300]
               [--info] [--keep DIR]

--info adds -info :sys to each run and reports the Schur route's contact DOFs |C| of the largest
body (BodySchurInverse's "Schur complement onto |C| contact DOFs of N_b"; "-" where no body took
the Schur route) and the multiplier solves' Newton iterations (from -mbc_monitor); --keep writes
each run's whole output to DIR (docs/performance-model.md reads the MUMPS statistics from it).
"""
import argparse
import glob
import json
import os
import re
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
from mbcontact.results import log_view_times  # noqa: E402

SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")
EVENTS = {"assemble": "MBCBodyAssemble", "factor": "MBCBodyFactor", "search": ("MBCContactGather", "MBCGlobalSearch", "MBCLocalSearch"),
          "D": "MBCFlexibilityAssemble", "PGS": "MBCMultiplierSolve", "solves": "MBCBodySolve", "output": "MBCOutput",
          "wait": "MBCRankWait"}  # wait: the ranks waiting for the slowest one before a contact gather (load imbalance)
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1")
STATIC_OK = dict(level=80.0, mu_base=1.0)  # the converging static case of tests/python/test_dam.py (height 100)


def solve(h5, ranks=1, timeout=300, *options):
    """Runs the solver; returns dict(wall, rss MiB, rc, phases..., points, multipliers, out)."""
    options = list(options)
    info = None
    if "-info" in options:  # each rank's -info lines into its own file: on stdout they interleaved with -log_view's table
        i = options.index("-info")
        info = os.path.join(os.path.dirname(h5), f"info{ranks}")
        for f in glob.glob(info + ".*"):
            os.remove(f)
        options[i + 1] = info + options[i + 1][options[i + 1].index(":"):] if i + 1 < len(options) and ":" in options[i + 1] else info
    cmd = [SOLVER, "-scene", h5, "-mbc_output", os.path.join(os.path.dirname(h5), f"out{ranks}"), "-log_view", "-mbc_view", "-mbc_monitor", *options]
    if ranks > 1:
        cmd = ["mpirun", "-n", str(ranks)] + cmd
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=ENV)
    try:
        out, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, _ = p.communicate()
        return dict(wall=time.perf_counter() - t0, rss=float("nan"), rc="timeout", out=out.decode(errors="replace"))
    wall = time.perf_counter() - t0
    import resource
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0  # largest child so far (monotone)
    out = out.decode(errors="replace")
    r = dict(wall=wall, rss=rss, rc=p.returncode, out=out)
    r.update(log_view_times(out, EVENTS))
    info_text = "".join(open(f, errors="replace").read() for f in sorted(glob.glob(info + ".*"))) if info else ""
    r["out"] = out + info_text
    r["dofs"] = sum(int(d) for d in re.findall(r"(\d+) DOFs", out))
    m = re.findall(r"(\d+) contact points", out)
    r["points"] = int(m[-1]) if m else -1
    m = re.findall(r"(\d+) multipliers", out)
    r["mult"] = int(m[-1]) if m else -1
    r["err"] = [l for l in out.splitlines() if re.search(r"DIVERGED|[Ee]rror|not converge", l) and "CONVERGED" not in l][:3]
    r["rebuilds"] = out.count("flexibility matrix rebuilt")
    schur = [(int(c), int(n)) for c, n in re.findall(r"Schur complement onto (\d+) contact DOFs of (\d+)", out + info_text)]
    r["C"], r["C_body"] = max(schur) if schur else (0, 0)  # the largest body's |C| and its DOFs
    its = [int(i) for i in re.findall(r"contact: newton \S+ in (\d+) iterations", out)]
    r["solves_newton"], r["newton_its"] = len(its), sum(its)
    r["iters"] = len(re.findall(r"static iteration \d+:", out))
    return r


def fit(x, y):
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = (y > 0) & np.isfinite(y)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


PH = ("assemble", "factor", "search", "D", "PGS", "solves", "output", "wait")


def row(label, r, extra=""):
    if r.get("C") or r.get("solves_newton"):
        extra = f"  |C| {r.get('C') or '-'} (of {r.get('C_body', 0)})  newton {r.get('newton_its', 0)} its in {r.get('solves_newton', 0)} solves" + extra
    return (f"{label:>8} {r.get('dofs', 0):8d} {r.get('points', 0):6d} {r.get('mult', 0):6d} "
            + " ".join(f"{r.get(k, float('nan')):8.3f}" for k in PH)
            + f" {r['wall']:8.2f} {r['rss']:8.0f} {r['load']:5.2f} {str(r['rc']):>4} {r.get('rebuilds', 0):3d}/{r.get('iters', 0):<3d}{extra}")


HEAD = (f"{'':>8} {'DOFs':>8} {'points':>6} {'mult':>6} " + " ".join(f"{k:>8}" for k in PH)
        + f" {'wall':>8} {'RSS MiB':>8} {'load':>5} {'rc':>4} D/it")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dofs", type=float, nargs="+", default=[5e3, 2e4, 5e4, 1e5])
    ap.add_argument("--scaling", type=float, default=5e4, help="size of the 1 -> P ranks table (0: none)")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--defaults", action="store_true", help="the builder's defaults (water 0.95 H, mu 0.8)")
    ap.add_argument("--joints", action="store_true", help="the contraction joints as contact couples too (the 1M-DOF dam's 37 620 multipliers)")
    ap.add_argument("--timeout", type=float, default=300)
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "dam_bench.png"))
    ap.add_argument("--json", default=None, help="also write the rows here")
    ap.add_argument("--options", default="", help="extra solver options, e.g. '-mbc_multiplier_rtol 1e-4'")
    ap.add_argument("--info", action="store_true", help="-info :sys: the Schur route's |C| of the largest body; Newton iterations")
    ap.add_argument("--keep", default=None, help="write each run's whole output to this directory")
    a = ap.parse_args()
    if a.info:
        a.options = (a.options + " -info :sys").strip()
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    params = dict({} if a.defaults else STATIC_OK, **({"joints": True} if a.joints else {}))
    work = tempfile.mkdtemp(prefix="mbc_dam_")
    print(f"dam, static, {'builder defaults' if a.defaults else 'water 0.8 H, mu_base 1.0'}, {'joints' if a.joints else 'no joints'}; one rank; times [s] from -log_view; "
          f"RSS: peak of the solver process; load: 1-min load average at the start")
    print(f"{'target':>8}" + HEAD[8:], flush=True)
    rows = []
    for n in a.dofs:
        d = os.path.join(work, f"d{int(n)}")
        h5 = build.build(d, "static", target_dofs=int(n), **params)
        # each size in its own python child so that RUSAGE_CHILDREN is this run's peak
        r = child(h5, 1, a.timeout, a.options.split())
        r["target"] = n
        r["build_dofs"] = build.build.info["dofs"]
        keep(a.keep, f"dam_{n:.0e}_np1.txt", r)
        rows.append(r)
        print(row(f"{n:.0e}", r), flush=True)
        if r["rc"] != 0:
            tail = "\n".join(r.get("err") or r["out"].strip().splitlines()[-3:])
            print(f"   (exit {r['rc']}: {tail})", flush=True)
        if r["rc"] == "timeout":
            print(f"   stopped: over {a.timeout:.0f} s", flush=True)
            break
    # a run that ends in DIVERGED_ITS still prints -log_view (one rank): assembly, factorization,
    # search and D are complete then; PGS, solves, output and wall are fitted on converged runs only
    got = [r for r in rows if r.get("dofs", 0) > 0]
    ok = [r for r in got if r["rc"] == 0]
    FULL = ("assemble", "factor", "search", "D", "rss")
    if len(got) >= 2:
        print("\nfitted exponents (log-log least squares; assemble/factor/search/D/RSS over every size with -log_view, the rest over converged runs)")
        for k in PH + ("wall", "rss"):
            rr = got if k in FULL else ok
            print(f"  {k:>8}: N^{fit([r['dofs'] for r in rr], [r[k] for r in rr]):.2f}   m^{fit([r['mult'] for r in rr], [r[k] for r in rr]):.2f}   ({len(rr)} sizes)")
        print(f"  multipliers: N^{fit([r['dofs'] for r in got], [r['mult'] for r in got]):.2f}")
        series = [(np.array([r["dofs"] for r in (got if k in FULL else ok)]), np.array([r[k] for r in (got if k in FULL else ok)]), s, k)
                  for k, s in zip(PH, ("o-", "s-", "^-", "d-", "v-", "<-", ">-"))]
        plot.loglog(a.plot, "dam (static): time per phase against DOFs (1 rank)", "DOFs", series)
    scal = []
    if a.options:
        print(f"solver options: {a.options}")
    if any(r.get("C") for r in rows):
        print("  |C| (largest body): " + ", ".join(f"{r['dofs']}: {r['C']}" for r in rows if r.get("C"))
              + f"   |C|: N^{fit([r['dofs'] for r in rows if r.get('C')], [r['C'] for r in rows if r.get('C')]):.2f}")
    if a.scaling:
        d = os.path.join(work, "scaling")
        h5 = build.build(d, "static", target_dofs=int(a.scaling), **params)
        print(f"\nstrong scaling at {build.build.info['dofs']} DOFs: 1 -> {a.ranks} ranks (speed-up = t1 / tP per phase)")
        print(f"{'ranks':>8}" + HEAD[8:], flush=True)
        for p in (1, a.ranks):
            r = child(h5, p, a.timeout, a.options.split())
            keep(a.keep, f"dam_scaling_{a.scaling:.0e}_np{p}.txt", r)
            scal.append(r)
            print(row(str(p), r), flush=True)
            if r["rc"] != 0:
                print("   " + "\n   ".join(r["out"].strip().splitlines()[-3:]), flush=True)
        if all(r["rc"] == 0 for r in scal):
            s1, s2 = scal
            print(f"{'speed-up':>8} {'':8} {'':6} {'':6} " + " ".join(f"{(s1[k] / s2[k] if s2[k] > 0 else float('nan')):8.2f}" for k in PH)
                  + f" {s1['wall'] / s2['wall']:8.2f}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(dict(sizes=[{k: v for k, v in r.items() if k != "out"} for r in rows],
                           scaling=[{k: v for k, v in r.items() if k != "out"} for r in scal]), f, indent=1)


def keep(directory, name, r):
    if directory:
        with open(os.path.join(directory, name), "w") as f:
            f.write(r.get("out", ""))


def child(h5, ranks, timeout, options=()):
    """solve() in a fresh python process so that RUSAGE_CHILDREN.ru_maxrss is the peak of this run alone."""
    load = os.getloadavg()[0]
    code = (f"import sys, json; sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r}); import dam; "
            f"r = dam.solve({h5!r}, {ranks}, {timeout}, *{list(options)!r}); print('@@JSON@@' + json.dumps(r))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV)
    j = p.stdout.rsplit("@@JSON@@", 1)
    if len(j) < 2:
        return dict(wall=float("nan"), rss=float("nan"), rc=f"py{p.returncode}", out=p.stdout + p.stderr, load=load)
    r = json.loads(j[1])
    r["load"] = load
    return r


if __name__ == "__main__":
    main()
