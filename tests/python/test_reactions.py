"""Reactions at prescribed surfaces (<output>_reactions.csv) against the loads they balance."""
import numpy as np
import pytest

from conftest import prep, solve
from mbcontact import meshgen

E, RHO, G, L = 30e9, 2500.0, 9.81, 10.0  # a concrete column, 1 m x 1 m x 10 m
WEIGHT = RHO * G * L


def column(tmp_path, cell, fixed, analysis):
    meshgen.box(tmp_path / "col.msh", (0, 0, 0), (1, 1, L), n=(1, 1, 10), cell=cell, volume_name="col")
    return prep(tmp_path, {
        "meshes": {"m": "col.msh"},
        "bodies": {"col": {"mesh": "m", "regions": ["col"], "material": {"E": E, "nu": 0.0, "density": RHO}}},
        "dirichlet": [{"surface": s, "components": "all"} for s in fixed],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G]}],
        "analysis": analysis,
        "output": {"every": 100, "fields": []},
    })


def reactions(out):
    """{surface: array of (t, fx, fy, fz)}."""
    rows = [l.split(",") for l in open(f"{out}_reactions.csv").read().splitlines()]
    assert rows[0] == ["t", "surface", "fx", "fy", "fz"]
    by = {}
    for r in rows[1:]:
        by.setdefault(r[1], []).append([float(r[0])] + [float(v) for v in r[2:]])
    return {k: np.array(v) for k, v in by.items()}


@pytest.mark.parametrize("cell,nproc", [("hex8", 1), ("tet4", 1), ("hex8", 2)])
def test_self_weight_on_a_fixed_base(tmp_path, cell, nproc):
    """Static, base fixed: the base carries the weight rho g V upwards, nothing sideways.
    Exact equilibrium of the discrete system: to roundoff (1e-10 of the weight)."""
    h5 = column(tmp_path, cell, ["zmin"], {"type": "static"})
    solve(h5, "-mbc_output", str(tmp_path / "r"), nproc=nproc)
    r = reactions(tmp_path / "r")
    assert list(r) == ["zmin"] and len(r["zmin"]) == 1
    assert np.allclose(r["zmin"][0, 1:], [0, 0, WEIGHT], rtol=0, atol=1e-10 * WEIGHT), r


def test_fixed_fixed_column_halves(tmp_path):
    """Both ends fixed (nu = 0): by symmetry each end carries half the weight."""
    h5 = column(tmp_path, "hex8", ["zmin", "zmax"], {"type": "static"})
    solve(h5, "-mbc_output", str(tmp_path / "r"))
    r = reactions(tmp_path / "r")
    for s in ("zmin", "zmax"):
        assert np.allclose(r[s][0, 1:], [0, 0, WEIGHT / 2], rtol=0, atol=1e-10 * WEIGHT), r


def test_dynamic_at_rest_carries_the_weight(tmp_path):
    """Dynamic from the static state under constant gravity: the column stays at rest and the
    base reaction (K u + M a + C v - F) is the weight at every step."""
    h5 = column(tmp_path, "hex8", ["zmin"], {"type": "dynamic", "dt": 1e-3, "final_time": 0.02})
    solve(h5, "-mbc_output", str(tmp_path / "r"))
    r = reactions(tmp_path / "r")["zmin"]
    assert len(r) == 21 and abs(r[-1, 0] - 0.02) < 1e-12
    assert np.allclose(r[:, 1:], [0, 0, WEIGHT], rtol=0, atol=1e-8 * WEIGHT), r
