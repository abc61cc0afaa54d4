"""Conditions and loads on nodes and lines, not only surfaces: Dirichlet conditions on scene node
sets (plane, sphere, box, their set operations), nodal forces on node sets and line forces on 1D
regions, against the exact uniaxial state; node-set inputs that select nothing or name nothing
refused. One to four hex8 cells: under a second each."""
import subprocess

import meshio
import numpy as np
import pytest
import yaml

from conftest import PREP, env, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body

E, NU, H = 1.0e3, 0.25, 2.0  # a 1 x 1 x 2 column


def column(tmp_path, lines=False):
    """The column as 1 x 2 hex8 cells, with (lines) its two top edges along y as the line region
    `top_edges`."""
    meshgen.box(str(tmp_path / "col.msh"), (0, 0, 0), (1, 1, H), n=(1, 1, 2), volume_name="col")
    if lines:
        m = meshio.read(str(tmp_path / "col.msh"))
        top = [i for i, x in enumerate(m.points) if abs(x[2] - H) < 1e-12]
        edge = lambda x0: sorted((i for i in top if abs(m.points[i][0] - x0) < 1e-12), key=lambda i: m.points[i][1])
        tag = max(int(v[0]) for v in m.field_data.values()) + 1
        m.cells.append(meshio.CellBlock("line", np.array([edge(0.0), edge(1.0)])))
        m.cell_data["gmsh:physical"].append(np.full(2, tag))
        m.cell_data["gmsh:geometrical"].append(np.full(2, tag))
        m.field_data["top_edges"] = np.array([tag, 1])
        meshio.write(str(tmp_path / "col.msh"), m, file_format="gmsh22", binary=False)
    return "col.msh"


SETS = {"bottom": {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}},
        "origin": {"sphere": {"centre": [0, 0, 0], "radius": 0.0}},
        "x_axis": {"box": {"lo": [0.5, -0.1, -0.1], "hi": [1.5, 0.1, 0.1]}},
        "top": {"plane": {"point": [0, 0, H], "normal": [0, 0, 1]}},
        "origin_column": {"box": {"lo": [-0.1, -0.1, 0], "hi": [0.1, 0.1, H]}},
        "top_not_corner": {"difference": ["top", "origin_column"]}}
SUPPORTS = [{"nodes": "bottom", "components": ["z"]}, {"nodes": "origin", "components": ["x", "y"]},
            {"nodes": "x_axis", "components": ["y"]}]


def assert_uniaxial(h5, stress):
    """sigma_zz = stress everywhere, the rest 0; u = (-nu x, -nu y, z) stress / E (the supports
    above hold only the rigid motions)."""
    r = read_body(result(h5, ".h5"), "col")
    x, u = r["vertices"], r["displacement"]
    exact = np.column_stack([-NU * x[:, 0], -NU * x[:, 1], x[:, 2]]) * stress / E
    assert np.abs(u - exact).max() < 1e-10 * abs(stress) / E * H
    assert np.abs(r["stress"][:, 5] - stress).max() < 1e-10 * abs(stress)
    assert np.abs(r["stress"][:, :5]).max() < 1e-10 * abs(stress)


@pytest.mark.parametrize("nproc", [1, 2])
def test_nodal_force_on_node_sets(tmp_path, nproc):
    """Supports on node sets only (the bottom plane in z, the origin node in x, y, the node at
    (1, 0, 0) in y: no rigid motion left, nothing else held) and 1/4 N down at each of the four top
    nodes (a node set, one through a set difference plus the node it takes out): the consistent
    nodal forces of 1 Pa on the 1 m2 top, so sigma_zz = -1 Pa exactly; the reactions CSV names each
    condition by its nodes, the bottom carrying the 1 N."""
    mesh = column(tmp_path)
    h5 = prep(tmp_path, {
        "meshes": {"m": mesh},
        "bodies": {"col": {"mesh": "m", "regions": "col", "material": {"E": E, "nu": NU}}},
        "node_sets": SETS | {"corner_top": {"intersection": ["top", "origin_column"]}},
        "dirichlet": SUPPORTS,
        "loads": [{"kind": "nodal_force", "nodes": "top_not_corner", "vector": [0, 0, -0.25]},
                  {"kind": "nodal_force", "nodes": "corner_top", "vector": [0, 0, -0.25]}],
        "analysis": {"type": "static"},
    })
    solve(h5, nproc=nproc)
    assert_uniaxial(h5, -1.0)
    rows = [l.split(",") for l in open(result(h5, "_reactions.csv")).read().splitlines()[1:]]
    named = {r[1]: np.array([float(v) for v in r[2:]]) for r in rows}
    assert set(named) == {"nodes:bottom", "nodes:origin", "nodes:x_axis"}  # each condition by its nodes
    assert abs(named["nodes:bottom"][2] - 1.0) < 1e-10 and np.abs(named["nodes:origin"]).max() < 1e-10


def test_line_force_on_line_region(tmp_path):
    """A line force of 1/2 N/m down along the two top edges (a 1D region of the mesh, 1 m each):
    half of each edge's 1/2 N at each of its ends, the same four 1/4 N as above: sigma_zz = -1 Pa."""
    mesh = column(tmp_path, lines=True)
    h5 = prep(tmp_path, {
        "meshes": {"m": mesh},
        "bodies": {"col": {"mesh": "m", "regions": "col", "material": {"E": E, "nu": NU}}},
        "node_sets": SETS,
        "dirichlet": SUPPORTS,
        "loads": [{"kind": "line_force", "line": "top_edges", "vector": [0, 0, -0.5]}],
        "analysis": {"type": "static"},
    })
    solve(h5)
    assert_uniaxial(h5, -1.0)


def bad(tmp_path, scene):
    yml = tmp_path / "bad.yaml"
    yml.write_text(yaml.safe_dump(scene))
    r = subprocess.run([PREP, str(yml), "-o", str(tmp_path / "bad.h5")], capture_output=True, text=True, env=env())
    assert r.returncode != 0 and "Traceback" not in r.stderr, r.stderr
    return r.stderr


def test_node_inputs_refused(tmp_path):
    """A node set that selects no node, a name that is no set, group or region, a line force on a
    surface, a Dirichlet condition with two places, a spring between two bodies: each refused,
    naming the key."""
    mesh = column(tmp_path)
    base = {"meshes": {"m": mesh}, "bodies": {"col": {"mesh": "m", "regions": "col", "material": {"E": E}}},
            "dirichlet": [{"surface": "zmin"}], "analysis": {"type": "static"}}
    assert "node_sets.far: selects no node" in bad(tmp_path, base | {
        "node_sets": {"far": {"sphere": {"centre": [9, 9, 9], "radius": 1}}},
        "loads": [{"kind": "nodal_force", "nodes": "far", "vector": [1, 0, 0]}]})
    err = bad(tmp_path, base | {"loads": [{"kind": "nodal_force", "nodes": "nowhere", "vector": [1, 0, 0]}]})
    assert "loads[0].nodes" in err and "'nowhere'" in err
    err = bad(tmp_path, base | {"loads": [{"kind": "line_force", "line": "zmax", "vector": [1, 0, 0]}]})
    assert "loads[0].line" in err and "2D" in err
    err = bad(tmp_path, base | {"dirichlet": [{"surface": "zmin", "nodes": "zmin"}]})
    assert "dirichlet[0]: give one of surface, nodes or body" in err
    err = bad(tmp_path, base | {"springs": [{"nodes": "zmax", "stiffness": [-1, 0, 0]}]})
    assert "springs[0].stiffness[0]" in err
