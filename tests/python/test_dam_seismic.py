"""The gravity dam's seismic options (meshes/dam/build.py, docs/dam.md): the modal check with
and without the reservoir's added mass; the staged analysis on a radiating foundation with three
record components, and the report of what engineers read from it (envelope, absolute
acceleration, response spectrum, plots); a massless foundation."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT, env, load_script, result, solve
from mbcontact.results import read_csv, read_modes

dam = load_script("meshes/dam/build.py", "dam_build_py_seismic")
REPORT = os.path.join(ROOT, "meshes", "dam", "report.py")
SMALL = dict(h=15.0, monoliths=3)


def test_modal_dam_with_reservoir(tmp_path):
    """The small dam's first ten modes with the couples tied, dry and with Westergaard's added
    mass: the reservoir lengthens the first stream-direction period (measured R_r = 1.26; asserted
    1.1 to 1.4) and leaves the mass along the dam's axis alone; the report prints the table."""
    dry = dam.build(tmp_path / "dry", "modal", **SMALL)
    wet = dam.build(tmp_path / "wet", "modal", added_mass=True, **SMALL)
    out = solve(wet).stdout
    solve(dry)
    assert "couples tied" in out
    fd, fw = read_modes(result(dry, ".h5")), read_modes(result(wet, ".h5"))
    assert np.all(np.diff(fw["frequency"]) >= 0) and fw["frequency"][0] > 0
    def first_stream_mode(m):  # the first mode moving the dam upstream-downstream (> 5 % of the x mass)
        return m["frequency"][np.flatnonzero(m["effective_mass"][:, 0] > 0.05 * m["total_mass"][0])[0]]
    rr = first_stream_mode(fd) / first_stream_mode(fw)  # dry: 3.29 Hz (a cross-stream mode, 3.13 Hz, comes first)
    assert 1.1 < rr < 1.4, rr
    assert fw["total_mass"][0] > fd["total_mass"][0] and fw["total_mass"][1] == pytest.approx(fd["total_mass"][1], rel=1e-12)
    r = subprocess.run([sys.executable, REPORT, result(wet, "")], capture_output=True, text=True, env=env())
    assert r.returncode == 0 and "m_x %" in r.stdout and len(r.stdout.strip().splitlines()) == 11, r.stdout + r.stderr


def test_staged_radiating_three_components(tmp_path):
    """Static stage (weight, water) on the held foundation, then 1 s of the strong motion in x, y
    and z entering through the absorbing bottom as the outcrop motion, the reservoir's added mass
    on: it runs with default options; the base carries the weight W at the static stage's end;
    every point reports its absolute motion; the report gives the envelope of the largest
    principal stress per body, the spectrum of the crest's absolute acceleration (its short-period
    end is the peak acceleration: 2 %) and the PNG plots."""
    h5 = dam.build(tmp_path, "staged", dt=0.02, eq_duration=1.0, record_from=3.0, foundation_model="radiating",
                   added_mass=True, components="xyz", **SMALL)
    solve(h5)
    c = read_csv(result(h5, "_contact.csv"))
    base = c["couple"] == 1
    W = dam.build.info["weight"] * 3
    assert c["fz"][base][0] == pytest.approx(W, rel=1e-6)  # the static stage: the held foundation carries it
    p = read_csv(result(h5, "_points.csv"))
    assert all(f"crest_m2_abs_a{x}" in p for x in "xyz")
    assert np.abs(p["crest_m2_abs_az"]).max() > 0.1  # the vertical component arrived
    prefix = result(h5, "")
    r = subprocess.run([sys.executable, REPORT, prefix, "--json", "--spectrum", "crest_m2", "--plots", str(tmp_path / "plots")],
                       capture_output=True, text=True, env=env())
    assert r.returncode == 0, r.stderr
    rep = json.loads(r.stdout)
    assert {e["body"] for e in rep["envelope"]} == {"m1", "m2", "m3", "foundation"}
    assert all(e["max_principal_stress"] > 0 for e in rep["envelope"])
    for x in "xyz":
        s = read_csv(rep["spectrum"]["file"])
        assert s[f"PSA_{x}"][0] == pytest.approx(rep["spectrum"][x]["peak_abs_acceleration"], rel=0.02)
    assert all(os.path.getsize(f) > 1000 for f in rep["plots"]) and len(rep["plots"]) == 2


def test_massless_foundation_dynamic(tmp_path):
    """The dynamic dam on a massless foundation (density 0, no inertia): the ramp and half a second
    of the record run with default options and the base carries W and T before the record (2 %:
    the ramp's ringing without the rock's inertia)."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0,
                   foundation_model="massless", **SMALL)
    solve(h5)
    c = read_csv(result(h5, "_contact.csv"))
    base = (c["couple"] == 1) & (c["t"] <= 1.0 + 1e-9) & (c["t"] >= 0.9)
    W, T = dam.build.info["weight"] * 3, dam.build.info["thrust"] * 3
    assert np.abs(c["fz"][base] / W - 1).max() < 0.02
    assert np.abs(-c["fx"][base] / T - 1).max() < 0.02
