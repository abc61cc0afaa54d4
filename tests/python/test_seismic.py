"""The seismic loads and boundaries (docs/scene.md: ground_acceleration, added_mass, absorbing,
massless; docs/dam.md): Westergaard's added mass node by node against the exact integral, on
vertical and inclined faces, hex8 and tet4; three record components along x, y, z; a soil column
under vertically propagating SH and P waves through a Lysmer-Kuhlemeyer base against the 1D
solution (free surface twice the incident wave, the energy out equal to the energy in); a massless
foundation giving the rigid-base answer; the envelope of the largest principal stress."""
import os
import re
import subprocess
import sys

import h5py
import numpy as np
import pytest
from scipy.integrate import quad

from conftest import BUILD, ROOT, env, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_csv

RHO_W = 1000.0


def operator_blocks(h5, body, which, tmp_path):
    """Nodal 3 x 3 blocks of M or Cb through the binding (drive_operators.py, one rank)."""
    e = env()
    e["PYTHONPATH"] = os.pathsep.join([os.path.join(ROOT, "python"), os.path.join(BUILD, "python")])
    out = tmp_path / f"{which}.npz"
    r = subprocess.run([sys.executable, os.path.join(ROOT, "tests", "python", "drive_operators.py"), str(h5), body, which, str(out)],
                       capture_output=True, text=True, env=e, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    d = np.load(out)
    return d["x"], d["blocks"]


def wet_box(tmp_path, cell, shear, level=3.0):
    """A 2 x 3 x 4 box (5 layers: the level 3 cuts the layer 2.4-3.2), xmin the plane x = shear z,
    nearly massless (density 1e-9) so M is the added mass; water on xmin to `level`."""
    part = meshgen.box_part("b", (0, 0, 0), (2, 3, 4), n=(2, 3, 5), cell=cell)
    part.points[:, 0] += shear * part.points[:, 2]
    meshgen.write_parts(str(tmp_path / "box.msh"), [part])
    return {"meshes": {"m": "box.msh"},
            "bodies": {"b": {"mesh": "m", "regions": "b", "material": {"E": 1e9, "nu": 0.2, "density": 1e-9}}},
            "dirichlet": [{"surface": "b_zmin"}],
            "added_mass": [{"surface": "b_xmin", "density": RHO_W, "level": level}],
            "analysis": {"type": "dynamic", "dt": 0.01, "final_time": 0.01}}


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_westergaard_vertical_face(tmp_path, cell):
    """Vertical face, H = 3 m of water over b = 3 m: a constant ground acceleration a gives
    p(z) = 7/8 rho a sqrt(H (H - z)), i.e. the nodal masses m_i = integral of N_i 7/8 rho
    sqrt(H (H - z)) dA, all along the normal x; the total 7/12 rho H^2 b acting 0.4 H above the
    floor. Node by node against scipy's quadrature of the exact integral (1e-9), totals 1e-11 (the box itself has 1e-9 kg/m3)."""
    H, b = 3.0, 3.0
    h5 = prep(tmp_path, wet_box(tmp_path, cell, 0.0, H))
    x, B = operator_blocks(h5, "b", "M", tmp_path)
    F = 7 / 12 * RHO_W * H**2 * b
    tot = B.sum(axis=0)
    assert tot[0, 0] == pytest.approx(F, rel=1e-11)
    assert np.abs(tot - np.diag([F, 0, 0])).max() < 1e-9 * F  # the body's own mass is 1e-9 kg/m3
    assert (B[:, 0, 0] * x[:, 2]).sum() / F == pytest.approx(0.4 * H, rel=1e-10)
    ys, zs = np.linspace(0, 3, 4), np.linspace(0, 4, 6)
    for i in np.flatnonzero(np.abs(x[:, 0]) < 1e-12):
        y, z = x[i, 1], x[i, 2]
        if cell == "hex8":  # the face's bilinear hats: a product of two 1D integrals
            iy = quad(lambda t: max(0.0, 1 - abs(t - y) / 1.0), max(0, y - 1), min(3, y + 1))[0]
            iz = quad(lambda t: max(0.0, 1 - abs(t - z) / 0.8) * np.sqrt(max(H - t, 0.0)), max(0, z - 0.8), min(H, z + 0.8), limit=200)[0] if z - 0.8 < H else 0.0
            expected = iy * 7 / 8 * RHO_W * np.sqrt(H) * iz
            assert B[i, 0, 0] == pytest.approx(expected, rel=1e-9, abs=1e-9 * F), (y, z)
        assert abs(B[i, 1, 1]) < 1e-9 * F and abs(B[i, 0, 1]) < 1e-9 * F
        if z > H + 1e-9 and z - 0.8 >= H - 1e-9:
            assert B[i, 0, 0] < 1e-9 * F  # dry nodes carry nothing
    if cell == "tet4":  # the face's row sums along a vertical line (the y-integral) are the hex8's
        prof = {round(z, 6): B[(np.abs(x[:, 0]) < 1e-12) & (np.abs(x[:, 2] - z) < 1e-9), 0, 0].sum() for z in zs}
        for z, m in prof.items():
            iz = quad(lambda t: max(0.0, 1 - abs(t - z) / 0.8) * np.sqrt(max(H - t, 0.0)), max(0, z - 0.8), min(H, z + 0.8), limit=200)[0] if z - 0.8 < H else 0.0
            assert m == pytest.approx(b * 7 / 8 * RHO_W * np.sqrt(H) * iz, rel=1e-9, abs=1e-9 * F), z


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_westergaard_inclined_face(tmp_path, cell):
    """Face x = 0.5 z (upstream slope 1:2): every node's block is m_i n n^T along the face normal
    n = (-1, 0, 0.5)/sqrt(1.25) (an acceleration a gives the pressure of its normal component
    a.n), and the sum of m_i is 7/12 rho H^2 b sqrt(1.25) (the face is longer by sqrt(1.25))."""
    H, b, s = 3.0, 3.0, 0.5
    h5 = prep(tmp_path, wet_box(tmp_path, cell, s, H))
    x, B = operator_blocks(h5, "b", "M", tmp_path)
    n = np.array([-1.0, 0.0, s]) / np.sqrt(1 + s * s)
    F = 7 / 12 * RHO_W * H**2 * b
    m = np.einsum("ijk,j,k->i", B, n, n)
    assert m.sum() == pytest.approx(F * np.sqrt(1 + s * s), rel=1e-11)
    wet = m > 1e-6 * F
    assert np.abs(B[wet] - m[wet, None, None] * np.outer(n, n)).max() < 1e-9 * F
    assert (m * x[:, 2]).sum() / m.sum() == pytest.approx(0.4 * H, rel=1e-10)


def box_dynamic(tmp_path, loads, nz=4, extra=None):
    meshgen.box(str(tmp_path / "b.msh"), lo=(0, 0, 0), hi=(1, 1, 2), n=(2, 2, nz), cell="hex8")
    scene = {"meshes": {"m": "b.msh"},
             "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": 1e9, "nu": 0.25, "density": 2000}}},
             "dirichlet": [{"surface": "zmin"}], "loads": loads,
             "analysis": {"type": "dynamic", "dt": 0.01, "final_time": 0.3},
             "output": {"fields": ["displacement"], "points": {"base": [0, 0, 0], "top": [1, 1, 2]}}}
    scene.update(extra or {})
    return prep(tmp_path, scene)


@pytest.mark.parametrize("nproc", [1, 2])
def test_three_components(tmp_path, nproc):
    """One ground_acceleration with x, y and z records (a table, a multi-column CSV, a .AT2 in g
    with scale): three loads, each -M e_d a_d(t) (-mbc_view: resultant -rho V e_d to 1e-12), and a
    base point (held: no relative motion) moves with the ground: its absolute acceleration,
    velocity and displacement are the three records and their exact integrals at every step."""
    (tmp_path / "m.csv").write_text("t,a1,a2\n0,0,0\n0.1,0.5,-1\n0.2,0,2\n0.3,0,0\n")
    (tmp_path / "r.AT2").write_text("PEER\nTEST\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS= 4, DT= 0.1 SEC\n0 0.01 -0.02 0\n")
    load = {"kind": "ground_acceleration", "x": {"table": [[0, 0], [0.1, 1], [0.3, 0]]},
            "y": {"csv": "m.csv", "column": 3}, "z": {"at2": "r.AT2", "scale": 2, "g": 9.81}}
    h5 = box_dynamic(tmp_path, [load])
    r = solve(h5, "-mbc_view", nproc=nproc)
    res = [np.array([float(v) for v in m.groups()]) for m in re.finditer(r"load \d+ \(ground_acceleration\): resultant (\S+) (\S+) (\S+),", r.stdout)]
    mass = 2000 * 2.0
    assert len(res) == 3
    for d in range(3):
        assert np.allclose(res[d], -mass * np.eye(3)[d], rtol=0, atol=1e-12 * mass), res[d]
    p = read_csv(result(h5, "_points.csv"))
    t = p["t"]
    ax = np.interp(t, [0, 0.1, 0.3], [0, 1, 0])
    ay = np.interp(t, [0, 0.1, 0.2, 0.3], [0, -1, 2, 0])
    az = np.interp(t, [0, 0.1, 0.2, 0.3], [0, 0.02 * 9.81, -0.04 * 9.81, 0])
    for c, a in zip("xyz", (ax, ay, az)):
        assert np.allclose(p[f"base_abs_a{c}"], a, rtol=0, atol=1e-12), c
        assert np.allclose(p[f"base_u{c}"], 0, atol=1e-15)
        v = np.concatenate([[0], np.cumsum(np.diff(t) * (a[1:] + a[:-1]) / 2)])
        assert np.allclose(p[f"base_abs_v{c}"], v, rtol=0, atol=1e-12), c
    assert np.abs(p["top_ux"]).max() > 1e-9  # the free top moves relative to the base


def soil_column(tmp_path, wave, wave_input, nproc=1):
    """A 1 x 1 x 100 m column of 100 hex8 (h = 1 m), c_s = 200 m/s, nu = 1/3 (c_p = 400 m/s), its
    sides free only along the wave's polarisation; the base absorbing with the record coming in;
    a velocity pulse v(t) = 0.1 sin^2(pi t / 0.2) (40 m long for the S wave) given by its
    acceleration."""
    H, rho, cs, nu = 100.0, 2000.0, 200.0, 1 / 3
    mu = rho * cs**2
    meshgen.box(str(tmp_path / "col.msh"), lo=(0, 0, 0), hi=(1, 1, H), n=(1, 1, 100), cell="hex8")
    T, dt = 0.2, 0.001
    t = np.arange(0, 0.4 + 1e-12, dt)
    a = np.where(t < T, 0.1 * np.pi / T * np.sin(2 * np.pi * t / T), 0.0)
    np.savetxt(tmp_path / "acc.csv", np.column_stack([t, a]), delimiter=",")
    comp, held = ("x", ["y", "z"]) if wave == "SH" else ("z", ["x", "y"])
    scene = {"meshes": {"m": "col.msh"},
             "bodies": {"soil": {"mesh": "m", "regions": "body", "material": {"E": 2 * mu * (1 + nu), "nu": nu, "density": rho}}},
             "dirichlet": [{"surface": s, "components": held} for s in ("xmin", "xmax", "ymin", "ymax")],
             "loads": [{"kind": "ground_acceleration", comp: {"csv": "acc.csv"}}],
             "absorbing": [{"surface": "zmin", "input": wave_input}],
             "analysis": {"type": "dynamic", "dt": 0.002 if wave == "SH" else 0.001, "final_time": 1.3 if wave == "SH" else 0.8},
             "output": {"fields": [], "energy": True, "points": {"top": [0, 0, H], "base": [0, 0, 0]}}}
    h5 = prep(tmp_path, scene)
    solve(h5, nproc=nproc)
    c = cs if wave == "SH" else np.sqrt((2 * mu * (1 + nu) / (2 * (1 + nu)) * (2 - 2 * nu) / (1 - 2 * nu)) / rho)
    vin = lambda tq: np.where((tq > 0) & (tq < T), 0.1 * np.sin(np.pi * np.clip(tq, 0, T) / T) ** 2, 0.0)
    return h5, read_csv(result(h5, "_points.csv")), read_csv(result(h5, "_energy.csv")), comp, c, H, rho, vin


@pytest.mark.parametrize("wave, nproc", [("SH", 1), ("P", 2)])
def test_soil_column_lysmer(tmp_path, wave, nproc):
    """Vertically propagating S (x) and P (z) waves entering as the incident wave 2 rho c v_i
    through a Lysmer-Kuhlemeyer base: the free surface moves with twice the incident wave, H/c
    later (1D solution v_top(t) = 2 v_i(t - H/c): to 1.5 % of the peak, the FE's dispersion at 40
    and 80 elements per pulse); the column holds at most the incident energy rho c A int v_i^2
    (0.5 %), and once the reflected wave has left through the base nothing is trapped (kinetic +
    strain < 1e-5 of it) and the work of the input equals what the dashpots took (1e-5)."""
    h5, p, e, comp, c, H, rho, vin = soil_column(tmp_path, wave, "incident", nproc)
    t = p["t"]
    top = p[f"top_abs_v{comp}"]
    assert top.max() == pytest.approx(0.2, rel=5e-3)
    assert t[top.argmax()] == pytest.approx(0.1 + H / c, abs=0.01)
    assert np.abs(top - 2 * vin(t - H / c)).max() < 0.015 * 0.2
    tt = np.linspace(0, 0.2, 20001)
    Ein = rho * c * 1.0 * np.trapz(vin(tt) ** 2, tt)
    held = e["kinetic"] + e["strain"]
    assert held.max() == pytest.approx(Ein, rel=5e-3)
    assert held[-1] < 1e-5 * Ein
    assert abs(e["external_work"][-1] - e["damping_dissipation"][-1]) < 1e-5 * Ein
    assert abs(e["total"]).max() < 1e-9 * Ein  # the energy balance holds with the dashpots in C


def test_soil_column_outcrop(tmp_path):
    """The record as the outcrop motion (input: outcrop, the default for a record measured on
    rock): the incident wave is half of it, so the column's free surface reproduces the record."""
    h5, p, e, comp, c, H, rho, vin = soil_column(tmp_path, "SH", "outcrop")
    t = p["t"]
    assert np.abs(p["top_abs_vx"] - vin(t - H / c)).max() < 0.015 * 0.1


def test_massless_foundation_is_the_rigid_base(tmp_path):
    """A block on a stiff (E x 1000) massless foundation, held by friction (static stage: its
    weight; dynamic stage: a horizontal record), moves as the same block on a fixed base: the
    record acts on the block only (the massless foundation takes no inertia load) and the
    foundation only transmits it. Top displacement histories agree to 2e-3 of their peak."""
    blocks = [dict(lo=(0, 0, 0), hi=(1, 1, 2), n=(2, 2, 4), cell="hex8", name="dam"),
              dict(lo=(-1, -1, -1), hi=(2, 2, 0), n=(3, 3, 1), cell="hex8", name="rock")]
    meshgen.boxes(str(tmp_path / "two.msh"), blocks)
    meshgen.box(str(tmp_path / "one.msh"), lo=(0, 0, 0), hi=(1, 1, 2), n=(2, 2, 4), cell="hex8")
    record = {"kind": "ground_acceleration", "x": {"table": [[0, 0], [1.05, 0], [1.1, 2], [1.2, -2], [1.3, 1], [1.4, 0]]}}
    stages = [{"name": "weight", "analysis": {"type": "static"}},
              {"name": "quake", "analysis": {"type": "dynamic", "dt": 0.005, "final_time": 1.6}, "loads": [record]}]
    concrete = {"E": 1e9, "nu": 0.2, "density": 2400}
    two = {"meshes": {"m": "two.msh"},
           "bodies": {"dam": {"mesh": "m", "regions": "dam", "material": concrete},
                      "rock": {"mesh": "m", "regions": "rock", "material": {"E": 1e12, "nu": 0.25}, "massless": True}},
           "couples": [{"master": "dam_zmin", "slave": "rock_zmax", "mu": 5.0}],
           "dirichlet": [{"surface": "rock_zmin"}],
           "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "bodies": ["dam"]}],
           "stages": stages, "output": {"fields": [], "points": {"top": {"x": [1, 1, 2], "body": "dam"}}}}
    one = {"meshes": {"m": "one.msh"},
           "bodies": {"dam": {"mesh": "m", "regions": "body", "material": concrete}},
           "dirichlet": [{"surface": "zmin"}],
           "loads": [{"kind": "gravity", "vector": [0, 0, -9.81]}],
           "stages": stages, "output": {"fields": [], "points": {"top": [1, 1, 2]}}}
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    for sub, sc, mesh in (("a", two, "two.msh"), ("b", one, "one.msh")):
        os.replace(tmp_path / mesh, tmp_path / sub / mesh)
    h2, h1 = prep(tmp_path / "a", two), prep(tmp_path / "b", one)
    solve(h2)
    solve(h1)
    p2, p1 = read_csv(result(h2, "_points.csv")), read_csv(result(h1, "_points.csv"))
    d2 = p2["top_ux"] - p2["top_ux"][0]
    d1 = p1["top_ux"] - p1["top_ux"][0]
    peak = np.abs(d1).max()
    assert peak > 1e-6
    assert np.abs(d2 - d1).max() < 2e-3 * peak, (np.abs(d2 - d1).max(), peak)


def test_envelope(tmp_path):
    """fields: [envelope]: per cell the largest principal stress over all steps and when; with an
    output at every step it is the largest over the outputs of the principal stress of the
    written stress (numpy's eigvalsh), to rounding, at the time of that output."""
    load = {"kind": "ground_acceleration", "x": {"table": [[0, 0], [0.05, 3], [0.1, -3], [0.15, 0]]}}
    h5 = box_dynamic(tmp_path, [load], extra={"output": {"fields": ["stress", "envelope"]}})
    solve(h5)
    f = result(h5, ".h5")
    with h5py.File(f) as h:
        n = int(h.attrs["num_outputs"])
        g = h["bodies/b"]
        s1 = []
        for k in range(n):
            st = g[f"step_{k}/stress"][...]  # xx xy xz yy yz zz
            T = np.stack([st[:, [0, 1, 2]], st[:, [1, 3, 4]], st[:, [2, 4, 5]]], axis=1)
            s1.append(np.linalg.eigvalsh(T)[:, -1])
        s1 = np.array(s1)
        env_ = g[f"step_{n - 1}/max_principal_stress"][...]
        tenv = g[f"step_{n - 1}/max_principal_stress_time"][...]
        times = h["time"][...]
    scale = np.abs(s1).max()
    assert np.allclose(env_, s1.max(axis=0), rtol=0, atol=1e-9 * scale)
    assert np.allclose(tenv, times[s1.argmax(axis=0)], atol=1e-12)
    assert np.all(env_ > 0)


def test_seismic_input_errors(tmp_path):
    """An absorbing input without a record, a ground acceleration in a static analysis and an
    added mass on a static scene are refused by the prep, naming the key."""
    meshgen.box(str(tmp_path / "b.msh"), lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), cell="hex8")
    base = {"meshes": {"m": "b.msh"}, "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": 1e9, "density": 1}}},
            "dirichlet": [{"surface": "zmin"}]}
    import yaml
    for extra, message in (
            ({"absorbing": [{"surface": "zmax", "input": "outcrop"}], "analysis": {"type": "dynamic", "dt": 0.1, "final_time": 0.1}}, "needs a ground_acceleration"),
            ({"loads": [{"kind": "ground_acceleration", "x": {"table": [[0, 0], [1, 1]]}}]}, "needs a dynamic analysis"),
            ({"added_mass": [{"surface": "xmin", "density": 1000, "level": 0.5}]}, "dynamic or modal analysis only"),
            ({"added_mass": [{"surface": "xmin", "density": 1000, "level": 0.5, "bottom": 0.2}], "analysis": {"type": "modal"}}, "reaches down to 0"),
            ({"absorbing": [{"surface": "zmax", "input": "sideways"}], "analysis": {"type": "dynamic", "dt": 0.1, "final_time": 0.1}}, "unknown value 'sideways'")):
        (tmp_path / "s.yaml").write_text(yaml.safe_dump({**base, **extra}))
        from conftest import PREP
        r = subprocess.run([PREP, str(tmp_path / "s.yaml"), "--check"], capture_output=True, text=True, env=env())
        assert r.returncode == 1 and message in r.stderr, (extra, r.stderr)


@pytest.mark.parametrize("first", ["static", "dynamic"])
def test_absorbing_base_keeps_the_static_state(tmp_path, first):
    """A block under its weight standing only on an absorbing base: the static state (a static
    stage, or the initial state of a dynamic analysis) holds the base; the dynamic steps free it
    with the reactions it carried as a constant load, so without ground motion nothing moves
    (displacement changes below 1e-10 of the settlement) and the settlement is the fixed base's
    rho g H^2 / (2 M) at the top (1D, nu = 0: 1e-9)."""
    H, rho, E = 10.0, 2000.0, 1e8
    meshgen.box(str(tmp_path / "b.msh"), lo=(0, 0, 0), hi=(1, 1, H), n=(1, 1, 10), cell="hex8")
    scene = {"meshes": {"m": "b.msh"},
             "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": E, "nu": 0.0, "density": rho}}},
             "dirichlet": [{"surface": s, "components": ["x", "y"]} for s in ("xmin", "xmax", "ymin", "ymax")],
             "absorbing": [{"surface": "zmin"}],
             "output": {"fields": [], "points": {"top": [0, 0, H]}}}
    if first == "static":
        scene["loads"] = [{"kind": "gravity", "vector": [0, 0, -9.81]}]
        scene["stages"] = [{"analysis": {"type": "static"}}, {"analysis": {"type": "dynamic", "dt": 0.01, "final_time": 1.3}}]
    else:
        scene["loads"] = [{"kind": "gravity", "vector": [0, 0, -9.81]}]  # constant: the initial static state
        scene["analysis"] = {"type": "dynamic", "dt": 0.01, "final_time": 0.3}
    h5 = prep(tmp_path, scene)
    solve(h5)
    p = read_csv(result(h5, "_points.csv"))
    settle = -rho * 9.81 * H**2 / (2 * E)
    assert p["top_uz"][0] == pytest.approx(settle, rel=1e-9)
    assert np.abs(p["top_uz"] - p["top_uz"][0]).max() < 1e-10 * abs(settle)
