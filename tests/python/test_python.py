"""The petsc4py binding (mbcontact._core, docs/python.md): the two-block example driven from
Python at 1 and 2 ranks gives the executable's result file, and the exact static state."""
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import BUILD, ROOT, env, load_script, result, solve
from mbcontact.results import output_times, read_body, read_csv

blocks = load_script("meshes/blocks/build.py", "blocks_build_py")
STATIC = ("-mbc_analysis", "static", "-mbc_dt", "1", "-mbc_final_time", "2")


def pyenv():
    e = env()
    e["PYTHONPATH"] = os.pathsep.join([os.path.join(ROOT, "python"), os.path.join(BUILD, "python")])
    return e


def run_python(args, nproc=1, check=True):
    cmd = [sys.executable, *args]
    if nproc > 1:
        cmd = ["mpirun", "-n", str(nproc), *cmd]
    r = subprocess.run(cmd, capture_output=True, text=True, env=pyenv(), timeout=600)
    if check:
        assert r.returncode == 0, r.stdout + r.stderr
    return r


@pytest.mark.parametrize("nproc", [1, 2])
def test_blocks_from_python(tmp_path, nproc):
    """Static two blocks (body force 100 N/m3 on block 2, 100 m high, E = 10 GPa, nu = 0): the
    top of block 2 at -1.5e-4 m exactly, the contact force the weight 1e8 N (to the PGS and
    static tolerances, 1e-4 as in test_contact_static.py); the result file is the executable's
    with the same options on the same ranks, to rounding (same code, same decomposition)."""
    h5 = blocks.build(tmp_path, dt=0.01, final_time=1.0)
    solve(h5, *STATIC, "-mbc_output", str(tmp_path / "exe"), nproc=nproc)
    r = run_python([os.path.join(ROOT, "tests", "python", "drive_blocks.py"), str(h5), str(tmp_path / "py")], nproc=nproc)
    out = dict(line.split(" ", 1) for line in r.stdout.strip().splitlines())
    assert out["steps"] == "1:1,2:2", out  # the monitor after each load step
    assert out["nbodies"] == "2" and out["comm_size"] == str(nproc)
    assert abs(float(out["block2_umin"]) / -1.5e-4 - 1) < 1e-4, out
    assert out["block1_same"] == "True" and out["block2_same"] == "True"  # the Vecs share the solver's memory
    assert abs(float(out["normal_force"]) / 1e8 - 1) < 1e-6, out
    assert out["points"] == "441" and out["stick"] == "441"  # block 2's 21 x 21 base vertices, sticking
    assert abs(float(out["pressure_mean"]) / 1e4 - 1) < 5e-3, out
    assert "every step is done" in out["error_after_end"], out
    for name in ("block1", "block2"):
        a, b = read_body(str(tmp_path / "exe.h5"), name), read_body(str(tmp_path / "py.h5"), name)
        scale = np.abs(a["displacement"]).max()
        assert np.abs(a["displacement"] - b["displacement"]).max() <= 1e-12 * scale, name
    pa, pb = read_csv(str(tmp_path / "exe_points.csv")), read_csv(str(tmp_path / "py_points.csv"))
    for k in pa:
        assert np.allclose(pa[k], pb[k], rtol=1e-12, atol=1e-12 * 1.5e-4), k


def test_errors_from_python(tmp_path):
    """C errors come back as PETSc.Error with the C message; a monitor's exception as itself."""
    script = tmp_path / "errors.py"
    script.write_text(f"""
from petsc4py import PETSc
import mbcontact
try:
    mbcontact.Scene().load({str(tmp_path / 'missing.h5')!r})
except PETSc.Error as e:
    print("load:", e)
s = mbcontact.Solver().create()
try:
    s.setUp()
except PETSc.Error as e:
    print("setup:", e)
try:
    s.getBody("block9")
except (KeyError, ValueError) as e:
    print("body:", type(e).__name__)
""")
    r = run_python([str(script)])
    assert f"load: Scene file {tmp_path / 'missing.h5'} does not exist or cannot be read" in r.stdout, r.stdout + r.stderr
    assert "setup: Call MBCSolverSetScene() first" in r.stdout, r.stdout + r.stderr
    assert "body: ValueError" in r.stdout, r.stdout + r.stderr


def test_scene_from_dict(tmp_path):
    """A scene built in Python (an in-memory meshio mesh with cell sets, the YAML's content as
    a dict), solved in-process: column under self-weight, hex8 layered in z, nu = 0, so the top's
    u_z = -rho g L^2 / (2E) and the centroid sigma_zz = -rho g (L - z_c) are exact (rounding,
    1e-10 and 1e-8 relative as in test_body.py); static: no velocity."""
    script = tmp_path / "fromdict.py"
    script.write_text(f"""
import meshio, numpy as np
from petsc4py import PETSc
import mbcontact
from mbcontact import meshgen
E, RHO, G, L = 30e9, 2500.0, 9.81, 10.0
meshgen.box({str(tmp_path / 'col.msh')!r}, (0, 0, 0), (1, 1, L), n=(1, 1, 10), cell="hex8", volume_name="col")
m = meshio.read({str(tmp_path / 'col.msh')!r})
tags = dict((n, t) for n, (t, d) in m.field_data.items())
sets = {{n: [np.flatnonzero(p == t) for p in m.cell_data["gmsh:physical"]] for n, t in tags.items()}}
mesh = meshio.Mesh(m.points, [(b.type, b.data) for b in m.cells], cell_sets=sets)  # no physical tags
scene = {{"meshes": {{}}, "bodies": {{"col": {{"mesh": "m", "regions": ["col"], "material": {{"E": E, "nu": 0.0, "density": RHO}}}}}},
         "dirichlet": [{{"surface": "zmin", "components": "all"}}], "loads": [{{"kind": "gravity", "vector": [0, 0, -G]}}],
         "analysis": {{"type": "static"}}, "output": {{"fields": ["displacement"]}}}}
sc = mbcontact.Scene.fromDict({str(tmp_path / 'built')!r}, "column", scene, meshes={{"m": mesh}})
s = mbcontact.Solver().create()
s.setScene(sc)
s.setFromOptions()
s.solve()
b = s.getBody(0)
u = b.getDisplacement()
exact = -RHO * G * L**2 / (2 * E)
assert abs(u.min()[1] - exact) < 1e-10 * abs(exact), (u.min(), exact)
st = b.getStress()
assert abs(st.strideMin(2)[1] + RHO * G * (L - 0.5)) < 1e-8 * RHO * G * L, st.strideMin(2)
assert abs(st.strideMax(2)[1] + RHO * G * 0.5) < 1e-8 * RHO * G * L, st.strideMax(2)
assert b.getVelocity() is None and b.getKSP() is not None and b.getDM().getDimension() == 3
try:
    mbcontact.Scene.fromDict({str(tmp_path / 'bad')!r}, "bad", dict(scene, bodies={{"col": {{"mesh": "m", "regions": ["nowhere"], "material": {{"E": E}}}}}}), meshes={{"m": mesh}})
except RuntimeError as e:
    print("bad scene:", e)
print("ok", sc.filename)
""")
    r = run_python([str(script)])
    assert "ok " + str(tmp_path / "built" / "column.h5") in r.stdout, r.stdout + r.stderr
    assert "bad scene: mbcontact.Scene.fromDict('bad')" in r.stdout, r.stdout + r.stderr
    assert "nowhere" in r.stderr, r.stderr  # mbcontact-prep names the missing region


hertz = load_script("meshes/hertz/build.py", "hertz_build_py")


@pytest.mark.parametrize("nproc", [1, 2])
def test_hertz_from_python(tmp_path, nproc):
    """The Hertz cylinders (hc 0.04 mm, static, frictionless) solved from Python at 1 and 2
    ranks: the contact points the binding returns are the result file's, and the executable's
    run gives the same pressures to rounding (same code, same decomposition). The accuracy
    against Hertz is test_hertz.py's."""
    from mbcontact.results import read_contact
    h5 = hertz.build(str(tmp_path), hc=0.04)
    solve(h5, "-mbc_output", str(tmp_path / "exe"), nproc=nproc)
    r = run_python([os.path.join(ROOT, "tests", "python", "drive_hertz.py"), str(h5), str(tmp_path / "py")], nproc=nproc)
    out = dict(line.split(" ", 1) for line in r.stdout.strip().splitlines())
    a, b = read_contact(str(tmp_path / "exe.h5")), read_contact(str(tmp_path / "py.h5"))
    assert int(out["points"]) == len(a["pressure"]) == len(b["pressure"])
    assert np.abs(a["pressure"] - b["pressure"]).max() <= 1e-10 * np.abs(a["pressure"]).max()
    assert abs(float(out["p_max"]) / b["pressure"].max() - 1) < 1e-12
    assert int(out["closed"]) == int((b["state"] > 0).sum()) > 0


def test_options_prefixes_reach_every_object(tmp_path):
    """Two solvers in one script with prefixes a_ and b_ (docs/python.md): each one's multiplier
    solve (-a_mbc_multiplier_type pgs, -b_mbc_multiplier_type newton: the monitor names the type),
    contact search (-a_mbc_contact_cell_factor), bodies' KSPs (prefix a_body_<name>_) and the
    -b_body_* options copied to b's bodies only. Before, everything but the solver's own options
    read unprefixed names, so two solvers could not differ in them."""
    h5 = blocks.build(tmp_path, dt=0.01, final_time=1.0)
    r = run_python([os.path.join(ROOT, "tests", "python", "drive_prefixes.py"), str(h5), str(tmp_path)],
                   check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    lines = r.stdout.splitlines()
    a = r.stdout[r.stdout.index("begin a_"):r.stdout.index("end a_")]
    b = r.stdout[r.stdout.index("begin b_"):r.stdout.index("end b_")]
    assert "contact: pgs CONVERGED" in a and "newton" not in a, a
    assert "contact: newton CONVERGED" in b and "pgs CONVERGED" not in b, b
    assert "couple" in a.lower() and "couple" not in b.lower()  # -a_mbc_contact_view
    for p in ("a_", "b_"):
        for name in ("block1", "block2"):
            assert f"{p} {name} ksp_prefix {p}body_{name}_" in lines, r.stdout
    assert "b_body_block1_ksp_type preonly" in lines and "a_body_block1_ksp_type " in lines, r.stdout


def test_two_solvers_share_one_scene(tmp_path):
    """One Scene object, two solvers in one process (a parametric study from Python): a_ static in
    two load steps, b_ dynamic with a lumped mass, set from options in the order b, a and stepped
    in turn. Each gives the result file it gives alone (the executable on the same scene with the
    same options) to 1e-12 of the displacement's scale. Before, the solvers wrote their analysis
    and mass into the shared scene and the bodies read them from there: b's bodies were built
    static, without M, and its first step crashed (SIGSEGV)."""
    from conftest import prep
    from mbcontact import meshgen
    meshgen.boxes(str(tmp_path / "two.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(2, 2, 2), name="base"),
                   dict(lo=(0, 0, 1), hi=(1, 1, 1.5), n=(3, 3, 2), name="block")])
    material = {"E": 1.0e9, "nu": 0.25, "density": 2000.0}
    scene = {"meshes": {"m": "two.msh"},
             "bodies": {b: {"mesh": "m", "regions": b, "material": material} for b in ("base", "block")},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.5}],
             "dirichlet": [{"surface": "base_zmin"}, {"surface": "block_zmax", "components": ["x", "y"]}],
             "loads": [{"kind": "pressure", "surface": "block_zmax", "value": 1.0e6, "time": {"table": [[0, 0], [1, 1]]}},
                       {"kind": "traction", "surface": "block_xmax", "vector": [-2.0e5, 0, 0], "time": {"table": [[0, 0], [1, 1]]}}],
             "analysis": {"type": "static"}}
    h5 = prep(tmp_path, scene, name="two")
    opts = {"a_": ["-mbc_analysis", "static", "-mbc_dt", "0.5", "-mbc_final_time", "1"],
            "b_": ["-mbc_analysis", "dynamic", "-mbc_mass", "lumped", "-mbc_dt", "0.01", "-mbc_final_time", "0.05"]}
    for p, o in opts.items():
        solve(h5, *o, "-mbc_output", str(tmp_path / f"{p}alone"))
    run_python([os.path.join(ROOT, "tests", "python", "drive_two_solvers.py"), str(h5), str(tmp_path)])
    for p in opts:
        times = output_times(str(tmp_path / f"{p}alone.h5"))
        assert list(output_times(str(tmp_path / f"{p}shared.h5"))) == list(times) and len(times) > 1
        for name in ("base", "block"):
            a = read_body(str(tmp_path / f"{p}alone.h5"), name)["displacement"]
            b = read_body(str(tmp_path / f"{p}shared.h5"), name)["displacement"]
            assert np.abs(a).max() > 0 and np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), (p, name)
