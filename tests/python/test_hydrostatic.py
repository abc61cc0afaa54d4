"""Hydrostatic pressure p = unit_weight (level - z) below the level (docs/scene.md): the
resultant force and moment of the assembled load (printed by -mbc_view) against the analytic
values, on vertical, inclined and distorted faces, hex8 and tet4, with the water level cutting
faces, and on two ranks. Also the CSV time table."""
import re

import h5py
import numpy as np
import pytest

from conftest import prep, solve
from mbcontact import meshgen

GAMMA, LEVEL = 9810.0, 3.0  # N/m3, m; the box is 2 x 3 x 4 m, 5 layers of 0.8 m: the level cuts a face


def resultants(stdout):
    """{load index: (F (3,), M (3,))} from the -mbc_view lines."""
    out = {}
    for m in re.finditer(r"load (\d+) \((\w+)\): resultant (\S+) (\S+) (\S+), moment about the origin (\S+) (\S+) (\S+)", stdout):
        v = np.array([float(x) for x in m.groups()[2:]])
        out[int(m.group(1))] = (v[:3], v[3:])
    return out


def box_scene(tmp_path, cell, shear=0.0, face_perturb=None, loads=None):
    part = meshgen.box_part("b", (0, 0, 0), (2, 3, 4), n=(2, 3, 5), cell=cell, face_perturb=face_perturb, seed=4)
    part.points[:, 0] += shear * part.points[:, 2]  # xmin becomes the plane x = shear z
    meshgen.write_parts(str(tmp_path / "box.msh"), [part])
    return {"meshes": {"m": "box.msh"},
            "bodies": {"b": {"mesh": "m", "regions": "b", "material": {"E": 1e9, "nu": 0.2}}},
            "dirichlet": [{"surface": "b_zmin"}],
            "loads": loads or [{"kind": "hydrostatic", "surface": "b_xmin", "level": LEVEL, "unit_weight": GAMMA}]}


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_vertical_face(tmp_path, cell):
    """Vertical face x = 0, 3 m wide, water 3 m deep over a 4 m face (the level cuts the layer
    2.4-3.2 m): F_x = gamma b h^2 / 2 at h/3 above the base, in the middle of the width, so
    M = (0, F z_bar, -F y_bar) with z_bar = 1, y_bar = 1.5. Exact quadrature: 1e-12. The opposite
    face (xmax, wet too) gets the opposite force: the load is against each face's outward normal."""
    loads = [{"kind": "hydrostatic", "surface": "b_xmin", "level": LEVEL, "unit_weight": GAMMA},
             {"kind": "hydrostatic", "surface": "b_xmax", "level": LEVEL, "unit_weight": GAMMA, "axis": "z",
              "time": "sudden"}]
    h5 = prep(tmp_path, box_scene(tmp_path, cell, loads=loads))
    r = resultants(solve(h5, "-mbc_view").stdout)
    F = GAMMA * 3.0 * LEVEL**2 / 2
    F0, M0 = r[0]
    assert np.allclose(F0, [F, 0, 0], rtol=0, atol=1e-12 * F)
    assert np.allclose(M0, [0, F * LEVEL / 3, -F * 1.5], rtol=0, atol=1e-12 * F)
    F1, M1 = r[1]  # x = 2: the same force pushing in -x; moment about the origin (2, y, z) x F
    assert np.allclose(F1, [-F, 0, 0], rtol=0, atol=1e-12 * F)
    assert np.allclose(M1, [0, -F * LEVEL / 3, F * 1.5], rtol=0, atol=1e-12 * F)


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_inclined_face(tmp_path, cell):
    """Upstream face inclined (x = 0.5 z): the water above it pushes down as well. With
    dF = gamma (3 - z) (1, 0, -0.5) dy dz over y in [0, 3], z in [0, 3]:
    F = gamma 13.5 (1, 0, -0.5), M = int r x dF = gamma (-10.125, 16.875, -20.25)."""
    h5 = prep(tmp_path, box_scene(tmp_path, cell, shear=0.5))
    F, M = resultants(solve(h5, "-mbc_view").stdout)[0]
    assert np.allclose(F, GAMMA * 13.5 * np.array([1, 0, -0.5]), rtol=0, atol=1e-12 * GAMMA * 13.5)
    assert np.allclose(M, GAMMA * np.array([-10.125, 16.875, -20.25]), rtol=0, atol=1e-12 * GAMMA * 20)


def test_distorted_face_two_ranks(tmp_path):
    """The face's vertices moved in its plane (quads no longer parallelograms, the level's trace
    curved in their reference square): the resultant is still the vertical face's, to the
    accuracy of 4 x 2 Gauss points on each wet piece (observed 3e-9, asserted 1e-7); two ranks
    (the body split) give the same numbers to rounding."""
    h5 = prep(tmp_path, box_scene(tmp_path, "hex8", face_perturb={"xmin": (0.2, 0.0)}))
    F, M = resultants(solve(h5, "-mbc_view").stdout)[0]
    Fx = GAMMA * 3.0 * LEVEL**2 / 2
    assert np.allclose(F, [Fx, 0, 0], rtol=0, atol=1e-7 * Fx)
    assert np.allclose(M, [0, Fx * LEVEL / 3, -Fx * 1.5], rtol=0, atol=1e-7 * Fx)
    F2, M2 = resultants(solve(h5, "-mbc_view", nproc=2).stdout)[0]
    assert np.allclose(F2, F, rtol=1e-12, atol=1e-9) and np.allclose(M2, M, rtol=1e-12, atol=1e-9)


def test_dry_and_time_csv(tmp_path):
    """A level below the face loads nothing; a level above the top loads the whole face; a CSV
    time table (`time: {csv: FILE, shift: s}`, comments and a header line skipped) reaches the
    scene file as the shifted table."""
    (tmp_path / "ramp.csv").write_text("# a ramp\nt,factor\n0.5, 0\n1.5, 1\n")
    loads = [{"kind": "hydrostatic", "surface": "b_xmin", "level": -1.0, "unit_weight": GAMMA},
             {"kind": "hydrostatic", "surface": "b_xmax", "level": 10.0, "unit_weight": GAMMA,
              "time": {"csv": "ramp.csv", "shift": -0.5}}]
    h5 = prep(tmp_path, box_scene(tmp_path, "hex8", loads=loads))
    r = resultants(solve(h5, "-mbc_view").stdout)
    assert np.all(r[0][0] == 0)
    # full load: gamma * 3 * (10 * 4 - 4^2 / 2) = gamma * 96, pushing -x
    assert abs(r[1][0][0] / (-GAMMA * 96) - 1) < 1e-12
    with h5py.File(h5, "r") as f:
        assert np.allclose(f["mbcontact/time_functions/0/table"][()], [[0, 0], [1, 1]])
