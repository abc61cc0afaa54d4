"""Modal analysis with SLEPc (analysis type modal, docs/scene.md): a clamped beam against the
analytic frequencies (axial exact in 1D with nu = 0, bending against Euler-Bernoulli); two bodies
tied by a couple equal the same mesh as one body, at 1, 2 and 4 ranks, hex8 and tet4; the
reservoir's added mass lengthens the period as the Rayleigh quotient of the dry mode predicts
(Fenves and Chopra's generalised-coordinate estimate with Westergaard's pressure); /modes and the
mode shapes in the result file; bad options refused."""
import h5py
import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_modes

E, RHO = 1e9, 1000.0


def beam(tmp_path, nu=0.0, modes=8, extra=None):
    L, a = 10.0, 0.5
    meshgen.box(str(tmp_path / "beam.msh"), lo=(0, 0, 0), hi=(a, a, L), n=(2, 2, 40), cell="hex8")
    scene = {"meshes": {"m": "beam.msh"},
             "bodies": {"beam": {"mesh": "m", "regions": "body", "material": {"E": E, "nu": nu, "density": RHO}}},
             "dirichlet": [{"surface": "zmin"}],
             "analysis": {"type": "modal", "modes": modes}, "output": {"fields": ["displacement", "stress"]}}
    scene.update(extra or {})
    return prep(tmp_path, scene), L, a


def test_clamped_beam(tmp_path):
    """Cantilever 0.5 x 0.5 x 10 m, nu = 0 (hex8i): the first axial mode is the 1D rod's
    c / (4 L) exactly but for the mesh (1e-3), recognised by its z effective mass; the first two
    bending pairs are Euler-Bernoulli's 1.8751^2 and 4.6941^2 / (2 pi L^2) sqrt(EI / rho A) within
    the shear deformation of a beam of L/h = 20 (0.5 % and 2 %, below). The x and y pairs are equal
    (square section); the effective masses sum below the total; the modes are mass-normalised in
    the file (phi^T M phi = 1: the sum of the nodal kinetic terms is checked through the lumped
    share rho V / n of every node only roughly, so the file's mode is checked for its frequency)."""
    h5, L, a = beam(tmp_path)
    out = solve(h5).stdout
    assert "Modal analysis" in out and "Rayleigh damping of 5 %" in out
    m = read_modes(result(h5, ".h5"))
    f = m["frequency"]
    I, A = a**4 / 12, a * a
    eb = np.array([1.875104, 4.694091]) ** 2 / (2 * np.pi * L**2) * np.sqrt(E * I / (RHO * A))
    assert f[0] == pytest.approx(f[1], rel=1e-8) and f[2] == pytest.approx(f[3], rel=1e-8)
    assert 0.995 * eb[0] < f[0] < eb[0]  # shear makes the real beam softer
    assert 0.98 * eb[1] < f[2] < eb[1]
    axial = np.argmax(m["effective_mass"][:, 2])
    assert m["effective_mass"][axial, 2] / m["total_mass"][2] > 0.7
    assert f[axial] == pytest.approx(np.sqrt(E / RHO) / (4 * L), rel=1e-3)
    assert np.all(m["effective_mass"].sum(axis=0) <= m["total_mass"] * (1 + 1e-9))
    assert np.allclose(m["period"], 1 / f)
    with h5py.File(result(h5, ".h5")) as h:
        assert np.allclose(h["time"][...], f)  # one output per mode, its time the frequency
    b = read_body(result(h5, ".h5"), "beam", step=0)
    assert b["num_steps"] == 8 and np.abs(b["displacement"]).max() > 0 and "stress" in b


@pytest.mark.parametrize("cell, nproc", [("hex8", 1), ("hex8", 2), ("tet4", 4)])
def test_tied_bodies_equal_one_body(tmp_path, cell, nproc):
    """The beam cut in two at mid-height into two bodies with matching meshes and a couple
    between them (mu 0.5): tied (the default), its frequencies are the one-body mesh's to 1e-9
    (the tie's regularisation is 1e-10 of the stiffest diagonal); untied (-mbc_modal_tie 0) the
    upper body floats: six rigid modes at 0 Hz come first."""
    L, a = 10.0, 0.5
    two, one = tmp_path / "two", tmp_path / "one"
    two.mkdir()
    one.mkdir()
    meshgen.boxes(str(two / "two.msh"), [dict(lo=(0, 0, 0), hi=(a, a, L / 2), n=(2, 2, 10), cell=cell, name="b1"),
                                         dict(lo=(0, 0, L / 2), hi=(a, a, L), n=(2, 2, 10), cell=cell, name="b2")])
    meshgen.box(str(one / "one.msh"), lo=(0, 0, 0), hi=(a, a, L), n=(2, 2, 20), cell=cell)
    mat = {"E": E, "nu": 0.2, "density": RHO}
    h2 = prep(two, {"meshes": {"m": "two.msh"},
                    "bodies": {"b1": {"mesh": "m", "regions": "b1", "material": mat}, "b2": {"mesh": "m", "regions": "b2", "material": mat}},
                    "couples": [{"master": "b1_zmax", "slave": "b2_zmin", "mu": 0.5}],
                    "dirichlet": [{"surface": "b1_zmin"}], "analysis": {"type": "modal", "modes": 6},
                    "output": {"fields": ["displacement"]}})
    h1 = prep(one, {"meshes": {"m": "one.msh"}, "bodies": {"b": {"mesh": "m", "regions": "body", "material": mat}},
                    "dirichlet": [{"surface": "zmin"}], "analysis": {"type": "modal", "modes": 6},
                    "output": {"fields": ["displacement"]}})
    solve(h2, nproc=nproc)
    solve(h1, nproc=1)
    f2, f1 = read_modes(result(h2, ".h5"))["frequency"], read_modes(result(h1, ".h5"))["frequency"]
    assert np.allclose(f2, f1, rtol=1e-9, atol=0), (f2, f1)
    solve(h2, "-mbc_modal_tie", "0", "-mbc_output", str(two / "free"), nproc=nproc)
    ff = read_modes(str(two / "free.h5"))["frequency"]
    assert np.all(ff < 1e-3 * f1[0])  # the floating body's rigid modes


def test_reservoir_lengthens_the_period(tmp_path):
    """A 'dam' block 10 m high, 4 m thick, 2 m wide (hex8i), water 9 m deep on its upstream face:
    the first period lengthens by R_r = T_wet / T_dry. Fenves and Chopra's generalised-coordinate
    form with Westergaard's pressure and the dry mode phi: R_r^2 = 1 + sum m_i phi_x,i^2 /
    phi^T M phi (phi mass-normalised: 1 + sum m_i phi_x,i^2), the Rayleigh quotient of the dry
    mode, an upper bound of omega_wet^2, so a lower bound of R_r: the computed R_r lies within 1 %
    above it. The added mass
    m_i comes from the solver itself (Westergaard, test_seismic.py checks it node by node)."""
    H, level = 10.0, 9.0
    meshgen.box(str(tmp_path / "dam.msh"), lo=(0, 0, 0), hi=(4, 2, H), n=(4, 2, 10), cell="hex8")
    mat = {"E": 25e9, "nu": 0.2, "density": 2400}
    base = {"meshes": {"m": "dam.msh"}, "bodies": {"dam": {"mesh": "m", "regions": "body", "material": mat}},
            "dirichlet": [{"surface": "zmin"}, {"surface": "ymin", "components": "y"}, {"surface": "ymax", "components": "y"}],
            "output": {"fields": ["displacement"]}}
    dry = prep(tmp_path, {**base, "analysis": {"type": "modal", "modes": 1}}, name="dry")
    wet = prep(tmp_path, {**base, "analysis": {"type": "modal", "modes": 1},
                          "added_mass": [{"surface": "xmin", "density": 1000.0, "level": level}]}, name="wet")
    solve(dry)
    solve(wet)
    fd, fw = read_modes(result(dry, ".h5"))["frequency"][0], read_modes(result(wet, ".h5"))["frequency"][0]
    solve(wet, "-mbc_output", str(tmp_path / "wet2"), nproc=2)  # the added mass assembled over two ranks
    assert read_modes(str(tmp_path / "wet2.h5"))["frequency"][0] == pytest.approx(fw, rel=1e-9)
    phi = read_body(result(dry, ".h5"), "dam", step=0)
    x = phi["vertices"]
    # the solver's nodal added masses: the wet run's total x mass minus the dry one's is their sum;
    # per node they are the exact integrals of test_seismic.py, here recomputed on this face
    from scipy.integrate import quad
    face = np.abs(x[:, 0]) < 1e-12
    m = np.zeros(len(x))
    for i in np.flatnonzero(face):
        y, z = x[i, 1], x[i, 2]
        iy = quad(lambda t: max(0.0, 1 - abs(t - y)), max(0, y - 1), min(2, y + 1))[0]
        iz = quad(lambda t: max(0.0, 1 - abs(t - z)) * np.sqrt(max(level - t, 0.0)), max(0, z - 1), min(level, z + 1), limit=200)[0] if z - 1 < level else 0.0
        m[i] = iy * 7 / 8 * 1000.0 * np.sqrt(level) * iz
    mw, md = read_modes(result(wet, ".h5"))["total_mass"], read_modes(result(dry, ".h5"))["total_mass"]
    assert mw[0] - md[0] == pytest.approx(m[x[:, 2] > 0].sum(), rel=1e-9)  # the base row is held
    assert m.sum() == pytest.approx(7 / 12 * 1000 * level**2 * 2, rel=1e-9)
    rr_est = np.sqrt(1 + (m * phi["displacement"][:, 0] ** 2).sum())
    rr = fd / fw
    assert rr > 1.05  # the water matters
    assert rr_est * (1 - 1e-9) <= rr <= 1.01 * rr_est, (rr, rr_est)


def test_modal_errors(tmp_path):
    """Bad modal options and scene keys: one message naming them, exit status 1."""
    h5, L, a = beam(tmp_path, modes=2)
    r = solve(h5, "-mbc_modal_nev", "0", check=False)
    assert r.returncode == 1 and "-mbc_modal_nev 0" in r.stderr
    import subprocess
    import yaml
    from conftest import PREP, env
    (tmp_path / "s.yaml").write_text(yaml.safe_dump({"meshes": {"m": "beam.msh"},
                                                      "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": 1e9, "density": 1}}},
                                                      "analysis": {"type": "modal", "dt": 0.1}}))
    r = subprocess.run([PREP, str(tmp_path / "s.yaml"), "--check"], capture_output=True, text=True, env=env())
    assert r.returncode == 1 and "analysis.dt: a modal analysis has no time steps" in r.stderr
