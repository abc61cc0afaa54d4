"""Contact search (docs/contact-search.md): search-only runs of the solver checked against exact
geometry, analytic surfaces and a brute-force nearest-node reference.

    cd /work/main && PYTHONPATH=python /usr/bin/python3 -m pytest -q tests/python/test_search.py

Every run is `mbcontact -scene S.h5 -mbc_contact_search_only -mbc_contact_dump PREFIX`; the
dumps PREFIX_pairs.csv / PREFIX_points.csv are read with mbcontact.results.read_csv. Scenes are
static with no boundary condition (search-only mode neither assembles a solve nor factors).

The test rebuilds what the solver sees of a couple (the labelled boundary faces of the bodies,
wound outward) with the preprocessor's own Python code, from the scene YAML; dumped nodes are
identified with mesh nodes by their coordinates (the dump has 17 digits, the meshes are read
back from the same .msh file). This process never imports h5py nor petsc4py.

Readings of the document made here:
body indices in the dump are 0-based in the scene order (BODY_BASE); h is computed as the
document defines it (Couple.h_unit) and the pair test puts the cutoff sharply between two
master nodes' distances; the -mbc_contact_view line format is parsed leniently (parse_view).
"""
import os
import re

import numpy as np
import pytest
from scipy.spatial import cKDTree

from conftest import prep, solve
from mbcontact import meshgen
from mbcontact.bodies import build_bodies, face_labels, read_mesh
from mbcontact.results import read_csv
from mbcontact.scene import load_yaml, parse_scene

BODY_BASE = 0  # index of the first body of the scene in the dump's master_body / slave_body
MATERIAL = {"E": 1.0e9, "nu": 0.3}
INSIDE_TOL = 1e-10  # the document's relative tolerance of the inside test
FEATURE_COS = 0.75  # faces around a node less than acos(0.75) = 41.4 degrees apart share its corner normal


# ---------------------------------------------------------------- scenes and runs

def couple_scene(mesh, bodies, master, slave, k=1):
    """Bodies (volume region = body name) of one mesh and one couple; no BC, no load."""
    return {"meshes": {"m": mesh},
            "bodies": {b: {"mesh": "m", "regions": [b], "material": dict(MATERIAL)} for b in bodies},
            "couples": [{"k": k, "master": master, "slave": slave, "mu": 0.3}]}


def search(folder, scene, *options, nproc=1, tag="dump"):
    """prep + one search-only run; returns (pairs, points, stdout, couple seen by the solver).
    The geometry checked here is the search's without the extension beyond the slave surface's
    free boundary (the static patch tests cover that); the solver's brute-force cross-check
    (-mbc_contact_check_search) runs on every geometry too."""
    h5 = prep(folder, scene)
    prefix = str(folder / tag)
    r = solve(h5, "-mbc_contact_search_only", "-mbc_contact_dump", prefix, "-mbc_contact_extension", "0",
              "-mbc_contact_check_search", *options, nproc=nproc)
    pairs, points = read_csv(prefix + "_pairs.csv"), read_csv(prefix + "_points.csv")
    return pairs, points, r.stdout, Couple(folder / "scene.yaml", scene["couples"][0]["k"])


# ---------------------------------------------------------------- what the solver sees

def newell(xyz):
    """Newell area vectors of faces xyz (nf, nv, 3) (exact for planar faces, any winding)."""
    d = xyz - xyz.mean(axis=1, keepdims=True)
    return 0.5 * np.cross(d, np.roll(d, -1, axis=1)).sum(axis=1)


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


class Side:
    """One side of a couple over all bodies: nodes (x, body), faces (node numbers, outward)."""

    def __init__(self, bodies, labels, column, k):
        xs, bs, fs, fbs, offset = [], [], [], [], 0
        for i, (body, lab) in enumerate(zip(bodies, labels)):
            faces = body.boundary_faces[lab[:, column] == k]
            if not len(faces):
                continue
            nv = np.unique(body.boundary_nv[lab[:, column] == k])
            assert len(nv) == 1, "one face type per side in these tests"
            faces = faces[:, :nv[0]]  # boundary_faces is -1 padded to the widest face (tri6)
            used = np.unique(faces)
            number = np.full(len(body.coords), -1)
            number[used] = offset + np.arange(len(used))
            xs.append(body.coords[used])
            bs.append(np.full(len(used), i))
            fs.append(number[faces])
            fbs.append(np.full(len(faces), i))
            offset += len(used)
        assert xs, f"couple {k} has no {('master', 'slave')[column - 1]} face"
        self.x, self.body = np.concatenate(xs), np.concatenate(bs)
        self.faces, self.face_body = np.concatenate(fs), np.concatenate(fbs)
        self.scale = np.linalg.norm(np.ptp(self.x, axis=0))
        self.tree = cKDTree(self.x)
        xyz = self.x[self.faces]
        self.normal = unit(newell(xyz))
        summed = np.zeros_like(self.x)
        np.add.at(summed, self.faces.ravel(), np.repeat(self.normal, self.faces.shape[1], axis=0))
        self.node_normal = unit(summed)  # normalised mean of the unit normals around the node
        # corner normals: per face corner, the mean of the unit normals of the faces around the
        # corner's node whose normal is within the feature angle of the face's (cos > FEATURE_COS)
        around = [[] for _ in range(len(self.x))]
        for j, f in enumerate(self.faces):
            for v in f:
                around[v].append(j)
        self.corner_normal = np.array([[unit(sum(self.normal[g] for g in around[v] if g == j or self.normal[g] @ self.normal[j] > FEATURE_COS))
                                        for v in f] for j, f in enumerate(self.faces)])
        self.face_index = {frozenset(f): j for j, f in enumerate(self.faces)}
        self.order = np.lexsort((self.x[:, 2], self.x[:, 1], self.x[:, 0], self.body))  # canonical

    def find(self, xyz, body):
        """Node numbers of points given by coordinates (asserting they are nodes of that body)."""
        xyz = np.atleast_2d(xyz)
        dist, index = self.tree.query(xyz)
        assert np.all(dist <= 1e-12 * self.scale), f"not a node of this side: {xyz[dist.argmax()]}"
        assert np.all(self.body[index] == np.asarray(body) - BODY_BASE), "node of another body"
        return index

    def edge_lengths(self, unique=False):
        e = np.stack([self.faces, np.roll(self.faces, -1, axis=1)], axis=-1).reshape(-1, 2)
        if unique:
            e = np.unique(np.sort(e, axis=1), axis=0)
        return np.linalg.norm(self.x[e[:, 1]] - self.x[e[:, 0]], axis=1)


class Couple:
    """Couple k as the solver gets it from the scene file (same code as mbcontact-prep)."""

    def __init__(self, yaml_path, k=1):
        scene = parse_scene(load_yaml(str(yaml_path)), os.path.dirname(os.path.abspath(yaml_path)))
        meshes = {name: read_mesh(name, path) for name, path in scene.meshes.items()}
        bodies = build_bodies(scene, meshes)
        labels, _ = face_labels(scene, bodies)
        self.k = k
        self.master, self.slave = Side(bodies, labels, 1, k), Side(bodies, labels, 2, k)

    def h_unit(self):
        """The cell edge for a unit cell factor, as docs/contact-search.md defines it: the larger
        of the mean length of every edge of every master and slave face (shared edges twice) and
        the longest slave face edge."""
        em, es = self.master.edge_lengths(), self.slave.edge_lengths()
        return max(np.concatenate([em, es]).mean(), es.max())

    def nearest_slave(self, nodes):
        """Brute force O(N M): distance from master nodes to every slave node; nearest with the
        document's tie rule (the slave node first in canonical order)."""
        s = self.slave
        d = np.linalg.norm(self.master.x[nodes][:, None, :] - s.x[s.order][None, :, :], axis=2)
        first = d.argmin(axis=1)  # argmin returns the first minimum: canonical order breaks ties
        return s.order[first], d[np.arange(len(nodes)), first]


def cell_factor_for(couple, nodes, factors=(1.0, 1.5, 2.0, 3.0)):
    """Smallest cell factor for which every given master node has a slave node within h, for
    h as documented; 1.0 (the default) whenever it suffices."""
    _, dist = couple.nearest_slave(nodes)
    h = couple.h_unit()
    for f in factors:
        if dist.max() < 0.99 * f * h:
            return f
    raise AssertionError(f"setup: master nodes too far from the slave nodes ({dist.max()} vs h {h})")


def factor_options(f):
    return () if f == 1.0 else ("-mbc_contact_cell_factor", repr(f))


# ---------------------------------------------------------------- reading and checking dumps

def vectors(table, prefix):
    return np.column_stack([table[prefix + c] for c in "xyz"])


def dump_points(points):
    """The points dump as arrays: M (master node), V (n, 4, 3), W (n, 4), P, N, T1, T2, nv, gap."""
    return {"M": vectors(points, "m"), "P": vectors(points, "p"), "N": vectors(points, "n"),
            "T1": vectors(points, "t1"), "T2": vectors(points, "t2"), "gap": points["gap"],
            "V": np.stack([vectors(points, f"v{i}") for i in range(4)], axis=1),
            "W": np.column_stack([points[f"w{i}"] for i in range(4)]),
            "nv": points["nv"].astype(int), "k": points["k"], "mbody": points["master_body"],
            "sbody": points["slave_body"]}


def assert_canonical(body, xyz):
    """Rows in canonical order (body, then x, y, z lexicographically), no row twice."""
    keys = np.column_stack([body, xyz])
    assert len(np.unique(keys, axis=0)) == len(keys), "a master node appears twice"
    order = np.lexsort((xyz[:, 2], xyz[:, 1], xyz[:, 0], body))
    assert np.array_equal(order, np.arange(len(order))), "rows not in canonical order"


def wachspress(xyz, p, n):
    """Reference weights: area coordinates (tri3); quad4: the bilinear shape functions at the
    (u, v) whose bilinear image is p in the face's plane (the slave element's trace), found here
    by scipy's root finder independently of the solver's Newton."""
    from scipy.optimize import fsolve
    nv = len(xyz)
    if nv == 3:
        def area(a, b, c):
            return 0.5 * np.dot(np.cross(b - a, c - a), n)
        w = np.array([area(p, xyz[(i + 1) % 3], xyz[(i + 2) % 3]) for i in range(3)])
        return w / w.sum()
    e1 = xyz[1] - xyz[0]
    e1 = e1 - np.dot(e1, n) * n
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    Y = np.array([[np.dot(x, e1), np.dot(x, e2)] for x in xyz])
    y = np.array([np.dot(p, e1), np.dot(p, e2)])

    def shape(uv):
        u, v = uv
        return np.array([(1 - u) * (1 - v), u * (1 - v), u * v, (1 - u) * v])

    uv = fsolve(lambda uv: shape(uv) @ Y - y, [0.5, 0.5], xtol=1e-14)
    return shape(uv)


def check_points(couple, points):
    """Everything the document says of each contact point, independently of the geometry.

    Returns (dump arrays, master node number of each row, slave face number of each row)."""
    d = dump_points(points)
    m, s = couple.master, couple.slave
    n = len(d["gap"])
    assert np.all(d["k"] == couple.k)
    assert_canonical(d["mbody"], d["M"])
    mi = m.find(d["M"], d["mbody"])
    faces = np.empty(n, int)
    for r in range(n):
        nv = d["nv"][r]
        assert nv == s.faces.shape[1], f"row {r}: nv {nv} for {s.faces.shape[1]}-vertex slave faces"
        assert np.all(d["V"][r, nv:] == 0) and np.all(d["W"][r, nv:] == 0), f"row {r}: unused slots not 0"
        xyz, w, p, nf = d["V"][r, :nv], d["W"][r, :nv], d["P"][r], d["N"][r]
        vi = s.find(xyz, np.full(nv, d["sbody"][r]))
        faces[r] = f = s.face_index.get(frozenset(vi), -1)
        assert f >= 0, f"row {r}: vertices {xyz} are not a slave face"
        size = np.linalg.norm(np.roll(xyz, -1, axis=0) - xyz, axis=1).max()
        # vertices counter-clockwise seen from outside; the normal: the face's corner normals
        # interpolated with the weights (on a flat surface the face's outward normal)
        assert np.abs(unit(newell(xyz[None]))[0] - s.normal[f]).max() < 1e-12, f"row {r}: vertices not counter-clockwise"
        corner = s.corner_normal[f][[list(s.faces[f]).index(v) for v in vi]]
        assert np.abs(nf - unit(w @ corner)).max() < 1e-12, f"row {r}: n {nf} is not the interpolated corner normal {unit(w @ corner)}"
        # frame: orthonormal, right-handed, t1 = normalise(e x n) with e a least aligned axis
        t1, t2 = d["T1"][r], d["T2"][r]
        basis = np.array([nf, t1, t2])
        assert np.abs(basis @ basis.T - np.eye(3)).max() < 1e-12, f"row {r}: frame not orthonormal"
        assert np.abs(np.cross(t1, t2) - nf).max() < 1e-12, f"row {r}: frame not right-handed"
        least = np.nonzero(np.abs(nf) <= np.abs(nf).min() + 1e-12)[0]
        assert any(np.abs(unit(np.cross(np.eye(3)[e], nf)) - t1).max() < 1e-12 for e in least), \
            f"row {r}: t1 {t1} is not normalise(e x n) for a least aligned axis e"
        # projection point: on the face's plane, inside the face, reproduced by the weights
        centroid = xyz.mean(axis=0)
        assert abs(np.dot(p - centroid, s.normal[f])) < 1e-12 * size, f"row {r}: p not on the face's plane"
        assert abs(w.sum() - 1) < 1e-12, f"row {r}: weights sum to {w.sum()}"
        assert w.min() > -INSIDE_TOL, f"row {r}: p outside the face (weights {w})"
        warp = np.abs((xyz - centroid) @ s.normal[f]).max()
        assert np.linalg.norm(w @ xyz - p) <= warp + 1e-12 * size, f"row {r}: sum w_i v_i != p"
        if warp < 1e-14 * size:  # planar face: the documented coordinates exactly
            assert np.abs(w - wachspress(xyz, p, s.normal[f])).max() < 1e-12, f"row {r}: weights {w} are not the documented ones"
        # projection along the master node's averaged normal; the gap
        xm, nm = d["M"][r], m.node_normal[mi[r]]
        assert np.linalg.norm(np.cross(p - xm, nm)) < 1e-12 * m.scale, f"row {r}: p not on the line x_m + t n_m"
        assert np.dot(s.normal[f], nm) < 0, f"row {r}: face normal does not oppose the master normal"
        assert np.dot(nf, nm) < 0, f"row {r}: contact normal does not oppose the master normal"
        # the gap: to the weights' point of the slave element (p itself on a planar face), along n
        assert abs(d["gap"][r] - np.dot(xm - w @ xyz, nf)) < 1e-12 * m.scale, f"row {r}: gap != (x_m - sum w_i x_i).n"
    return d, mi, faces


def check_pairs(couple, pairs):
    """Structure of the pairs dump; returns (master node numbers, slave node numbers)."""
    assert np.all(pairs["k"] == couple.k)
    mx, sx = vectors(pairs, "m"), vectors(pairs, "s")
    assert_canonical(pairs["master_body"], mx)
    mi = couple.master.find(mx, pairs["master_body"])
    si = couple.slave.find(sx, pairs["slave_body"])
    assert np.abs(pairs["distance"] - np.linalg.norm(mx - sx, axis=1)).max(initial=0) < 1e-12 * couple.master.scale
    return mi, si


# ---------------------------------------------------------------- flat contact

FLAT = [  # slave block, slave cell, master cell, gap, in-plane moves, cells of the slave, of the master
    ("lower", "hex8", "tet4", 0.0, 0.0, (4, 4, 2), (6, 5, 2)),
    ("lower", "tet4", "hex8", 1e-3, 0.0, (4, 4, 2), (6, 5, 2)),
    ("upper", "hex8", "tet4", 1e-3, 0.2, (6, 5, 2), (4, 4, 2)),
    ("upper", "tet4", "hex8", 0.0, 0.2, (6, 5, 2), (4, 4, 2)),
    # stretched, distorted triangles under a fine master: the nearest slave node is sometimes no
    # vertex of the triangle under the master node (the fallback to the next nearest nodes runs)
    ("lower", "tet4", "hex8", 0.0, 0.25, (4, 8, 2), (15, 14, 2)),
]


@pytest.mark.parametrize("slave_block,slave_cell,master_cell,gap,in_plane,n_slave,n_master", FLAT,
                         ids=["quad-slave-touching", "tri-slave-gap", "quad-slave-above-gap-distorted",
                              "tri-slave-above-touching-distorted", "tri-slave-fallback"])
def test_flat_nonmatching(tmp_path, slave_block, slave_cell, master_cell, gap, in_plane, n_slave, n_master):
    """Two blocks meeting on z = 1 (or 1e-3 apart) with non-matching faces (tri3 against quad4,
    different sizes, interior nodes moved, and with in_plane > 0 the contact faces' nodes moved
    in their planes: general convex quads, distorted triangles). Footprints [0,1]^2 (lower) and
    [0.1,1.3]x[-0.2,0.9] (upper) overlap partly. Every master node strictly inside the slave
    footprint (by 1e-9) has exactly one contact point, none strictly outside; the gap is exact
    (1e-12), p = (x_m, y_m, z_slave), n = (0, 0, +-1), the weights are the documented ones and
    reproduce p (check_points)."""
    lower_is_slave = slave_block == "lower"
    cells = (slave_cell, master_cell) if lower_is_slave else (master_cell, slave_cell)
    n = (n_slave, n_master) if lower_is_slave else (n_master, n_slave)
    info = meshgen.perturbed_blocks(tmp_path / "flat.msh", z0=1.0, gap=gap, cells=cells, n=n,
                                    in_plane=in_plane, out_of_plane=0.0, perturb=0.1, seed=3)
    lower, upper = info["lower_top"], info["upper_bottom"]
    master, slave = (upper, lower) if lower_is_slave else (lower, upper)
    scene = couple_scene("flat.msh", ["lower", "upper"], master, slave)
    pre = _couple_before_run(tmp_path, scene)
    (x0, y0), (x1, y1) = info["footprints"][0 if lower_is_slave else 1]
    xm = pre.master.x
    margin = 1e-9
    inside = (xm[:, 0] > x0 + margin) & (xm[:, 0] < x1 - margin) & (xm[:, 1] > y0 + margin) & (xm[:, 1] < y1 - margin)
    outside = (xm[:, 0] < x0 - margin) | (xm[:, 0] > x1 + margin) | (xm[:, 1] < y0 - margin) | (xm[:, 1] > y1 + margin)
    assert inside.sum() >= 9 and outside.sum() >= 5, "setup: both kinds of master nodes"
    f = cell_factor_for(pre, np.nonzero(inside)[0])
    z_slave = 1.0 + (0.0 if lower_is_slave else gap)
    if n_master[0] > 10:  # the fallback case: some partners must not be a vertex of the face under the node
        nodes = np.nonzero(inside)[0]
        partner, _ = pre.nearest_slave(nodes)
        under = np.column_stack([xm[nodes, :2], np.full(len(nodes), z_slave)])
        faces = pre.slave.faces
        fallback = 0
        for point, s in zip(under, partner):
            fallback += not np.any(faces[_faces_containing(pre.slave, point)] == s)
        assert fallback >= 3, "setup: the fallback to the next nearest slave nodes is not exercised"

    pairs, points, _, couple = search(tmp_path, scene, *factor_options(f))
    check_pairs(couple, pairs)
    d, mi, _ = check_points(couple, points)
    found = np.zeros(len(xm), bool)
    found[mi] = True
    assert found[inside].all(), f"inside master nodes without contact point: {xm[inside & ~found]}"
    assert not found[outside].any(), f"contact points of master nodes outside the slave: {xm[outside & found]}"
    normal = np.array([0, 0, 1.0 if lower_is_slave else -1.0])
    assert np.abs(d["gap"] - gap).max() < 1e-12
    assert np.abs(d["N"] - normal).max() < 1e-12
    assert np.abs(d["P"] - np.column_stack([d["M"][:, :2], np.full(len(mi), z_slave)])).max() < 1e-12


def _faces_containing(side, p):
    """Mask of the faces of `side` whose plane contains p and whose inside test accepts it."""
    xyz = side.x[side.faces]
    size = np.linalg.norm(np.roll(xyz, -1, axis=1) - xyz, axis=2).max(axis=1)
    ok = np.abs(np.einsum("fj,fj->f", p - xyz.mean(axis=1), side.normal)) <= 1e-12 * size
    for i in range(xyz.shape[1]):
        e = np.roll(xyz, -1, axis=1)[:, i] - xyz[:, i]
        ok &= np.einsum("fj,fj->f", np.cross(e, p - xyz[:, i]), side.normal) >= -INSIDE_TOL * (e**2).sum(axis=1)
    return ok


def _couple_before_run(folder, scene):
    """The couple as the solver will see it, before running it (writes scene.yaml)."""
    import yaml

    (folder / "scene.yaml").write_text(yaml.safe_dump(scene, sort_keys=False))
    return Couple(folder / "scene.yaml", scene["couples"][0]["k"])


# ---------------------------------------------------------------- curved contact: second order

def convergence(levels, build, zone, h_of_level, bound):
    """Runs each level (build(level, folder) -> scene, exact distance function); per level the
    max over the zone's master nodes of |gap - exact distance|. Asserts one point per zone node,
    error <= bound * h^2 (and > bound/20 * h^2 at the coarsest level: it is the discretisation
    that is measured) and an observed order >= 1.7 between successive levels."""
    errors, sizes = [], []
    for level, folder in levels:
        scene, distance = build(level, folder)
        pre = _couple_before_run(folder, scene)
        nodes = np.nonzero(zone(pre.master.x))[0]
        assert len(nodes) >= 3, "setup: too few master nodes in the contact zone"
        pairs, points, _, couple = search(folder, scene, *factor_options(cell_factor_for(pre, nodes)))
        check_pairs(couple, pairs)
        d, mi, _ = check_points(couple, points)
        rows = {node: r for r, node in enumerate(mi)}
        missing = [couple.master.x[n] for n in nodes if n not in rows]
        assert not missing, f"zone master nodes without contact point: {missing}"
        r = np.array([rows[n] for n in nodes])
        err = np.abs(d["gap"][r] - distance(d["M"][r])).max()
        h = h_of_level(level)
        assert err <= bound * h**2, f"level {level}: error {err} > {bound} h^2 (h = {h})"
        errors.append(err)
        sizes.append(h)
    assert errors[0] > bound / 20 * sizes[0]**2, f"errors {errors}: no discretisation error measured?"
    order = np.log(np.array(errors[:-1]) / errors[1:]) / np.log(np.array(sizes[:-1]) / sizes[1:])
    assert np.all(order >= 1.7), f"observed orders {order} (errors {errors}, h {sizes})"
    return errors, order


def refinement(tmp_path, levels):
    out = []
    for i, level in enumerate(levels):
        (tmp_path / f"level{i}").mkdir()
        out.append((level, tmp_path / f"level{i}"))
    return out


def test_cylinder_on_cylinder_second_order(tmp_path):
    """Two parallel cylinders R = 1 (40 degree sectors, axes along y), 1e-3 apart on the line
    x = 0; master: the upper curved surface (tet4), slave: the lower one (hex8, odd n_theta: a
    face centre on the contact line). Refined n_theta = 7, 15, 31 (master 8, 16, 32).

    Compared quantity: the exact distance from the master node (which lies exactly on its own
    cylinder) to the slave cylinder, |x_m - c| - R. The computed gap (x_m - p).n_f is the
    distance from x_m to the plane of the selected facet, a chord plane: near the node's radial
    foot it differs from the cylinder by at most the sagitta R (1 - cos(dtheta/2)) ~ h^2/(8R)
    (attained by the node over the face centre on x = 0). The projection along the master normal
    selects the facet at the ray's hit point, which is shifted from the radial foot by about
    gap * angle(n_m, radial); that adds O(gap * angle * h / R), first order, but negligible in
    the zone |x| <= 0.1 R used here (gap <= 6e-3, angle <= 0.2). Unlike the distance along the
    projection direction, this quantity involves no discrete normal at all."""
    R, s = 1.0, 1e-3

    def build(level, folder):
        ns, nm = level
        info = meshgen.cylinder_pair(folder / "cyl.msh", radii=(R, R), separation=s, lengths=(0.5, 0.4),
                                     angle_deg=(40.0, 40.0), n=((2, ns, 3), (2, nm, 2)), cells=("hex8", "tet4"))
        scene = couple_scene("cyl.msh", info["bodies"], info["curved"]["cyl2"], info["curved"]["cyl1"])
        return scene, info["distance"]["cyl1"]

    convergence(refinement(tmp_path, [(7, 8), (15, 16), (31, 32)]), build,
                zone=lambda x: np.abs(x[:, 0]) <= 0.1 * R, h_of_level=lambda lv: R * np.radians(40.0) / lv[0],
                bound=0.2 / R)


def test_sphere_on_plane_second_order(tmp_path):
    """A ball R = 1 (cube-to-sphere mesh, hex8, n = 5, 9, 17 cells per cube edge: a face centre at
    its lowest point) 1e-3 above a flat block (tet4, vertex at the origin); master: the plane,
    slave: the whole sphere surface. Compared quantity: the exact distance |x_m - c| - R from the
    master node to the sphere (see the cylinder test for why); the facet planes are chord planes
    of the warped quads (Newell normal, through the centroid), whose distance to the sphere is
    O(h^2/R), h = R (pi/2)/n the angular size of a cell; the zone is r <= 0.12 R."""
    R, s = 1.0, 1e-3

    def build(n, folder):
        info = meshgen.sphere_on_plane(folder / "sph.msh", radius=R, separation=s, n_ball=n, ball_cell="hex8",
                                       half_width=0.3, n_plane=(n + 1, n + 1, 1), plane_cell="tet4",
                                       thickness=0.1)
        return couple_scene("sph.msh", info["bodies"], info["plane_top"], info["ball_surface"]), info["distance"]

    convergence(refinement(tmp_path, [5, 9, 17]), build, zone=lambda x: np.hypot(x[:, 0], x[:, 1]) <= 0.12 * R,
                h_of_level=lambda n: R * np.pi / 2 / n, bound=0.35 / R)


# ---------------------------------------------------------------- blind spot

def accepting_faces(side, x, directions=None):
    """For points x: how many faces of `side` accept the projection of the point on the face's
    plane along `directions` (one per point; the local search's inside test), or, without
    directions, along the FACE normal (orthogonal projection: the classic node-to-face search)."""
    xyz = side.x[side.faces]
    centroid = xyz.mean(axis=1)
    hits = np.zeros(len(x), int)
    for j in range(len(side.faces)):
        nf = side.normal[j]
        if directions is None:
            p = x - np.outer((x - centroid[j]) @ nf, nf)
            ok = np.ones(len(x), bool)
        else:
            along = directions @ nf
            ok = along < 0
            p = x + (((centroid[j] - x) @ nf) / np.where(ok, along, 1.0))[:, None] * directions
        for i in range(xyz.shape[1]):
            e = xyz[j, (i + 1) % xyz.shape[1]] - xyz[j, i]
            ok &= (np.cross(e, p - xyz[j, i]) @ nf) >= -INSIDE_TOL * np.dot(e, e)
        hits += ok
    return hits


def test_blind_spot_ridge_and_valley(tmp_path):
    """Slave: a hex8 block whose top zigzags with slopes +-0.5: a convex ridge at x = 0.6 and a
    concave valley at x = 1.4 (edges along y); master: a finer tet4 block above it following the
    fold 0.02 higher, with a line of nodes right over the ridge and one right over the valley.
    Every master node (all lie over the slave) has exactly one contact point, with 0 < gap <=
    0.02. Projecting along the face normals instead would miss the ridge line (no face accepts
    its orthogonal projection) and find two faces under the valley line: checked here, so the
    test really exercises both. Along the (vertical, by symmetry) master normal of the inner
    nodes of both lines, the ray hits the slave edge itself: two faces accept, one point only."""
    info = meshgen.folded_blocks(tmp_path / "fold.msh")
    scene = couple_scene("fold.msh", ["lower", "upper"], info["master"], info["slave"])
    pre = _couple_before_run(tmp_path, scene)
    xm = pre.master.x
    hits = accepting_faces(pre.slave, xm)
    ridge_line = np.abs(xm[:, 0] - info["ridge_x"]) < 1e-12
    valley_line = np.abs(xm[:, 0] - info["valley_x"]) < 1e-12
    assert ridge_line.sum() >= 3 and valley_line.sum() >= 3
    assert np.all(hits[ridge_line] == 0), "setup: the ridge line should be in the face-normal blind spot"
    assert np.all(hits[valley_line] >= 2), "setup: the valley line should be seen by two faces"
    along = accepting_faces(pre.slave, xm, pre.master.node_normal)
    assert np.all(along >= 1), "setup: every master node's ray should hit the slave"
    assert (along[ridge_line] >= 2).sum() >= 2 and (along[valley_line] >= 2).sum() >= 2, \
        "setup: rays along the master normal should hit the ridge and valley edges"
    f = cell_factor_for(pre, np.arange(len(xm)))

    pairs, points, _, couple = search(tmp_path, scene, *factor_options(f))
    check_pairs(couple, pairs)
    d, mi, _ = check_points(couple, points)  # includes: no master node twice
    missing = np.setdiff1d(np.arange(len(couple.master.x)), mi)
    assert not len(missing), f"master nodes without contact point: {couple.master.x[missing]}"
    s = info["separation"]
    assert d["gap"].min() > 0 and d["gap"].max() <= s + 1e-12
    # the points of the ridge line lie on the faces along the ridge (two vertices on it)
    ridge_rows = np.abs(d["M"][:, 0] - info["ridge_x"]) < 1e-12
    assert np.all((np.abs(d["V"][ridge_rows, :, 0] - info["ridge"]) < 1e-12).sum(axis=1) >= 2)


# ---------------------------------------------------------------- global search against brute force

def sharp_factor(couple, dist, lowest=0.5, highest=2.5, margin=1e-3):
    """A cell factor f putting the cutoff f * h halfway (geometrically) between two successive
    nearest-slave distances of master nodes that are at least 2 margin apart, choosing the
    narrowest such gap: the cutoff is tested sharply (a node just inside, one just outside).
    At least 5 master nodes on each side."""
    h1 = couple.h_unit()
    d = np.sort(dist)
    best = None
    for j in range(4, len(d) - 5):
        ratio = d[j + 1] / d[j]
        f = np.sqrt(d[j] * d[j + 1]) / h1
        if ratio > (1 + margin) ** 2 and lowest <= f <= highest and (best is None or ratio < best[0]):
            best = ratio, f
    assert best, "setup: no cutoff between two master nodes' distances in the factor range"
    ratio, f = best
    assert ratio < 1.05, f"setup: the cutoff is not tested sharply (successive distances ratio {ratio})"
    return f, f * h1


@pytest.mark.parametrize("cells,gap,seed", [(("hex8", "tet4"), 0.0, 1), (("tet4", "hex8"), 0.02, 2)])
def test_pairs_brute_force(tmp_path, cells, gap, seed):
    """Randomly perturbed non-matching blocks (contact-face nodes moved in and out of plane,
    interior nodes moved), footprints [0,1]^2 and [0.3,1.6]x[-0.4,0.8]: the dumped pairs are
    exactly the brute-force O(N M) nearest slave node within h of every master node (nodes
    identified by coordinates); a KD-tree gives the same partners."""
    meshgen.perturbed_blocks(tmp_path / "rand.msh", z0=1.0, gap=gap, cells=cells,
                             footprints=(((0, 0), (1, 1)), ((0.3, -0.4), (1.6, 0.8))), n=((6, 6, 2), (7, 8, 2)),
                             in_plane=0.2, out_of_plane=0.1, perturb=0.1, seed=seed)
    scene = couple_scene("rand.msh", ["lower", "upper"], "upper_zmin", "lower_zmax")
    pre = _couple_before_run(tmp_path, scene)
    all_master = np.arange(len(pre.master.x))
    nearest, dist = pre.nearest_slave(all_master)
    f, h = sharp_factor(pre, dist)
    expected = {int(m): int(s) for m, s, dd in zip(all_master, nearest, dist) if dd <= h}
    # KD-tree: the same nearest nodes
    kd_dist, kd_index = pre.slave.tree.query(pre.master.x, distance_upper_bound=h)
    kd = {int(m): int(s) for m, s, dd in zip(all_master, kd_index, kd_dist) if np.isfinite(dd)}
    assert kd == expected

    pairs, points, _, couple = search(tmp_path, scene, *factor_options(f))
    mi, si = check_pairs(couple, pairs)
    got = dict(zip(mi.tolist(), si.tolist()))
    assert set(got) == set(expected), (f"master nodes with a partner differ: missing "
                                       f"{couple.master.x[sorted(set(expected) - set(got))]}, extra "
                                       f"{couple.master.x[sorted(set(got) - set(expected))]}")
    wrong = [m for m in got if got[m] != expected[m]]
    assert not wrong, f"wrong partners for master nodes {couple.master.x[wrong]}"
    check_points(couple, points)


# ---------------------------------------------------------------- parallel runs

def parallel_scene(name, folder):
    if name == "blocks":
        meshgen.perturbed_blocks(folder / "par.msh", z0=1.0, gap=0.01, cells=("hex8", "tet4"),
                                 footprints=(((0, 0), (1, 1)), ((0.1, -0.1), (1.2, 0.9))), n=((8, 8, 3), (9, 7, 3)),
                                 in_plane=0.2, out_of_plane=0.1, perturb=0.1, seed=5)
        return couple_scene("par.msh", ["lower", "upper"], "upper_zmin", "lower_zmax")
    info = meshgen.sphere_on_plane(folder / "par.msh", separation=1e-3, n_ball=7, half_width=0.4,
                                   n_plane=(12, 12, 2), plane_cell="tet4")  # 507 and 512 vertices
    return couple_scene("par.msh", info["bodies"], info["plane_top"], info["ball_surface"])


@pytest.mark.parametrize("name", ["blocks", "sphere"])
def test_same_pairs_and_points_at_1_2_4_ranks(tmp_path, name):
    """Two bodies of about the same vertex count, the two sides of the couple: one rank each at
    2 ranks, two ranks each at 4 (checked in the -mbc_view report). The dumps (canonical order)
    agree to 1e-12 with the serial run, column by column."""
    scene = parallel_scene(name, tmp_path)
    h5 = prep(tmp_path, scene)
    runs = {}
    for n in (1, 2, 4):
        prefix = str(tmp_path / f"np{n}")
        r = solve(h5, "-mbc_contact_search_only", "-mbc_contact_dump", prefix, "-mbc_view", nproc=n)
        runs[n] = read_csv(prefix + "_pairs.csv"), read_csv(prefix + "_points.csv")
        bodies = list(scene["bodies"])
        if n == 2:
            ranks = [re.search(rf"body {b}: ranks (\d+)-(\d+)", r.stdout).groups() for b in bodies]
            assert sorted(ranks) == [("0", "0"), ("1", "1")], r.stdout
        if n == 4:
            ranks = [re.search(rf"body {b}: ranks (\d+)-(\d+)", r.stdout).groups() for b in bodies]
            assert sorted(ranks) == [("0", "1"), ("2", "3")], r.stdout
    pairs1, points1 = runs[1]
    assert len(pairs1["k"]) >= 20 and len(points1["k"]) >= 20
    for n in (2, 4):
        for serial, parallel in zip(runs[1], runs[n]):
            assert list(parallel) == list(serial)
            for col in serial:
                assert parallel[col].shape == serial[col].shape, (n, col)
                assert np.abs(parallel[col] - serial[col]).max() <= 1e-12, (n, col)


# ---------------------------------------------------------------- -mbc_contact_view

VIEW_LABELS = {"master": "master nodes", "slave": "slave nodes", "pairs": "test pairs", "points": "contact points"}
NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"


def parse_view(text, k):
    """The -mbc_contact_view report of couple k. Expected one line (or block) per couple such as
    `couple 1: master nodes 120, slave nodes 80, test pairs 100, contact points 90, gap range
    [-0.001, 0.002]`; accepted too: `label: N`, `label = N`, `N label`, and any two numbers
    after the word "gap"."""
    blocks = re.split(r"(?i)(?=couple\b)", text)  # (the scene summary of -mbc_view names couples too)
    block = [b for b in blocks if re.match(rf"(?i)couple\s*(?:k\s*=\s*)?{k}\b", b)
             and all(re.search(rf"(?i){label}", b) for label in VIEW_LABELS.values())]
    assert block, f"no couple {k} with {', '.join(VIEW_LABELS.values())} in the -mbc_contact_view output:\n{text}"
    block = block[0]
    out = {}
    for key, label in VIEW_LABELS.items():
        m = (re.search(rf"(?i){label}\s*[:=]?\s*(\d+)", block) or re.search(rf"(?i)(\d+)\s+{label}", block))
        assert m, f"no '{label}' count for couple {k} in:\n{block}"
        out[key] = int(m.group(1))
    m = re.search(r"(?i)gap(.*)", block, re.S)
    numbers = re.findall(NUMBER, m.group(1)) if m else []
    assert len(numbers) >= 2, f"no gap range for couple {k} in:\n{block}"
    out["gap"] = (float(numbers[0]), float(numbers[1]))
    return out


def test_contact_view_counts(tmp_path):
    """-mbc_contact_view prints per couple the master and slave node counts, the test pairs, the
    contact points and the gap range; they agree with the mesh and the dump. "Test pairs" may
    be the (master node, slave face) pairs tried (the faces around each partner, more where the
    fallback to the next nearest nodes ran) or the master nodes with a partner (the rows of
    _pairs.csv): the document reads both ways, both are accepted."""
    info = meshgen.folded_blocks(tmp_path / "fold.msh")
    scene = couple_scene("fold.msh", ["lower", "upper"], info["master"], info["slave"])
    pairs, points, out, couple = search(tmp_path, scene, "-mbc_contact_view", "-mbc_contact_cell_factor", "2")
    view = parse_view(out, 1)
    assert view["master"] == len(couple.master.x)
    assert view["slave"] == len(couple.slave.x)
    assert view["points"] == len(points["gap"])
    mi, si = check_pairs(couple, pairs)
    _, pmi, pfaces = check_points(couple, points)
    slave_faces = couple.slave.faces
    around = [set(np.nonzero(np.any(slave_faces == s, axis=1))[0]) for s in si]
    partner_row = {m: r for r, m in enumerate(mi)}
    fallback = len(mi) - len(pmi) + sum(f not in around[partner_row[m]] for m, f in zip(pmi, pfaces))
    valence = np.bincount(slave_faces.ravel()).max()
    low = sum(len(a) for a in around)
    assert view["pairs"] == len(mi) or low <= view["pairs"] <= low + fallback * 8 * valence, \
        (view, len(mi), low, fallback)
    gap = points["gap"]
    for printed, exact in zip(view["gap"], (gap.min(), gap.max())):
        assert abs(printed - exact) <= 1e-5 * abs(exact) + 1e-12, (view["gap"], gap.min(), gap.max())


# ---------------------------------------------------------------- the generators (no solver needed)

def _outward(part, surface, center_of):
    """Unit normals of a surface's faces and the direction from `center_of(points)` to the faces."""
    xyz = part.surface_points(surface)
    c = xyz.mean(axis=1)
    return unit(newell(xyz)), unit(c - center_of(c))


def _separate_bodies(msh, names):
    mesh = read_mesh("m", str(msh))
    sets = [set(np.unique(np.concatenate(list(mesh.regions[n].blocks.values())))) for n in names]
    assert not sets[0] & sets[1], "the bodies share vertices"


@pytest.mark.parametrize("cells", [("hex8", "tet4"), ("tet4", "hex8")])
def test_generator_cylinder_pair(tmp_path, cells):
    """Curved vertices on the exact cylinders, curved faces wound outward, the given separation
    on the line x = 0, bodies with their own vertices, and a scene the preprocessor accepts."""
    s = 1e-3
    info = meshgen.cylinder_pair(tmp_path / "cyl.msh", radii=(1.0, 0.7), separation=s, cells=cells,
                                 n=((2, 9, 3), (2, 12, 2)))
    for part in info["parts"]:
        name = part.name
        c, axis = info["centers"][name], info["axis"]
        curved = part.points[np.unique(part.surfaces[f"{name}_curved"])]
        assert np.abs(info["distance"][name](curved)).max() < 1e-14
        n, radial = _outward(part, f"{name}_curved", lambda x: c + np.outer((x - c) @ axis, axis))
        assert np.all(np.einsum("ij,ij->i", n, radial) > 0.99)
        inner = part.points[np.unique(part.surfaces[f"{name}_inner"])]
        assert np.all(info["distance"][name](inner) < 0)
    upper = info["parts"][1]
    upper_curved = upper.points[np.unique(upper.surfaces["cyl2_curved"])]  # even n_theta: a vertex at x = 0
    assert abs(info["distance"]["cyl1"](upper_curved).min() - s) < 1e-15
    _separate_bodies(tmp_path / "cyl.msh", info["bodies"])
    prep(tmp_path, couple_scene("cyl.msh", info["bodies"], info["curved"]["cyl2"], info["curved"]["cyl1"]))


@pytest.mark.parametrize("cell", ["hex8", "tet4"])
def test_generator_sphere_on_plane(tmp_path, cell):
    """Ball vertices of the surface on the exact sphere, faces outward, lowest point (a face
    centre for odd n) `separation` above the plane z = 0; both surface naming schemes prep."""
    info = meshgen.sphere_on_plane(tmp_path / "sph.msh", separation=2e-3, n_ball=5, ball_cell=cell,
                                   ball_surfaces="patches")
    ball = info["parts"][1]
    names = info["ball_surface"]
    assert len(names) == 6
    nodes = ball.points[np.unique(np.concatenate([ball.surfaces[nm] for nm in names]))]
    assert np.abs(info["distance"](nodes)).max() < 1e-14
    for nm in names:
        n, radial = _outward(ball, nm, lambda x: info["center"])
        assert np.all(np.einsum("ij,ij->i", n, radial) > 0.9)
    bottom = ball.points[np.unique(ball.surfaces["ball_zmin"])]
    lowest = bottom[np.argsort(bottom[:, 2])[:4]]  # odd n: the 4 corners of the face under the centre
    assert np.abs(lowest[:, 2] - lowest[0, 2]).max() < 1e-15 and np.abs(lowest[:, :2].mean(axis=0)).max() < 1e-15
    assert np.hypot(bottom[:, 0], bottom[:, 1]).min() > 0.1
    plane = info["parts"][0]
    assert np.all(plane.surface_points("plane_zmax")[..., 2] == 0)
    _separate_bodies(tmp_path / "sph.msh", info["bodies"])
    prep(tmp_path, couple_scene("sph.msh", info["bodies"], info["plane_top"], names))
    single = meshgen.sphere_on_plane(tmp_path / "one.msh", n_ball=4, ball_cell=cell)
    prep(tmp_path, couple_scene("one.msh", single["bodies"], single["plane_top"], single["ball_surface"]), name="one")


def test_generator_folded_blocks(tmp_path):
    """The slave top is exactly the zigzag F with grid lines on the ridge and the valley, the
    master bottom is F + separation with vertex lines at ridge_x and valley_x; non-matching."""
    info = meshgen.folded_blocks(tmp_path / "fold.msh")
    lower, upper = info["parts"]
    top = lower.points[np.unique(lower.surfaces[info["slave"]])]
    bottom = upper.points[np.unique(upper.surfaces[info["master"]])]
    assert np.abs(top[:, 2] - info["F"](top[:, 0])).max() < 1e-14
    assert np.abs(bottom[:, 2] - info["F"](bottom[:, 0]) - info["separation"]).max() < 1e-14
    for x in (info["ridge"], info["valley"]):
        assert np.any(np.abs(top[:, 0] - x) < 1e-15)
    for x in (info["ridge_x"], info["valley_x"]):
        assert np.any(np.abs(bottom[:, 0] - x) < 1e-15)
    assert len(np.unique(top[:, 0])) != len(np.unique(bottom[:, 0]))
    _separate_bodies(tmp_path / "fold.msh", ["lower", "upper"])
    prep(tmp_path, couple_scene("fold.msh", ["lower", "upper"], info["master"], info["slave"]))


def test_generator_perturbed_blocks(tmp_path):
    """Contact-face vertices moved in plane (footprint kept) and out of plane by at most the
    requested fractions of the cell size; with out_of_plane = 0 the faces stay on z = z0."""
    n = ((4, 4, 2), (6, 5, 2))
    info = meshgen.perturbed_blocks(tmp_path / "p.msh", gap=0.01, n=n, in_plane=0.2, out_of_plane=0.1, seed=4)
    for part, side, (lo, hi), nn, z in zip(info["parts"], (info["lower_top"], info["upper_bottom"]),
                                           info["footprints"], n, (1.0, 1.01)):
        x = part.points[np.unique(part.surfaces[side])]
        assert np.allclose(x[:, :2].min(axis=0), lo, atol=1e-15) and np.allclose(x[:, :2].max(axis=0), hi, atol=1e-15)
        hz = 0.5 / nn[2]
        assert 0.02 * hz < np.abs(x[:, 2] - z).max() <= 0.1 * hz + 1e-15
        spacing = (np.array(hi) - lo) / nn[:2]
        off_grid = np.abs((x[:, :2] - lo) / spacing - np.rint((x[:, :2] - lo) / spacing))
        assert off_grid.max() > 0.05 and off_grid.max() <= 0.2 + 1e-12
    _separate_bodies(tmp_path / "p.msh", ["lower", "upper"])
    prep(tmp_path, couple_scene("p.msh", ["lower", "upper"], info["upper_bottom"], info["lower_top"]))
    flat = meshgen.perturbed_blocks(tmp_path / "f.msh", in_plane=0.25, out_of_plane=0.0, perturb=0.2, seed=1)
    for part, side in zip(flat["parts"], (flat["lower_top"], flat["upper_bottom"])):
        assert np.all(part.surface_points(side)[..., 2] == 1.0)
    with pytest.raises(ValueError, match="inverts"):
        meshgen.perturbed_blocks(tmp_path / "bad.msh", out_of_plane=0.9, perturb=0.2)
