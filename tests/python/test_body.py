"""Bodies without contact: statics, patch test, Newmark dynamics, output and parallel runs.
Each test compares with an exact or analytic solution."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_csv

E, RHO, G, L = 30e9, 2500.0, 9.81, 10.0  # a concrete column, 1 m x 1 m x 10 m


def column_scene(mesh, analysis=None, loads=None, **material):
    mat = {"E": E, "nu": 0.0, "density": RHO}
    mat.update(material)
    return {
        "meshes": {"m": mesh},
        "bodies": {"col": {"mesh": "m", "regions": ["col"], "material": mat}},
        "dirichlet": [{"surface": "zmin", "components": "all", "value": 0.0}],
        "loads": loads or [{"kind": "gravity", "vector": [0, 0, -G]}],
        "analysis": analysis or {"type": "static"},
        "output": {"every": 1, "fields": ["displacement", "stress"], "points": {"top": [0.5, 0.5, L]}},
    }


@pytest.mark.parametrize("cell,ends", [("hex8", "fixed-free"), ("hex8", "fixed-fixed"), ("tet4", "fixed-fixed")])
def test_self_weight_static_exact(tmp_path, cell, ends):
    """Column under self-weight, nu = 0. Fixed base, free top: u_z = -rho g (L z - z^2/2) / E;
    both ends fixed (a column between rigid slabs): u_z = -rho g z (L - z) / (2E).
    Linear elements on a mesh layered in z reproduce the exact nodal values (1D superconvergence)
    when the consistent load of every free vertex balances its layers' stiffness: always for hex8;
    for tet4 (Kuhn split = prisms cut in 3 tets) on every interior plane, where the prisms above
    and below cancel, but not on a free end plane, so tet4 is tested between two fixed ends.
    The only error left is rounding: 1e-10 relative."""
    meshgen.box(tmp_path / "col.msh", (0, 0, 0), (1, 1, L), n=(2, 2, 10), cell=cell, volume_name="col")
    scene = column_scene("col.msh")
    if ends == "fixed-fixed":
        scene["dirichlet"].append({"surface": "zmax", "components": "all"})
        scene["output"]["points"] = {"mid": [0.5, 0.5, L / 2]}
    h5 = prep(tmp_path, scene)
    solve(h5)
    r = read_body(result(h5, ".h5"), "col")
    z = r["vertices"][:, 2]
    exact = -RHO * G * (L * z - z**2 / 2) / E if ends == "fixed-free" else -RHO * G * z * (L - z) / (2 * E)
    scale = np.abs(exact).max()
    assert np.abs(r["displacement"][:, 2] - exact).max() < 1e-10 * scale
    assert np.abs(r["displacement"][:, :2]).max() < 1e-10 * scale
    # sigma_zz = -rho g (L - z) (or rho g (z - L/2)) is linear: the centroid value is exact on hexes
    if cell == "hex8":
        zc = r["vertices"][r["cells"]][:, :, 2].mean(axis=1)
        szz = -RHO * G * (L - zc) if ends == "fixed-free" else RHO * G * (zc - L / 2)
        assert np.abs(r["stress"][:, 5] - szz).max() < 1e-8 * RHO * G * L  # zz: column 5 (xx xy xz yy yz zz)
    points = read_csv(result(h5, "_points.csv"))
    if ends == "fixed-free":
        assert abs(points["top_uz"][-1] + RHO * G * L**2 / (2 * E)) < 1e-10 * scale
    else:
        assert abs(points["mid_uz"][-1] + RHO * G * L**2 / (8 * E)) < 1e-10 * scale


def test_patch_test_distorted_hex(tmp_path):
    """Constant-stress patch test on a distorted hex8 mesh: traction p on x = 1, pressure q on y = 1,
    symmetry planes x = 0, y = 0, z = 0. Exact: sigma = diag(p, -q, 0) everywhere, u linear."""
    p, q, Em, nu = 3.0e6, 1.0e6, 2.0e10, 0.25
    meshgen.box(tmp_path / "cube.msh", (0, 0, 0), (1, 1, 1), n=(3, 3, 3), cell="hex8", volume_name="cube", perturb=0.25, seed=7)
    scene = {
        "meshes": {"m": "cube.msh"},
        "bodies": {"cube": {"mesh": "m", "regions": ["cube"], "material": {"E": Em, "nu": nu}}},
        "dirichlet": [{"surface": "xmin", "components": ["x"]}, {"surface": "ymin", "components": ["y"]},
                      {"surface": "zmin", "components": ["z"]}],
        "loads": [{"kind": "traction", "surface": "xmax", "vector": [p, 0, 0]},
                  {"kind": "pressure", "surface": "ymax", "value": q}],
    }
    h5 = prep(tmp_path, scene)
    solve(h5)
    r = read_body(result(h5, ".h5"), "cube")
    x = r["vertices"]
    assert np.ptp(x[r["cells"]][:, :, 0], axis=1).std() > 0.02, "the mesh is not distorted"
    s = r["stress"]
    exact = np.array([p, 0, 0, -q, 0, 0])  # xx xy xz yy yz zz
    assert np.abs(s - exact).max() < 1e-10 * p
    eps = np.array([p + nu * q, -q - nu * p, -nu * (p - q)]) / Em
    assert np.abs(r["displacement"] - x * eps).max() < 1e-10 * np.abs(eps).max()


def bar_scene(mesh, dt, final_time, damping=0.0, every=100, mass="consistent"):
    """A slender bar (E = 1e6, rho = 1, wave speed 1000, L = 1), base fixed, gravity 10 applied suddenly."""
    return {
        "meshes": {"m": mesh},
        "bodies": {"bar": {"mesh": "m", "regions": ["bar"], "material": {"E": 1e6, "nu": 0.0, "density": 1.0, "damping": damping}}},
        "dirichlet": [{"surface": "zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -10.0], "time": "sudden"}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": final_time, "mass": mass},
        "output": {"every": every, "fields": ["displacement"], "energy": True, "points": {"tip": [0.025, 0.025, 1.0]}},
    }


BAR_STATIC_TIP = -10.0 * 1.0**2 / (2 * 1e6)  # rho g L^2 / (2E)
BAR_PERIOD = 4.0 / 1000.0  # first mode of a fixed-free bar: 4 L / c


def upward_crossings(t, y):
    i = np.where((y[:-1] < 0) & (y[1:] >= 0))[0]
    return t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i])


def test_sudden_load_undamped_bar(tmp_path):
    """Mean tip displacement over whole periods = static; period = 4L/c within 1 %;
    trapezoidal Newmark conserves T + U - W to 1e-8 over 2000 steps."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(1, 1, 40), cell="hex8", volume_name="bar")
    dt = BAR_PERIOD / 400
    h5 = prep(tmp_path, bar_scene("bar.msh", dt, 5 * BAR_PERIOD))
    solve(h5)
    tip = read_csv(result(h5, "_points.csv"))
    t, uz = tip["t"], tip["tip_uz"]
    assert len(t) == 2001 and abs(t[-1] - 5 * BAR_PERIOD) < 1e-12
    mean = np.trapz(uz, t) / t[-1]
    assert abs(mean / BAR_STATIC_TIP - 1) < 5e-3
    crossings = upward_crossings(t, -(uz - BAR_STATIC_TIP))
    assert len(crossings) >= 4
    period = np.diff(crossings).mean()
    assert abs(period / BAR_PERIOD - 1) < 0.01
    e = read_csv(result(h5, "_energy.csv"))
    assert e["strain"].max() > 0 and e["kinetic"].max() > 0
    assert np.abs(e["total"] - e["total"][0]).max() < 1e-8 * e["strain"].max()
    # the XDMF index points at datasets that exist, with their shapes
    import h5py
    root = ET.parse(result(h5, ".xmf")).getroot()
    items = [d for d in root.iter("DataItem") if d.get("Format") == "HDF"]
    assert items
    for d in items:
        fname, path = d.text.strip().split(":")
        with h5py.File(tmp_path / fname, "r") as f:
            assert list(f[path].shape) == [int(v) for v in d.get("Dimensions").split()]
    assert len(root.findall(".//Time")) == 2000 // 100 + 1


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_sudden_load_damped_bar_settles(tmp_path, mass):
    """With C = c M (c = 314: 10 % of critical in the first mode) the bar settles on the static
    solution; the energy balance T + U - W + dissipated stays constant."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(1, 1, 20), cell="hex8", volume_name="bar")
    h5 = prep(tmp_path, bar_scene("bar.msh", BAR_PERIOD / 50, 20 * BAR_PERIOD, damping=314.0, every=1000, mass=mass))
    solve(h5)
    tip = read_csv(result(h5, "_points.csv"))
    assert abs(tip["tip_uz"][-1] / BAR_STATIC_TIP - 1) < 1e-4
    e = read_csv(result(h5, "_energy.csv"))
    assert e["damping_dissipation"][-1] > 0.4 * e["external_work"][-1]
    assert np.abs(e["total"] - e["total"][0]).max() < 1e-8 * e["external_work"][-1]


def two_column_scene(analysis):
    """Two independent columns, hex8 and tet4, in one mesh file."""
    return {
        "meshes": {"m": "two.msh"},
        "bodies": {name: {"mesh": "m", "regions": [name], "material": {"E": E, "nu": 0.0, "density": RHO}} for name in ("b1", "b2")},
        "dirichlet": [{"surface": "b1_zmin", "components": "all"}, {"surface": "b2_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G], "time": "sudden" if analysis["type"] == "dynamic" else "constant"}],
        "analysis": analysis,
        "output": {"every": 50, "points": {"top1": {"x": [0.5, 0.5, L], "body": "b1"}, "top2": {"x": [3.5, 0.5, L], "body": "b2"}}},
    }


@pytest.mark.parametrize("analysis", [{"type": "static"}, {"type": "dynamic", "dt": 1e-4, "final_time": 0.02}])
def test_two_bodies_same_at_1_2_4_ranks(tmp_path, analysis):
    """Two bodies, one per rank at 2 ranks, each spread over 2 ranks at 4: same histories."""
    meshgen.boxes(tmp_path / "two.msh", [dict(lo=(0, 0, 0), hi=(1, 1, L), n=(2, 2, 10), cell="hex8", name="b1"),
                                         dict(lo=(3, 0, 0), hi=(4, 1, L), n=(2, 2, 10), cell="tet4", name="b2")])
    h5 = prep(tmp_path, two_column_scene(analysis))
    runs = {}
    for n in (1, 2, 4):
        out = str(tmp_path / f"np{n}")
        r = solve(h5, "-mbc_output", out, "-mbc_view", nproc=n)
        runs[n] = read_csv(out + "_points.csv")
        if n == 2:
            assert "body b1: ranks 0-0" in r.stdout or "body b1: ranks 1-1" in r.stdout
            assert "body b2: ranks 0-0" in r.stdout or "body b2: ranks 1-1" in r.stdout
        if n == 4:
            assert "ranks 0-1" in r.stdout and "ranks 2-3" in r.stdout
    scale = RHO * G * L**2 / (2 * E)
    for n in (2, 4):
        for k in runs[1]:  # displacements to their scale; the absolute velocities and accelerations to theirs
            kind = k.split("_abs_")[1][0] if "_abs_" in k else "u"
            same = [c for c in runs[1] if kind != "u" and f"_abs_{kind}" in c]
            tol = 1e-9 * (max(np.abs(runs[1][c]).max() for c in same) if same else scale)
            assert np.abs(runs[n][k] - runs[1][k]).max() < tol, (n, k)
    if analysis["type"] == "static":
        assert abs(runs[1]["top1_uz"][-1] + scale) < 1e-10 * scale  # hex8: nodally exact
        assert abs(runs[1]["top2_uz"][-1] + scale) < 1e-3 * scale  # tet4, free top: discretisation error


def test_log_view_has_phase_events(tmp_path):
    meshgen.box(tmp_path / "col.msh", (0, 0, 0), (1, 1, L), n=(1, 1, 4), cell="hex8", volume_name="col")
    h5 = prep(tmp_path, column_scene("col.msh"))
    out = solve(h5, "-log_view").stdout
    for event in ("MBCSceneLoad", "MBCBodyLoad", "MBCBodyAssemble", "MBCBodyFactor", "MBCBodySolve", "MBCOutput"):
        line = [l for l in out.splitlines() if l.startswith(event)]
        assert line and int(line[0].split()[1]) >= 1, event


def test_damped_bar_rayleigh_stiffness(tmp_path):
    """Stiffness-proportional Rayleigh damping (C = beta K, 10 % of critical in the first mode)
    also settles on the static solution with a balanced energy budget."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(1, 1, 20), cell="hex8", volume_name="bar")
    scene = bar_scene("bar.msh", BAR_PERIOD / 50, 30 * BAR_PERIOD, every=2000)
    omega1 = 2 * np.pi / BAR_PERIOD
    scene["bodies"]["bar"]["material"]["rayleigh_beta"] = 2 * 0.1 / omega1
    h5 = prep(tmp_path, scene)
    solve(h5)
    tip = read_csv(result(h5, "_points.csv"))
    assert abs(tip["tip_uz"][-1] / BAR_STATIC_TIP - 1) < 1e-4
    e = read_csv(result(h5, "_energy.csv"))
    assert np.abs(e["total"] - e["total"][0]).max() < 1e-8 * e["external_work"][-1]


def test_prescribed_displacement_table_static(tmp_path):
    """Top of a bar pulled by a prescribed displacement ramp (time table), static load steps:
    u_z = g(t) z / L, sigma_zz = E g(t) / L, for every step."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (1, 1, 4), n=(2, 2, 4), cell="tet4", volume_name="bar")
    scene = {
        "meshes": {"m": "bar.msh"},
        "bodies": {"bar": {"mesh": "m", "regions": ["bar"], "material": {"E": 2e11, "nu": 0.3}}},
        "dirichlet": [{"surface": "zmin", "components": ["z"]}, {"surface": "xmin", "components": ["x"]},
                      {"surface": "ymin", "components": ["y"]},
                      {"surface": "zmax", "components": ["z"], "value": 1e-3, "time": {"table": [[0, 0], [1, 1], [2, 0.5]]}}],
        "analysis": {"type": "static", "dt": 0.5, "final_time": 2.0},
        "output": {"every": 1, "points": {"top": [1, 1, 4], "mid": [0, 0, 2]}},
    }
    h5 = prep(tmp_path, scene)
    solve(h5)
    p = read_csv(result(h5, "_points.csv"))
    g = 1e-3 * np.interp(p["t"], [0, 1, 2], [0, 1, 0.5])
    assert np.allclose(p["t"], [0.5, 1.0, 1.5, 2.0])
    assert np.abs(p["top_uz"] - g).max() < 1e-12 and np.abs(p["mid_uz"] - g / 2).max() < 1e-12
    assert np.abs(p["top_ux"] + 0.3 * g / 4).max() < 1e-12  # lateral contraction -nu eps x
    r = read_body(result(h5, ".h5"), "bar")
    assert np.abs(r["stress"][:, 5] - 2e11 * 0.5e-3 / 4).max() < 1e-9 * 2e11 * 1e-3 / 4


def test_prescribed_base_motion_dynamic(tmp_path):
    """A free bar carried by a slow prescribed base ramp (period of the ramp 50x the bar's):
    it moves almost rigidly, the top following the base to within 1 %."""
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(1, 1, 10), cell="hex8", volume_name="bar")
    ramp = 50 * BAR_PERIOD
    t = np.linspace(0, ramp, 41)
    table = np.column_stack([t, 0.5 * (1 - np.cos(np.pi * t / ramp))]).tolist()  # smooth from 0 to 1
    scene = bar_scene("bar.msh", BAR_PERIOD / 20, ramp, every=1000)
    scene["loads"] = []
    scene["dirichlet"] = [{"surface": "zmin", "components": ["x", "y"]},
                          {"surface": "zmin", "components": ["z"], "value": 1e-3, "time": {"table": table}}]
    h5 = prep(tmp_path, scene)
    solve(h5)
    p = read_csv(result(h5, "_points.csv"))
    base = 1e-3 * 0.5 * (1 - np.cos(np.pi * p["t"] / ramp))
    assert abs(p["tip_uz"][-1] - 1e-3) < 1e-2 * 1e-3
    assert np.abs(p["tip_uz"] - base).max() < 1e-2 * 1e-3


def test_per_body_solver_options(tmp_path):
    """-body_* applies to every body's KSP, -body_<name>_* to one body only."""
    meshgen.boxes(tmp_path / "two.msh", [dict(lo=(0, 0, 0), hi=(1, 1, L), n=(1, 1, 2), cell="hex8", name="b1"),
                                         dict(lo=(3, 0, 0), hi=(4, 1, L), n=(1, 1, 2), cell="hex8", name="b2")])
    scene = two_column_scene({"type": "static"})  # its history points at the columns' tops, z = L
    h5 = prep(tmp_path, scene)
    out = solve(h5, "-body_pc_factor_mat_solver_type", "petsc", "-body_b2_pc_factor_mat_solver_type", "mumps",
                "-body_ksp_view").stdout
    views = out.split("KSP Object:")[1:]
    assert len(views) == 2
    b1 = [v for v in views if "(body_b1_)" in v][0]
    b2 = [v for v in views if "(body_b2_)" in v][0]
    assert "mumps" not in b1 and "MUMPS" not in b1
    assert "mumps" in b2
