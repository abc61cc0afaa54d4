"""Contact points on prescribed nodes (docs/design.md, "Prescribed contact nodes"): no traction
along a direction both sides are held in (a symmetry plane across the load), whatever the
point's frame; nodes taken out of contact (a couple's `exclude`), the warning naming a node
prescribed on its side only, and the contact resultant against the reactions."""
import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_contact, read_csv


@pytest.mark.parametrize("nproc", [1, 2, 4])
def test_no_traction_across_a_symmetry_plane(tmp_path, nproc):
    """A block (E 10 GPa, nu 0.4) on a base (E 20 GPa, nu 0.1), both halves of a symmetric model
    with u_y = 0 on their y = 0 faces, pressed by p = 1 MPa and sheared along x by 0.3 p (mu 0.6,
    static). The meshes do not match (3 x 3 block faces on 5 x 5 base faces), so a master node on
    the plane has mortar weights on base nodes off it, which expand sideways unlike the block:
    before, a multiplier across the plane resisted that, |q_y| up to 0.13 mu p at the points on
    the plane, where symmetry makes it 0. Now q_y = 0 there (< 1e-8 mu p) at 1, 2 and 4 ranks,
    while the points off the plane carry a q_y (friction against the Poisson expansion), and the
    resultants balance the loads: fx = -0.3 p A, fz = p A to 1e-8."""
    meshgen.boxes(str(tmp_path / "sym.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(5, 5, 1), name="base"),
                   dict(lo=(0, 0, 0.5), hi=(1, 1, 1.0), n=(3, 3, 2), name="block")])
    p, mu = 1.0e6, 0.6
    scene = {"meshes": {"m": "sym.msh"},
             "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 2.0e10, "nu": 0.1}},
                        "block": {"mesh": "m", "regions": "block", "material": {"E": 1.0e10, "nu": 0.4}}},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": mu}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"}, {"surface": "base_ymin", "components": ["y"]},
                           {"surface": "block_ymin", "components": ["y"]}],
             "loads": [{"kind": "pressure", "surface": "block_zmax", "value": p},
                       {"kind": "traction", "surface": "block_zmax", "vector": [0.3 * p, 0, 0]}],
             "analysis": {"type": "static"}}
    h5 = prep(tmp_path, scene, name="sym")
    r = solve(h5, nproc=nproc)
    assert "warning" not in r.stdout, r.stdout
    q = read_contact(result(h5, ".h5"))
    on = np.abs(q["reference"][:, 1]) < 1e-12
    assert on.sum() == 4 and np.all(q["pressure"] > 0)
    assert np.abs(q["traction"][on, 1]).max() < 1e-8 * mu * p, q["traction"][on]
    assert np.abs(q["traction"][~on, 1]).max() > 1e-2 * mu * p
    c = read_csv(result(h5, "_contact.csv"))
    assert abs(c["fx"][-1] + 0.3 * p) < 1e-8 * p and abs(c["fz"][-1] - p) < 1e-8 * p, (c["fx"], c["fz"])


@pytest.mark.parametrize("nproc", [1, 2])
def test_no_traction_across_a_symmetry_plane_on_a_curved_surface(tmp_path, nproc):
    """Half a cylinder sector (R = 1, axis along x) pressed on a flat by 4 mm and then sheared
    along its axis, u_y = 0 on both bodies' y = 0 faces (the contact line lies in that plane). The
    cylinder is the slave: at its nodes on the plane the averaged normals lean off the plane
    (n_y = 0.033, only the faces on one side count), so the points' frames have no tangent along
    the plane's normal. Before, the multiplier across the plane was free to take any value
    within the cone: |q_y| up to 0.99 mu p at the points on the plane (a sphere sheared the same
    way gave 0.95 mu p). Now the frame is turned to the held direction: q_y = 0 there (< 1e-8 mu p)."""
    s30, c30 = 0.5, np.sqrt(3) / 2
    cyl = meshgen.cylinder_block("cyl", center=(0, 0, 1.0005), radius=1.0, length=1.0, axis_dir=(1, 0, 0),
                                 mid_dir=(0, s30, -c30), angle_deg=60, inner=0.6, n=(2, 16, 4))
    flat = meshgen.box_part("flat", (-0.6, 0, -0.4), (0.6, 0.5, 0), n=(5, 7, 1))
    meshgen.write_parts(str(tmp_path / "cyl.msh"), [cyl, flat])
    mu = 0.3
    material = {"E": 1.0e9, "nu": 0.3}
    scene = {"meshes": {"m": "cyl.msh"},
             "bodies": {"cyl": {"mesh": "m", "regions": "cyl", "material": material},
                        "flat": {"mesh": "m", "regions": "flat", "material": material}},
             "couples": [{"master": "flat_zmax", "slave": "cyl_curved", "mu": mu}],
             "dirichlet": [{"surface": "flat_zmin", "components": "all"}, {"surface": "flat_ymin", "components": ["y"]},
                           {"surface": "cyl_side0", "components": ["y"]},
                           {"surface": "cyl_inner", "components": ["z"], "value": -0.004},
                           {"surface": "cyl_inner", "components": ["x"], "value": 2e-4,
                            "time": {"table": [[0, 0], [0.5, 0], [1, 1]]}}],
             "analysis": {"type": "static", "dt": 0.5, "final_time": 1.0}}
    h5 = prep(tmp_path, scene, name="cyl")
    solve(h5, nproc=nproc)
    q = read_contact(result(h5, ".h5"))
    on = (np.abs(q["reference"][:, 1]) < 1e-12) & (q["state"] > 0)
    assert on.sum() >= 4 and np.abs(q["normal"][on, 1]).min() > 0.01
    p = q["pressure"][on].max()
    assert np.abs(q["traction"][on, 1]).max() < 1e-8 * mu * p, q["traction"][on]
    assert np.abs(q["traction"][on, 0]).max() > 1e-3 * mu * p  # the shear along the plane is there


def plate(tmp_path, exclude):
    """A plate 4 x 1 x 0.5 (8 x 2 x 2 hex) on a base 5 x 1 x 0.5 (7 x 2 x 1, non-matching, its
    bottom fixed), mu = 1, both with u_y = 0 on y = 0; the plate pressed by p = 1 MPa on its top
    and by 0.5 p on its side x = 0 against a wall at x = 4 (u_x = 0 on its face x = 4, whose bottom
    edge, 3 master nodes, lies on the contact surface and on no base node). Returns the scene file
    and the loads' resultant on the plate."""
    meshgen.boxes(str(tmp_path / "plate.msh"),
                  [dict(lo=(0, 0, 0), hi=(5, 1, 0.5), n=(7, 2, 1), name="base"),
                   dict(lo=(0, 0, 0.5), hi=(4, 1, 1.0), n=(8, 2, 2), name="plate")])
    p = 1.0e6
    couple = {"master": "plate_zmin", "slave": "base_zmax", "mu": 1.0}
    if exclude:
        couple["exclude"] = "plate_xmax"  # its nodes on the master surface: the corner edge
    material = {"E": 2.0e10, "nu": 0.2}
    scene = {"meshes": {"m": "plate.msh"},
             "bodies": {b: {"mesh": "m", "regions": b, "material": material} for b in ("base", "plate")},
             "couples": [couple],
             "dirichlet": [{"surface": "base_zmin", "components": "all"}, {"surface": "base_ymin", "components": ["y"]},
                           {"surface": "plate_ymin", "components": ["y"]}, {"surface": "plate_xmax", "components": ["x"]}],
             "loads": [{"kind": "pressure", "surface": "plate_zmax", "value": p},
                       {"kind": "pressure", "surface": "plate_xmin", "value": 0.5 * p}],
             "analysis": {"type": "static"}}
    return prep(tmp_path, scene, name="plate"), np.array([0.5 * p * 0.5, 0, -p * 4])


def balance(h5, loads):
    """The plate's loads + its supports' reactions + the contact resultant on it (the CSV's, on the
    master side), and the base's reactions - that resultant: both 0 in equilibrium."""
    import csv
    c = read_csv(result(h5, "_contact.csv"))
    with open(result(h5, "_reactions.csv")) as f:
        R = {row["surface"]: np.array([float(row[k]) for k in ("fx", "fy", "fz")]) for row in csv.DictReader(f)}
    F = np.array([c["fx"][-1], c["fy"][-1], c["fz"][-1]])
    return loads + R["plate_ymin"] + R["plate_xmax"] + F, R["base_zmin"] + R["base_ymin"] - F, c


@pytest.mark.parametrize("nproc", [1, 2])
def test_plate_corner_taken_out_of_contact(tmp_path, nproc):
    """The couple's `exclude` (as Code_Aster's SANS_GROUP_NO) takes the plate's corner edge out of
    contact: 24 points instead of 27, none on the wall's plane, no warning, and the contact
    resultant balances the plate's loads and reactions and the base's reactions to 1e-8 of the load
    p A; -mbc_contact_check_search, which checks every master node by brute force, passes over the
    excluded ones."""
    h5, loads = plate(tmp_path, exclude=True)
    r = solve(h5, "-mbc_contact_check_search", nproc=nproc)
    assert "warning" not in r.stdout, r.stdout
    q = read_contact(result(h5, ".h5"))
    assert len(q["state"]) == 24 and np.all(q["reference"][:, 0] < 4 - 1e-12) and np.all(q["state"] > 0)
    on_plate, on_base, c = balance(h5, loads)
    assert np.abs(on_plate).max() < 1e-8 * 4e6 and np.abs(on_base).max() < 1e-8 * 4e6, (on_plate, on_base)


def test_prescribed_contact_node_is_named_and_reactions_balance(tmp_path):
    """The same plate with its corner edge in contact: those 3 master nodes are x-prescribed on
    the plate's side only (no base node on the wall's plane), so their contact force along x goes
    into the wall, not into the plate: a warning names them. The reactions count that force on
    the prescribed rows (R = K u - F - H lambda with the contact force H leaves out there), so
    the plate's loads, reactions and contact resultant still balance to 1e-8 of p A; before, the
    wall's reaction missed it and the plate was 2.2e-2 p out of balance along x."""
    h5, loads = plate(tmp_path, exclude=False)
    r = solve(h5)
    warn = [line for line in r.stdout.splitlines() if "warning" in line]
    assert len(warn) == 1 and "3 contact points lie on master nodes prescribed on their side only" in warn[0], r.stdout
    assert "node (4., 0., 0.5) of body 'plate' (x prescribed)" in warn[0] and "`exclude`" in warn[0], warn
    on_plate, on_base, c = balance(h5, loads)
    assert c["points"][-1] == 27
    assert np.abs(on_plate).max() < 1e-8 * 4e6 and np.abs(on_base).max() < 1e-8 * 4e6, (on_plate, on_base)
