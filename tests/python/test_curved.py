"""A curved conforming contact interface (issue 17, docs/stability-curved.md): the lame scene of
bench/extremes_poisson.py, two concentric quarter tubes 1 <= r <= 1.5 and 1.5 <= r <= 2 (3 x 12 x 1
hex8b cells each, matching vertices at r = 1.5), frictionless, plane strain, symmetry planes,
internal pressure p. The problem is symmetric about the 45 degree plane and, by Lame, the interface
pressure is uniform: q = p a^2 / (b^2 - a^2) (b^2 / c^2 - 1) with a = 1, c = 1.5, b = 2.

Before the fix the contact normal of a point on a slave vertex was the normal of whichever of the
two faces the tie rule picked (always the same side), tilted by half the facet angle (3.75 deg):
the pressure fell from 1.055 q at theta = 0 to 0.946 q at 90 deg (asymmetry 0.11 q), and with the
concave face as slave the static iteration flipped the point between the two faces every iterate
("no equilibrium after 50 iterations"). Measured after (hex8b, nu 0 ... 0.499, either side as
master, integrated or collocated): every interior node 0.9970 ... 0.9974 q, the two symmetry-plane
nodes 0.9991 ... 0.9996 q (their slave vertex has one face: its normal is 3.75 deg off radial),
symmetric to 6e-11 q, both sides as master equal to 1e-9, 2 static iterations. Tolerances:
PRESSURE_TOL 1 % (3x the discretization error, 0.30 %, one fifth of the defect's 5.5 %);
symmetry 1e-6 q; either side as master 1e-6. About 15 s."""
import numpy as np
import pytest

from conftest import load_script, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_contact

ep = load_script("bench/extremes_poisson.py", "bench_extremes_poisson")

PRESSURE_TOL = 0.01  # every node's pressure against Lame's q (measured worst 0.30 %, the defect 5.5 %)
SYMMETRY_TOL = 1e-6  # |p(theta) - p(90 - theta)| / q (measured <= 6e-11, the defect 0.11)
SWAP_TOL = 1e-6      # either side as master: displacements / max|u|, pressures / q (measured <= 1e-9)
Q = ep.P * ep.RA**2 / (ep.RC**2 - ep.RA**2) * (ep.RC**2 / ep.RB**2 - 1)  # Lame's interface pressure
SLAVES = {"convex": ("tout_inner", "tin_curved"), "concave": ("tin_curved", "tout_inner")}  # (master, slave)


def lame(tmp_path, nu, slave, *options, n_in=(3, 12, 1), n_out=(3, 12, 1)):
    """The lame scene with the given face as slave; returns (contact datasets, bodies, monitor)."""
    kw = dict(center=(0, 0, ep.LZ / 2), length=ep.LZ, axis_dir=(0, 0, 1), mid_dir=(1, 1, 0), angle_deg=90.0, cell="hex8")
    meshgen.write_parts(str(tmp_path / "lame.msh"), [meshgen.cylinder_block("tin", radius=ep.RB, inner=ep.RA / ep.RB, n=n_in, **kw),
                                                     meshgen.cylinder_block("tout", radius=ep.RC, inner=ep.RB / ep.RC, n=n_out, **kw)])
    scene = ep.lame_scene("lame.msh", nu, "hex8b")
    master, slave_face = SLAVES[slave]
    scene["couples"] = [{"master": master, "slave": slave_face, "mu": 0.0}]
    h5 = prep(tmp_path, scene)
    r = solve(h5, "-mbc_monitor", *options)
    bodies = {b: read_body(result(h5, ".h5"), b) for b in ("tin", "tout")}
    return read_contact(result(h5, ".h5")), bodies, r.stdout


def theta(x):
    return np.degrees(np.arctan2(x[:, 1], x[:, 0]))


@pytest.mark.parametrize("integrate", [1, 0])
@pytest.mark.parametrize("slave", ["convex", "concave"])
@pytest.mark.parametrize("nu", [0.0, 0.3, 0.499])
def test_lame_interface_pressure_is_uniform_and_symmetric(tmp_path, nu, slave, integrate):
    c, _, out = lame(tmp_path, nu, slave, "-mbc_contact_integrate", str(integrate))
    x, p = c["reference"], c["pressure"] / Q
    th = theta(x)
    assert len(p) == 26, len(p)  # 13 vertices x 2 ends, every master node in contact
    assert np.all(np.abs(p - 1) < PRESSURE_TOL), f"p/q {p.min():.5f} ... {p.max():.5f} at theta {th[p.argmin()]:.2f}, {th[p.argmax()]:.2f}"
    mirror = {(round(t, 6), round(z, 6)): v for t, z, v in zip(th, x[:, 2], p)}
    asym = max(abs(v - mirror[(round(90 - t, 6), round(z, 6))]) for (t, z), v in mirror.items())
    assert asym < SYMMETRY_TOL, f"p(theta) - p(90 - theta) up to {asym:.3g} q"
    # the contact normal of an interior node is radial (both faces around its slave vertex agree)
    radial = np.c_[x[:, 0], x[:, 1], 0 * x[:, 0]] / np.hypot(x[:, 0], x[:, 1])[:, None]
    inner = (th > 1e-6) & (th < 90 - 1e-6)
    cosine = np.abs(np.einsum("ij,ij->i", c["normal"][inner], radial[inner]))
    assert np.all(cosine > 1 - 1e-12), f"normal off radial by up to {np.degrees(np.arccos(cosine.min())):.3g} deg"
    assert out.count("static iteration") <= 3, out  # measured 2 (before: 4, and 50 then failure with the concave slave)


@pytest.mark.parametrize("integrate", [1, 0])
def test_lame_either_side_as_master(tmp_path, integrate):
    """The concave face as slave was refused (no equilibrium after 50 iterations); now either side
    as master gives the same answer (matching meshes: to rounding and the multiplier tolerance)."""
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
    a = lame(tmp_path / "a", 0.3, "convex", "-mbc_contact_integrate", str(integrate))
    b = lame(tmp_path / "b", 0.3, "concave", "-mbc_contact_integrate", str(integrate))
    for body in ("tin", "tout"):
        ua, ub = a[1][body]["displacement"], b[1][body]["displacement"]
        scale = np.abs(ua).max()
        assert np.abs(ua - ub).max() < SWAP_TOL * scale, f"{body}: {np.abs(ua - ub).max() / scale:.3g}"
    # the same points (the contact points sit on the master nodes, which coincide here)
    ka = {tuple(np.round(x, 9)): v for x, v in zip(a[0]["reference"], a[0]["pressure"])}
    kb = {tuple(np.round(x, 9)): v for x, v in zip(b[0]["reference"], b[0]["pressure"])}
    assert ka.keys() == kb.keys()
    assert max(abs(ka[k] - kb[k]) for k in ka) < SWAP_TOL * Q
