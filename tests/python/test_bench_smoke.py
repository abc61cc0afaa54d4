"""Benches must not rot: every script in bench/ runs at its smallest size (exit 0, its table
printed, its plot written with matplotlib's Agg backend): 80 s in all at load average 10."""
import glob
import os
import re
import subprocess
import sys

import importlib.util

import pytest

from conftest import ROOT, env

BENCH = os.path.join(ROOT, "bench")


def fclib_dir():
    """Where bench/fclib.py looks for the FCLIB problems (loaded without putting bench/ on sys.path)."""
    spec = importlib.util.spec_from_file_location("bench_fclib", os.path.join(BENCH, "fclib.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.fclib_dir()

# script -> (smallest-size options; a line of its table; whether it writes --plot)
SMOKE = {
    "body_phases.py": (["--sizes", "4", "--steps", "2"], r"^\s+375\s", True),
    "contact.py": (["--sizes", "3", "--steps", "2", "--tol-size", "3", "--tols", "1e-4", "--tol-final-time", "0.05"],
                   r"^\s+1e-04\s+pgs \+ AS 20", True),
    "dam.py": (["--dofs", "1e3", "2e3", "--scaling", "1e3", "--ranks", "2"], r"^speed-up", True),
    "extremes.py": (["--smoke"], r"^\s+bounce\s+100 periods\s+CONVERGED_RTOL\s.*pass", True),
    "fclib.py": (["--smoke"], r"^\| local_problem_test\.hdf5 \| local \| 48 \|.*\| mbcontact \|", False),
    "hertz_convergence.py": (["--smoke"], r"^\s+0\.400\s+\d+", True),
    "newton_lu.py": (["--n", "300", "--bodies", "2", "5"], r"^\s+dam\s+5\s+300\s", True),
    "quake.py": (["--dofs", "5e3", "--steps", "3"], r"^\s+4752\s+124\s+3\s", True),
    "search.py": (["--sizes", "1000"], r"^\s+1060\s", True),
}
HELPERS = {"plot.py", "monitor.py", "extremes_poisson.py", "extremes_dynamic.py"}  # imported by the benches (extremes.py --smoke runs extremes_*.py's smallest cases)


def test_every_bench_has_a_smoke_run():
    scripts = {os.path.basename(p) for p in glob.glob(os.path.join(BENCH, "*.py"))} - HELPERS
    assert scripts == set(SMOKE), "add the new bench to SMOKE (or drop the removed one)"


@pytest.mark.parametrize("script", sorted(SMOKE))
def test_bench_smoke(tmp_path, script):
    options, line, plots = SMOKE[script]
    if script == "fclib.py" and not os.path.isdir(fclib_dir()):
        pytest.skip("shared/benchmarks/fclib is not beside the clone")
    plot = tmp_path / "plot.png"
    e = env()
    e.update(MPLBACKEND="Agg", TMPDIR=str(tmp_path))  # the dam and Hertz benches keep their work directory
    cmd = [sys.executable, os.path.join(BENCH, script), *options, *(["--plot", str(plot)] if plots else [])]
    r = subprocess.run(cmd, capture_output=True, text=True, env=e, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert re.search(line, r.stdout, re.M), r.stdout
    assert "Traceback" not in r.stderr, r.stderr
    if plots:
        assert plot.stat().st_size > 1000, f"{script} wrote no plot"
    if script == "dam.py":  # a failed solve is a row with its exit status, not a failed bench
        assert "(exit " not in r.stdout, r.stdout
    if script == "fclib.py":
        # the problem mbcontact alone must keep solving: FCLIB's merit recomputed from its solution
        merit = float(re.search(r"^\| local_problem_test\.hdf5 .*\| mbcontact \| (\w+) \|.*\| ([0-9.e+-]+) \|$", r.stdout, re.M).group(2))
        assert merit < 1e-8, r.stdout


def test_search_plot_without_brute_force(tmp_path):
    """Every size above --brute-max leaves the brute-force series empty: the plot used to crash
    unpacking it (ValueError: not enough values to unpack)."""
    plot = tmp_path / "search.png"
    r = subprocess.run([sys.executable, os.path.join(BENCH, "search.py"), "--sizes", "1000", "--brute-max", "10", "--plot", str(plot)],
                       capture_output=True, text=True, env=dict(env(), MPLBACKEND="Agg"), timeout=120, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert re.search(r"^\s+1060\s.*\bnan\b", r.stdout, re.M) and plot.stat().st_size > 1000


def test_dam_bench_info_at_two_ranks(tmp_path):
    """With --info, rank 1's -info lines went to stdout and broke -log_view's table lines: the
    2-rank scaling row read assemble 0.000 (measured at 198k). They now go to a file per rank, and
    the Schur route's |C| is still read from them."""
    out = tmp_path / "dam.json"
    e = dict(env(), MPLBACKEND="Agg", TMPDIR=str(tmp_path))
    r = subprocess.run([sys.executable, os.path.join(BENCH, "dam.py"), "--dofs", "1e3", "--scaling", "1e3", "--ranks", "2", "--info",
                        "--plot", str(tmp_path / "p.png"), "--json", str(out)], capture_output=True, text=True, env=e, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    import json
    rows = json.load(open(out))
    for s in rows["scaling"] + rows["sizes"]:
        assert s["rc"] == 0 and s["assemble"] > 0 and s["factor"] > 0 and s["D"] > 0 and s["C"] > 0, s
    assert len(glob.glob(str(tmp_path / "**" / "scaling" / "info2.*"), recursive=True)) == 2, "one -info file per rank"
