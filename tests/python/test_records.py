"""Ground-motion records (mbcontact.records, docs/scene.md "Ground motion"): PEER .AT2 and
tables read equal to their values, the prep's checks naming the file and key, the exact
integration and baseline correction, response spectra against closed-form oscillators, Rayleigh
coefficients. Python only: seconds."""
import subprocess

import numpy as np
import pytest
import yaml

from conftest import PREP, env
from mbcontact import meshgen
from mbcontact.records import (RecordError, baseline_correct, integrate, rayleigh, read_at2, read_table,
                               response_spectrum)

AT2 = """PEER NGA STRONG MOTION DATABASE RECORD
IMPERIAL VALLEY 10/15/79 2316, EL CENTRO ARRAY #6, 140
ACCELERATION TIME SERIES IN UNITS OF G
NPTS=    12, DT=   .0050 SEC
  .1234567E-02  .2345678E-02 -.3456789E-02  .4567890E-02 -.5678901E-02
 -.6789012E-02  .7890123E-02  .8901234E-02 -.9012345E-02  .1012345E-01
  .1123456E-01 -.1234567E-01
"""
VALUES = [.1234567E-02, .2345678E-02, -.3456789E-02, .4567890E-02, -.5678901E-02, -.6789012E-02,
          .7890123E-02, .8901234E-02, -.9012345E-02, .1012345E-01, .1123456E-01, -.1234567E-01]


def test_at2_read_equal_to_its_values(tmp_path):
    """Every value, NPTS and DT as the file states them; the older header form '12 .005 NPTS, DT'
    too."""
    p = tmp_path / "r.AT2"
    p.write_text(AT2)
    dt, a = read_at2(str(p))
    assert dt == 0.005 and np.array_equal(a, VALUES)
    p.write_text(AT2.replace("NPTS=    12, DT=   .0050 SEC", "   12    .0050    NPTS, DT"))
    dt, a = read_at2(str(p))
    assert dt == 0.005 and np.array_equal(a, VALUES)


@pytest.mark.parametrize("text, message", [
    (AT2.replace("UNITS OF G", "UNITS OF CM/S/S"), "not an acceleration in g"),
    (AT2.replace("NPTS=    12", "NPTS=    13"), "NPTS = 13 but the file holds 12"),
    (AT2.replace("DT=   .0050", "DT=   -.0050"), "DT must be > 0"),
    (AT2.replace("-.9012345E-02", "nan"), "value 9 is not a finite number"),
    (AT2.replace("-.9012345E-02", "x9"), "line 6: 'x9' is not a number"),
    ("\n".join(AT2.splitlines()[:3]), "4 header lines"),
])
def test_at2_errors(tmp_path, text, message):
    p = tmp_path / "r.AT2"
    p.write_text(text)
    with pytest.raises(RecordError, match=message):
        read_at2(str(p))


def test_tables(tmp_path):
    """Two columns (t, a); several columns with `column`; one column with dt; a header line."""
    p = tmp_path / "m.csv"
    p.write_text("t,ax,ay,az\n0,1,2,3\n0.01,4,5,6\n0.02,7,8,9\n")
    t, a = read_table(str(p), column=3)
    assert np.array_equal(t, [0, 0.01, 0.02]) and np.array_equal(a, [2, 5, 8])
    t, a = read_table(str(p), column=2)
    assert np.array_equal(a, [1, 4, 7])
    p.write_text("# one column\n0.5\n-0.25\n0.125\n")
    t, a = read_table(str(p), dt=0.02)
    assert np.allclose(t, [0, 0.02, 0.04]) and np.array_equal(a, [0.5, -0.25, 0.125])
    p.write_text("0 1\n0.01 2\n0.01 3\n")
    with pytest.raises(RecordError, match="line 3: t must be strictly increasing"):
        read_table(str(p))
    with pytest.raises(RecordError, match="column 5"):
        read_table(str(p), column=5)


def test_integration_exact_and_baseline():
    """A piecewise-linear acceleration integrates exactly at the rows (a = t on [0, 1]: v = t^2/2,
    d = t^3/6); a baseline correction of order n removes a polynomial drift of degree n exactly,
    and from a record at rest at both ends gives the record back."""
    t = np.linspace(0, 1, 11)
    v, d = integrate(t, t.copy())
    assert np.allclose(v, t**2 / 2, atol=1e-15) and np.allclose(d, t**3 / 6, atol=1e-15)
    t = np.arange(0, 10, 0.01)
    drift = 0.05 - 0.004 * t  # a baseline of order 1: its displacement t^2, t^3 is in the fit's basis
    assert np.abs(baseline_correct(t, drift, 1)).max() < 1e-12
    assert np.abs(baseline_correct(t, 0.05 + 0 * t, 0)).max() < 1e-12
    a = np.sin(2 * np.pi * 1.3 * t) * np.exp(-0.3 * t) * np.sin(np.pi * t / 10) ** 2  # at rest at both ends
    ac = baseline_correct(t, a + drift, 1)
    assert np.abs(ac - a).max() < 2e-3 * np.abs(a).max()  # the record back, but for its own small drift
    assert np.array_equal(baseline_correct(t, a, -1), a)


def test_response_spectrum_closed_forms():
    """A step of ground acceleration a0 (linear between samples: exact in Nigam-Jennings): the
    oscillator's peak is SD = a0/w^2 (1 + exp(-z pi / sqrt(1 - z^2))); z = 0: 2 a0/w^2. Very
    stiff oscillators follow the ground: PSA -> PGA."""
    dt = 0.001
    t = np.arange(0, 20, dt)
    a0 = 2.0
    a = np.full_like(t, a0)
    a[0] = 0.0  # from rest, the step over the first sample
    periods = np.array([0.2, 0.5, 1.0])
    for z in (0.0, 0.05):
        s = response_spectrum(t, a, periods, damping=z)
        w = 2 * np.pi / periods
        expected = a0 / w**2 * (1 + np.exp(-z * np.pi / np.sqrt(1 - z * z)))
        assert np.allclose(s["SD"], expected, rtol=2e-3), (z, s["SD"] / expected)  # the ramp over one sample
    tt = np.arange(0, 5, 0.005)
    ag = np.sin(2 * np.pi * 1.0 * tt) * np.exp(-tt)
    s = response_spectrum(tt, ag, [0.01], damping=0.05)
    assert s["PSA"][0] == pytest.approx(np.abs(ag).max(), rel=2e-3)
    assert s["SA"][0] == pytest.approx(np.abs(ag).max(), rel=2e-3)


def test_rayleigh():
    """alpha/(2w) + beta w/2 is the damping ratio asked at both frequencies."""
    alpha, beta = rayleigh(2.0, 10.0, 0.05)
    for f in (2.0, 10.0):
        w = 2 * np.pi * f
        assert alpha / (2 * w) + beta * w / 2 == pytest.approx(0.05, rel=1e-12)
    alpha, beta = rayleigh(1.0, 5.0, 0.02, 0.06)
    assert alpha / (4 * np.pi) + beta * np.pi == pytest.approx(0.02, rel=1e-12)
    with pytest.raises(ValueError):
        rayleigh(1.0, 1.0)


def prep_errors(tmp_path, load, files=()):
    meshgen.box(str(tmp_path / "b.msh"), lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), cell="hex8")
    for name, text in files:
        (tmp_path / name).write_text(text)
    scene = {"meshes": {"m": "b.msh"},
             "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": 1e9, "density": 1}}},
             "dirichlet": [{"surface": "zmin"}], "loads": [load],
             "analysis": {"type": "dynamic", "dt": 0.01, "final_time": 0.1}}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(scene))
    return subprocess.run([PREP, str(tmp_path / "s.yaml"), "--check"], capture_output=True, text=True, env=env())


@pytest.mark.parametrize("load, files, message", [
    ({"kind": "ground_acceleration", "x": {"at2": "r.AT2"}}, [("r.AT2", AT2.replace("NPTS=    12", "NPTS=    20"))],
     r"loads\[0\]\.x: .*r\.AT2: the header says NPTS = 20"),
    ({"kind": "ground_acceleration", "x": {"at2": "missing.AT2"}}, [], r"loads\[0\]\.x: cannot read .*missing\.AT2"),
    ({"kind": "ground_acceleration", "y": {"csv": "m.csv", "column": 4}}, [("m.csv", "0,1,2\n0.01,3,4\n")],
     r"loads\[0\]\.y: .*m\.csv line 1: has 3 columns, the record is column 4"),
    ({"kind": "ground_acceleration", "z": {"csv": "m.csv", "dt": 0}}, [("m.csv", "1\n2\n")], r"loads\[0\]\.z\.dt: must be > 0"),
    ({"kind": "ground_acceleration"}, [], "at least one of x, y, z"),
    ({"kind": "ground_acceleration", "w": {"table": [[0, 0], [1, 1]]}}, [], r"loads\[0\]\.w: unknown key"),
    ({"kind": "ground_acceleration", "x": {"table": [[0, 0], [1, 1]]}, "baseline": "quartic"}, [], "unknown value 'quartic'"),
    ({"kind": "ground_acceleration", "x": {"table": [[0, 0], [1, 1]], "csv": "m.csv"}}, [], "give the record as one of"),
])
def test_prep_record_errors(tmp_path, load, files, message):
    """A bad record stops the prep with one line naming the key (and the file and line)."""
    r = prep_errors(tmp_path, load, files)
    assert r.returncode == 1 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert __import__("re").search(message, r.stderr), r.stderr
