"""The solver run with -mbc_monitor, and what its lines say (for the benches of bench/extremes*.py)."""
import os
import re
import subprocess
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def run(h5, options=(), nproc=1):
    """The solver on h5 with -mbc_monitor and options, on nproc ranks: (CompletedProcess, wall s)."""
    mpi = ["mpirun", "-n", str(nproc), "--oversubscribe"] if nproc > 1 else []
    t0 = time.perf_counter()
    r = subprocess.run(mpi + [SOLVER, "-scene", h5, "-mbc_monitor", *options], capture_output=True, text=True, env=ENV)
    return r, time.perf_counter() - t0


def stats(out):
    """The converged reasons of the multiplier solves (a solve prints "contact: newton
    CONVERGED_RTOL in 2 iterations (merit ...)", a failed one that cuts the step "contact: newton
    solve DIVERGED_ITS ..."), their iterations and the static iterations."""
    reasons = sorted(set(re.findall(r"contact: \w+ (\w+) in", out)) | set(re.findall(r"contact: \w+ solve (\w+)", out))) or ["(none)"]
    its = sum(int(i) for i in re.findall(r" in (\d+) iterations", out))
    return reasons, its, len(re.findall(r"static iteration", out))


def converged(reasons):
    return bool(reasons) and all(r.startswith("CONVERGED") for r in reasons)
