"""Time integration beyond Newmark's defaults, against closed forms: Newmark, HHT-alpha and
generalized-alpha reproduce their own one-DOF recurrence step by step (so their spectral radius
and numerical damping are the closed-form ones), generalized-alpha converges at second order
(one DOF, and HHT too on a block sliding against friction and springs),
a spring-dashpot oscillator follows its damped solution, initial conditions from the scene and from
Python, and a bar set moving at 1 m/s hits another (SDNL111-like) with the impedance's force.
One-element or 40-element models: about a second each."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import BUILD, ROOT, env, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import point_history, read_body, read_csv

# One hex8 cube [0,1]^3, nu = 0, held at x = 0 and in y, z everywhere: its x = 1 face moving as
# one (the uniform mode u = U x, exact for the symmetric initial state) is a single DOF of
# stiffness E A / L and consistent mass rho A L / 3: omega^2 = 3 E / rho.
E1, RHO1, U0 = 3.0e3, 1.0, 1.0e-3
OMEGA1 = math.sqrt(3 * E1 / RHO1)


def one_dof_scene(tmp_path, analysis, name="one", initial=True):
    meshgen.box(str(tmp_path / "cube.msh"), (0, 0, 0), (1, 1, 1), n=(1, 1, 1))
    scene = {
        "meshes": {"m": "cube.msh"},
        "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": E1, "nu": 0.0, "density": RHO1}}},
        "node_sets": {"tip": {"plane": {"point": [1, 0, 0], "normal": [1, 0, 0]}}},
        "dirichlet": [{"surface": "xmin", "components": "all"}, {"body": "b", "components": ["y", "z"]}],
        "analysis": dict(type="dynamic", **analysis),
        "output": {"every": 1000000, "fields": ["displacement"], "energy": True,
                   "points": {"p": {"x": [1, 1, 1], "body": "b"}}},
    }
    if initial:
        scene["initial"] = [{"nodes": "tip", "displacement": [U0, 0, 0]}]
    return prep(tmp_path, scene, name=name)


def weights(scheme, rho_inf=0.8, alpha=-0.3, beta=0.25, gamma=0.5):
    """(alpha_m, alpha_f, beta, gamma) of each scheme (Chung and Hulbert 1993; HHT in Code_Aster's sign)."""
    if scheme == "newmark":
        return 0.0, 0.0, beta, gamma
    am, af = (0.0, -alpha) if scheme == "hht" else ((2 * rho_inf - 1) / (rho_inf + 1), rho_inf / (rho_inf + 1))
    return am, af, 0.25 * (1 - am + af) ** 2, 0.5 - am + af


def amplification(w, h, am, af, beta, gamma):
    """The scheme's one-step matrix on (u, h v, h^2 a) of u'' + w^2 u = 0, in closed form: the
    balance (1 - am) a1 + am a0 + w^2 ((1 - af) u1 + af u0) = 0 with Newmark's updates."""
    k = (w * h) ** 2
    A = np.zeros((3, 3))
    for j, x0 in enumerate(np.eye(3)):
        u, v, a = x0  # v, a scaled by h, h^2
        a1 = (-am * a - k * af * u - k * (1 - af) * (u + v + (0.5 - beta) * a)) / ((1 - am) + k * (1 - af) * beta)
        u1 = u + v + (0.5 - beta) * a + beta * a1
        v1 = v + (1 - gamma) * a + gamma * a1
        A[:, j] = (u1, v1, a1)
    return A


def recurrence(w, h, n, params):
    A = amplification(w, h, *params)
    x = np.array([U0, 0.0, -(w * h) ** 2 * U0])  # a_0 from the equation at t = 0
    out = [x[0]]
    for _ in range(n):
        x = A @ x
        out.append(x[0])
    return np.array(out)


SCHEMES = [("newmark", {}), ("hht", {"alpha": -0.3}), ("generalized_alpha", {"rho_inf": 0.5})]


@pytest.mark.parametrize("scheme,extra", SCHEMES, ids=[s for s, _ in SCHEMES])
def test_scheme_is_its_recurrence(tmp_path, scheme, extra):
    """At omega h = 0.3 and at omega h = 200 (a mode far above what the step resolves) the tip's
    displacement is the scheme's closed-form recurrence, step by step, to 1e-9 of U0 (the
    direct solve's rounding): so the numerical damping is the closed form's, whose spectral radius
    at omega h -> infinity is rho_inf (generalized-alpha), (1 + alpha) / (1 - alpha) (HHT) and 1
    (the trapezoidal rule). At omega h = 200 the dissipative schemes take 95 % of the amplitude
    in 12 steps (the trapezoidal rule none: its recurrence is a rotation)."""
    params = weights(scheme, **extra)
    for wh, steps in ((0.3, 60), (200.0, 12)):
        dt = wh / OMEGA1
        analysis = {"dt": dt, "final_time": steps * dt}
        if scheme != "newmark":
            analysis.update(scheme=scheme, **extra)
        h5 = one_dof_scene(tmp_path, analysis, name=f"s{int(wh)}")
        solve(h5)
        u = point_history(result(h5, "_points.csv"), "p")["u"][:, 0]
        assert len(u) == steps + 1
        expected = recurrence(OMEGA1, dt, steps, params)
        assert np.abs(u - expected).max() < 1e-9 * U0, (scheme, wh, u, expected)
    radius = max(abs(np.linalg.eigvals(amplification(OMEGA1, 1e6 / OMEGA1, *params))))
    limit = {"newmark": 1.0, "hht": (1 - 0.3) / (1 + 0.3), "generalized_alpha": 0.5}[scheme]
    assert abs(radius - limit) < 1e-3
    if scheme != "newmark":  # the high mode's amplitude at omega h = 200: 12 steps took most of it
        assert abs(u[-1]) < 0.05 * U0


def test_generalized_alpha_second_order(tmp_path):
    """rho_inf = 0.8: the error against U0 cos(omega t) over one period falls by 4 (3.6 to 4.4)
    per halving of the step, from T/20 to T/80 (a first-order scheme, e.g. rho_inf with gamma
    != 1/2 - am + af, would halve it)."""
    period = 2 * math.pi / OMEGA1
    errors = []
    for n in (20, 40, 80):
        h5 = one_dof_scene(tmp_path, {"dt": period / n, "final_time": period, "scheme": "generalized_alpha",
                                      "rho_inf": 0.8}, name=f"n{n}")
        solve(h5)
        p = point_history(result(h5, "_points.csv"), "p")
        errors.append(np.abs(p["u"][:, 0] - U0 * np.cos(OMEGA1 * p["t"])).max())
    ratios = [errors[i] / errors[i + 1] for i in range(2)]
    assert all(3.6 < r < 4.4 for r in ratios), (errors, ratios)


SLIDE_MU, SLIDE_K, SLIDE_F = 0.3, 4.0e4, 6.0e3
SLIDE_PERIOD = 2 * math.pi / math.sqrt(SLIDE_K / 1000.0)


def sliding_block_scene(tmp_path, n, analysis, name):
    """A 1 m cube (1 000 kg, stiff: E 1e10) resting on a rigid base with mu = 0.3, held back by
    springs of 40 kN/m in all (10 kN/m at each top corner), pushed by 6 kPa on its side from t = 0
    under gravity: it slides forward from rest, x(t) = (F - mu m g) / k (1 - cos omega t), until
    it stops at T / 2. Run to T / 4 with dt = T / n."""
    meshgen.boxes(str(tmp_path / "slide.msh"), [dict(lo=(-0.5, -0.5, -1), hi=(1.5, 1.5, 0), n=(2, 2, 1), name="base"),
                                                dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), name="block")])
    dt = float(SLIDE_PERIOD / n)
    always = {"table": [[0, 1], [100, 1]]}
    return prep(tmp_path, {
        "meshes": {"m": "slide.msh"},
        "node_sets": {"top": {"plane": {"point": [0, 0, 1], "normal": [0, 0, 1]}, "bodies": ["block"]}},
        "bodies": {"base": {"mesh": "m", "regions": "base", "rigid": True},
                   "block": {"mesh": "m", "regions": "block", "material": {"E": 1.0e10, "nu": 0.0, "density": 1000.0}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": SLIDE_MU}],
        "dirichlet": [{"body": "base"}, {"body": "block", "components": ["y"]}],
        "springs": [{"nodes": "top", "stiffness": [SLIDE_K / 4, 0, 0]}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "time": always},
                  {"kind": "pressure", "surface": "block_xmin", "value": SLIDE_F, "time": always}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": float(n // 4 * dt), **analysis},
        "output": {"every": 1000000, "points": {"c": {"x": [0, 0, 1], "body": "block"}}},
    }, name=name)


@pytest.mark.parametrize("analysis", [{"scheme": "generalized_alpha", "rho_inf": 0.8}, {"scheme": "hht", "alpha": -0.3}],
                         ids=["generalized_alpha", "hht"])
def test_second_order_on_a_sliding_block(tmp_path, analysis):
    """The block sliding against friction and its springs (sliding_block_scene): its displacement
    at T / 4 converges at second order with the contact in every step, the error falling by 4
    (3.6 to 4.4; measured 3.95 and 3.98 for generalized-alpha, 3.87 and 3.95 for HHT) per halving
    of the step from T / 20 to T / 80 (Newmark with gamma 0.6, first order: 2.5 and 2.3), and within 1.5e-3 of
    the exact value at T / 80 (measured 8.5e-4 and 1.2e-3)."""
    omega = 2 * math.pi / SLIDE_PERIOD
    errors = []
    for n in (20, 40, 80):
        h5 = sliding_block_scene(tmp_path, n, analysis, f"slide{n}")
        solve(h5)
        p = point_history(result(h5, "_points.csv"), "c")
        t, x = p["t"][-1], p["u"][-1, 0]
        exact = (SLIDE_F - SLIDE_MU * 1000.0 * 9.81) / SLIDE_K * (1 - math.cos(omega * t))
        assert abs(t - SLIDE_PERIOD / 4) < SLIDE_PERIOD / 80
        errors.append(abs(x - exact) / exact)
    ratios = [errors[i] / errors[i + 1] for i in range(2)]
    assert all(3.6 < r < 4.4 for r in ratios), (errors, ratios)
    assert errors[-1] < 1.5e-3, errors


def test_spring_dashpot_oscillator(tmp_path):
    """A stiff cube (E 1e9, 1000 kg) free along x on eight springs k = 1e5 N/m and dashpots c to
    the ground, started at v0 = 1 m/s: the uniform motion is an exact mode (K and the dashpots
    are k I, c I on it, M's rows sum to m / 8), so u = v0 / wd exp(-zeta w t) sin(wd t), w^2 =
    8 k / m, zeta = 0.05. Trapezoidal rule at T / 200: the phase error (w h)^2 / 12 per radian
    over 4 pi radians is 1.0e-3 of the amplitude at most; measured 5.5e-4. The energy balance
    closes (total 0 to 1e-9 of the initial kinetic energy 500 J)."""
    rho, k, zeta, v0 = 1000.0, 1.0e5, 0.05, 1.0
    w = math.sqrt(8 * k / rho)
    c = 2 * zeta * math.sqrt(8 * k * rho) / 8
    period = 2 * math.pi / w
    meshgen.box(str(tmp_path / "cube.msh"), (0, 0, 0), (1, 1, 1), n=(1, 1, 1))
    h5 = prep(tmp_path, {
        "meshes": {"m": "cube.msh"},
        "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": 1.0e9, "nu": 0.0, "density": rho}}},
        "dirichlet": [{"body": "b", "components": ["y", "z"]}],
        "springs": [{"nodes": "body", "stiffness": [k, 0, 0], "damping": [c, 0, 0]}],
        "initial": [{"body": "b", "velocity": [v0, 0, 0]}],
        "analysis": {"type": "dynamic", "dt": period / 200, "final_time": 2 * period},
        "output": {"every": 1000000, "fields": ["displacement"], "energy": True,
                   "points": {"p": {"x": [1, 1, 1], "body": "b"}}},
    })
    solve(h5)
    p = point_history(result(h5, "_points.csv"), "p")
    wd = w * math.sqrt(1 - zeta ** 2)
    exact = v0 / wd * np.exp(-zeta * w * p["t"]) * np.sin(wd * p["t"])
    assert np.abs(p["u"][:, 0] - exact).max() < 1.0e-3 * v0 / w
    e = read_csv(result(h5, "_energy.csv"))
    assert abs(e["kinetic"][0] / (0.5 * rho * v0 ** 2) - 1) < 1e-12
    assert np.abs(e["total"]).max() < 1e-9 * 500
    assert e["damping_dissipation"][-1] > 0.5 * 500  # zeta w t = 0.05 * 4 pi: 1 - exp(-2 zeta w t) = 0.72 of it


def test_initial_state_from_python(tmp_path):
    """Body.setInitialState before solve(): the same run as the scene's `initial` (to rounding),
    not overwritten by the dynamic start; on a static start it is refused, not ignored."""
    dt = 0.3 / OMEGA1
    h5 = one_dof_scene(tmp_path, {"dt": dt, "final_time": 10 * dt}, name="scene")
    solve(h5)
    expected = point_history(result(h5, "_points.csv"), "p")["u"][:, 0]
    bare = one_dof_scene(tmp_path, {"dt": dt, "final_time": 10 * dt}, name="bare", initial=False)
    script = tmp_path / "drive.py"
    script.write_text(f"""
import sys
import mbcontact
from mbcontact.results import point_history
scene = mbcontact.Scene(); scene.load({str(bare)!r})
s = mbcontact.Solver(); s.create(); s.setScene(scene); s.setFromOptions(); s.setUp()
b = s.getBody(0)
u0 = b.getDisplacement().duplicate(); u0.set(0.0)
coords = b.getDM().getCoordinates().getArray().reshape(-1, 3)
x = u0.getArray().reshape(-1, 3)  # the body's owned nodes in the coordinates' order (one rank, vertices only)
x[coords[:, 0] > 0.5, 0] = {U0!r}
b.setInitialState(u0, None)
s.solve()
""")
    e = env()
    e["PYTHONPATH"] = os.pathsep.join([os.path.join(ROOT, "python"), os.path.join(BUILD, "python")])
    r = subprocess.run([sys.executable, str(script)],
                       capture_output=True, text=True, env=e, timeout=120)
    assert r.returncode == 0, r.stderr
    u = point_history(result(bare, "_points.csv"), "p")["u"][:, 0]
    assert np.abs(u - expected).max() < 1e-12 * U0 + 1e-15
    r = solve(h5, "-mbc_analysis", "static", "-mbc_dt", "1", "-mbc_final_time", "1", check=False)
    assert r.returncode != 0 and "initial displacement or velocity" in r.stderr and "'b'" in r.stderr


L_BAR, A_BAR, N_BAR = 1.0, 0.01, 20  # two bars 1 m long, 0.1 x 0.1 m, E = rho = 1: c = 1 m/s


@pytest.mark.parametrize("nproc", [1, 2])
def test_two_bars_impact(tmp_path, nproc):
    """SDNL111-like: bar 1 starts at v0 = 1 m/s (`initial`) against bar 2 at rest, frictionless,
    nu = 0 and y, z held (a 1D wave). Exact: the contact force is rho c A v0 / 2 = 5e-3 N from
    t = 0 to 2 L / c = 2 s, then both bars part, bar 1 at rest and bar 2 at v0. Generalized-alpha
    (rho_inf 0.8) at c dt / dx = 1/2: the force's median over 0.3 to 1.7 s within 2 % (measured
    0.01 %), contact ending at 2 s within two steps, the impulse m v0 = 1e-2 N s within 2 %
    (measured 1.5 %) and bar 2's mass centre moving at v0 after parting within 2 %."""
    meshgen.boxes(str(tmp_path / "bars.msh"), [
        dict(lo=(0, 0, 0), hi=(L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar1"),
        dict(lo=(L_BAR, 0, 0), hi=(2 * L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar2")])
    dt = 0.025
    h5 = prep(tmp_path, {
        "meshes": {"m": "bars.msh"},
        "bodies": {b: {"mesh": "m", "regions": b, "material": {"E": 1.0, "nu": 0.0, "density": 1.0}}
                   for b in ("bar1", "bar2")},
        "couples": [{"master": "bar1_xmax", "slave": "bar2_xmin"}],
        "dirichlet": [{"body": "bar1", "components": ["y", "z"]}, {"body": "bar2", "components": ["y", "z"]}],
        "initial": [{"body": "bar1", "velocity": [1.0, 0, 0]}],
        "analysis": {"type": "dynamic", "dt": dt, "final_time": 3.0, "scheme": "generalized_alpha", "rho_inf": 0.8},
        "output": {"every": 20, "fields": ["displacement"], "energy": True},
    })
    solve(h5, nproc=nproc)
    c = read_csv(result(h5, "_contact.csv"))
    t, f = c["t"], c["normal_force"]
    plateau = A_BAR / 2
    assert abs(np.median(f[(t > 0.3) & (t < 1.7)]) / plateau - 1) < 0.02
    touching = t[f > 1e-3 * plateau]
    assert abs(touching.max() - 2 * L_BAR) <= 2 * dt and touching.min() <= dt
    assert abs(np.sum(f[1:]) * dt / (A_BAR * L_BAR) - 1) < 0.02
    # bar 2's mass centre (nodal weights of a uniform 1D mesh: dx, dx / 2 at the ends) from t = 2.5 to 3
    moved = []
    for step in (-2, -1):
        r = read_body(result(h5, ".h5"), "bar2", step=step)
        x = r["vertices"][:, 0]
        w = np.where((np.abs(x - L_BAR) < 1e-9) | (np.abs(x - 2 * L_BAR) < 1e-9), 0.5, 1.0)
        moved.append((r["time"], np.sum(w * r["displacement"][:, 0]) / np.sum(w)))
    velocity = (moved[1][1] - moved[0][1]) / (moved[1][0] - moved[0][0])
    assert abs(velocity - 1.0) < 0.02, moved


def test_initial_field_and_stages(tmp_path):
    """The initial displacement as a point field of the mesh file (`{field: u0}`, u0 = (U0 x, 0,
    0)) gives the nodes' U0 at the tip as `nodes: tip` does; two dynamic stages, Newmark's
    trapezoidal rule for 10 steps then generalized-alpha (rho_inf 0.5) for 10, follow the chained
    closed-form recurrences (the second stage starting from the first's u, v and the acceleration
    its forces give) to 1e-9 of U0."""
    import meshio
    meshgen.box(str(tmp_path / "cube.msh"), (0, 0, 0), (1, 1, 1), n=(1, 1, 1))
    m = meshio.read(str(tmp_path / "cube.msh"))
    m.point_data = {"u0": np.column_stack([U0 * m.points[:, 0], 0 * m.points[:, 0], 0 * m.points[:, 0]])}
    meshio.write(str(tmp_path / "cube_u0.msh"), m, file_format="gmsh22", binary=False)
    dt = 0.3 / OMEGA1
    h5 = prep(tmp_path, {
        "meshes": {"m": "cube_u0.msh"},
        "bodies": {"b": {"mesh": "m", "regions": "body", "material": {"E": E1, "nu": 0.0, "density": RHO1}}},
        "dirichlet": [{"surface": "xmin", "components": "all"}, {"body": "b", "components": ["y", "z"]}],
        "initial": [{"body": "b", "displacement": {"field": "u0"}}],
        "stages": [{"name": "trapezoidal", "analysis": {"type": "dynamic", "dt": dt, "final_time": 10 * dt}},
                   {"name": "dissipative", "analysis": {"type": "dynamic", "dt": dt, "final_time": 20 * dt,
                                                        "scheme": "generalized_alpha", "rho_inf": 0.5}}],
        "output": {"every": 1000000, "fields": ["displacement"], "points": {"p": {"x": [1, 1, 1], "body": "b"}}},
    })
    solve(h5)
    u = point_history(result(h5, "_points.csv"), "p")["u"][:, 0]
    x = np.array([U0, 0.0, -(OMEGA1 * dt) ** 2 * U0])
    expected = [x[0]]
    for params in (weights("newmark"), weights("generalized_alpha", rho_inf=0.5)):
        x[2] = -(OMEGA1 * dt) ** 2 * x[0]  # a stage starts from M a = F - K u
        A = amplification(OMEGA1, dt, *params)
        for _ in range(10):
            x = A @ x
            expected.append(x[0])
    assert len(u) == 21 and np.abs(u - np.array(expected)).max() < 1e-9 * U0


def test_generalized_alpha_restart(tmp_path):
    """The two-bar impact under generalized-alpha checkpointed at step 40 of 80 (mid-contact: the
    force average needs lambda_n) and restarted: the last step's displacements equal the
    uninterrupted run's to 1e-12."""
    meshgen.boxes(str(tmp_path / "bars.msh"), [
        dict(lo=(0, 0, 0), hi=(L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar1"),
        dict(lo=(L_BAR, 0, 0), hi=(2 * L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar2")])
    h5 = prep(tmp_path, {
        "meshes": {"m": "bars.msh"},
        "bodies": {b: {"mesh": "m", "regions": b, "material": {"E": 1.0, "nu": 0.0, "density": 1.0}}
                   for b in ("bar1", "bar2")},
        "couples": [{"master": "bar1_xmax", "slave": "bar2_xmin"}],
        "dirichlet": [{"body": "bar1", "components": ["y", "z"]}, {"body": "bar2", "components": ["y", "z"]}],
        "initial": [{"body": "bar1", "velocity": [1.0, 0, 0]}],
        "analysis": {"type": "dynamic", "dt": 0.025, "final_time": 2.0, "scheme": "generalized_alpha"},
        "output": {"every": 1000000, "fields": ["displacement"]},
    })
    solve(h5, "-mbc_output", str(tmp_path / "full"))
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "40", "-mbc_final_time", "1.0")
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor")
    assert "restarted from" in r.stdout
    for body in ("bar1", "bar2"):
        a = read_body(str(tmp_path / "full.h5"), body)
        b = read_body(part + "_restart.h5", body)
        assert a["time"] == b["time"] == pytest.approx(2.0)
        assert np.abs(a["displacement"] - b["displacement"]).max() <= 1e-12 * np.abs(a["displacement"]).max()


def two_bars_scene(tmp_path, cell="hex8", final_time=3.0, every=20, analysis=None):
    """The two bars of test_two_bars_impact under the scene's default scheme (Newmark's
    trapezoidal rule) unless `analysis` adds to it; c dt / dx = 1/2."""
    meshgen.boxes(str(tmp_path / "bars.msh"), [
        dict(lo=(0, 0, 0), hi=(L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar1", cell=cell),
        dict(lo=(L_BAR, 0, 0), hi=(2 * L_BAR, 0.1, 0.1), n=(N_BAR, 1, 1), name="bar2", cell=cell)])
    return prep(tmp_path, {
        "meshes": {"m": "bars.msh"},
        "bodies": {b: {"mesh": "m", "regions": b, "material": {"E": 1.0, "nu": 0.0, "density": 1.0}}
                   for b in ("bar1", "bar2")},
        "couples": [{"master": "bar1_xmax", "slave": "bar2_xmin"}],
        "dirichlet": [{"body": "bar1", "components": ["y", "z"]}, {"body": "bar2", "components": ["y", "z"]}],
        "initial": [{"body": "bar1", "velocity": [1.0, 0, 0]}],
        "analysis": {"type": "dynamic", "dt": 0.025, "final_time": final_time, **(analysis or {})},
        "output": {"every": every, "fields": ["displacement"], "energy": True},
    })


def bar_velocity(h5, body, x0):
    """A bar's mass-centre velocity between the last two outputs (nodal weights of a uniform 1D
    mesh: dx, dx / 2 at the ends; a free bar's mass centre moves uniformly)."""
    moved = []
    for step in (-2, -1):
        r = read_body(result(h5, ".h5"), body, step=step)
        x = r["vertices"][:, 0]
        w = np.where((np.abs(x - x0) < 1e-9) | (np.abs(x - x0 - L_BAR) < 1e-9), 0.5, 1.0)
        moved.append((r["time"], np.sum(w * r["displacement"][:, 0]) / np.sum(w)))
    return (moved[1][1] - moved[0][1]) / (moved[1][0] - moved[0][0])


@pytest.mark.parametrize("cell,nproc", [("hex8", 1), ("hex8", 2), ("tet4", 1), ("tet4", 2)])
def test_two_bars_part_with_the_default_scheme(tmp_path, cell, nproc):
    """The two bars with Newmark's trapezoidal rule (the default) part as the exact solution
    does: bar 1 at rest, bar 2 at v0 = 1 m/s. The contact points are separated for the steps
    before the search loses them (tet4: their slave faces change while separated) and carry the
    rule's period-2 oscillation of the multipliers; released at that rebuild, their force goes
    on as a separated point's (src/interface/interfacerelease.c). Before, their last force stayed
    in the acceleration alone and kicked the bars apart: bar 2 at 1.49 (hex8) or 1.39 m/s (tet4)
    with 28 or 37 times the impact's energy. Measured now: velocities 0.0142 and 0.9858 (hex8),
    0.0087 and 0.9913 (tet4), the same as generalized-alpha with rho_inf 1 gives (the trapezoidal
    rule in the alpha form, lambda_n applied explicitly); the 1-1.5 % is the impulse the
    discrete contact misses (test_two_bars_impact: 1.5 %), hence 2 %. Kinetic plus strain energy
    never above the impact's (the contact only dissipates, 0.07-0.7 % here) and the energy
    balance closed to 1e-10 of it (measured 1e-13)."""
    h5 = two_bars_scene(tmp_path, cell)
    solve(h5, nproc=nproc)
    e = read_csv(result(h5, "_energy.csv"))
    e0 = 0.5 * L_BAR * A_BAR * 1.0  # (1/2) m v0^2
    mech = e["kinetic"] + e["strain"]
    assert abs(mech[0] / e0 - 1) < 1e-12
    assert mech.max() <= e0 * (1 + 1e-12), mech.max() / e0
    assert np.abs(e["total"]).max() < 1e-10 * e0
    v1, v2 = bar_velocity(h5, "bar1", 0.0), bar_velocity(h5, "bar2", L_BAR)
    assert abs(v1) < 0.02 and abs(v2 - 1) < 0.02, (v1, v2)


def test_two_bars_release_restart(tmp_path):
    """Checkpointed at t = 2.5 s (steps after the contact points were released: their force is
    in the acceleration and in the checkpoint, `contact_force_released`) and restarted: the last
    step's displacements equal the uninterrupted run's to 1e-12."""
    import h5py
    h5 = two_bars_scene(tmp_path, final_time=3.0, every=1000000)
    solve(h5, "-mbc_output", str(tmp_path / "full"))
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "100", "-mbc_final_time", "2.5")
    with h5py.File(part + "_checkpoint.h5", "r") as f:
        released = [np.abs(f[f"bodies/{b}/contact_force_released"][:]).max() for b in ("bar1", "bar2")]
    assert min(released) > 1e-4 * A_BAR, released  # the force the restart must go on with (~A_BAR / 2)
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor")
    assert "restarted from" in r.stdout
    for body in ("bar1", "bar2"):
        a = read_body(str(tmp_path / "full.h5"), body)
        b = read_body(part + "_restart.h5", body)
        assert a["time"] == b["time"] == pytest.approx(3.0)
        assert np.abs(a["displacement"] - b["displacement"]).max() <= 1e-12 * np.abs(a["displacement"]).max()
