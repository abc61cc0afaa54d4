#!/usr/bin/python3
"""The public FCLIB problems (../shared/benchmarks/fclib beside the clone), mbcontact side by side
with Siconos NSGS and NSN_AC (Debian python3-siconos; installed with apt when missing, except with
--smoke or --no-siconos). One table: for each problem and solver the solver's own verdict, its
iterations, its CPU time and FCLIB's merit recomputed here from the solution (mbcontact.fclib,
fcmer.c's definition) on the same local problem for every solver (a global problem condensed in
Python, W = H^T M^-1 H, q = H^T M^-1 f + w, as mbcontact does; Siconos gets that local problem).

CPU time is process CPU, not wall (the machine is shared): Siconos's is time.process_time() around
fc3d_driver; mbcontact's is its process's user + system time (getrusage of children) minus the
same command's start-up (PETSc and MPI initialisation, reading, condensing, writing), measured by
running it again warm-started from its own solution, which takes 0 iterations. When mbcontact did
not converge that run would iterate again, so the start-up is kept in and the figure is marked *.
Short runs are repeated (--repeat) and the least CPU kept; the subtraction resolves ~0.01 s.
Siconos's verdict is its own test: 4.4's fc3d_compute_error divides the same natural-map norm by
max(norm, |r|, |u|), not by 1 + sqrt(|q|), so "converged" may leave FCLIB's merit above --tol.

  bench/fclib.py [--mbc "-mbc_multiplier_type newton"] [--mbc ""] [--problems NAME ...] [--smoke]

Each --mbc is one mbcontact row per problem with those extra options (default: one row, defaults).
"""
import argparse
import glob
import importlib
import os
import re
import resource
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import fclib  # noqa: E402



def fclib_dir():
    """../shared/benchmarks/fclib beside the clone; from a git worktree, beside its main checkout."""
    here = os.path.join(os.path.dirname(ROOT), "shared", "benchmarks", "fclib")
    if os.path.isdir(here):
        return here
    try:
        common = subprocess.run(["git", "-C", ROOT, "rev-parse", "--path-format=absolute", "--git-common-dir"],
                                capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return here
    main = os.path.join(os.path.dirname(os.path.dirname(common)), "shared", "benchmarks", "fclib")
    return main if os.path.isdir(main) else here


SHORT = 0.3  # s of process CPU: below it, mbcontact runs are repeated
RESOLUTION = 0.01  # s: what the start-up subtraction resolves (its run-to-run spread on this machine)
SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_mbcontact(path, options, work, repeat):
    """mbcontact -fclib, the least CPU of repeat runs when a run is short (the start-up is most of it
    then and varies by ~0.02 s under load), one run otherwise: (verdict, iterations, process CPU, r)."""
    out = os.path.join(work, "solution.hdf5")
    cpu = float("inf")
    for k in range(repeat):
        c0 = child_cpu()
        p = subprocess.run([SOLVER, "-fclib", path, *options, "-fclib_write", out], capture_output=True, text=True)
        cpu = min(cpu, child_cpu() - c0)
        if cpu > SHORT:
            break
    if p.returncode not in (0, 2):  # 2: ran, did not converge
        raise RuntimeError(f"mbcontact -fclib {path} {' '.join(options)} exited with {p.returncode}:\n{p.stdout}{p.stderr}")
    reason = re.search(r"\b((?:CONVERGED|DIVERGED)_\w+)", p.stdout)
    its = re.search(r"\bin (\d+) (?:sweeps|iterations|its)\b", p.stdout)
    if not (reason and its):
        raise RuntimeError(f"mbcontact -fclib {path}: no verdict or iteration count in its output:\n{p.stdout}")
    return reason.group(1), int(its.group(1)), cpu, fclib.read_solution(out)


def startup_cpu(path, options, r, work, repeat):
    """CPU of the same mbcontact command warm-started from r (the problem's file copied with r as
    /solution/r); None when that run still iterates (then it measured more than the start-up)."""
    copy = os.path.join(work, "warm.hdf5")
    shutil.copyfile(path, copy)
    with h5py.File(copy, "a") as f:
        if "solution" in f:
            del f["solution"]
        f["solution/r"] = r
    best = None
    for _ in range(repeat):  # the least disturbed run
        c0 = child_cpu()
        p = subprocess.run([SOLVER, "-fclib", copy, *options, "-fclib_warm_start", "-fclib_write", os.path.join(work, "again.hdf5")],
                           capture_output=True, text=True)
        cpu = child_cpu() - c0
        its = re.search(r"\bin (\d+) (?:sweeps|iterations|its)\b", p.stdout)
        if p.returncode != 0 or not its or int(its.group(1)) != 0:
            return None
        best = cpu if best is None else min(best, cpu)
    return best


def import_siconos(install):
    """siconos.numerics, installed with apt first when missing and install is set; None without it."""
    try:
        return importlib.import_module("siconos.numerics")
    except ImportError:
        if not install:
            return None
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    print("python3-siconos is missing: installing it with apt-get", flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    rc = subprocess.run([*sudo, "apt-get", "install", "-y", "-qq", "--no-install-recommends", "python3-siconos"], env=env).returncode
    if rc != 0:
        raise RuntimeError(f"apt-get install python3-siconos exited with {rc} (--no-siconos: mbcontact only)")
    importlib.invalidate_caches()
    return importlib.import_module("siconos.numerics")


def run_siconos(sn, W, q, mu, solver, max_it, tol):
    """Siconos fc3d_driver on u = W r + q, W as a sparse block matrix of 3x3 blocks (the storage
    Siconos's own FCLIB reader gives a local problem): (verdict, iterations, CPU, r)."""
    A = W.tocsc()
    A.indices, A.indptr = A.indices.astype(np.int64), A.indptr.astype(np.int64)  # Siconos's index type
    problem = sn.FrictionContactProblem(3, A, np.ascontiguousarray(q, float), np.ascontiguousarray(mu, float))
    info, sbm = sn.SBM_from_csparse(3, A)
    if info == 0:
        M = sn.NM_create(sn.NM_SPARSE_BLOCK, A.shape[0], A.shape[1])
        M.matrix1 = sbm
        problem.M = M  # keeps the compressed-column W otherwise
    options = sn.SolverOptions(solver)
    options.dparam[sn.SICONOS_DPARAM_TOL] = tol
    options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = max_it
    r, u = np.zeros(len(q)), np.zeros(len(q))
    t0 = time.process_time()
    status = sn.fc3d_driver(problem, r, u, options)
    cpu = time.process_time() - t0
    return ("converged" if status == 0 else f"info {status}"), int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE]), cpu, r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mbc", action="append", default=None, metavar="OPTIONS",
                    help="extra mbcontact options, one row each (repeatable; default: one row, no options)")
    ap.add_argument("--problems", nargs="+", default=None, help="file names in the FCLIB directory (default: all)")
    ap.add_argument("--fclib-dir", default=None, help="default: ../shared/benchmarks/fclib beside the clone")
    ap.add_argument("--tol", type=float, default=1e-8, help="Siconos tolerance and the merit threshold counted")
    ap.add_argument("--nsgs-max-it", type=int, default=100000)
    ap.add_argument("--nsn-max-it", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=5, help="runs of a short mbcontact solve and of its start-up, the least CPU kept")
    ap.add_argument("--no-siconos", action="store_true")
    ap.add_argument("--smoke", action="store_true",
                    help="local_problem_test.hdf5 only, Siconos only if it is already installed")
    a = ap.parse_args()
    a.fclib_dir = a.fclib_dir or fclib_dir()
    if a.smoke:
        a.problems, a.repeat = a.problems or ["local_problem_test.hdf5"], 1
    paths = sorted(glob.glob(os.path.join(a.fclib_dir, "*.hdf5"))) if a.problems is None else [os.path.join(a.fclib_dir, p) for p in a.problems]
    if not paths:
        sys.exit(f"bench/fclib.py: no FCLIB problem (*.hdf5) in {a.fclib_dir}")
    for p in paths:
        if not os.path.isfile(p):
            sys.exit(f"bench/fclib.py: FCLIB problem {p} does not exist")
    if not os.access(SOLVER, os.X_OK):
        sys.exit(f"bench/fclib.py: {SOLVER} is missing (make build)")
    sn = None if a.no_siconos else import_siconos(install=not a.smoke)
    mbc = [shlex.split(o) for o in (a.mbc or [""])]
    solvers = [("mbcontact" + (" " + " ".join(o) if o else ""), o) for o in mbc]
    if sn is not None:
        solvers += [("Siconos NSGS", (sn.SICONOS_FRICTION_3D_NSGS, a.nsgs_max_it)),
                    ("Siconos NSN_AC", (sn.SICONOS_FRICTION_3D_NSN_AC, a.nsn_max_it))]

    rows, starts = [], []
    for path in paths:
        name = os.path.basename(path)
        kind, W, q, mu = fclib.read(path)
        for label, what in solvers:
            if label.startswith("mbcontact"):
                with tempfile.TemporaryDirectory() as work:
                    verdict, its, cpu, r = run_mbcontact(path, what, work, a.repeat)
                    if len(r) != len(q):
                        raise RuntimeError(f"mbcontact wrote {len(r)} reactions for {len(q)} unknowns of {name}")
                    start = startup_cpu(path, what, r, work, a.repeat) if verdict.startswith("CONVERGED") else None
                mark = "" if start is not None else "*"
                starts += [start] if start is not None else []
                cpu = cpu - start if start is not None else cpu
            else:
                verdict, its, cpu, r = run_siconos(sn, W, q, mu, *what, a.tol)
                mark = ""
            rows.append((name, kind, len(mu), np.linalg.norm(q), label, verdict, its, cpu, mark, fclib.merit_local(W, q, mu, r)))

    print(f"\nFCLIB problems side by side, merit by fcmer.c recomputed from each solution, "
          f"threshold {a.tol:.0e}, one core, CPU seconds\n")
    print("| problem | kind | contacts | ‖q‖₂ | solver | verdict | iterations | CPU [s] | FCLIB merit |")
    print("|---|---|---:|---:|---|---|---:|---:|---:|")
    for name, kind, nc, nq, label, verdict, its, cpu, mark, e in rows:
        t = f"< {RESOLUTION:g}" if cpu < RESOLUTION else f"{cpu:.3f}"
        print(f"| {name} | {kind} | {nc} | {nq:.3g} | {label} | {verdict} | {its} | {t}{mark} | {e:.2e} |")
    print("\n| solver | merit < {:.0e} | CPU [s], sum over the problems |".format(a.tol))
    print("|---|---:|---:|")
    for label, _ in solvers:
        mine = [r for r in rows if r[4] == label]
        print(f"| {label} | {sum(r[9] < a.tol for r in mine)}/{len(mine)} | {sum(r[7] for r in mine):.3f} |")
    if any(r[8] for r in rows):
        print("\n* mbcontact did not converge: process CPU including its start-up"
              + (f" ({min(starts):.3f}-{max(starts):.3f} s on the others)" if starts else ""))
    if sn is None and not a.no_siconos:
        print("\nSiconos (python3-siconos) is not installed: mbcontact only")


if __name__ == "__main__":
    try:
        main()
    except RuntimeError as e:
        sys.exit(f"bench/fclib.py: {e}")
