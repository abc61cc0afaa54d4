"""Long runs: every completed output step survives kill -9, SIGTERM, a full disk; the monitor's
timing; -help; file modes. A killed or stopped run must hold exactly the steps of an
uninterrupted run up to where it stopped (bit for bit: same binary, options and ranks)."""
import os
import resource
import signal
import stat
import subprocess
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from conftest import SOLVER, env, prep, solve
from mbcontact import meshgen

DT, STEPS = 1e-5, 1000  # a run far longer than the tests wait for


def bar(tmp_path, time="sudden"):
    """A slender bar under sudden gravity (as test_body's), every step written."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(2, 2, 40), cell="hex8", volume_name="bar")
    return prep(tmp_path, {
        "meshes": {"m": "bar.msh"},
        "bodies": {"bar": {"mesh": "m", "regions": ["bar"], "material": {"E": 1e6, "nu": 0.0, "density": 1.0}}},
        "dirichlet": [{"surface": "zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -10.0], "time": time}],
        "analysis": {"type": "dynamic", "dt": DT, "final_time": STEPS * DT},
        "output": {"every": 1, "fields": ["displacement", "stress"], "energy": True, "points": {"tip": [0.025, 0.025, 1.0]}},
    })


def start(h5, out, nproc=1, extra=(), preexec=None):
    cmd = [SOLVER, "-scene", str(h5), "-mbc_output", str(out), "-mbc_monitor", *extra]
    if nproc > 1:
        cmd = ["mpirun", "-n", str(nproc), *cmd]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env(), preexec_fn=preexec)


def wait_for_step(p, n):
    """Reads the monitor until step n is announced (its output is then under way, that of step
    n - 1 committed)."""
    lines = []
    for line in p.stdout:
        lines.append(line)
        if line.startswith("step") and int(line.split()[1]) >= n:
            return lines
    raise AssertionError("the run ended before step %d:\n%s\n%s" % (n, "".join(lines), p.stderr.read()))


def outputs(path):
    """{k: (time, displacement, stress)} of the committed outputs, as num_outputs says."""
    with h5py.File(path, "r") as f:
        n = int(f.attrs["num_outputs"])
        t = f["time"][...]
        assert len(t) == n
        return {k: (t[k], f[f"bodies/bar/step_{k}/displacement"][...], f[f"bodies/bar/step_{k}/stress"][...]) for k in range(n)}


def assert_xdmf(out, n, killed=False):
    """The index lists the n committed outputs (killed: n or n - 1, as the index is renamed into
    place just after the file's flush), every HDF item an existing dataset of the item's shape
    (no XDMF 2 reader works on Debian 12: VTK is built without Xdmf, python3-xdmf does not
    import, meshio reads XDMF 3 only)."""
    root = ET.parse(f"{out}.xmf").getroot()
    steps = root.find("Domain/Grid").findall("Grid")
    assert len(steps) in ((n, n - 1) if killed else (n,))
    if not killed:
        assert not os.path.exists(f"{out}.xmf.part")
    with h5py.File(f"{out}.h5", "r") as f:
        assert [float(g.find("Time").get("Value")) for g in steps] == list(f["time"][:len(steps)])
        for d in root.iter("DataItem"):
            dset = d.text.strip().split(":")[1]
            assert list(f[dset].shape) == [int(v) for v in d.get("Dimensions").split()], d.text


def assert_csv_whole(path, nrows):
    """Every line complete: as many fields as the header, each a number; at least nrows rows."""
    lines = open(path).read().split("\n")
    assert lines[-1] == ""  # ends with a newline: no line cut mid-number
    head, rows = lines[0].split(","), lines[1:-1]
    assert len(rows) >= nrows
    for r in rows:
        assert len(r.split(",")) == len(head)
        [float(v) for v in r.split(",")]
    return np.array([[float(v) for v in r.split(",")] for r in rows])


def assert_same_as_uninterrupted(tmp_path, h5, got, nproc):
    """The first outputs equal those of a run that stops there by itself: bit for bit at 1 rank;
    at 2 the parallel direct solve is not bitwise reproducible from run to run, so to 1e-12 of
    the field's largest value (roundoff of the solve: the bar's K is well conditioned)."""
    n = len(got)
    ref = tmp_path / "ref"
    solve(h5, "-mbc_output", str(ref), "-mbc_final_time", str((n - 1) * DT), nproc=nproc)
    want = outputs(f"{ref}.h5")
    assert len(want) == n
    for k in range(n):
        assert got[k][0] == want[k][0]
        for a, b in zip(got[k][1:], want[k][1:]):
            if nproc == 1:
                assert np.array_equal(a, b), k
            else:
                assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max(), k


@pytest.mark.parametrize("nproc", [1, 2])
def test_kill9_keeps_completed_steps(tmp_path, nproc):
    """kill -9 (at 2 ranks: of one rank) after step 30: outputs 0..29 (t = 0 is output 0) read
    back, equal to an uninterrupted run's, indexed by the XDMF; CSV lines whole."""
    h5, out, n = bar(tmp_path), tmp_path / "run", 30
    p = start(h5, out, nproc)
    wait_for_step(p, n)
    if nproc == 1:
        os.kill(p.pid, signal.SIGKILL)
    else:
        ranks = subprocess.run(["pgrep", "-P", str(p.pid), "-f", SOLVER], capture_output=True, text=True).stdout.split()
        assert len(ranks) == nproc
        os.kill(int(ranks[-1]), signal.SIGKILL)
    p.communicate(timeout=60)
    assert p.returncode != 0
    got = outputs(f"{out}.h5")
    assert n <= len(got) < STEPS
    assert_xdmf(out, len(got), killed=True)
    assert_csv_whole(f"{out}_points.csv", n)
    assert_csv_whole(f"{out}_energy.csv", n)
    assert_same_as_uninterrupted(tmp_path, h5, {k: got[k] for k in range(n)}, nproc)


def test_sigterm_writes_the_step_and_stops(tmp_path):
    """SIGTERM: the run ends after the current step with it written (also between output
    steps), a message naming the signal and the files, exit status 128 + 15, -log_view."""
    h5, out = bar(tmp_path), tmp_path / "run"
    p = start(h5, out, extra=("-mbc_output_every", "7", "-log_view"))
    wait_for_step(p, 20)
    p.send_signal(signal.SIGTERM)
    stdout, stderr = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM, stderr
    assert "Stopped by signal 15 (SIGTERM) after step" in stderr and "run.h5" in stderr, stderr
    assert "PETSc Performance Summary" in stdout and "MBCBodySolve" in stdout  # -log_view
    last = int(stderr.split("after step ")[1].split()[0])
    got = outputs(f"{out}.h5")
    assert [round(got[k][0] / DT) for k in range(len(got))] == list(range(0, last + 1, 7)) + ([last] if last % 7 else [])
    rows = assert_csv_whole(f"{out}_points.csv", last + 1)
    assert len(rows) == last + 1 and abs(rows[-1, 0] - last * DT) < 1e-12
    assert_xdmf(out, len(got))


@pytest.mark.parametrize("nproc", [1, 2])
def test_error_stop_keeps_completed_steps(tmp_path, nproc):
    """An error at step 21 (the load's time table jumps to 1e308 after t = 0.0002: the body moves
    by ~1e298, which the displacement check refuses as no small-strain answer; a step later the
    increment would not even be finite): one message naming the body and the time, exit
    status 1, -log_view printed (also at 2 ranks: every rank has the error), the outputs of
    steps 0..20 equal to an uninterrupted run's, indexed, CSV lines whole."""
    table = [[0, 0], [20 * DT, 1], [20.5 * DT, 1e308], [1, 1e308]]
    h5, out = bar(tmp_path, {"table": table}), tmp_path / "run"
    r = solve(h5, "-mbc_output", str(out), "-log_view", nproc=nproc, check=False)
    assert r.returncode == 1, r.stderr
    assert "at t = 0.00021 body 'bar' moves by" in r.stderr and "no small-strain answer" in r.stderr, r.stderr
    assert "PETSc Performance Summary" in r.stdout and "MBCBodySolve" in r.stdout
    got = outputs(f"{out}.h5")
    assert len(got) == 21
    assert_xdmf(out, 21)
    assert len(assert_csv_whole(f"{out}_points.csv", 21)) == 21
    assert_same_as_uninterrupted(tmp_path, h5, got, nproc)


def test_full_disk_stops_cleanly(tmp_path):
    """A file-size limit (ulimit -f 400 KiB) met after some steps: one message naming the file
    and the cause, exit status 1, no crash, -log_view; the file holds the outputs before it, as
    an uninterrupted run, and the XDMF lists them."""
    h5, out = bar(tmp_path), tmp_path / "run"

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (400 * 1024, resource.RLIM_INFINITY))

    e = env()
    e["PMIX_MCA_gds"] = "hash"  # Open MPI's shared-memory store would meet the limit in MPI_Init
    cmd = [SOLVER, "-scene", str(h5), "-mbc_output", str(out), "-log_view"]
    r = subprocess.run(cmd, capture_output=True, text=True, env=e, preexec_fn=limit, timeout=120)
    assert r.returncode == 1, r.stderr
    assert "mbcontact: error:" in r.stderr and "run.h5" in r.stderr and "File too large" in r.stderr and "ulimit -f" in r.stderr, r.stderr
    for crash in ("Segmentation", "signal", "core dumped"):
        assert crash not in r.stderr, r.stderr
    assert "PETSc Performance Summary" in r.stdout and "MBCBodySolve" in r.stdout  # -log_view
    got = outputs(f"{out}.h5")
    assert 5 <= len(got) < STEPS
    assert_xdmf(out, len(got))
    assert_csv_whole(f"{out}_points.csv", len(got))
    assert_same_as_uninterrupted(tmp_path, h5, got, 1)


def test_monitor_timing(tmp_path):
    """Each step line ends with the step's wall time, the elapsed time (growing) and an ETA,
    0 at the last step."""
    h5 = bar(tmp_path)
    r = solve(h5, "-mbc_output", str(tmp_path / "m"), "-mbc_monitor", "-mbc_final_time", str(20 * DT))
    lines = [l for l in r.stdout.splitlines() if l.startswith("step")]
    assert len(lines) == 21
    timing = [l.split("time: step ")[1].split() for l in lines]  # [step, "s", "elapsed", e, "s", "ETA", eta, "s"]
    elapsed = [float(t[3]) for t in timing]
    assert all(float(t[0]) >= 0 for t in timing) and elapsed == sorted(elapsed)
    assert float(timing[-1][6]) == 0 and float(timing[10][6]) > 0


@pytest.mark.parametrize("with_scene", [False, True])
def test_help_lists_every_option(tmp_path, with_scene):
    """-help lists the program's own options and the contact and multiplier-solve ones (both types), with a contact-free
    scene or none."""
    args = ["-help", "-mbc_output", str(tmp_path / "h")] + (["-mbc_final_time", str(DT)] if with_scene else [])
    r = solve(bar(tmp_path) if with_scene else "", *args)
    for opt in ("-scene", "-fclib ", "-fclib_write", "-fclib_warm_start", "-mbc_error_traceback", "-mbc_output_every",
                "-mbc_monitor", "-mbc_contact_cell_factor", "-mbc_contact_view", "-mbc_multiplier_type", "-mbc_multiplier_rtol",
                "-mbc_multiplier_max_it", "-mbc_newton_rho", "-mbc_pgs_omega"):
        assert opt in r.stdout, opt


@pytest.mark.parametrize("mask", [0o022, 0o027])
def test_files_follow_the_umask(tmp_path, mask):
    """Scene and result files get 0666 & ~umask (mkstemp and MPI-IO used to make them 0600)."""
    old = os.umask(mask)
    try:
        h5 = bar(tmp_path)
        solve(h5, "-mbc_output", str(tmp_path / "u"), "-mbc_final_time", str(2 * DT), nproc=2)
    finally:
        os.umask(old)
    for f in (h5, *(tmp_path / f"u{s}" for s in (".h5", ".xmf", "_points.csv", "_energy.csv"))):
        assert stat.S_IMODE(os.stat(f).st_mode) == 0o666 & ~mask, f
