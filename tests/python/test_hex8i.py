"""hex8 with incompatible modes (hex8i, Wilson-Taylor, CalculiX's C3D8I): the constant-stress patch
test on a distorted mesh, pure bending with two elements through the depth (where plain hex8
locks), the stress at the element centres, dynamics, and the option's errors."""
import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, stress_component

# ---------------------------------------------------------------- (a) patch test


def patch_scene(element=None):
    body = {"mesh": "m", "regions": ["cube"], "material": {"E": 2.0e10, "nu": 0.25}}
    if element:
        body["element"] = element
    return {
        "meshes": {"m": "cube.msh"},
        "bodies": {"cube": body},
        "dirichlet": [{"surface": "xmin", "components": ["x"]}, {"surface": "ymin", "components": ["y"]},
                      {"surface": "zmin", "components": ["z"]}],
        "loads": [{"kind": "traction", "surface": "xmax", "vector": [3.0e6, 0, 0]},
                  {"kind": "pressure", "surface": "ymax", "value": 1.0e6}],
    }


@pytest.mark.parametrize("how,nproc", [("scene", 1), ("option", 2), ("body option", 4)])
def test_patch_test_distorted_hex8i(tmp_path, how, nproc):
    """Constant stress diag(p, -q, 0) on a 3x3x3 hex mesh with interior vertices moved by up to
    0.25 h: Taylor's modification (incompatible gradients with J0, times det J0 / det J) makes
    them integrate to zero over every cell, so a linear field leaves the internal DOFs at 0 and
    hex8i passes the patch test like hex8. Measured: stress error 1.6e-15 p, displacement error
    1.3e-15 of the strain (rounding); asserted 1e-10. Without Taylor's modification (Wilson's
    modes with the Jacobian of each Gauss point) the stress error on this mesh is 3.2 % of p
    (measured once with the element edited), so the test sees a missing modification.
    Chosen three ways (scene key, -body_element, -body_cube_element) on 1, 2, 4 ranks."""
    p, q, Em, nu = 3.0e6, 1.0e6, 2.0e10, 0.25
    meshgen.box(tmp_path / "cube.msh", (0, 0, 0), (1, 1, 1), n=(3, 3, 3), cell="hex8", volume_name="cube", perturb=0.25, seed=7)
    h5 = prep(tmp_path, patch_scene("hex8i" if how == "scene" else None))
    opts = {"scene": (), "option": ("-body_element", "hex8i"), "body option": ("-body_cube_element", "hex8i")}[how]
    r = solve(h5, "-mbc_view", *opts, nproc=nproc)
    assert "(element hex8i)" in r.stdout
    b = read_body(result(h5, ".h5"), "cube")
    x = b["vertices"]
    assert np.ptp(x[b["cells"]][:, :, 0], axis=1).std() > 0.02, "the mesh is not distorted"
    exact = np.array([p, 0, 0, -q, 0, 0])  # xx xy xz yy yz zz
    assert np.abs(b["stress"] - exact).max() < 1e-10 * p
    eps = np.array([p + nu * q, -q - nu * p, -nu * (p - q)]) / Em
    assert np.abs(b["displacement"] - x * eps).max() < 1e-10 * np.abs(eps).max()


# ---------------------------------------------------------------- (b), (c) pure bending

EB, NU, L, H, B, GAMMA = 1.0e9, 0.0, 10.0, 1.0, 1.0, 1.0e6  # sigma_xx = GAMMA y at x = L
KAPPA = GAMMA / EB


def bending_mesh(path, n=(10, 2, 1), distort=0.0):
    """Beam [0, L] x [-H/2, H/2] x [0, B]; distort > 0 makes the cells trapezoids: every
    interior cross-section x_i is tilted, its top moving by (-1)^i distort * dx and its bottom
    by the opposite (MacNeal-Harder's trapezoid pattern); the ends and the y and z faces stay plane."""
    dx = L / n[0]

    def mapping(p):
        p = p.copy()
        i = np.rint(p[:, 0] / dx).astype(int)
        inner = (i > 0) & (i < n[0])
        p[inner, 0] += distort * dx * (2 * p[inner, 1] / H) * (-1.0) ** i[inner]
        return p

    side_names = {s: s for s in ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")}
    part = meshgen._mapped_part("beam", "hex8", (0, -H / 2, 0), (L, H / 2, B), n, mapping, side_names)
    meshgen.write_parts(path, [part])


def bending_scene(element, nu=NU, clamp=False):
    """Pure bending: on x = L the traction sigma_xx = GAMMA y, as a hydrostatic pressure
    GAMMA (H/2 - y) plus a uniform pull GAMMA H/2; x = 0 is a symmetry plane with v = 0 too
    (exact for nu = 0: v = -kappa x^2 / 2), z = 0 a symmetry plane. clamp: x = 0 fixed in all
    directions (a cantilever under an end moment)."""
    return {
        "meshes": {"m": "beam.msh"},
        "bodies": {"beam": {"mesh": "m", "regions": ["beam"], "material": {"E": EB, "nu": nu}, "element": element}},
        "dirichlet": [{"surface": "beam_xmin", "components": "all" if clamp else ["x", "y"]}, {"surface": "beam_zmin", "components": ["z"]}],
        "loads": [{"kind": "hydrostatic", "surface": "beam_xmax", "level": H / 2, "unit_weight": GAMMA, "axis": "y"},
                  {"kind": "traction", "surface": "beam_xmax", "vector": [GAMMA * H / 2, 0, 0]}],
    }


def exact_bending(x, nu=NU):
    """u = kappa x y, v = -kappa (x^2 + nu (y^2 - z^2)) / 2, w = -nu kappa y z: sigma_xx = E kappa y, all else 0."""
    X, Y, Z = x.T
    return np.stack([KAPPA * X * Y, -KAPPA / 2 * (X**2 + nu * (Y**2 - Z**2)), -nu * KAPPA * Y * Z], axis=1)


def run_bending(tmp_path, element, distort=0.0, nproc=1, **kw):
    bending_mesh(tmp_path / "beam.msh", distort=distort)
    h5 = prep(tmp_path, bending_scene(element, **kw))
    solve(h5, nproc=nproc)
    b = read_body(result(h5, ".h5"), "beam")
    x, u = b["vertices"], b["displacement"]
    ue = exact_bending(x, kw.get("nu", NU))
    d = u - ue
    tip = np.argmin(np.linalg.norm(x - [L, 0, 0], axis=1))
    root = np.argmin(np.linalg.norm(x - [0, 0, 0], axis=1))
    deflection = (u[tip, 1] - u[root, 1]) / (-KAPPA * L**2 / 2)  # computed / exact
    return b, deflection, np.abs(d).max() / np.abs(ue).max()


def _mk(tmp_path, name):
    d = tmp_path / name
    d.mkdir()
    return d


@pytest.mark.parametrize("nproc", [1, 2])
def test_pure_bending_hex8i_exact_plain_hex8_locks(tmp_path, nproc):
    """10 x 2 x 1 cells of 1 x 0.5 x 1 (two through the depth), nu = 0. The exact field's
    quadratic term x^2 is a bubble (an incompatible mode) and its bilinear one xy is in Q1, so
    hex8i is exact on this rectangular mesh: measured deflection ratio 1 - 1e-11, nodal error
    1e-11 of max |u| (rounding of the condensation and the factorization; asserted 1e-9). Plain hex8 locks in parasitic shear: measured 0.667 of the
    deflection (asserted < 0.75: the test sees a locking element)."""
    _, ratio8i, err8i = run_bending(_mk(tmp_path, "i"), "hex8i", nproc=nproc)
    assert abs(ratio8i - 1) < 1e-9 and err8i < 1e-9, (ratio8i, err8i)
    _, ratio8, _ = run_bending(_mk(tmp_path, "p"), "hex8", nproc=nproc)
    assert ratio8 < 0.75, ratio8


def test_pure_bending_distorted_mesh(tmp_path):
    """The same beam with trapezoidal cells: every interior cross-section tilted, its top moved by
    +-0.03 dx and its bottom by the opposite (7 degrees). hex8i is no longer exact (the
    trapezoid is its known weakness): measured deflection ratio 0.9912 (distortion 0.01: 0.9990,
    0.05: 0.976, 0.1: 0.911); asserted within 2 %. Plain hex8: 0.663, asserted < 0.75."""
    _, ratio8i, _ = run_bending(_mk(tmp_path, "i"), "hex8i", distort=0.03)
    assert abs(ratio8i - 1) < 0.02, ratio8i
    _, ratio8, _ = run_bending(_mk(tmp_path, "p"), "hex8", distort=0.03)
    assert ratio8 < 0.75, ratio8


def test_cantilever_end_moment_poisson(tmp_path):
    """nu = 0.3, x = 0 clamped (all components), the end moment on x = L: Euler-Bernoulli's
    deflection kappa L^2 / 2 at the tip's neutral axis. hex8i on 10 x 2 x 1 cells: measured
    ratio 0.9844; the clamp, which stops the Poisson contraction at x = 0, stiffens the 3D beam
    by ~1 % (hex8i on 20 x 4 x 2 cells 0.9883, 40 x 8 x 4: 0.9907), so asserted within 2 %.
    Plain hex8: 0.684, asserted < 0.75."""
    _, ratio8i, _ = run_bending(_mk(tmp_path, "i"), "hex8i", nu=0.3, clamp=True)
    assert abs(ratio8i - 1) < 0.02, ratio8i
    _, ratio8, _ = run_bending(_mk(tmp_path, "p"), "hex8", nu=0.3, clamp=True)
    assert ratio8 < 0.75, ratio8


VTK_CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                        [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)


def centre_stress(x, u, E, nu):
    """Stress (xx xy xz yy yz zz) at xi = 0 of every cell from its vertex coordinates x and
    displacements u (nc, 8, 3; VTK order). The incompatible modes' gradients -2 xi vanish there,
    so this is the hex8i stress at the centre whatever the internal DOFs are."""
    dN = VTK_CORNERS / 8  # dN_a / dxi_k at xi = 0
    J = np.einsum("cai,ak->cik", x, dN)
    grad = np.einsum("cai,ak,ckj->cij", u, dN, np.linalg.inv(J))  # du_i / dx_j
    eps = 0.5 * (grad + grad.transpose(0, 2, 1))
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    s = 2 * mu * eps + lam * np.trace(eps, axis1=1, axis2=2)[:, None, None] * np.eye(3)
    return np.stack([s[:, 0, 0], s[:, 0, 1], s[:, 0, 2], s[:, 1, 1], s[:, 1, 2], s[:, 2, 2]], axis=1)


def test_pure_bending_stress_at_centres(tmp_path):
    """(c) Rectangular mesh: hex8i's cell stress is the exact sigma_xx = GAMMA y_c at each
    centre, all other components 0: measured error 4e-12 GAMMA H (asserted 1e-9). The written
    stress is the compatible gradient at the centre, where the incompatible modes' gradients
    vanish (so recovering the internal DOFs changes nothing); on the distorted mesh the written
    stress (9.9 % off the exact there) equals that centre value computed here from the nodal
    displacements to 1e-12 (measured 7e-15): PETSc's P0 projection evaluates at the reference
    centre."""
    b, _, _ = run_bending(_mk(tmp_path, "r"), "hex8i")
    xc = b["vertices"][b["cells"]].mean(axis=1)
    s = b["stress"]
    exact = np.zeros_like(s)
    exact[:, 0] = GAMMA * xc[:, 1]
    assert np.abs(s - exact).max() < 1e-9 * GAMMA * H, np.abs(s - exact).max() / GAMMA
    b, _, _ = run_bending(_mk(tmp_path, "d"), "hex8i", distort=0.1)
    assert np.abs(b["stress"] - exact).max() > 1e-3 * GAMMA * H  # distorted: not exact, the check below means something
    mine = centre_stress(b["vertices"][b["cells"]], b["displacement"][b["cells"]], EB, NU)
    assert np.abs(b["stress"] - mine).max() < 1e-12 * GAMMA * H


# ---------------------------------------------------------------- dynamics


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_dynamic_damped_bar_hex8i(tmp_path, mass):
    """Dynamic (Newmark's effective stiffness K + a0 M + a1 C, the plain hex8 mass: the internal
    modes are massless) on 2 ranks: test_body's damped bar under sudden gravity, hex8i by
    -body_element, settles on the static tip displacement (1e-4, as for hex8) and conserves
    T + U - W + dissipated to 1e-8."""
    damped_bar_settles(tmp_path, "hex8i", mass)


def damped_bar_settles(tmp_path, element, mass):
    """test_body's damped bar under sudden gravity with the element by -body_element, on 2
    ranks: the static tip displacement to 1e-4, T + U - W + dissipated conserved to 1e-8."""
    from test_body import BAR_PERIOD, BAR_STATIC_TIP, bar_scene
    from mbcontact.results import read_csv
    meshgen.box(tmp_path / "bar.msh", (0, 0, 0), (0.05, 0.05, 1.0), n=(1, 1, 20), cell="hex8", volume_name="bar")
    h5 = prep(tmp_path, bar_scene("bar.msh", BAR_PERIOD / 50, 20 * BAR_PERIOD, damping=314.0, every=1000, mass=mass))
    r = solve(h5, "-mbc_view", "-body_element", element, nproc=2)
    assert f"(element {element})" in r.stdout
    tip = read_csv(result(h5, "_points.csv"))
    assert abs(tip["tip_uz"][-1] / BAR_STATIC_TIP - 1) < 1e-4
    e = read_csv(result(h5, "_energy.csv"))
    assert e["damping_dissipation"][-1] > 0.4 * e["external_work"][-1]
    assert np.abs(e["total"] - e["total"][0]).max() < 1e-8 * e["external_work"][-1]


# ---------------------------------------------------------------- (d) errors


@pytest.mark.parametrize("option", ["-body_element", "-body_cube_element"])
def test_bad_element_option(tmp_path, option):
    """An unknown value names the option, the body and the allowed values; exit status 1."""
    meshgen.box(tmp_path / "cube.msh", (0, 0, 0), (1, 1, 1), n=(1, 1, 1), cell="hex8", volume_name="cube")
    h5 = prep(tmp_path, patch_scene())
    r = solve(h5, option, "hex20", check=False)
    text = r.stdout + r.stderr
    assert r.returncode == 1, text
    for w in ("-body_cube_element hex20", "-body_element", "'cube'", "hex8, hex8i or hex8b"):
        assert w in text, (w, text)


def test_bad_element_scene_key(tmp_path):
    """The prep refuses an unknown element (naming the key and the allowed values, hex8b among
    them) and a hex element on a tet body (hex8i and hex8b), naming the key."""
    import subprocess
    from conftest import PREP, env
    import yaml
    for cell, element, words in (("tet4", "hex20", ("bodies.cube.element", "hex20", "hex8, hex8i")),
                                 ("tet4", "hex8i", ("bodies.cube.element", "tet4")),
                                 ("hex8", "hex8c", ("bodies.cube.element", "hex8c", "hex8, hex8i, hex8b")),
                                 ("tet4", "hex8b", ("bodies.cube.element", "tet4"))):
        meshgen.box(tmp_path / "cube.msh", (0, 0, 0), (1, 1, 1), n=(1, 1, 1), cell=cell, volume_name="cube")
        (tmp_path / "s.yaml").write_text(yaml.safe_dump(patch_scene(element)))
        r = subprocess.run([PREP, str(tmp_path / "s.yaml"), "--check"], capture_output=True, text=True, env=env())
        assert r.returncode != 0
        for w in words:
            assert w in r.stderr, (w, r.stderr)


def test_tet_body_ignores_option(tmp_path):
    """-body_element applies to hex bodies only: a tet4 body keeps tet4 (documented in scene.md)."""
    meshgen.box(tmp_path / "cube.msh", (0, 0, 0), (1, 1, 1), n=(1, 1, 1), cell="tet4", volume_name="cube")
    h5 = prep(tmp_path, patch_scene())
    r = solve(h5, "-mbc_view", "-body_element", "hex8i")
    assert "(element tet4)" in r.stdout
