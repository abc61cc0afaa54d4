"""Tests of mbcontact-prep and the mesh generators.

    cd /work/main && PYTHONPATH=python /usr/bin/python3 -m pytest -q tests/python/test_prep.py

This process uses h5py; everything touching petsc4py runs in a subprocess
(their HDF5 libraries must not share a process).
"""
import copy
import json
import subprocess
import textwrap
from pathlib import Path

import h5py
import meshio
import numpy as np
import pytest
import yaml

from mbcontact import meshgen
from mbcontact.cells import min_corner_volume
from mbcontact.prep import main

ROOT = Path(__file__).resolve().parents[2]
PREP = ROOT / "python" / "mbcontact-prep"
PYTHON = "/usr/bin/python3"

# Two independent boxes: b1 (hex, 3x3x2) below b2 (tet, 2x2x2, distorted).
N1, N2 = (3, 3, 2), (2, 2, 2)
BOXES = [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=N1, cell="hex8", name="b1"),
         dict(lo=(0, 0, 1), hi=(1, 1, 2), n=N2, cell="tet4", name="b2", perturb=0.15, seed=3)]


def base_scene():
    return {
        "title": "two blocks",
        "meshes": {"main": "blocks.msh"},
        "bodies": {
            "block1": {"mesh": "main", "regions": ["b1"],
                       "material": {"E": 1.0e10, "nu": 0.25, "density": 10.0, "damping": 200.0}},
            "block2": {"mesh": "main", "regions": "b2",
                       "material": {"E": 2.0e9, "density": 5.0, "rayleigh_beta": 0.01}},
        },
        "couples": [{"master": ["b1_zmax"], "slave": "b2_zmin", "mu": 0.6}],
        "dirichlet": [
            {"surface": "b1_zmin", "components": ["z"], "value": 0.0},
            {"surface": "b1_xmin", "components": "all", "value": 1.0e-3,
             "time": {"table": [[0, 0], [1, 1]]}},
        ],
        "loads": [
            {"kind": "gravity", "vector": [0, 0, -9.81], "time": "sudden", "bodies": ["block2"]},
            {"kind": "body_force", "vector": [0, 0, -100.0]},
            {"kind": "pressure", "surface": "b2_xmax", "value": 1.0e5},
            {"kind": "traction", "surface": "b2_zmax", "vector": [0, 0, -1.0e3],
             "time": {"table": [[0, 0], [0.5, 1], [3, 1]]}},
        ],
        "analysis": {"type": "dynamic", "dt": 0.01, "final_time": 3.0,
                     "newmark": {"beta": 0.3025, "gamma": 0.6}, "mass": "lumped"},
        "output": {"every": 10, "fields": ["displacement"], "energy": True,
                   "points": {"top": [0.5, 0.5, 2.0], "mid": {"x": [0.5, 0.5, 1.0], "body": "block2"}}},
    }


@pytest.fixture
def case(tmp_path):
    """Folder with the two-box mesh; case(scene) writes scene.yaml and runs the prep."""
    meshgen.boxes(tmp_path / "blocks.msh", BOXES)

    def run(scene, text=None, extra=()):
        (tmp_path / "scene.yaml").write_text(text if text is not None else yaml.safe_dump(scene, sort_keys=False))
        return run_main([str(tmp_path / "scene.yaml"), "-o", str(tmp_path / "scene.h5"), *extra])

    run.dir = tmp_path
    return run


def run_main(argv):
    """Run prep.main in-process; return (exit status, stdout, stderr)."""
    import contextlib
    import io
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def text(value):
    return value.decode() if isinstance(value, bytes) else value


def read_list(group):
    return [{k: text(v) for k, v in group[str(i)].attrs.items()} for i in range(group.attrs["count"])]


# ---------------------------------------------------------------- mesh generators

@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_box_regions_and_orientation(tmp_path, cell):
    path = tmp_path / "box.msh"
    meshgen.box(path, (0, 0, 0), (2, 1, 1), n=(4, 3, 2), cell=cell, volume_name="solid", perturb=0.2)
    mesh = meshio.read(path)
    assert set(mesh.field_data) == {"solid", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}
    volume = "hexahedron" if cell == "hex8" else "tetra"
    cells = np.concatenate([b.data for b in mesh.cells if b.type == volume])
    assert len(cells) == 24 * (1 if cell == "hex8" else 6)
    assert np.all(min_corner_volume(cell, mesh.points, cells) > 0)
    faces_per_square = 1 if cell == "hex8" else 2
    tags = np.concatenate(mesh.cell_data["gmsh:physical"])
    assert np.count_nonzero(tags == mesh.field_data["zmin"][0]) == 4 * 3 * faces_per_square
    assert np.count_nonzero(tags == mesh.field_data["xmax"][0]) == 3 * 2 * faces_per_square


def test_tets_stay_in_z_layers(tmp_path):
    meshgen.box(tmp_path / "t.msh", (0, 0, 0), (1, 1, 1), n=(2, 2, 4), cell="tet4")
    mesh = meshio.read(tmp_path / "t.msh")
    z = mesh.points[mesh.cells_dict["tetra"]][:, :, 2]
    assert np.allclose(z.max(axis=1) - z.min(axis=1), 0.25)


def test_boxes_are_independent_bodies(tmp_path):
    meshgen.boxes(tmp_path / "two.msh", BOXES)
    mesh = meshio.read(tmp_path / "two.msh")
    assert {"b1", "b2", "b1_zmax", "b2_zmin"} <= set(mesh.field_data)
    assert len(mesh.points) == np.prod(np.add(N1, 1)) + np.prod(np.add(N2, 1))


# ---------------------------------------------------------------- round trip

def test_two_box_scene_metadata(case):
    status, out, err = case(base_scene())
    assert status == 0 and err == "", err
    assert "body block2: 48 tet4 cells" in out
    with h5py.File(case.dir / "scene.h5", "r") as f:
        root = f["mbcontact"]
        assert root.attrs["format_version"] == 1 and text(root.attrs["title"]) == "two blocks"
        assert isinstance(root.attrs["title"], bytes)  # fixed-length ASCII string

        b1, b2 = read_list(root["bodies"])
        assert b1 == dict(name="block1", cell_type="hex8", num_cells=18, num_vertices=48, E=1.0e10,
                          nu=0.25, density=10.0, damping=200.0, rayleigh_alpha=0.0, rayleigh_beta=0.0)
        assert (b2["cell_type"], b2["num_cells"], b2["num_vertices"], b2["nu"], b2["rayleigh_beta"]) \
            == ("tet4", 6 * 8, 27, 0.0, 0.01)
        assert root["bodies/0"].attrs["num_cells"].dtype == np.int32

        surfaces = read_list(root["surfaces"])
        # ids in order of first appearance: couples, then dirichlet, then loads
        assert [(s["name"], s["id"], s["num_faces"]) for s in surfaces] == [
            ("b1_zmax", 1, 9), ("b2_zmin", 2, 2 * 4), ("b1_zmin", 3, 9), ("b1_xmin", 4, 3 * 2),
            ("b2_xmax", 5, 2 * 4), ("b2_zmax", 6, 2 * 4)]

        couples = read_list(root["couples"])
        # per body, its faces on each side: 3x3 master faces on b1, 2x4 slave faces on b2
        assert [list(couples[0].pop(k)) for k in ("master_faces", "slave_faces")] == [[9, 0], [0, 8]]
        assert couples == [dict(k=1, mu=0.6, master="b1_zmax", slave="b2_zmin")]

        dirichlet = read_list(root["dirichlet"])
        assert [(d["surface"], d["surface_id"], d["component"], d["time"], d["time_function"])
                for d in dirichlet] == [("b1_zmin", 3, 2, "constant", -1)] + \
            [("b1_xmin", 4, c, "table", 0) for c in range(3)]
        assert dirichlet[1]["value"] == 1.0e-3

        loads = read_list(root["loads"])
        assert [(l["kind"], l["surface_id"], l["bodies"], l["time"], l["time_function"]) for l in loads] == [
            ("gravity", -1, "block2", "sudden", -1), ("body_force", -1, "", "constant", -1),
            ("pressure", 5, "", "constant", -1), ("traction", 6, "", "table", 1)]
        assert np.array_equal(loads[0]["vector"], [0, 0, -9.81]) and loads[0]["vector"].dtype == np.float64
        assert loads[2]["value"] == 1.0e5 and np.array_equal(loads[2]["vector"], [0, 0, 0])

        tables = root["time_functions"]
        assert tables.attrs["count"] == 2 and text(tables["0"].attrs["kind"]) == "table"
        assert np.array_equal(tables["1/table"][()], [[0, 0], [0.5, 1], [3, 1]])

        analysis = {k: text(v) for k, v in root["analysis"].attrs.items()}
        assert analysis == dict(type="dynamic", dt=0.01, final_time=3.0, newmark_beta=0.3025,
                                newmark_gamma=0.6, mass="lumped")

        output = root["output"]
        assert (output.attrs["every"], text(output.attrs["fields"]), output.attrs["energy"],
                output.attrs["points_count"]) == (10, "displacement", 1, 2)
        points = read_list(output["points"])
        assert [(p["name"], list(p["x"]), p["body"]) for p in points] == [
            ("top", [0.5, 0.5, 2.0], ""), ("mid", [0.5, 0.5, 1.0], "block2")]
        assert set(f["topologies"]) == {"block1", "block2"}


def test_defaults(case):
    scene = base_scene()
    for key in ("couples", "dirichlet", "loads", "analysis", "output"):
        del scene[key]
    scene["bodies"]["block1"]["material"] = {"E": 1}
    status, _, err = case(scene)
    assert status == 0, err
    with h5py.File(case.dir / "scene.h5", "r") as f:
        root = f["mbcontact"]
        analysis = {k: text(v) for k, v in root["analysis"].attrs.items()}
        assert analysis == dict(type="static", dt=1.0, final_time=1.0, newmark_beta=0.25,
                                newmark_gamma=0.5, mass="consistent")
        output = {k: text(v) for k, v in root["output"].attrs.items()}
        assert output == dict(every=1, fields="displacement,stress", energy=0, points_count=0)
        for group in ("surfaces", "couples", "dirichlet", "loads", "time_functions"):
            assert root[group].attrs["count"] == 0
        material = read_list(root["bodies"])[0]
        assert (material["nu"], material["density"], material["damping"]) == (0.0, 0.0, 0.0)


LOAD_SCRIPT = textwrap.dedent("""
    import json, sys
    import numpy as np
    import petsc4py
    petsc4py.init([])
    from petsc4py import PETSc

    def geometry_ok(dm, prefix):
        # DMPlexCheckGeometry: every cell must have |J| > 0
        PETSc.Options().setValue(prefix + "dm_plex_check_geometry", True)
        dm.setOptionsPrefix(prefix)
        try:
            dm.setFromOptions()
            return True
        except PETSc.Error:
            return False

    path, names = sys.argv[1], sys.argv[2:]
    viewer = PETSc.Viewer().createHDF5(path, "r", comm=PETSc.COMM_SELF)
    result = {}
    for name in names:
        dm = PETSc.DMPlex().create(comm=PETSc.COMM_SELF)
        dm.setName(name)
        dm.load(viewer)
        start, end = dm.getHeightStratum(0)
        labels = {}
        for label in ("Face Sets", "contact_master", "contact_slave"):
            if dm.hasLabel(label):  # DMView does not store empty labels
                labels[label] = {int(v): dm.getStratumSize(label, int(v))
                                 for v in dm.getLabelIdIS(label).getIndices()}
        faces = [p for v in labels.get("Face Sets", {}) for p in dm.getStratumIS("Face Sets", v).getIndices()]
        result[name] = dict(cells=end - start, labels=labels, geometry_ok=geometry_ok(dm, "t_" + name + "_"),
                            boundary=all(dm.getSupportSize(p) == 1 for p in faces))
    # negative control: a Gmsh-ordered tet, not permuted for PETSc, must fail the check
    tet = PETSc.DMPlex().createFromCellList(3, np.array([[0, 1, 2, 3]], dtype=PETSc.IntType),
        np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]), comm=PETSc.COMM_SELF)
    result["control_ok"] = not geometry_ok(tet, "t_control_")
    print(json.dumps(result))
""")


def test_petsc_loads_body_meshes(case):
    status, _, err = case(base_scene())
    assert status == 0, err
    done = subprocess.run([PYTHON, "-c", LOAD_SCRIPT, str(case.dir / "scene.h5"), "block1", "block2"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.splitlines()[-1])
    assert result["control_ok"]
    block1, block2 = result["block1"], result["block2"]
    assert block1["cells"] == 18 and block2["cells"] == 48
    assert block1["geometry_ok"] and block2["geometry_ok"]
    assert block1["boundary"] and block2["boundary"]
    # surface ids: 1 b1_zmax, 2 b2_zmin, 3 b1_zmin, 4 b1_xmin, 5 b2_xmax, 6 b2_zmax
    assert block1["labels"] == {"Face Sets": {"1": 9, "3": 9, "4": 6}, "contact_master": {"1": 9}}
    assert block2["labels"] == {"Face Sets": {"2": 8, "5": 8, "6": 8}, "contact_slave": {"1": 8}}


def test_cli_script(case):
    (case.dir / "scene.yaml").write_text(yaml.safe_dump(base_scene()))
    done = subprocess.run([str(PREP), str(case.dir / "scene.yaml"), "-q"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (case.dir / "scene.h5").exists() and done.stdout == ""
    assert [p.name for p in case.dir.iterdir() if p.name.startswith(".")] == []  # no temp file left

    broken = base_scene()
    broken["bodies"]["block1"]["material"]["E"] = -5
    (case.dir / "bad.yaml").write_text(yaml.safe_dump(broken))
    done = subprocess.run([str(PREP), str(case.dir / "bad.yaml")], capture_output=True, text=True)
    assert done.returncode == 1
    assert "mbcontact-prep: error:" in done.stderr and "bodies.block1.material.E" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (case.dir / "bad.h5").exists()


def test_check_only_writes_nothing(case):
    status, out, err = case(base_scene(), extra=["--check"])
    assert status == 0, err
    assert "checked" in out and not (case.dir / "scene.h5").exists()


# ---------------------------------------------------------------- user errors

def setter(*path, value=None, delete=False):
    """Mutation of the base scene: set (or delete) the entry at path."""
    def mutate(scene):
        node = scene
        for key in path[:-1]:
            node = node[key]
        if delete:
            del node[path[-1]]
        else:
            node[path[-1]] = value
    return mutate


MATERIAL = ("bodies", "block1", "material")
HYDROSTATIC = {"kind": "hydrostatic", "surface": "b2_xmax", "level": 1.5, "unit_weight": 9810.0}
SCENE_ERRORS = [
    ("unknown top key", setter("bodys", value={}), ["bodys", "unknown key"]),
    ("unknown nested key", setter(*MATERIAL, "Young", value=1), ["material.Young"]),
    ("unknown newmark key", setter("analysis", "newmark", "alpha", value=1), ["analysis.newmark.alpha"]),
    ("missing E", setter(*MATERIAL, "E", delete=True), ["block1.material", "'E'"]),
    ("unknown mesh", setter("bodies", "block1", "mesh", value="other"), ["block1.mesh", "'other'"]),
    ("body name", lambda s: s["bodies"].update({"block-3": s["bodies"]["block1"]}), ["block-3", "identifier"]),
    ("E zero", setter(*MATERIAL, "E", value=0), ["material.E", "> 0"]),
    ("E nan", setter(*MATERIAL, "E", value=float("nan")), ["material.E", "finite"]),
    ("E text", setter(*MATERIAL, "E", value="stiff"), ["material.E", "'stiff'"]),
    ("nu -1", setter(*MATERIAL, "nu", value=-1.0), ["material.nu", "> -1"]),
    ("nu 0.5", setter(*MATERIAL, "nu", value=0.5), ["material.nu", "< 0.5"]),
    ("density", setter(*MATERIAL, "density", value=-1), ["material.density"]),
    ("damping", setter(*MATERIAL, "damping", value=-1), ["material.damping"]),
    ("rayleigh", setter(*MATERIAL, "rayleigh_alpha", value=-1e-3), ["material.rayleigh_alpha"]),
    ("dynamic massless", setter(*MATERIAL, "density", value=0), ["block1", "density", "dynamic"]),
    ("dt zero", setter("analysis", "dt", value=0), ["analysis.dt"]),
    ("final < dt", setter("analysis", "final_time", value=0.001), ["analysis.final_time", "dt"]),
    ("analysis type", setter("analysis", "type", value="transient"), ["analysis.type", "'transient'"]),
    ("mass", setter("analysis", "mass", value="diagonal"), ["analysis.mass", "'diagonal'"]),
    ("load kind", setter("loads", 1, "kind", value="weight"), ["loads[1].kind", "'weight'"]),
    ("load time", setter("loads", 0, "time", value="slowly"), ["loads[0].time", "'slowly'"]),
    ("dirichlet sudden", setter("dirichlet", 0, "time", value="sudden"), ["dirichlet[0].time"]),
    ("component", setter("dirichlet", 0, "components", value=["w"]), ["dirichlet[0].components", "'w'"]),
    ("mu", setter("couples", 0, "mu", value=-0.1), ["couples[0].mu"]),
    ("empty master", setter("couples", 0, "master", value=[]), ["couples[0].master", "k=1"]),
    ("table order", setter("loads", 3, "time", value={"table": [[0, 0], [1, 1], [1, 2]]}),
     ["loads[3].time.table[2]", "increasing"]),
    ("point length", setter("output", "points", "top", value=[1, 2]), ["output.points.top", "3 numbers"]),
    ("point body", setter("output", "points", "mid", "body", value="block9"), ["output.points.mid.body", "block9"]),
    ("unknown load body", setter("loads", 0, "bodies", value=["nobody"]), ["loads[0].bodies", "nobody"]),
    ("traction vector", setter("loads", 3, "vector", value=[0, 0]), ["loads[3].vector"]),
    ("field", setter("output", "fields", value=["strain"]), ["output.fields", "'strain'"]),
    ("every", setter("output", "every", value=0), ["output.every"]),
    ("missing mesh file", setter("meshes", "main", value="nothere.msh"), ["meshes.main", "nothere.msh"]),
    ("region absent", setter("bodies", "block1", "regions", value=["b9"]),
     ["block1.regions", "'b9'", "volume regions there: b1, b2"]),
    ("region 2D", setter("bodies", "block1", "regions", value=["b1_zmin"]), ["'b1_zmin'", "2D"]),
    ("region twice", setter("bodies", "block2", "regions", value=["b1"]), ["'b1'", "block1"]),
    ("surface absent", setter("dirichlet", 0, "surface", value="floor"), ["'floor'", "dirichlet[0]"]),
    ("surface is volume", setter("loads", 2, "surface", value="b2"), ["'b2'", "loads[2]", "3D"]),
    ("surface off bodies", lambda s: [s["bodies"].pop("block2"), s["loads"].pop(0),
                                      s["output"].pop("points")], ["'b2_zmin'", "k=1", "boundary"]),
    ("master is slave", setter("couples", 0, "slave", value="b1_zmax"), ["k=1", "master", "slave"]),
    ("hydrostatic level", setter("loads", 2, value={"kind": "hydrostatic", "surface": "b2_xmax", "unit_weight": 9810.0}),
     ["loads[2]", "'level'"]),
    ("hydrostatic unit weight", setter("loads", 2, value=HYDROSTATIC | {"unit_weight": -1.0}), ["loads[2].unit_weight", ">= 0"]),
    ("hydrostatic axis", setter("loads", 2, value=HYDROSTATIC | {"axis": "up"}), ["loads[2].axis", "'up'"]),
    ("hydrostatic value", setter("loads", 2, value=HYDROSTATIC | {"value": 1.0}), ["loads[2].value", "unknown key"]),
    ("time csv absent", setter("loads", 3, "time", value={"csv": "nothere.csv"}), ["loads[3].time.csv", "nothere.csv"]),
    ("time csv key", setter("loads", 3, "time", value={"csv": "a.csv", "scale": 2}), ["loads[3].time.scale", "unknown key"]),
    # issue 13: integers beyond int32 were written wrapped (k 2**31 as -2147483648, every 2**40 as 0)
    ("k int32", setter("couples", 0, "k", value=2**31), ["couples[0].k", "<= 2147483647"]),
    ("every int32", setter("output", "every", value=2**40), ["output.every", "<= 2147483647"]),
    ("title 1 MB", setter("title", value="t" * 2**20), ["title", "longer than 255"]),  # was a traceback
    ("mu absurd", setter("couples", 0, "mu", value=1e20), ["couples[0].mu", "at most 1000"]),
    ("dt 1e9 steps", setter("analysis", "dt", value=1e-9), ["analysis.dt", "more than 1e+07"]),
]


@pytest.mark.parametrize("mutate, expected", [e[1:] for e in SCENE_ERRORS], ids=[e[0] for e in SCENE_ERRORS])
def test_scene_errors(case, mutate, expected):
    scene = copy.deepcopy(base_scene())
    mutate(scene)
    assert_error(case(scene), expected)
    assert not (case.dir / "scene.h5").exists()


def assert_error(result, expected):
    status, out, err = result
    assert status == 1
    assert err.startswith("mbcontact-prep: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    for piece in expected:
        assert piece in err, f"{piece!r} not in {err!r}"


CSV_ERRORS = [
    ("t,factor\n0,0\n1,x\n", ["line 3", "two numbers"]),
    ("0,0\n1,1,2\n", ["line 2", "two columns"]),
    ("0,0\n0,1\n", ["line 2", "increasing"]),
    ("0,0\n1,nan\n", ["line 2", "finite"]),
    ("# only a comment\n", ["no 't, factor' rows"]),
]


@pytest.mark.parametrize("text, expected", CSV_ERRORS, ids=["text", "columns", "order", "nan", "empty"])
def test_time_csv_errors(case, text, expected):
    """A bad `time: {csv: FILE}` names the key path, the file and the line."""
    (case.dir / "record.csv").write_text(text)
    scene = base_scene()
    scene["loads"][3]["time"] = {"csv": "record.csv"}
    assert_error(case(scene), ["loads[3].time.csv", "record.csv"] + expected)


def test_hydrostatic_and_csv_written(case):
    """A hydrostatic load's level, unit weight and axis, and a CSV time table (shifted), in the file."""
    (case.dir / "record.csv").write_text("time [s]; a [m/s2]\n0; 0\n0.01; 0.5\n0.02; -0.25\n")
    scene = base_scene()
    scene["loads"][2] = HYDROSTATIC | {"axis": "y"}
    scene["loads"][3]["time"] = {"csv": "record.csv", "shift": 2.0}
    status, _, err = case(scene)
    assert status == 0, err
    with h5py.File(case.dir / "scene.h5", "r") as f:
        loads = read_list(f["mbcontact/loads"])
        assert (loads[2]["kind"], loads[2]["level"], loads[2]["unit_weight"], loads[2]["axis"]) == ("hydrostatic", 1.5, 9810.0, 1)
        assert loads[2]["axis"].dtype == np.int32 and "level" not in loads[3]
        assert np.array_equal(f["mbcontact/time_functions/1/table"][()], [[2, 0], [2.01, 0.5], [2.02, -0.25]])


def test_missing_scene_file(tmp_path):
    assert_error(run_main([str(tmp_path / "none.yaml")]), ["none.yaml", "cannot read"])


def test_yaml_syntax_error(case):
    assert_error(case(None, text="bodies: [a\nmeshes: {"), ["scene.yaml", "YAML syntax error", "line"])


def test_duplicate_yaml_key(case):
    assert_error(case(None, text="meshes: {a: x.msh}\nmeshes: {b: y.msh}\n"), ["duplicate key 'meshes'"])


def test_unstable_newmark_warns(case):
    scene = base_scene()
    scene["analysis"]["newmark"] = {"beta": 0.1, "gamma": 0.5}
    status, _, err = case(scene, extra=["--check"])
    assert status == 0 and "warning: analysis.newmark" in err


def test_dynamic_needs_dt(case):
    scene = base_scene()
    del scene["analysis"]["dt"]
    assert_error(case(scene), ["analysis.dt", "dynamic"])


def add_region(path, name, dim, cell_type, cells):
    """Add a named gmsh physical region to a mesh file."""
    mesh = meshio.read(path)
    tag = max(int(v[0]) for v in mesh.field_data.values()) + 1
    mesh.cells.append(meshio.CellBlock(cell_type, np.asarray(cells)))
    for key in ("gmsh:physical", "gmsh:geometrical"):
        mesh.cell_data[key].append(np.full(len(cells), tag))
    mesh.field_data[name] = np.array([tag, dim])
    meshio.write(path, mesh, file_format="gmsh22", binary=False)


def test_overlapping_surface_regions(case):
    mesh = meshio.read(case.dir / "blocks.msh")
    zmin = mesh.field_data["b1_zmin"][0]
    quads = np.concatenate([b.data for b in mesh.cells if b.type == "quad"])
    quad_tags = np.concatenate([t for b, t in zip(mesh.cells, mesh.cell_data["gmsh:physical"]) if b.type == "quad"])
    add_region(case.dir / "blocks.msh", "patch", 2, "quad", quads[quad_tags == zmin][:2])
    scene = base_scene()
    scene["loads"].append({"kind": "pressure", "surface": "patch", "value": 1.0})
    assert_error(case(scene), ["'b1_zmin'", "'patch'", "overlap", "block1"])


def test_unsupported_cell_type(case):
    add_region(case.dir / "blocks.msh", "brick20", 3, "hexahedron20", [list(range(20))])
    scene = base_scene()
    scene["bodies"]["block1"]["regions"] = ["b1", "brick20"]
    assert_error(case(scene), ["'brick20'", "'hexahedron20'", "tet4", "hex8", "wedge6", "tet10"])


def test_inverted_element(case):
    path = case.dir / "blocks.msh"
    mesh = meshio.read(path)
    hexes = next(b for b in mesh.cells if b.type == "hexahedron").data
    hexes[4, [1, 3]] = hexes[4, [3, 1]]
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    assert_error(case(base_scene()), ["block1", "blocks.msh", "element 5", "region 'b1'", "inverted"])


def test_nan_coordinate(case):
    path = case.dir / "blocks.msh"
    mesh = meshio.read(path)
    mesh.points[7, 1] = np.nan
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    assert_error(case(base_scene()), ["block1", "node 8", "non-finite"])


def test_unreadable_mesh(case):
    (case.dir / "blocks.msh").write_text("$MeshFormat\ngarbage\n")
    assert_error(case(base_scene()), ["meshes.main", "blocks.msh"])


def test_unmatched_surface_faces_warn(case):
    mesh = meshio.read(case.dir / "blocks.msh")
    hexes = next(b for b in mesh.cells if b.type == "hexahedron").data
    interior = [hexes[0][[4, 5, 6, 7]]]  # top of the first layer: inside block1
    boundary = [hexes[0][[0, 3, 2, 1]]]  # on zmin
    add_region(case.dir / "blocks.msh", "mixed", 2, "quad", np.concatenate([interior, boundary]))
    scene = base_scene()
    scene["loads"].append({"kind": "pressure", "surface": "mixed", "value": 1.0})
    scene["dirichlet"][0]["surface"] = "b1_xmax"
    status, _, err = case(scene, extra=["--check"])
    assert status == 0, err
    assert "warning" in err and "'mixed'" in err and "1 of 2 faces" in err


def test_couple_exclude(case):
    """A couple's `exclude` takes the master nodes of the named regions out of contact: b1_xmin
    meets the master surface b1_zmax in the 4 nodes of the edge x = 0, z = 1 of b1 (3 x 3 x 2
    cells), written as (body, vertex) rows; a region that is not there, one with no master node and
    a volume are refused, naming the key."""
    scene = base_scene()
    scene["couples"][0]["exclude"] = "b1_xmin"
    status, out, err = case(scene)
    assert status == 0, err
    assert "4 master nodes out of contact" in out
    with h5py.File(case.dir / "scene.h5", "r") as f:
        ex = f["mbcontact/couples/0/exclude"][...]
        x = f["topologies/block1/dms/coordinateDM/vecs/coordinates/coordinates"][...].reshape(-1, 3)
    assert ex.shape == (4, 2) and np.all(ex[:, 0] == 0)
    assert np.allclose(x[ex[:, 1]][:, [0, 2]], [0, 1])
    for region, words in (("nowhere", "region 'nowhere' not found"), ("b2_zmax", "no node on the couple's master surfaces"),
                          ("b1", "is a volume")):
        scene["couples"][0]["exclude"] = region
        status, out, err = case(scene)
        assert status == 1 and "couples[0].exclude (couple k=1)" in err and words in err, err
