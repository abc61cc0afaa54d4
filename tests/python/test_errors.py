"""Bad inputs reaching the solver: each must give one clear message naming the input and a
non-zero exit, never a crash or a hang (also when only one rank finds the error)."""
import os
import re
import sys

import h5py
import numpy as np
import pytest

from conftest import ROOT, prep, solve
from mbcontact import meshgen


def good_scene(tmp_path, two=False):
    if two:
        meshgen.boxes(tmp_path / "m.msh", [dict(lo=(0, 0, 0), hi=(1, 1, 2), n=(1, 1, 2), cell="hex8", name="b1"),
                                           dict(lo=(3, 0, 0), hi=(4, 1, 2), n=(1, 1, 2), cell="tet4", name="b2")])
        bodies, fixed = ("b1", "b2"), ["b1_zmin", "b2_zmin"]
    else:
        meshgen.box(tmp_path / "m.msh", (0, 0, 0), (1, 1, 2), n=(1, 1, 2), cell="hex8", volume_name="b1")
        bodies, fixed = ("b1",), ["zmin"]
    scene = {
        "meshes": {"m": "m.msh"},
        "bodies": {b: {"mesh": "m", "regions": [b], "material": {"E": 1e9, "nu": 0.2, "density": 1000.0}} for b in bodies},
        "dirichlet": [{"surface": s, "components": "all"} for s in fixed],
        "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
    }
    return prep(tmp_path, scene)


def expect_error(h5, *words, options=(), nproc=1):
    r = solve(h5, *options, nproc=nproc, check=False, timeout=120)
    text = r.stdout + r.stderr
    assert r.returncode > 0, text
    assert "mbcontact: error:" in text, text
    for w in words:
        assert w in text, (w, text)
    for crash in ("Segmentation", "signal 11", "Caught signal", "core dumped", "AddressSanitizer", "runtime error:"):
        assert crash not in text, text
    return text


def edit(h5, path, attr, value):
    with h5py.File(h5, "a") as f:
        f[path].attrs[attr] = value


def test_missing_scene_file(tmp_path):
    expect_error(tmp_path / "nowhere.h5", "nowhere.h5", "does not exist")


def test_no_scene_option(tmp_path):
    r = solve("", check=False)
    assert r.returncode > 0 and "-scene" in r.stderr


def test_not_hdf5(tmp_path):
    bad = tmp_path / "text.h5"
    bad.write_text("not a scene\n")
    expect_error(bad, "text.h5", "not an HDF5 file")


def test_hdf5_without_scene(tmp_path):
    bad = tmp_path / "empty.h5"
    with h5py.File(bad, "w") as f:
        f["x"] = np.zeros(3)
    expect_error(bad, "empty.h5", "mbcontact-prep")


@pytest.mark.parametrize("attr,value,words", [
    ("E", 0.0, ["b1", "Young's modulus", "E = 0"]),
    ("E", -5.0, ["b1", "Young's modulus"]),
    ("nu", 0.5, ["b1", "Poisson", "0.5"]),
    ("nu", 0.7, ["b1", "Poisson"]),
    ("E", float("nan"), ["E", "not finite"]),
])
def test_bad_material(tmp_path, attr, value, words):
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/bodies/0", attr, value)
    expect_error(h5, *words)


@pytest.mark.parametrize("attr,value", [("E", 1e-308), ("E", 1e308), ("density", 1e308), ("damping", 1e101)])
def test_material_beyond_double_precision(tmp_path, attr, value):
    """Material constants no unit system gives, whose stiffness, mass or energies leave double
    precision: E = 1e-308 ran to exit 0, E = 1e308 stopped with "cell 0 is degenerate" and
    density 1e308 with "every contact DOF is prescribed", neither naming the value. Refused by the
    solver (a hand-edited file) and by the prep, naming the key and the value."""
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/bodies/0", attr, value)
    expect_error(h5, "b1", f"material {attr} = {value:g}", "lies outside [1e-100, 1e+100]")
    from mbcontact.scene import InputError, parse_scene
    with pytest.raises(InputError, match=re.escape(f"bodies.b1.material.{attr}: {value:g} lies outside")):
        parse_scene({"meshes": {"m": "m.msh"}, "bodies": {"b1": {"mesh": "m", "regions": "b1",
                     "material": {"E": 1e9, "density": 1000.0, attr: value}}}}, str(tmp_path))


def test_history_point_far_from_every_body(tmp_path):
    """A history point 1.7e6 m from a 2 m body (another unit, a typo) was snapped to the nearest
    vertex without a word, and its history was that vertex's; refused, naming it. A point off the
    mesh by less than the model's size is still snapped (the nearest vertex, docs/scene.md)."""
    meshgen.box(tmp_path / "m.msh", (0, 0, 0), (1, 1, 2), n=(1, 1, 2), cell="hex8", volume_name="b1")
    scene = {"meshes": {"m": "m.msh"},
             "bodies": {"b1": {"mesh": "m", "regions": ["b1"], "material": {"E": 1e9, "nu": 0.2, "density": 1000.0}}},
             "dirichlet": [{"surface": "zmin", "components": "all"}],
             "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
             "output": {"points": {"top": [0.5, 0.5, 2.0], "far": [1.7e6, 0.0, 0.0]}}}
    expect_error(prep(tmp_path, scene), "output point 'far'", "at (1.7e+06,", "farther than the size of the model")
    scene["output"]["points"]["far"] = {"x": [0.5, 0.5, 2.4], "body": "b1"}
    solve(prep(tmp_path, scene))


@pytest.mark.parametrize("options,words", [
    (("-mbc_static_stabilize", "-1"), ["-mbc_static_stabilize -1", "must be >= 0"]),
    (("-mbc_fclib_write_step", "-5"), ["-mbc_fclib_write_step -5", "must be a step number >= 1"]),
])
def test_bad_solver_option_value(tmp_path, options, words):
    """-mbc_static_stabilize -1 was taken as "off" and -mbc_fclib_write_step -5 as "the last step"."""
    expect_error(good_scene(tmp_path), *words, options=options)


def test_nan_load(tmp_path):
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/loads/0", "vector", np.array([0.0, np.nan, -9.81]))
    expect_error(h5, "vector", "loads/0", "not finite")


def test_unknown_enum_in_file(tmp_path):
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/loads/0", "kind", np.bytes_("magnetic"))
    expect_error(h5, "magnetic", "gravity")


def mirror(h5, body):
    with h5py.File(h5, "a") as f:
        c = f[f"topologies/{body}/dms/coordinateDM/vecs/coordinates/coordinates"]
        x = c[...].reshape(-1, 3)
        x[:, 0] *= -1
        c[...] = x.ravel()


def test_inverted_element(tmp_path):
    h5 = good_scene(tmp_path)
    mirror(h5, "b1")  # a mirror image turns every cell inside out
    expect_error(h5, "b1", "inverted")


def test_inverted_element_on_one_rank_does_not_hang(tmp_path):
    h5 = good_scene(tmp_path, two=True)
    mirror(h5, "b2")
    expect_error(h5, "b2", "inverted", nproc=2)


@pytest.mark.parametrize("option,value", [("-mbc_analysis", "quasistatic"), ("-mbc_mass", "diagonalish")])
def test_unknown_option_value(tmp_path, option, value):
    h5 = good_scene(tmp_path)
    expect_error(h5, value, options=(option, value))


def test_bad_step_option(tmp_path):
    h5 = good_scene(tmp_path)
    expect_error(h5, "-mbc_dt", options=("-mbc_dt", "-0.5"))


def test_unconstrained_static_body(tmp_path):
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/dirichlet", "count", 0)
    expect_error(h5, "b1", "singular")


def test_dynamic_without_density(tmp_path):
    h5 = good_scene(tmp_path)
    edit(h5, "mbcontact/bodies/0", "density", 0.0)
    expect_error(h5, "b1", "density", options=("-mbc_analysis", "dynamic"))


def test_help_without_scene_lists_options():
    r = solve("", "-help", check=False)
    assert r.returncode == 0, r.stderr
    for option in ("-mbc_analysis", "-mbc_dt", "-mbc_monitor", "-mbc_output"):
        assert option in r.stdout


def test_couple_without_faces_in_the_meshes(tmp_path):
    """A couple whose real constant matches no labelled face (a hand-edited scene file): the
    solver names k and the surfaces instead of searching nothing."""
    meshgen.boxes(tmp_path / "m.msh", [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), cell="hex8", name="b1"),
                                       dict(lo=(0, 0, 1), hi=(1, 1, 2), n=(1, 1, 1), cell="hex8", name="b2")])
    scene = {
        "meshes": {"m": "m.msh"},
        "bodies": {b: {"mesh": "m", "regions": [b], "material": {"E": 1e9, "nu": 0.2}} for b in ("b1", "b2")},
        "couples": [{"k": 1, "master": "b2_zmin", "slave": "b1_zmax", "mu": 0.5}],
    }
    h5 = prep(tmp_path, scene)
    edit(h5, "mbcontact/couples/0", "k", 7)
    expect_error(h5, "k = 7", "b2_zmin", options=("-mbc_contact_search_only",))


@pytest.mark.parametrize("nproc", [1, 2])
def test_result_file_cannot_be_created(tmp_path, nproc):
    """The collective result file in a folder that does not exist: one message per rank naming the
    file, exit status 1, no hang."""
    h5 = good_scene(tmp_path, two=True)
    out = tmp_path / "nowhere" / "r"
    text = expect_error(h5, f"Cannot create the result file {out}.h5", options=("-mbc_output", str(out)), nproc=nproc)
    assert len([l for l in text.splitlines() if "mbcontact: error:" in l]) <= nproc, text


# ---------------------------------------------------------------- the catalogue of issue 13
# (a) the scene file's meshes: checked before PETSc's DMPlex loaders (which would crash or hang)
TOPO = "topologies/b1/topology"


def edit_dataset(h5, path, change):
    """Rewrites dataset path with change(values) (which may return another shape or dtype),
    keeping its attributes."""
    with h5py.File(h5, "a") as f:
        new = change(f[path][...])
        attrs = dict(f[path].attrs)
        del f[path]
        f[path] = new
        f[path].attrs.update(attrs)


def set_entry(i, v, dtype=None):
    def change(a):
        a = a.astype(dtype or a.dtype)
        a.reshape(-1)[i] = v
        return a
    return change


@pytest.mark.parametrize("path,change,words", [
    (f"{TOPO}/cells", set_entry(3, -1), ["topology/cells[3] = -1", "cone of cell 0"]),  # hung in DMPlexStratify
    (f"{TOPO}/order", lambda a: a[::-1].copy(), ["topology/order[0] = 44"]),  # hung in DMPlexStratify
    (f"{TOPO}/cones", set_entry(0, 5), ["topology/cells has 96 values, expected 95"]),
    (f"{TOPO}/cones", lambda a: a[:-1].copy(), ["topology/order has 45 values, expected 44"]),
    (f"{TOPO}/cells", lambda a: a.astype(float), ["topology/cells must hold integers"]),
    (f"{TOPO}/cells", lambda a: a.reshape(-1, 2), ["topology/cells must have shape (n,) or (n, 1)"]),
    (f"{TOPO}/cells", set_entry(0, 2**40, np.int64), ["topology/cells[0] = 1099511627776"]),
    (f"{TOPO}/cells", set_entry(12, 14), ["topology/cells[12] = 14", "cone of face 14 must hold edges"]),
    (f"{TOPO}/orientation", set_entry(0, 9), ["topology/orientation[0] = 9", "outside [-4, 4)"]),
    ("topologies/b1/labels/Face Sets/1/indices", set_entry(0, 10**6), ["Face Sets/1/indices[0] = 1000000", "not a point"]),
    ("topologies/b1/labels/Face Sets/1/indices", set_entry(0, 15), ["Face Sets/1/indices[0] = 15", "not a boundary face"]),
    ("topologies/b1/dms/coordinateDM/section/atlasOff", set_entry(1, 10**6), ["section/atlasOff[1] = 1000000"]),
    ("topologies/b1/dms/coordinateDM/vecs/coordinates/coordinates", set_entry(4, np.inf), ["body 'b1'", "coordinate y of vertex 1 is inf"]),
    ("topologies/b1/dms/coordinateDM/vecs/coordinates/coordinates", lambda a: a * 1e300, ["coordinate", "beyond"]),
])
def test_bad_mesh_dataset(tmp_path, path, change, words):
    h5 = good_scene(tmp_path)
    edit_dataset(h5, path, change)
    expect_error(h5, "scene.h5", *words)


def test_truncated_scene_file(tmp_path):
    h5 = good_scene(tmp_path)
    data = h5.read_bytes()
    h5.write_bytes(data[:len(data) * 2 // 3])
    expect_error(h5, "scene.h5")


def test_wrong_face_sets_value(tmp_path):
    """A Face Sets stratum renamed to an id no surface has: was the Dirichlet condition dropped silently."""
    h5 = good_scene(tmp_path)
    with h5py.File(h5, "a") as f:
        f.move("topologies/b1/labels/Face Sets/1", "topologies/b1/labels/Face Sets/7")
    expect_error(h5, "Face Sets/7", "surface id 7")


@pytest.mark.parametrize("path,attr,value,words", [
    ("mbcontact/dirichlet/0", "surface_id", 9, ["dirichlet/0 has surface_id 9", "surfaces 1 to 1"]),  # was dropped silently
    ("mbcontact/loads/0", "bodies", np.bytes_("b1,ghost"), ["loads/0 names body 'ghost'"]),  # was dropped silently
    ("mbcontact/bodies", "count", 2**31 - 1, ["/mbcontact/bodies has count = 2147483647 but holds only 1"]),  # was "SceneRead"
    ("mbcontact/bodies/0", "num_cells", 2**40, ["num_cells", "outside the range of a 32-bit integer"]),
    ("mbcontact/bodies/0", "E", 1e-308, ["'b1'", "material E = 1e-308 lies outside"]),  # was "displacement increment is not finite" with a load, exit 0 without
    ("mbcontact/bodies/0", "name", np.bytes_("x" * 5000), ["longer than 255 characters"]),  # was a PETSc error dump
    ("mbcontact/surfaces/0", "id", 3, ["surfaces/0 has id 3, expected 1"]),
    ("mbcontact/bodies/0", "density", 1e308, ["body 'b1': material density = 1e+308 lies outside"]),  # was misleading, then named the gravity
])
def test_bad_scene_reference(tmp_path, path, attr, value, words):
    h5 = good_scene(tmp_path)
    edit(h5, path, attr, value)
    expect_error(h5, *words)


# (e) physically meaningless input
def two_blocks(tmp_path, overlap=0.0, mu=0.5):
    meshgen.boxes(tmp_path / "m.msh", [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), cell="hex8", name="lo"),
                                       dict(lo=(0, 0, 1 - overlap), hi=(1, 1, 2 - overlap), n=(1, 1, 1), cell="hex8", name="up")])
    scene = {
        "meshes": {"m": "m.msh"},
        "bodies": {b: {"mesh": "m", "regions": [b], "material": {"E": 1e9, "nu": 0.25, "density": 2000.0}} for b in ("lo", "up")},
        "couples": [{"k": 1, "master": "lo_zmax", "slave": "up_zmin", "mu": mu}],
        "dirichlet": [{"surface": "lo_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
    }
    return prep(tmp_path, scene)


def test_huge_friction_coefficient(tmp_path):
    """mu >= 1e20 made every point "separated" and the upper block fell through (exit 0)."""
    h5 = two_blocks(tmp_path)
    edit(h5, "mbcontact/couples/0", "mu", 1e20)
    expect_error(h5, "couple k = 1", "mu = 1e+20", "above 1000")


def test_initial_penetration(tmp_path):
    """Blocks overlapping by 0.2 at t = 0 (the energy jumped by 2.1e7 J in one step): refused with
    the bodies, the depth and the place; -mbc_contact_accept_penetration turns it into a warning."""
    h5 = two_blocks(tmp_path, overlap=0.2)
    expect_error(h5, "couple k = 1", "'lo' (master)", "'up' (slave)", "by 0.2 at (")
    r = solve(h5, "-mbc_contact_accept_penetration", "-mbc_static_max_it", "1", check=False)
    assert "warning" in r.stdout and "by 0.2 at" in r.stdout, r.stdout
    r = solve(h5, "-mbc_contact_search_only")  # a search report, no steps: not checked


def test_touching_blocks_are_not_penetrating(tmp_path):
    r = solve(two_blocks(tmp_path))
    assert "penetrates" not in r.stdout + r.stderr


@pytest.mark.parametrize("options,words", [
    (("-mbc_contact_cell_factor", "1e-9"), ["-mbc_contact_cell_factor 1e-09", "[1, 1000]"]),  # contact points 9 -> 0
    (("-mbc_contact_margin", "1e300"), ["couple k = 1", "-mbc_contact_margin"]),
])
def test_search_parameters_that_cannot_work(tmp_path, options, words):
    expect_error(two_blocks(tmp_path), *words, options=("-mbc_contact_search_only", *options))


@pytest.mark.parametrize("options,words", [
    (("-mbc_dt", "1e-9"), ["-mbc_dt 1e-09", "1e+09 steps, more than 1e+07"]),  # reserved 12 GB up front
    (("-mbc_dt", "1e-300"), ["-mbc_dt 1e-300", "steps, more than"]),  # an undefined float-to-int cast
    (("-mbc_dt", "inf"), ["-mbc_dt inf", "finite"]),
])
def test_step_count_beyond_reason(tmp_path, options, words):
    expect_error(good_scene(tmp_path), *words, options=options)


# (d) files closed on error paths, unknown options
def test_full_disk_no_crash_at_exit(tmp_path):
    """The result file on a full disk (/dev/full): one message, exit 1, no segfault at exit (HDF5
    used to close the file again inside MPI_Finalize)."""
    h5 = good_scene(tmp_path)
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "r.h5").symlink_to("/dev/full")
    r = solve(h5, "-mbc_output", str(tmp_path / "full" / "r"), check=False, timeout=120)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert "is the disk full" in r.stderr and "Segmentation" not in r.stderr, r.stderr


def test_unknown_mbc_option_warns(tmp_path):
    r = solve(good_scene(tmp_path), "-mbc_dtt", "1")
    assert "warning: option -mbc_dtt 1 was not used" in r.stdout, r.stdout
    assert "-mbc_dt " not in r.stdout.replace("-mbc_dtt", "")


def test_used_options_do_not_warn(tmp_path):
    r = solve(good_scene(tmp_path), "-mbc_dt", "0.5", "-mbc_monitor")
    assert "warning" not in r.stdout, r.stdout


# (b) FCLIB files: built from the two blocks (global as the solver writes it, local as -fclib_write)
@pytest.fixture(scope="module")
def fclib_files(tmp_path_factory):
    """local.hdf5: the two blocks' multiplier problem as the solver writes it; global.hdf5: a small
    global problem (M in compressed rows, H in triplets, tests/fuzz/fuzz.py)."""
    sys.path.insert(0, os.path.join(ROOT, "tests", "fuzz"))
    import fuzz
    d = tmp_path_factory.mktemp("fclib")
    solve(two_blocks(d), "-mbc_fclib_write", str(d / "local.hdf5"))
    fuzz.write_global_fclib(d / "global.hdf5")
    solve("", "-fclib", str(d / "global.hdf5"))
    return d


def fclib_mutant(src, dst, change):
    import shutil
    shutil.copy(src, dst)
    with h5py.File(dst, "a") as f:
        change(f)
    return dst


def replace(f, path, value):
    del f[path]
    f[path] = value


@pytest.mark.parametrize("which,change,words", [
    ("local", lambda f: f["fclib_local/W/p"].__setitem__(2, 0), ["W/p[2] = 0 after", "must not decrease"]),  # heap corruption, then a hang
    ("local", lambda f: replace(f, "fclib_local/W/p", f["fclib_local/W/p"][...][::-1].copy()), ["W/p[0] =", "expected 0"]),
    ("local", lambda f: f["fclib_local/vectors/q"].__setitem__(0, np.inf), ["vectors/q[0] = inf"]),  # was CONVERGED in 0 sweeps
    ("local", lambda f: f["fclib_local/vectors/q"].__setitem__(1, 1e308), ["vectors/q[1] = 1e+308"]),  # the same
    ("local", lambda f: f["fclib_local/W/x"].__setitem__(0, np.nan), ["W/x[0] = nan"]),  # was DIVERGED_NANORINF, no message
    ("local", lambda f: replace(f, "fclib_local/W/m", np.array([2**40])), ["W/m = 1099511627776", "32-bit"]),  # was "expected 0"
    ("local", lambda f: replace(f, "fclib_local/W/n", f["fclib_local/W/n"][...] + 3), ["W is", "not square"]),  # a PETSc-internal message
    ("local", lambda f: f["fclib_local/W/x"].__setitem__(slice(None), 0.0), ["W_nn = 0"]),  # ran silently to the iteration limit
    ("global", lambda f: f["fclib_global/M/x"].__setitem__(slice(None), 0.0), ["row 0 of the mass matrix M is zero"]),  # a bare MUMPS error code
    ("global", lambda f: f["fclib_global/vectors/f"].__setitem__(0, np.nan), ["vectors/f[0] = nan"]),
    ("global", lambda f: replace(f, "fclib_global/H/i", f["fclib_global/H/i"][...] + 10**6), ["H", "outside"]),
])
def test_bad_fclib(fclib_files, tmp_path, which, change, words):
    bad = fclib_mutant(fclib_files / f"{which}.hdf5", tmp_path / "bad.hdf5", change)
    r = solve("", "-fclib", str(bad), check=False, timeout=120)
    text = r.stdout + r.stderr
    assert r.returncode == 1 and "mbcontact: error: FCLIB file" in text and "bad.hdf5" in text, text
    for w in words:
        assert w in text, (w, text)


@pytest.mark.parametrize("which", ["scene", "result"])
def test_long_path_refused(tmp_path, which):
    """Open MPI 4.1's ompio aborted ("buffer overflow detected") on paths of 246 characters or more."""
    h5 = good_scene(tmp_path)
    deep = tmp_path / ("d" * 120) / ("e" * 120)
    deep.mkdir(parents=True)
    if which == "scene":
        (deep / "s.h5").write_bytes(h5.read_bytes())
        expect_error(deep / "s.h5", "scene file", "OMPI_MCA_io=romio321", options=("-mbc_output", str(tmp_path / "r")))
    else:
        expect_error(h5, "result file", "OMPI_MCA_io=romio321", options=("-mbc_output", str(deep / "r")))


def test_stretched_cell(tmp_path):
    """A vertex of the tet4 body moved to y = 1e9 (fuzzed): no cell inverted, but a mesh no more;
    the model's extent grew with it, so the displacement-size check let it through (exit 0)."""
    h5 = good_scene(tmp_path, two=True)
    with h5py.File(h5, "a") as f:
        c = f["topologies/b2/dms/coordinateDM/vecs/coordinates/coordinates"]
        x = c[...].reshape(-1, 3)
        top = np.flatnonzero((x[:, 1] == 1) & (x[:, 2] == 2))[0]
        x[top, 1] = 1e9
        c[...] = x.ravel()
    expect_error(h5, "b2", "is degenerate", "cube of its longest edge")
