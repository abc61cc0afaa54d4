#!/usr/bin/python3
"""The paper's Hertz example: two parallel cylinders R1 = R2 = 5 mm, E = 210 GPa (210000 MPa),
nu = 0.3, frictionless, 1 mm long in plane strain (u_z = 0 on both ends), a quarter of each
modelled (x >= 0, symmetry u_x = 0 on x = 0): the upper one's flat face y = R is moved by
-0.03 mm, the lower one's flat face y = -R is fixed vertically. Units mm, N, MPa, s, tonne.

Each quarter disc is a structured hex8 mesh of three mapped blocks (transfinite interpolation):
block 1 holds the contact point (0, 0) at a right-angle corner, with square elements of edge
`hc` over `fine` mm along the arc and inward, growing by at most `growth` beyond; blocks 2 and 3
fill the rest coarsely. One element through the length (the field does not vary along z).

  meshes/hertz/build.py OUTDIR [--hc 0.01] [--dynamic]    writes hertz.msh, hertz.yaml, hertz.h5 (static unless --dynamic)

A second, 3D case (sphere(): an eighth of a sphere on a quarter block, graded towards the pole)
checks Hertz point contact.
"""
import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402

R, E, NU, LENGTH, DELTA = 5.0, 210000.0, 0.3, 1.0, 0.03
DENSITY, DAMPING = 7.85e-9, 200.0  # t/mm3 (the paper's 7.85e-6 kg/mm3), 1/s


def graded(length, hc, fine, growth, hmax):
    """Points 0 .. length: steps hc up to `fine`, then growing by `growth` up to hmax, the
    last stretch scaled to end on `length`. Returns the normalised parameters (0 .. 1)."""
    x, h = [0.0], hc
    while x[-1] < length - 1e-12:
        if x[-1] >= fine - 1e-12:
            h = min(h * growth, hmax)
        x.append(x[-1] + h)
    x = np.array(x)
    if len(x) > 2 and x[-1] - length > 0.5 * (x[-1] - x[-2]):
        x = x[:-1]
    # stretch the graded part so the last point lands on length, keep the uniform part
    k = np.searchsorted(x, min(fine, length) - 1e-12)
    if x[-1] > x[k] and k < len(x) - 1:
        x[k:] = x[k] + (x[k:] - x[k]) * (length - x[k]) / (x[-1] - x[k])
    else:
        x *= length / x[-1]
    return x / length


def tfi(bottom, top, left, right, s, t):
    """Transfinite interpolation of four boundary curves (callables on [0, 1] -> (2,)) at the
    parameters s (along bottom/top) and t (along left/right): points (len(t), len(s), 2)."""
    S, T = np.meshgrid(s, t)
    B, Tp = np.array([bottom(v) for v in s]), np.array([top(v) for v in s])
    L, Rt = np.array([left(v) for v in t]), np.array([right(v) for v in t])
    p00, p10, p01, p11 = bottom(0.0), bottom(1.0), top(0.0), top(1.0)
    out = ((1 - T)[..., None] * B[None, :, :] + T[..., None] * Tp[None, :, :]
           + (1 - S)[..., None] * L[:, None, :] + S[..., None] * Rt[:, None, :]
           - ((1 - S) * (1 - T))[..., None] * p00 - (S * (1 - T))[..., None] * p10
           - ((1 - S) * T)[..., None] * p01 - (S * T)[..., None] * p11)
    return out


def line(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return lambda u: a + u * (b - a)


def quarter_disc(hc, fine, growth=1.15, hmax=None, inner=0.45):
    """2D quad mesh of the upper cylinder's quarter x >= 0, y <= R (centre (0, R)); the
    contact point (0, 0). Returns points (n, 2), quads (m, 4) counter-clockwise."""
    hmax = hmax or R / 10
    a = inner * R
    O = np.array([0.0, R])
    arc = lambda phi0, phi1: (lambda u: O + R * np.array([np.cos(phi0 + u * (phi1 - phi0)), np.sin(phi0 + u * (phi1 - phi0))]))  # noqa: E731
    A, B, E_, G = np.array([0.0, 0.0]), O + R * np.array([np.cos(-np.pi / 4), np.sin(-np.pi / 4)]), np.array([R, R]), O
    C, D, F = np.array([a, R - a]), np.array([0.0, R - a]), np.array([a, R])
    s1 = graded(R * np.pi / 4, hc, fine, growth, hmax)                # along the arc from the contact
    t1 = graded(R - a, hc, fine, growth, hmax)                          # inward from the arc
    s2 = np.linspace(0, 1, max(2, int(np.ceil(R * np.pi / 4 / hmax))) + 1)  # arc B -> E, coarse
    blocks = [tfi(arc(-np.pi / 2, -np.pi / 4), line(D, C), line(A, D), line(B, C), s1, t1),   # A B C D
              tfi(arc(-np.pi / 4, 0.0), line(C, F), line(B, C), line(E_, F), s2, t1),          # B E F C
              tfi(line(D, C), line(G, F), line(D, G), line(C, F), s1, s2)]                    # D C F G
    points, quads = [], []
    for blk in blocks:
        nt, ns = blk.shape[:2]
        base = sum(len(p) for p in points)
        points.append(blk.reshape(-1, 2))
        idx = base + np.arange(nt * ns).reshape(nt, ns)
        quads.append(np.stack([idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]], -1).reshape(-1, 4))
    points, quads = np.concatenate(points), np.concatenate(quads)
    key = np.round(points / (1e-9 * R)).astype(np.int64)  # merge the blocks' shared edges
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return points[first], inverse.reshape(-1)[quads]


def extrude(name, points2, quads, length, flip_y=False):
    """One hex8 layer through z in [0, length]; surfaces by position: <name>_arc (curved),
    <name>_flat (y = +-R), <name>_sym (x = 0), <name>_ends (z = 0 and z = length)."""
    p2 = points2 * (1, -1) if flip_y else points2
    q = quads[:, ::-1] if flip_y else quads  # mirroring reverses the winding
    n = len(p2)
    pts = np.concatenate([np.c_[p2, np.zeros(n)], np.c_[p2, np.full(n, length)]])
    hexes = np.c_[q, q + n]
    edges = {}
    for quad in q:  # boundary edges: in one quad only, kept with that quad's (ccw) direction
        for i in range(4):
            e = (quad[i], quad[(i + 1) % 4])
            key = (min(e), max(e))
            edges[key] = None if key in edges else e
    surfaces = {f"{name}_arc": [], f"{name}_flat": [], f"{name}_sym": []}
    centre = np.array([0.0, -R if flip_y else R])
    for e in edges.values():
        if e is None:
            continue
        a, b = p2[e[0]], p2[e[1]]
        mid = 0.5 * (a + b)
        if abs(a[0]) < 1e-9 and abs(b[0]) < 1e-9:
            side = "sym"
        elif abs(abs(a[1]) - R) < 1e-9 and abs(abs(b[1]) - R) < 1e-9:
            side = "flat"
        elif abs(np.linalg.norm(a - centre) - R) < 1e-6 and abs(np.linalg.norm(b - centre) - R) < 1e-6 and np.linalg.norm(mid - centre) < R:
            side = "arc"
        else:
            raise RuntimeError(f"unclassified boundary edge {a} {b}")
        surfaces[f"{name}_{side}"].append((e[0], e[1], e[1] + n, e[0] + n))
    surfaces[f"{name}_ends"] = np.concatenate([q[:, ::-1], q + n])
    return meshgen.Part(name, "hex8", pts, hexes, {k: np.asarray(v) for k, v in surfaces.items()})


def _prism_tets(v):
    """The 3 tets of the prism v (bottom v0 v1 v2, top v3 v4 v5 above them): each quad side face
    cut along the diagonal through its smallest (global) vertex, so neighbours agree (Dompierre
    et al.'s rule)."""
    rot = {0: [0, 1, 2, 3, 4, 5], 1: [1, 2, 0, 4, 5, 3], 2: [2, 0, 1, 5, 3, 4],
           3: [3, 5, 4, 0, 2, 1], 4: [4, 3, 5, 1, 0, 2], 5: [5, 4, 3, 2, 1, 0]}[int(np.argmin(v))]
    w = [v[i] for i in rot]  # w0 the smallest
    if min(w[1], w[5]) < min(w[2], w[4]):
        return [[w[0], w[1], w[2], w[5]], [w[0], w[1], w[5], w[4]], [w[0], w[4], w[5], w[3]]]
    return [[w[0], w[1], w[2], w[4]], [w[0], w[4], w[2], w[5]], [w[0], w[4], w[5], w[3]]]


def tet10_part(part, centre):
    """The one-layer hex8 part of extrude() as tet10: each hex two prisms (its quads cut along
    (q0, q2)), each prism 3 tets; a midside node on every edge, on the cylinder (radius R about
    the axis through `centre` in x, y) where both ends are; surfaces as tri6, each quad cut as the
    tets cut it (along the diagonal through its smallest vertex)."""
    pts, hexes = part.points, part.cells
    tets = []
    for h in hexes:
        for t in ((0, 1, 2), (0, 2, 3)):
            tets.extend(_prism_tets([h[t[0]], h[t[1]], h[t[2]], h[4 + t[0]], h[4 + t[1]], h[4 + t[2]]]))
    tets = np.array(tets)
    x = pts[tets]
    vol = np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0])
    tets[vol < 0] = tets[vol < 0][:, [0, 2, 1, 3]]
    edges = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    pairs = np.sort(np.concatenate([tets[:, e] for e in edges]), axis=1)
    key, inverse = np.unique(pairs, axis=0, return_inverse=True)
    mid = 0.5 * (pts[key[:, 0]] + pts[key[:, 1]])
    r = lambda p: np.linalg.norm(p[:, :2] - centre, axis=1)  # noqa: E731
    arc = (np.abs(r(pts[key[:, 0]]) - R) < 1e-6) & (np.abs(r(pts[key[:, 1]]) - R) < 1e-6)
    mid[arc, :2] = centre + (mid[arc, :2] - centre) * (R / r(mid[arc]))[:, None]
    n = len(pts)
    cells = np.hstack([tets, n + inverse.ravel().reshape(6, -1).T])
    lookup = {tuple(k): n + m for m, k in enumerate(key)}

    def tri6(faces):
        tris = []
        for f in faces:
            if len(f) == 4:
                a = int(np.argmin(f))
                f = [f[(a + i) % 4] for i in range(4)]
                tris += [[f[0], f[1], f[2]], [f[0], f[2], f[3]]]
            else:
                tris.append(list(f))
        return np.array([[a, b, c] + [lookup[tuple(sorted(e))] for e in ((a, b), (b, c), (c, a))] for a, b, c in tris])

    surfaces = {}
    for name, faces in part.surfaces.items():
        if name.endswith("_ends"):  # the prisms' triangles, not the quads' min-vertex cut
            m = len(faces) // 2
            bottom, top = faces[:m][:, ::-1], faces[m:]
            faces = [t for q in bottom for t in ([q[0], q[2], q[1]], [q[0], q[3], q[2]])] + [t for q in top for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])]
        surfaces[name] = tri6(faces)
    return meshgen.Part(part.name, "tet10", np.vstack([pts, mid]), cells, surfaces)


def cylinders_scene(analysis="static", dt=0.01, final_time=3.0, ramp=1.0):
    material = {"E": E, "nu": NU}
    if analysis == "dynamic":
        material.update(density=DENSITY, damping=DAMPING)
    scene = {
        "title": "Hertz: two parallel cylinders (Li, Liu, Xiao, Ma)",
        "meshes": {"m": "hertz.msh"},
        "bodies": {"upper": {"mesh": "m", "regions": "upper", "material": material},
                   "lower": {"mesh": "m", "regions": "lower", "material": material}},
        "couples": [{"k": 1, "master": "upper_arc", "slave": "lower_arc", "mu": 0.0}],
        "dirichlet": [{"surface": "upper_sym", "components": ["x"]}, {"surface": "lower_sym", "components": ["x"]},
                      {"surface": "upper_ends", "components": ["z"]}, {"surface": "lower_ends", "components": ["z"]},
                      {"surface": "lower_flat", "components": ["y"]},
                      {"surface": "upper_flat", "components": ["y"], "value": -DELTA,
                       "time": {"table": [[0, 0], [ramp, 1], [max(final_time, ramp) + 1, 1]]} if analysis == "dynamic" else "constant"}],
        "analysis": {"type": analysis},
        "output": {"fields": ["displacement"]},
    }
    if analysis == "dynamic":
        scene["analysis"].update(dt=dt, final_time=final_time)
        scene["output"]["every"] = 1000000
    return scene


def build(outdir, hc=0.01, fine=None, analysis="static", dt=0.01, final_time=3.0, cell="hex8"):
    """Writes the cylinder pair with contact element edge hc (uniform over `fine` mm, default
    4 half-widths) and its scene; returns the scene file. cell "tet10": the same hexes as 6 tets
    each with their midside nodes on the arcs (tet10_part); "tet4": those tets alone."""
    os.makedirs(outdir, exist_ok=True)
    fine = fine if fine is not None else 0.75
    p2, quads = quarter_disc(hc, fine)
    parts = [extrude("upper", p2, quads, LENGTH), extrude("lower", p2, quads, LENGTH, flip_y=True)]
    if cell in ("tet10", "tet4"):
        parts = [tet10_part(parts[0], np.array([0.0, R])), tet10_part(parts[1], np.array([0.0, -R]))]
    if cell == "tet4":  # the same tets without their midside nodes
        parts = [meshgen.Part(p.name, "tet4", p.points[:p.cells[:, :4].max() + 1], p.cells[:, :4],
                              {k: f[:, :3] for k, f in p.surfaces.items()}) for p in parts]
    meshgen.write_parts(os.path.join(outdir, "hertz.msh"), parts)
    return prepare(outdir, "hertz", cylinders_scene(analysis, dt, final_time))


def _graded_axis(length, hc, fine, growth, hmax):
    return graded(length, hc, fine, growth, hmax) * length


def _lattice(nx, ny, nz):
    """Reference points and hex8 cells of the integer lattice [0,nx]x[0,ny]x[0,nz], and its
    boundary faces per side (counter-clockwise from outside), from meshgen's box."""
    return meshgen._box_arrays((0, 0, 0), (nx, ny, nz), (nx, ny, nz), "hex8", 0.0, 0)


def _fix_orientation(points, cells):
    """Swap the two hex faces where the map reversed the orientation."""
    from mbcontact.cells import min_corner_volume
    bad = min_corner_volume("hex8", points, cells) < 0
    cells = cells.copy()
    cells[bad] = cells[bad][:, [4, 5, 6, 7, 0, 1, 2, 3]]
    return cells, bad.any()


def sphere_parts(radius, hc, fine, growth=1.2, hmax=None, block=None, cap_radius=None, block_hc=None):
    """An eighth of a sphere (centre (0, 0, radius), pole at the origin, x, y >= 0,
    z <= radius) on a quarter block [0, W]^2 x [-W, 0], W = block (default: the radius), both
    graded towards the contact point, the block from block_hc (default hc). The cube-to-sphere
    map makes the ball's elements at the pole hc / sqrt(2): with block_hc = hc the master (the
    ball, where the multipliers live) is finer than the slave there. The ball octant is the cube-to-sphere map of the graded
    unit cube (fine towards x = 0, y = 0 and the pole face). The master surface is the cap of
    the pole face within cap_radius (default: the fine zone) of the axis: farther faces cannot
    touch, and every master node costs a column of X = A^-1 H."""
    hmax = hmax or radius / 8
    W = block or radius
    cap_radius = cap_radius or fine
    ax = graded(radius, hc, fine, growth, hmax)       # 0 .. 1, fine at 0
    ref, cells, sides = _lattice(len(ax) - 1, len(ax) - 1, len(ax) - 1)
    n = len(ax) - 1
    u = np.interp(ref / n, np.linspace(0, 1, n + 1), ax)  # graded reference in [0,1]^3 per axis...
    q = np.c_[u[:, 0], u[:, 1], 1 - np.interp(1 - ref[:, 2] / n, np.linspace(0, 1, n + 1), ax)]  # ... fine at w = 1 (the pole face)
    sn = np.abs(q).max(axis=1)
    unit = np.zeros_like(q)
    nz = sn > 0
    unit[nz] = meshgen.cube_to_sphere(q[nz] / sn[nz, None])
    pts = radius * sn[:, None] * unit
    pts = np.c_[pts[:, 0], pts[:, 1], radius - pts[:, 2]]
    cells, flipped = _fix_orientation(pts, cells)
    flip = (lambda f: f[:, ::-1]) if flipped else (lambda f: f)
    pole = sides["zmax"]
    cap = pole[np.linalg.norm(pts[pole][:, :, :2].mean(axis=1), axis=1) < cap_radius]  # the faces that can touch
    ball = meshgen.Part("ball", "hex8", pts, cells, {"ball_pole": flip(cap), "ball_flat": flip(sides["zmin"]),
                                                       "ball_symx": flip(sides["xmin"]), "ball_symy": flip(sides["ymin"])})
    gx = _graded_axis(W, block_hc or hc, fine, growth, hmax)
    ref, cells, sides = _lattice(len(gx) - 1, len(gx) - 1, len(gx) - 1)
    m = len(gx) - 1
    bp = np.c_[np.interp(ref[:, 0], np.arange(m + 1), gx), np.interp(ref[:, 1], np.arange(m + 1), gx),
               -np.interp(m - ref[:, 2], np.arange(m + 1), gx)]
    blk = meshgen.Part("block", "hex8", bp, cells, {"block_top": sides["zmax"], "block_bottom": sides["zmin"],
                                                      "block_symx": sides["xmin"], "block_symy": sides["ymin"]})
    return ball, blk


SPHERE_R, SPHERE_DELTA = 10.0, 0.02


def sphere_scene():
    material = {"E": E, "nu": NU}
    return {
        "title": "Hertz: sphere on a half-space (an eighth and a quarter block)",
        "meshes": {"m": "sphere.msh"},
        "bodies": {"ball": {"mesh": "m", "regions": "ball", "material": material},
                   "block": {"mesh": "m", "regions": "block", "material": material}},
        "couples": [{"k": 1, "master": "ball_pole", "slave": "block_top", "mu": 0.0}],
        "dirichlet": [{"surface": "ball_symx", "components": ["x"]}, {"surface": "block_symx", "components": ["x"]},
                      {"surface": "ball_symy", "components": ["y"]}, {"surface": "block_symy", "components": ["y"]},
                      {"surface": "block_bottom", "components": ["z"]},
                      {"surface": "ball_flat", "components": ["z"], "value": -SPHERE_DELTA}],
        "analysis": {"type": "static"},
        "output": {"fields": ["displacement"]},
    }


def build_sphere(outdir, hc=0.05, fine=0.8, block_hc=None):
    os.makedirs(outdir, exist_ok=True)
    meshgen.write_parts(os.path.join(outdir, "sphere.msh"), list(sphere_parts(SPHERE_R, hc, fine, block_hc=block_hc)))
    return prepare(outdir, "sphere", sphere_scene())


def two_spheres_scene(delta):
    material = {"E": E, "nu": NU}
    return {
        "title": "Hertz: two equal spheres (an eighth of each)",
        "meshes": {"m": "two_spheres.msh"},
        "bodies": {"upper": {"mesh": "m", "regions": "upper", "material": material},
                   "lower": {"mesh": "m", "regions": "lower", "material": material}},
        "couples": [{"k": 1, "master": "upper_pole", "slave": "lower_pole", "mu": 0.0}],
        "dirichlet": [{"surface": f"{b}_sym{a}", "components": [a]} for b in ("upper", "lower") for a in "xy"]
                     + [{"surface": "upper_flat", "components": ["z"], "value": -delta / 2},
                        {"surface": "lower_flat", "components": ["z"], "value": delta / 2}],
        "analysis": {"type": "static"},
        "output": {"fields": ["displacement"]},
    }


def build_two_spheres(outdir, hc, fine, delta, radius=SPHERE_R):
    """Two equal spheres of radius R touching at the origin, an eighth of each (the upper one is
    sphere_parts' ball, the lower its mirror image in z = 0), pressed together by the approach
    delta of their flat faces (each moves delta / 2). Hertz: the effective radius is R / 2 and
    a^2 = delta R / 2, so a / R = 0.2 at delta = 0.08 R."""
    os.makedirs(outdir, exist_ok=True)
    ball, _ = sphere_parts(radius, hc, fine)
    upper = meshgen.Part("upper", "hex8", ball.points, ball.cells,
                         {k.replace("ball", "upper"): f for k, f in ball.surfaces.items()})
    lower = meshgen.Part("lower", "hex8", ball.points * np.array([1.0, 1.0, -1.0]), ball.cells[:, [4, 5, 6, 7, 0, 1, 2, 3]],
                         {k.replace("ball", "lower"): f[:, ::-1] for k, f in ball.surfaces.items()})  # a mirror turns cells and faces inside out
    meshgen.write_parts(os.path.join(outdir, "two_spheres.msh"), [upper, lower])
    return prepare(outdir, "two_spheres", two_spheres_scene(delta))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--hc", type=float, default=0.01, help="element edge at the contact [mm]")
    ap.add_argument("--dynamic", action="store_true", help="the paper's dynamic route (dt 0.01 s to 3 s)")
    a = ap.parse_args()
    print(build(a.outdir, a.hc, analysis="dynamic" if a.dynamic else "static"))
