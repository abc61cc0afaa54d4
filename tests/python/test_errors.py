"""Bad inputs reaching the solver: each must give one clear message naming the input and a
non-zero exit, never a crash or a hang (also when only one rank finds the error)."""
import h5py
import numpy as np
import pytest

from conftest import prep, solve
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
    for crash in ("Segmentation", "signal 11", "Caught signal", "core dumped"):
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
