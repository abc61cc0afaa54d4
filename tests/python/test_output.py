"""The result file <output>.h5, written collectively by all ranks: the same datasets at any rank
count (each body's vertices and cells in the scene's order, the order mbcontact-prep wrote; fields
to rounding), and an XDMF index whose every reference is a dataset of that file with its shape and
type. This process reads with h5py; the solver (PETSc, MPI HDF5) runs in its own processes."""
import os
import re
import subprocess
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from conftest import load_script, prep, solve
from mbcontact import meshgen
from mbcontact.bodies import build_bodies, read_mesh
from mbcontact.cells import min_corner_volume
from mbcontact.results import body_names, read_body, read_contact
from mbcontact.scene import load_yaml, parse_scene

blocks = load_script("meshes/blocks/build.py", "blocks_build_output")
RANKS = (1, 2, 4)


def datasets(path):
    """Every dataset of an HDF5 file by path, as numpy arrays."""
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda name, obj: out.__setitem__(name, obj[...]) if isinstance(obj, h5py.Dataset) else None)
    return out


def prep_bodies(yml):
    """The bodies as mbcontact-prep builds them (vertices and Gmsh/XDMF-order cells), without
    PETSc: the scene order the result file must follow."""
    scene = parse_scene(load_yaml(str(yml)), os.path.dirname(str(yml)))
    meshes = {name: read_mesh(name, path) for name, path in scene.meshes.items()}
    return {b.name: b for b in build_bodies(scene, meshes)}


def spans(view):
    """Number of ranks of each body, from the -mbc_view output."""
    return {m[0]: int(m[2]) - int(m[1]) + 1 for m in re.findall(r"body (\w+): ranks (\d+)-(\d+)", view)}


def run_ranks(tmp_path, h5, *options):
    """Solves at 1, 2 and 4 ranks; returns {ranks: (result file, -mbc_view output)}."""
    runs = {}
    for n in RANKS:
        out = tmp_path / f"np{n}"
        r = solve(h5, "-mbc_output", str(out), "-mbc_view", *options, nproc=n)
        runs[n] = (str(out) + ".h5", r.stdout)
    return runs


# scale of the comparison of each dataset: its own largest value, or a related one where the
# dataset itself is (near) zero: tangential tractions against the pressure, slips and gaps
# against the displacements
SCALE_OF = {"traction": "pressure", "slip": "displacement", "gap": "displacement", "multiplier": "force"}


def assert_same_files(runs, exact=("vertices", "cells", "couple", "state", "reference", "time")):
    """Every dataset of every run equals the 1-rank one: integers and reference geometry exactly,
    computed values to 1e-9 of their scale."""
    ref = datasets(runs[1][0])
    umax = max(np.abs(v).max() for k, v in ref.items() if k.endswith("displacement"))
    for n in RANKS[1:]:
        other = datasets(runs[n][0])
        assert sorted(other) == sorted(ref), (n, set(other) ^ set(ref))
        for name, a in ref.items():
            b, leaf = other[name], name.split("/")[-1]
            assert a.shape == b.shape and a.dtype == b.dtype, (n, name)
            if leaf in exact:
                assert np.array_equal(a, b), (n, name)
                continue
            if leaf in ("slip", "gap", "displacement"):
                scale = umax
            elif leaf in SCALE_OF:
                scale = np.abs(ref[name.replace(leaf, SCALE_OF[leaf])]).max()
            else:
                scale = np.abs(a).max() if a.size else 0
            finite = np.isfinite(a)
            assert np.array_equal(finite, np.isfinite(b)), (n, name)  # NaN slips of frictionless couples
            err = np.abs(a[finite] - b[finite]).max() if finite.any() else 0
            assert err <= 1e-9 * scale, (n, name, err, scale)


def assert_scene_order(path, bodies):
    """Vertices and cells exactly as mbcontact-prep wrote them; cells positively oriented in the
    XDMF (VTK) vertex order, so ParaView sees valid cells."""
    assert body_names(path) == list(bodies)
    for name, b in bodies.items():
        r = read_body(path, name)
        assert np.array_equal(r["vertices"], b.coords), name
        assert np.array_equal(r["cells"], b.cells), name
        assert r["cell_type"] == b.cell_type
        assert min_corner_volume(b.cell_type, r["vertices"], r["cells"]).min() > 0, name


@pytest.fixture(scope="module")
def two_blocks(tmp_path_factory):
    """The paper's two blocks (contact, friction), 3 Newmark steps, every field at every step, at
    1, 2 (a block per rank) and 4 ranks (each block on two)."""
    tmp_path = tmp_path_factory.mktemp("blocks")
    meshgen.boxes(str(tmp_path / "blocks.msh"),
                  [dict(lo=(0, 0, 0), hi=(100, 100, 100), n=(10, 10, 10), cell="hex8", name="block1"),
                   dict(lo=(0, 0, 100), hi=(100, 100, 200), n=(20, 20, 10), cell="hex8", name="block2")])
    scene = blocks.scene(0.01, 0.03)
    scene["output"].update({"every": 1, "fields": ["displacement", "stress"]})
    h5 = prep(tmp_path, scene, name="blocks")
    runs = run_ranks(tmp_path, h5, "-mbc_multiplier_rtol", "1e-12")
    assert spans(runs[2][1]) == {"block1": 1, "block2": 1} and max(spans(runs[4][1]).values()) > 1, runs[4][1]
    return tmp_path, runs


def test_two_blocks_same_file_at_1_2_4_ranks(two_blocks):
    tmp_path, runs = two_blocks
    assert_same_files(runs)
    assert_scene_order(runs[1][0], prep_bodies(tmp_path / "blocks.yaml"))
    # one result file per run, no per-body or contact HDF5 files
    assert sorted(p.name for p in tmp_path.glob("np*.h5")) == [f"np{n}.h5" for n in RANKS]
    r = read_body(runs[4][0], "block2")
    assert r["num_steps"] == 4 and abs(r["time"] - 0.03) < 1e-12
    assert r["displacement"][:, 2].min() < -1e-5  # block 2 sinks under its body force
    c = read_contact(runs[4][0])
    assert len(c["pressure"]) == 441 and np.all(c["couple"] == 1) and c["pressure"].max() > 0


def test_bodies_sharing_and_spanning_ranks(tmp_path):
    """Three columns under self-weight, static, two load steps: at 2 ranks the two small ones
    share a rank, at 4 the large one (a perturbed tet4 mesh) spans two; the file is the same."""
    L = 10.0
    meshgen.boxes(str(tmp_path / "three.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, L), n=(3, 3, 24), cell="tet4", name="big", perturb=0.2, seed=3),
                   dict(lo=(3, 0, 0), hi=(4, 1, L), n=(1, 1, 6), cell="hex8", name="s1"),
                   dict(lo=(6, 0, 0), hi=(7, 1, L), n=(1, 1, 6), cell="tet4", name="s2")])
    scene = {
        "meshes": {"m": "three.msh"},
        "bodies": {n: {"mesh": "m", "regions": [n], "material": {"E": 30e9, "nu": 0.2, "density": 2500.0}} for n in ("big", "s1", "s2")},
        "dirichlet": [{"surface": f"{n}_zmin", "components": "all"} for n in ("big", "s1", "s2")],
        "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
        "analysis": {"type": "static", "dt": 0.5, "final_time": 1.0},
        "output": {"every": 1, "fields": ["displacement", "stress"]},
    }
    h5 = prep(tmp_path, scene, name="three")
    runs = run_ranks(tmp_path, h5)
    assert re.findall(r"body s1: ranks (\d+-\d+)", runs[2][1]) == re.findall(r"body s2: ranks (\d+-\d+)", runs[2][1]), runs[2][1]
    assert spans(runs[4][1])["big"] > 1, runs[4][1]
    assert_same_files(runs)
    assert_scene_order(runs[1][0], prep_bodies(tmp_path / "three.yaml"))
    with h5py.File(runs[4][0], "r") as f:
        assert "contact" not in f and list(f["time"][...]) == [0.5, 1.0]


def test_xdmf_references_datasets_of_the_file(two_blocks):
    """Each run's XDMF: a temporal collection of spatial collections (the two blocks and the
    contact points) at the file's output times, every HDF item a dataset of the one result file
    with the item's dimensions and number type, topologies as large as the cells datasets."""
    tmp_path, runs = two_blocks
    for n, (path, _) in runs.items():
        xmf = path[:-3] + ".xmf"
        root = ET.parse(xmf).getroot()
        top = root.find("Domain/Grid")
        assert top.get("CollectionType") == "Temporal"
        steps = top.findall("Grid")
        with h5py.File(path, "r") as f:
            times = f["time"][...]
            assert [float(g.find("Time").get("Value")) for g in steps] == list(times)
            for g in steps:
                assert g.get("CollectionType") == "Spatial"
                assert [c.get("Name") for c in g.findall("Grid")] == ["block1", "block2", "contact"]
            items = [d for d in root.iter("DataItem") if d.get("Format") == "HDF"]
            assert len(items) == len(steps) * (2 * 4 + 8)
            for d in items:
                fname, dset = d.text.strip().split(":")
                assert fname == os.path.basename(path), d.text
                assert dset in f, d.text
                assert list(f[dset].shape) == [int(v) for v in d.get("Dimensions").split()], d.text
                kind = {"Float": "f", "Int": "i"}[d.get("NumberType")]
                assert f[dset].dtype.kind == kind and f[dset].dtype.itemsize == int(d.get("Precision")), d.text
            for grid in root.iter("Grid"):
                topo = grid.find("Topology")
                if topo is not None and topo.get("TopologyType") == "Hexahedron":
                    cells = f[topo.find("DataItem").text.split(":")[1]]
                    assert int(topo.get("NumberOfElements")) == cells.shape[0] and cells.shape[1] == 8
                    for a in grid.findall("Attribute"):
                        rows = f[a.find("DataItem").text.split(":")[1]].shape[0]
                        assert rows == (cells.shape[0] if a.get("Center") == "Cell" else f[grid.find("Geometry/DataItem").text.split(":")[1]].shape[0])


# XDMF's Tensor6 (xx xy xz yy yz zz) as the full 3x3 tensor, row-major: the expansion of
# vtkXdmfHeavyData (vtkConvertTensor6), the reader ParaView uses.
TENSOR6_TO_3X3 = [0, 1, 2, 1, 3, 4, 2, 4, 5]


def xdmf_cell_tensors(xmf, grid_name, attribute):
    """The cellwise Tensor6 attribute of a grid of the .xmf's last step, read as an XDMF reader
    does: the DataItem's HDF reference resolved relative to the .xmf, expanded to (nc, 3, 3) the
    way vtkXdmfReader does. vtkXdmfReader itself reads it in test_xdmf_read_by_vtkxdmfreader,
    from PyPI's vtk in a venv: Debian 12's python3-vtk9 (9.1) is built without vtkIOXdmf2/3,
    python3-paraview (which has it) replaces python3-vtk9, and python3-xdmf fails to import
    (undefined symbol XdmfUnstructuredGridCast)."""
    root = ET.parse(xmf).getroot()
    grid = [g for g in root.find("Domain/Grid").findall("Grid")][-1]
    grid = [g for g in grid.findall("Grid") if g.get("Name") == grid_name][0]
    attr = [a for a in grid.findall("Attribute") if a.get("Name") == attribute][0]
    assert attr.get("AttributeType") == "Tensor6" and attr.get("Center") == "Cell"
    item = attr.find("DataItem")
    fname, dset = item.text.strip().split(":")
    with h5py.File(os.path.join(os.path.dirname(str(xmf)), fname), "r") as f:
        values = f[dset][...].reshape([int(v) for v in item.get("Dimensions").split()])
    return values[:, TENSOR6_TO_3X3].reshape(-1, 3, 3)


def test_xdmf_stress_is_tensor6_in_xdmf_order(tmp_path):
    """A column 1 x 1 x 10 m (hex8 1x1x8, nu = 0, rho 2500, base fixed) under self-weight, static:
    sigma_zz = -rho g (h - z) is linear, so exact at the centroids of the hex cells, and every other
    component is 0 (nu = 0: no lateral stress even at the fixed base). Read through the .xmf as
    ParaView reads it (xdmf_cell_tensors), ZZ must be -rho g (h - z_c) and the rest 0 to 1e-8 rho g h (rounding of a
    direct solve); with the Voigt order the file used to hold, ZZ showed the xz shear (0) and the
    weight showed up as XZ. read_body gives the same array in the same order."""
    L, rho, g = 10.0, 2500.0, 9.81
    meshgen.box(str(tmp_path / "column.msh"), (0, 0, 0), (1, 1, L), n=(1, 1, 8), cell="hex8", volume_name="column")
    scene = {"meshes": {"m": "column.msh"},
             "bodies": {"column": {"mesh": "m", "regions": "column", "material": {"E": 30e9, "nu": 0.0, "density": rho}}},
             "dirichlet": [{"surface": "zmin"}], "loads": [{"kind": "gravity", "vector": [0, 0, -g]}],
             "output": {"fields": ["displacement", "stress"]}}
    h5 = prep(tmp_path, scene, name="column")
    solve(h5)
    sigma = xdmf_cell_tensors(str(h5)[:-3] + "_result.xmf", "column", "stress")
    r = read_body(str(h5)[:-3] + "_result.h5", "column")
    zc = r["vertices"][r["cells"]][:, :, 2].mean(axis=1)
    exact = np.zeros_like(sigma)
    exact[:, 2, 2] = -rho * g * (L - zc)
    assert len(sigma) == 8
    assert np.abs(sigma - exact).max() < 1e-8 * rho * g * L, sigma[0]
    assert np.abs(r["stress"][:, TENSOR6_TO_3X3].reshape(-1, 3, 3) - exact).max() < 1e-8 * rho * g * L


def vtk_python():
    """A Python with PyPI's vtk (vtkXdmfReader): $MBC_VTK_PYTHON, else the venv `make test`
    makes in the build directory (<build>/venv-vtk)."""
    from conftest import BUILD
    py = os.environ.get("MBC_VTK_PYTHON", os.path.join(BUILD, "venv-vtk", "bin", "python"))
    return py if os.path.exists(py) else None


@pytest.mark.skipif(vtk_python() is None, reason="no Python with vtk's vtkXdmfReader (make test makes <build>/venv-vtk)")
def test_xdmf_read_by_vtkxdmfreader(tmp_path):
    """The column under self-weight read through its .xmf by VTK's own vtkXdmfReader (what ParaView
    opens .xmf with), not by our reading of the format: the last time step is t = 1, the body's
    block has 8 cells and 36 points, the stress is the 9-component tensor VTK makes of Tensor6 with
    ZZ = -rho g (h - z) at every cell centre and every other component 0 (to 1e-8 rho g h), and
    the displacement of the top points is the exact -rho g h^2 / (2 E)."""
    import json
    L, rho, g, E = 10.0, 2500.0, 9.81, 30e9
    meshgen.box(str(tmp_path / "column.msh"), (0, 0, 0), (1, 1, L), n=(1, 1, 8), cell="hex8", volume_name="column")
    scene = {"meshes": {"m": "column.msh"},
             "bodies": {"column": {"mesh": "m", "regions": "column", "material": {"E": E, "nu": 0.0, "density": rho}}},
             "dirichlet": [{"surface": "zmin"}], "loads": [{"kind": "gravity", "vector": [0, 0, -g]}],
             "output": {"fields": ["displacement", "stress"]}}
    h5 = prep(tmp_path, scene, name="column")
    solve(h5)
    e = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    r = subprocess.run([vtk_python(), os.path.join(os.path.dirname(__file__), "vtk_read_xdmf.py"), str(h5)[:-3] + "_result.xmf"],
                       capture_output=True, text=True, env=e, timeout=120)
    assert r.returncode == 0, r.stderr
    d = json.loads(r.stdout)
    assert d["times"][-1] == 1.0
    b = d["blocks"]["column"]
    assert b["cells"] == 8 and b["points"] == 36
    sigma = np.array(b["arrays"]["cell:stress"]).reshape(-1, 3, 3)
    zc = np.array(b["centres"])[:, 2]
    exact = np.zeros_like(sigma)
    exact[:, 2, 2] = -rho * g * (L - zc)
    assert np.abs(sigma - exact).max() < 1e-8 * rho * g * L, sigma[0]
    u = np.array(b["arrays"]["point:displacement"])
    # the points' coordinates are not in the JSON: the top (z = L) has the largest settlement
    assert abs(u[:, 2].min() / (-rho * g * L**2 / (2 * E)) - 1) < 1e-8
