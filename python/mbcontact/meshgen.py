"""Structured box meshes written as Gmsh 2.2 ASCII files through meshio.

Volumes and boundary surfaces carry gmsh physical tags and names, so the files
read back with meshio (and PETSc) with their regions and can be used directly
as mbcontact-prep input.

    box("b.msh", lo=(0, 0, 0), hi=(1, 1, 1), n=(4, 4, 2), cell="tet4")
    boxes("two.msh", [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(2, 2, 2), name="b1"),
                      dict(lo=(0, 0, 1), hi=(1, 1, 2), n=(3, 3, 3), name="b2")])

Contact-search geometries (two separate bodies per file, analytic data returned):
cylinder_pair, sphere_on_plane, folded_blocks, perturbed_blocks; built from the parts
box_part, cylinder_block, ball and written with write_parts.
"""
import itertools

import meshio
import numpy as np

from .cells import min_corner_volume

SIDES = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")

# Hex corners as (dx, dy, dz) in Gmsh order.
_HEX_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def _kuhn_tets():
    """Kuhn/Freudenthal split of the unit cube into 6 positive tets.

    One tet per axis order (a, b, c): 0 -> e_a -> e_a+e_b -> (1,1,1). All share the
    main diagonal and split every cube face along the diagonal from its lowest to
    its highest corner, so neighbouring cubes match.
    """
    tets = []
    for perm in itertools.permutations(range(3)):
        path = [np.zeros(3, int)]
        for axis in perm:
            path.append(path[-1] + np.eye(3, dtype=int)[axis])
        tet = [tuple(p) for p in path]
        if np.linalg.det(np.array(tet[1:]) - tet[0]) < 0:
            tet[1], tet[2] = tet[2], tet[1]
        tets.append(tet)
    return tets


_CELL_CORNERS = {"hex8": [_HEX_CORNERS], "tet4": _kuhn_tets()}
_MESHIO_TYPE = {"hex8": "hexahedron", "tet4": "tetra", "tet10": "tetra10"}
_FACE_TYPE = {"hex8": "quad", "tet4": "triangle", "tet10": "triangle6"}


def _box_arrays(lo, hi, n, cell, perturb, seed, face_perturb=None):
    """Points, volume cells and {side: faces} of one structured box.

    face_perturb: {side: (tangential, normal)} moves the vertices of a side after the
    interior perturbation (see boxes())."""
    lo, hi, n = np.asarray(lo, float), np.asarray(hi, float), np.asarray(n, int)
    if cell not in _CELL_CORNERS:
        raise ValueError(f"cell must be 'hex8' or 'tet4', got {cell!r}")
    if np.any(n < 1) or np.any(hi <= lo):
        raise ValueError(f"need n >= 1 and hi > lo, got n={n}, lo={lo}, hi={hi}")

    def node(i, j, k):
        return i + (n[0] + 1) * (j + (n[1] + 1) * k)

    ijk = np.stack(np.meshgrid(*(np.arange(m + 1) for m in n), indexing="ij"), -1)
    ijk = ijk.transpose(2, 1, 0, 3).reshape(-1, 3)  # i fastest, matches node()
    h = (hi - lo) / n
    points = lo + ijk * h
    rng = np.random.default_rng(seed)
    if perturb:
        interior = np.all((ijk > 0) & (ijk < n), axis=1)
        shift = rng.uniform(-1, 1, points.shape) * perturb * h
        points[interior] += shift[interior]
    for side, (tangential, normal) in sorted((face_perturb or {}).items()):
        if side not in SIDES:
            raise ValueError(f"face_perturb: unknown side {side!r}, expected one of {SIDES}")
        axis = SIDES.index(side) // 2
        on_side = ijk[:, axis] == (n[axis] if side.endswith("max") else 0)
        shift = rng.uniform(-1, 1, points.shape) * h
        for u in range(3):
            if u == axis:
                move = on_side  # out of plane: every vertex of the side, corners included
                amount = normal
            else:  # in plane: along the face's axis u, only vertices strictly inside in u
                move = on_side & (ijk[:, u] > 0) & (ijk[:, u] < n[u])
                amount = tangential
            points[move, u] += amount * shift[move, u]

    base = np.stack(np.meshgrid(*(np.arange(m) for m in n), indexing="ij"), -1).reshape(-1, 3)
    cells = np.concatenate([
        np.stack([node(*(base + corner).T) for corner in corners], axis=1)
        for corners in _CELL_CORNERS[cell]])

    if np.any(min_corner_volume(cell, points, cells) <= 0):
        raise ValueError(f"perturb={perturb}, face_perturb={face_perturb} inverts elements; "
                         "use smaller values")
    return points, cells, _box_sides(n, node, cell)


def _box_sides(n, node, cell):
    """Boundary faces of each box side, outward winding, split like the Kuhn tets."""
    sides = {}
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3  # e_u x e_v = +e_axis
        a, b = (g.ravel() for g in np.meshgrid(np.arange(n[u]), np.arange(n[v]), indexing="ij"))
        for name, fixed, outward in ((SIDES[2 * axis], 0, False), (SIDES[2 * axis + 1], n[axis], True)):
            def corner(du, dv):
                ijk = [None] * 3
                ijk[axis], ijk[u], ijk[v] = np.full_like(a, fixed), a + du, b + dv
                return node(*ijk)
            p00, p10, p11, p01 = corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)
            if cell == "hex8":
                faces = np.stack([p00, p10, p11, p01], axis=1)
            else:
                faces = np.concatenate([np.stack([p00, p10, p11], axis=1),
                                        np.stack([p00, p11, p01], axis=1)])
            sides[name] = faces if outward else faces[:, ::-1]
    return sides


def box(path, lo, hi, n=(1, 1, 1), cell="hex8", volume_name="body",
        perturb=0.0, seed=0, surfaces=True):
    """Write one box [lo, hi] split into n cells per axis.

    cell: "hex8" or "tet4" (6 Kuhn tets per hex). Volume region `volume_name`;
    with surfaces=True also the boundary regions xmin, xmax, ymin, ymax, zmin, zmax
    (quad4 / tri3). perturb moves interior nodes randomly by up to perturb*h per axis.
    """
    boxes(path, [dict(lo=lo, hi=hi, n=n, cell=cell, name=volume_name, perturb=perturb,
                      seed=seed, surfaces=surfaces)], prefix_surfaces=False)


def boxes(path, specs, prefix_surfaces=True):
    """Write several independent boxes (nodes not merged) into one mesh file.

    specs: dicts with keys lo, hi, n, cell ("hex8"), name, perturb (0), seed (0),
    surfaces (True), face_perturb (None). Each box is the volume region `name`; its
    sides are the surface regions `<name>_xmin`, ... (just `xmin`, ... if
    prefix_surfaces is False).

    face_perturb = {side: (tangential, normal)}, e.g. {"zmax": (0.2, 0.05)}: after the
    interior perturbation, every vertex of that side moves out of its plane by up to
    normal*h (h: cell size along the side's axis; corners and edges too), and in the
    plane, along each in-plane axis u, by up to tangential*h_u if it is not on the
    side's border in u (so vertices on the side's edges slide along them and the
    footprint keeps its shape). Uniform random from `seed`; ValueError if an element
    inverts (values up to about 0.2 each keep structured hex8 and tet4 boxes valid).
    """
    points, blocks, regions = [], [], []  # regions: (name, dim, cell type, cells)
    offset = 0
    for spec in specs:
        spec = dict(spec)
        name, cell = spec.pop("name"), spec.pop("cell", "hex8")
        with_surfaces = spec.pop("surfaces", True)
        p, cells, sides = _box_arrays(spec.pop("lo"), spec.pop("hi"), spec.pop("n", (1, 1, 1)),
                                      cell, spec.pop("perturb", 0.0), spec.pop("seed", 0),
                                      spec.pop("face_perturb", None))
        if spec:
            raise ValueError(f"box {name!r}: unknown keys {sorted(spec)}")
        points.append(p)
        regions.append((name, 3, _MESHIO_TYPE[cell], cells + offset))
        if with_surfaces:
            for side, faces in sides.items():
                label = f"{name}_{side}" if prefix_surfaces else side
                regions.append((label, 2, _FACE_TYPE[cell], faces + offset))
        offset += len(p)
    _write_gmsh(path, np.concatenate(points), regions)


def write_mesh(mesh, path, binary=False):
    """Write an in-memory meshio.Mesh as a Gmsh 2.2 file mbcontact-prep reads, every named
    region kept: its Gmsh physical groups (gmsh:physical + field_data) or its cell sets, which
    Gmsh 2.2 has no place for (meshio drops them), each region as its own physical group."""
    from .bodies import _regions

    regions = _regions(mesh)
    if not regions:
        raise ValueError(f"{path}: the mesh has no named regions (Gmsh physical names or meshio cell sets)")
    points = np.asarray(mesh.points, dtype=float)
    if points.shape[1] < 3:
        points = np.hstack([points, np.zeros((len(points), 3 - points.shape[1]))])
    cells, physical, field_data = [], [], {}
    for tag, (name, region) in enumerate(regions.items(), start=1):
        for cell_type, data in region.blocks.items():  # a region of several cell types: one tag
            cells.append((cell_type, np.asarray(data)))
            physical.append(np.full(len(data), tag, dtype=np.int32))
        field_data[name] = np.array([tag, region.dim])
    out = meshio.Mesh(points, cells, field_data=field_data,
                      cell_data={"gmsh:physical": physical, "gmsh:geometrical": physical})
    meshio.write(str(path), out, file_format="gmsh22", binary=binary)


def _write_gmsh(path, points, regions, binary=False):
    """Write regions as gmsh physical groups (one tag per region, unique over dims); binary
    Gmsh 2.2 writes and reads several times faster for meshes of millions of DOFs."""
    names = [r[0] for r in regions]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate region names in {names}")
    cells, physical, field_data = [], [], {}
    for tag, (name, dim, cell_type, data) in enumerate(regions, start=1):
        cells.append((cell_type, np.asarray(data)))
        physical.append(np.full(len(data), tag, dtype=np.int32))
        field_data[name] = np.array([tag, dim])
    mesh = meshio.Mesh(points, cells, field_data=field_data,
                       cell_data={"gmsh:physical": physical, "gmsh:geometrical": physical})
    meshio.write(str(path), mesh, file_format="gmsh22", binary=binary)


# ---------------------------------------------------------------------------
# Bodies for the contact-search tests (docs/contact-search.md): parts built in
# memory (box, cylinder sector, ball) and scenes of two bodies written together,
# each body with its own vertices (nothing merged).

class Part:
    """One body of a mesh file: the volume region `name` and its surface regions.

    points (n, 3); cells (nc, 8 | 4) in Gmsh order with positive volume; surfaces:
    surface region name -> faces (nf, 4 | 3) as indices into points, wound
    counter-clockwise seen from outside the body (quad4 for hex8, tri3 for tet4).
    """

    def __init__(self, name, cell, points, cells, surfaces):
        self.name, self.cell = name, cell
        self.points, self.cells, self.surfaces = np.asarray(points, float), np.asarray(cells), dict(surfaces)
        bad = np.count_nonzero(min_corner_volume(cell, self.points, self.cells) <= 0)
        if bad:
            raise ValueError(f"part {name!r}: {bad} of {len(self.cells)} {cell} cells are inverted or "
                             "degenerate; refine the mesh or reduce the distortion")

    def surface_points(self, surface):
        """Coordinates of the faces of one surface region, (nf, nv, 3)."""
        return self.points[self.surfaces[surface]]


def write_parts(path, parts):
    """Write parts (each an independent body: no vertex shared) into one Gmsh 2.2 file."""
    points, regions, offset = [], [], 0
    for part in parts:
        points.append(part.points)
        regions.append((part.name, 3, _MESHIO_TYPE[part.cell], part.cells + offset))
        for name, faces in part.surfaces.items():
            regions.append((name, 2, _FACE_TYPE[part.cell], np.asarray(faces) + offset))
        offset += len(part.points)
    _write_gmsh(path, np.concatenate(points), regions)


def box_part(name, lo, hi, n=(1, 1, 1), cell="hex8", perturb=0.0, seed=0, face_perturb=None):
    """A structured box as a Part; surfaces <name>_xmin, ..., <name>_zmax (see boxes())."""
    points, cells, sides = _box_arrays(lo, hi, n, cell, perturb, seed, face_perturb)
    return Part(name, cell, points, cells, {f"{name}_{side}": faces for side, faces in sides.items()})


def _mapped_part(name, cell, lo, hi, n, mapping, side_names):
    """A structured box in reference coordinates mapped by `mapping` (orientation-preserving).

    side_names: reference side (xmin, ...) -> surface suffix; sides mapped to the same
    suffix are joined into one surface region.
    """
    ref, cells, sides = _box_arrays(lo, hi, n, cell, 0.0, 0)
    surfaces = {}
    for side, faces in sides.items():
        label = f"{name}_{side_names[side]}"
        surfaces[label] = np.concatenate([surfaces[label], faces]) if label in surfaces else faces
    return Part(name, cell, mapping(ref), cells, surfaces)


def _unit(v, what):
    v = np.asarray(v, float)
    norm = np.linalg.norm(v)
    if v.shape != (3,) or not norm > 0:
        raise ValueError(f"{what} must be a non-zero 3-vector, got {v}")
    return v / norm


def cylinder_block(name, center=(0, 0, 0), radius=1.0, length=1.0, axis_dir=(0, 1, 0),
                   mid_dir=(0, 0, 1), angle_deg=90.0, inner=0.5, n=(2, 12, 2), cell="hex8"):
    """Sector of a thick-walled cylinder (a quarter cylinder for angle_deg=90, half for 180).

    The body is inner*radius <= r <= radius, |theta| <= angle_deg/2, |s| <= length/2 in
    cylindrical coordinates around the axis through `center` along `axis_dir`, theta
    measured from `mid_dir` (made orthogonal to the axis) towards axis_dir x mid_dir, s
    along the axis from `center`. n = (n_radial, n_theta, n_axial) cells, uniform in r,
    theta and s; tet4 splits each hex in 6 Kuhn tets. Vertices of the curved surface lie
    on the exact cylinder; its faces are planar (chords).

    Surfaces: <name>_curved (r = radius), <name>_inner (r = inner*radius),
    <name>_side0 / <name>_side1 (theta = -angle/2 / +angle/2), <name>_end0 / <name>_end1
    (s = -length/2 / +length/2). Returns a Part (write it with write_parts()).
    """
    a = _unit(axis_dir, "axis_dir")
    m = _unit(np.asarray(mid_dir, float) - np.dot(mid_dir, a) * a, "mid_dir (orthogonal to the axis)")
    b = np.cross(a, m)
    c = np.asarray(center, float)
    if not 0 < inner < 1 or not 0 < angle_deg < 360 or radius <= 0 or length <= 0:
        raise ValueError(f"need 0 < inner < 1, 0 < angle_deg < 360, radius > 0, length > 0; got "
                         f"inner={inner}, angle_deg={angle_deg}, radius={radius}, length={length}")
    half = np.radians(angle_deg) / 2

    def mapping(ref):  # reference (r, theta, s): d/dr x d/dtheta . d/ds > 0
        r, th, s = ref.T
        direction = np.cos(th)[:, None] * m + np.sin(th)[:, None] * b
        return c + s[:, None] * a + r[:, None] * direction

    return _mapped_part(name, cell, (inner * radius, -half, -length / 2), (radius, half, length / 2), n,
                        mapping, {"xmin": "inner", "xmax": "curved", "ymin": "side0", "ymax": "side1",
                                  "zmin": "end0", "zmax": "end1"})


def cube_to_sphere(q):
    """The standard cube-to-sphere map of points q (k, 3) of the cube surface |q|_inf = 1:
    x' = x sqrt(1 - y^2/2 - z^2/2 + y^2 z^2/3) and cyclically; |x'| = 1."""
    x2 = q**2
    y2, z2 = np.roll(x2, -1, axis=1), np.roll(x2, -2, axis=1)
    return q * np.sqrt(1 - y2 / 2 - z2 / 2 + y2 * z2 / 3)


def ball(name, center=(0, 0, 0), radius=1.0, n=8, cell="hex8", surfaces="single"):
    """A ball from the cube [-1, 1]^3 of n^3 cells (6 n^3 Kuhn tets for tet4).

    A reference point p goes to center + radius * |p|_inf * cube_to_sphere(p / |p|_inf):
    each cube shell |p|_inf = const becomes a sphere, the cube's surface the ball's
    surface (its vertices exactly on the sphere; the quad faces are slightly warped,
    triangles are chords). With n odd the six face centres of the cube, e.g. the
    lowest point of the ball, are face centres of the mesh; with n even they are
    vertices.

    surfaces="single": one surface region <name>_surface; "patches": the six mapped cube
    faces <name>_xmin, ..., <name>_zmax. Returns a Part.
    """
    c = np.asarray(center, float)
    if surfaces not in ("single", "patches"):
        raise ValueError(f"surfaces must be 'single' or 'patches', got {surfaces!r}")

    def mapping(ref):
        rinf = np.abs(ref).max(axis=1)
        unit = np.zeros_like(ref)
        inside = rinf > 0
        unit[inside] = cube_to_sphere(ref[inside] / rinf[inside, None])
        return c + radius * rinf[:, None] * unit

    names = {side: ("surface" if surfaces == "single" else side) for side in SIDES}
    return _mapped_part(name, cell, (-1, -1, -1), (1, 1, 1), (n, n, n), mapping, names)


def cylinder_distance(points, center, axis_dir, radius):
    """Signed distance of points (k, 3) to the infinite cylinder (> 0 outside)."""
    a = _unit(axis_dir, "axis_dir")
    d = np.asarray(points, float) - center
    return np.linalg.norm(d - np.outer(d @ a, a), axis=1) - radius


def sphere_distance(points, center, radius):
    """Signed distance of points (k, 3) to the sphere (> 0 outside)."""
    return np.linalg.norm(np.asarray(points, float) - center, axis=1) - radius


def cylinder_pair(path, radii=(1.0, 1.0), separation=1e-3, lengths=(0.5, 0.4), angle_deg=(60.0, 60.0),
                  n=((2, 15, 3), (2, 18, 2)), cells=("hex8", "tet4"), inner=0.6, names=("cyl1", "cyl2")):
    """Two cylinder sectors with parallel axes (along y), for the Hertz line contact.

    Lower body names[0]: radius radii[0], axis through (0, 0, -radii[0]), curved surface up
    (mid_dir +z), top line at z = 0. Upper body names[1]: radius radii[1], axis through
    (0, 0, radii[1] + separation), curved surface down: the surfaces are `separation` apart
    on the line x = 0 (touching for 0). lengths, angle_deg, n = (n_r, n_theta, n_axial), cells:
    per body (see cylinder_block); an odd n_theta puts a face centre on the top line, an
    even one a vertex line. Writes `path` and returns a dict: bodies, curved (surface
    names per body), centers, radii, axis, separation, and distance: body name ->
    function(points) giving the signed distance to that body's exact cylinder.
    """
    r1, r2 = radii
    centers = {names[0]: np.array([0.0, 0.0, -r1]), names[1]: np.array([0.0, 0.0, r2 + separation])}
    mids = {names[0]: (0, 0, 1), names[1]: (0, 0, -1)}
    parts = [cylinder_block(nm, centers[nm], r, length, (0, 1, 0), mids[nm], ang, inner, nn, cell)
             for nm, r, length, ang, nn, cell in zip(names, radii, lengths, angle_deg, n, cells)]
    write_parts(path, parts)
    axis = np.array([0.0, 1.0, 0.0])
    return {"bodies": list(names), "curved": {nm: f"{nm}_curved" for nm in names}, "centers": centers,
            "radii": dict(zip(names, radii)), "axis": axis, "separation": separation, "parts": parts,
            "distance": {nm: (lambda p, c=centers[nm], r=r: cylinder_distance(p, c, axis, r))
                         for nm, r in zip(names, radii)}}


def sphere_on_plane(path, radius=1.0, separation=1e-3, n_ball=9, ball_cell="hex8", half_width=0.4,
                    n_plane=(10, 10, 2), plane_cell="tet4", thickness=0.2, names=("plane", "ball"),
                    ball_surfaces="single"):
    """A ball above a flat block: the sphere-on-plane (Hertz point) contact.

    Block names[0] = [-half_width, half_width]^2 x [-thickness, 0] (n_plane cells; even
    counts put a vertex at the origin), top surface <plane>_zmax at z = 0. Ball names[1]
    (see ball()) of `radius` centred at (0, 0, radius + separation): its lowest point is
    `separation` above the origin. Writes `path`, returns a dict: bodies, plane_top,
    ball_surface (a list of names for ball_surfaces="patches"), center, radius,
    separation, distance(points) (signed distance to the exact sphere).
    """
    center = np.array([0.0, 0.0, radius + separation])
    plane = box_part(names[0], (-half_width, -half_width, -thickness), (half_width, half_width, 0.0),
                     n_plane, plane_cell)
    sphere = ball(names[1], center, radius, n_ball, ball_cell, ball_surfaces)
    write_parts(path, [plane, sphere])
    surface = (f"{names[1]}_surface" if ball_surfaces == "single"
               else [f"{names[1]}_{side}" for side in SIDES])
    return {"bodies": list(names), "plane_top": f"{names[0]}_zmax", "ball_surface": surface,
            "center": center, "radius": radius, "separation": separation, "parts": [plane, sphere],
            "distance": lambda p: sphere_distance(p, center, radius)}


def _remap_axis(points, axis, lo, h, knots):
    """Move the grid planes of a structured box along one axis, piecewise linearly, so
    that grid plane i_k lands on x_k for the knots [(i_k, x_k)] (monotone: stays valid)."""
    index = np.rint((points[:, axis] - lo) / h)
    i, x = zip(*sorted(knots))
    points[:, axis] = np.interp(index, i, x)


def folded_blocks(path, x_range=(0.0, 2.0), y_range=(0.0, 1.0), height=1.0, ridge=0.6, valley=1.4,
                  slope=0.5, separation=0.02, n_slave=(10, 3, 2), cell_slave="hex8",
                  master_x=(0.1, 1.9), master_y=(0.1, 0.9), thickness=0.5, n_master=(13, 4, 2),
                  cell_master="tet4", ridge_offset=0.0, valley_offset=0.0, names=("lower", "upper")):
    """A slave block with a folded top and a master block following the fold: the blind spot.

    Lower block names[0] over x_range x y_range, base z = 0, top z = F(x), a zigzag of slopes
    +slope, -slope, +slope: F = height - slope |x - ridge| up to the valley, then rising again
    with slope +slope. So a convex ridge (an edge along y) at x = ridge, z = height, and a
    concave valley at x = valley, both symmetric (slopes +-slope on either side). The lower
    grid planes in x are moved so that two of them lie exactly on the ridge and the valley
    (the slave surface is exactly F).

    Upper block names[1] over master_x x master_y (inside the lower footprint), bottom
    z = F(x) + separation (vertical offset), `thickness` thick, n_master cells (other sizes:
    non-matching). Its grid planes in x are moved so that one lies at x = ridge + ridge_offset
    and one at x = valley + valley_offset. For |ridge_offset| < blind (the half-width
    separation*slope/(1+slope^2) of the blind spot) the master vertices of that line see
    neither slave face next to the ridge along the face normals (the orthogonal projection
    on each face's plane falls outside the face); along the master normal they hit a face
    (with offset 0 and a vertical master normal, exactly the ridge edge: two faces accept).
    Under the valley both faces accept the orthogonal projection.

    Surfaces: <lower>_zmax (folded top, the slave), <upper>_zmin (the master), and the
    other box sides. Writes `path` and returns a dict with F, ridge, valley, slope,
    separation, blind (the half-width above), ridge_x and valley_x (x of the master vertex
    lines placed there), slave, master, parts.
    """
    if not x_range[0] < ridge < valley < x_range[1]:
        raise ValueError("need x_range[0] < ridge < valley < x_range[1]")
    blind = separation * slope / (1 + slope**2)
    ridge_x, valley_x = ridge + ridge_offset, valley + valley_offset
    if not master_x[0] < ridge_x < valley_x < master_x[1]:
        raise ValueError("the master block must cover the ridge and the valley")

    def F(x):
        x = np.asarray(x, float)
        return np.where(x <= valley, height - slope * np.abs(x - ridge),
                        height - slope * (valley - ridge) + slope * (x - valley))

    def knots(lo, hi, nx, xs):
        h = (hi - lo) / nx
        out = [(0, lo), (nx, hi)]
        for x in xs:
            i = int(np.clip(np.rint((x - lo) / h), 1, nx - 1))
            if any(i == k for k, _ in out):
                raise ValueError(f"{nx} cells over [{lo}, {hi}] are too few to place a grid plane at {x}")
            out.append((i, x))
        return out

    lower_lo, lower_hi = (x_range[0], y_range[0], 0.0), (x_range[1], y_range[1], height)
    p, cells, sides = _box_arrays(lower_lo, lower_hi, n_slave, cell_slave, 0.0, 0)
    _remap_axis(p, 0, x_range[0], (x_range[1] - x_range[0]) / n_slave[0],
                knots(x_range[0], x_range[1], n_slave[0], (ridge, valley)))
    p[:, 2] += (F(p[:, 0]) - height) * p[:, 2] / height
    lower = Part(names[0], cell_slave, p, cells, {f"{names[0]}_{s}": f for s, f in sides.items()})

    z0 = height + separation
    upper_lo, upper_hi = (master_x[0], master_y[0], z0), (master_x[1], master_y[1], z0 + thickness)
    q, cells, sides = _box_arrays(upper_lo, upper_hi, n_master, cell_master, 0.0, 0)
    _remap_axis(q, 0, master_x[0], (master_x[1] - master_x[0]) / n_master[0],
                knots(master_x[0], master_x[1], n_master[0], (ridge_x, valley_x)))
    q[:, 2] += (F(q[:, 0]) - height) * (z0 + thickness - q[:, 2]) / thickness
    upper = Part(names[1], cell_master, q, cells, {f"{names[1]}_{s}": f for s, f in sides.items()})
    write_parts(path, [lower, upper])
    return {"F": F, "ridge": ridge, "valley": valley, "slope": slope, "separation": separation,
            "blind": blind, "ridge_x": ridge_x, "valley_x": valley_x,
            "slave": f"{names[0]}_zmax", "master": f"{names[1]}_zmin", "parts": [lower, upper]}


def perturbed_blocks(path, z0=1.0, gap=0.0, footprints=(((0, 0), (1, 1)), ((0.1, -0.2), (1.3, 0.9))),
                     thickness=(0.5, 0.5), n=((4, 4, 2), (6, 5, 2)), cells=("hex8", "tet4"),
                     in_plane=0.2, out_of_plane=0.05, perturb=0.1, seed=0, names=("lower", "upper")):
    """Two blocks meeting at z = z0 (the upper one `gap` higher), with randomly moved contact faces.

    Lower block names[0]: footprints[0] = ((x0, y0), (x1, y1)) x [z0 - thickness[0], z0];
    upper block names[1]: footprints[1] x [z0 + gap, z0 + gap + thickness[1]]; n and cells
    per block (different sizes: non-matching meshes). Interior vertices move by up to
    perturb*h per axis; the vertices of the contact faces (<lower>_zmax, <upper>_zmin)
    move in plane by up to in_plane*h and out of plane by up to out_of_plane*h (see
    boxes(), face_perturb); with out_of_plane = 0 the faces stay exactly in their planes.
    Seeds seed and seed + 1. Writes `path`, returns a dict with the surface names
    (lower_top, upper_bottom), z0, gap, footprints, parts.
    """
    zs = ((z0 - thickness[0], z0), (z0 + gap, z0 + gap + thickness[1]))
    sides = ("zmax", "zmin")
    parts = [box_part(nm, (*fp[0], za), (*fp[1], zb), nn, cell, perturb, seed + i,
                      {side: (in_plane, out_of_plane)})
             for i, (nm, fp, (za, zb), nn, cell, side) in enumerate(zip(names, footprints, zs, n, cells, sides))]
    write_parts(path, parts)
    return {"lower_top": f"{names[0]}_zmax", "upper_bottom": f"{names[1]}_zmin", "z0": z0, "gap": gap,
            "footprints": footprints, "parts": parts}


# ---------------------------------------------------------------------------
# Meshes of the other element types: a box of hexes, pyramids and prisms (a mixed mesh, as
# Salome and Gmsh make between hex and tet regions) and a box of tet10 (quadratic tets).

def mixed_box(path, lo=(0, 0, 0), hi=(1, 1, 1), n=(3, 2, 2), name="body", perturb=0.0, seed=0):
    """A box whose cells along x are, by thirds: hexahedra, six pyramids around each hex's centre
    (a node added there), two prisms per hex (split along the diagonal of its z faces, so their
    triangles lie on z layers): conforming, in Gmsh order, positive. Surfaces xmin ... zmax of
    quads and (prisms' z faces) triangles. With perturb the interior vertices move as box()'s."""
    points, hexes, _ = _box_arrays(lo, hi, n, "hex8", perturb, seed)
    h = (np.asarray(hi, float) - np.asarray(lo, float)) / np.asarray(n)
    third = [n[0] / 3, 2 * n[0] / 3]
    points = list(points)
    blocks = {"hexahedron": [], "pyramid": [], "wedge": []}
    faces = {s: {"quad": [], "triangle": []} for s in SIDES}
    outward = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    side_of = ["zmin", "zmax", "ymin", "xmax", "ymax", "xmin"]
    for index, cell in enumerate(hexes):
        i = index // (n[1] * n[2])  # _box_arrays numbers hexes x-major
        j, k = (index // n[2]) % n[1], index % n[2]
        x0 = np.asarray(lo) + h * (i, j, k)
        kind = "hex" if i < third[0] else "pyr" if i < third[1] else "wedge"
        on = {"xmin": i == 0, "xmax": i == n[0] - 1, "ymin": j == 0, "ymax": j == n[1] - 1, "zmin": k == 0, "zmax": k == n[2] - 1}
        if kind == "hex":
            blocks["hexahedron"].append(cell)
        elif kind == "pyr":
            points.append(np.asarray(points)[cell].mean(axis=0))
            c = len(points) - 1
            for f in outward:
                blocks["pyramid"].append([*cell[f][::-1], c])  # base wound towards the apex
        else:
            blocks["wedge"] += [[cell[0], cell[1], cell[2], cell[4], cell[5], cell[6]],
                                [cell[0], cell[2], cell[3], cell[4], cell[6], cell[7]]]
        for f, side in zip(outward, side_of):
            if not on[side]:
                continue
            if kind == "wedge" and side in ("zmin", "zmax"):
                q = cell[f]
                faces[side]["triangle"] += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
            else:
                faces[side]["quad"].append(cell[f])
        del x0
    points = np.asarray(points)
    regions = [(name, 3, t, np.array(c)) for t, c in blocks.items() if c]
    for side in SIDES:
        for t, c in faces[side].items():
            if c:
                regions.append((f"{side}" if t == "quad" else f"{side}_tri", 2, t, np.array(c)))
    # one region per side: the triangles join the quads' name
    cells, physical, field_data = [], [], {}
    tags = {}
    for region, dim, t, data in regions:
        base = region[:-4] if region.endswith("_tri") else region
        tag = tags.setdefault(base, len(tags) + 1)
        cells.append((t, data))
        physical.append(np.full(len(data), tag, dtype=np.int32))
        field_data[base] = np.array([tag, dim])
    mesh = meshio.Mesh(points, cells, field_data=field_data,
                       cell_data={"gmsh:physical": physical, "gmsh:geometrical": physical})
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)
    return mesh


def tet10_box(path, lo=(0, 0, 0), hi=(1, 1, 1), n=(2, 2, 2), name="body", perturb=0.0, seed=0, curve=None):
    """box(cell="tet4") with a midside node on every edge (tet10, Gmsh order), surfaces xmin ...
    zmax as tri6. curve(points) -> points may move the nodes (corners and midside nodes alike:
    a curved mapping keeps the midside nodes on the curved edges)."""
    points, tets, sides = _box_arrays(lo, hi, n, "tet4", perturb, seed)
    edges = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
    pairs = np.sort(np.concatenate([tets[:, e] for e in edges]), axis=1)
    key, inverse = np.unique(pairs, axis=0, return_inverse=True)
    mid = len(points) + inverse.ravel().reshape(6, -1).T
    points = np.vstack([points, 0.5 * (points[key[:, 0]] + points[key[:, 1]])])
    cells10 = np.hstack([tets, mid])
    lookup = {tuple(k): len(points) - len(key) + m for m, k in enumerate(key)}

    def tri6(faces):
        out = []
        for a, b, c in faces:
            out.append([a, b, c] + [lookup[tuple(sorted(e))] for e in ((a, b), (b, c), (c, a))])
        return np.array(out)

    if curve is not None:
        points = curve(points)
    regions = [(name, 3, "tetra10", cells10)] + [(side, 2, "triangle6", tri6(faces)) for side, faces in sides.items()]
    _write_gmsh(path, points, regions)
