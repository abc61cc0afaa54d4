"""Structured box meshes written as Gmsh 2.2 ASCII files through meshio.

Volumes and boundary surfaces carry gmsh physical tags and names, so the files
read back with meshio (and PETSc) with their regions and can be used directly
as mbcontact-prep input.

    box("b.msh", lo=(0, 0, 0), hi=(1, 1, 1), n=(4, 4, 2), cell="tet4")
    boxes("two.msh", [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(2, 2, 2), name="b1"),
                      dict(lo=(0, 0, 1), hi=(1, 1, 2), n=(3, 3, 3), name="b2")])
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
_MESHIO_TYPE = {"hex8": "hexahedron", "tet4": "tetra"}
_FACE_TYPE = {"hex8": "quad", "tet4": "triangle"}


def _box_arrays(lo, hi, n, cell, perturb, seed):
    """Points, volume cells and {side: faces} of one structured box."""
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
    if perturb:
        interior = np.all((ijk > 0) & (ijk < n), axis=1)
        shift = np.random.default_rng(seed).uniform(-1, 1, points.shape) * perturb * h
        points[interior] += shift[interior]

    base = np.stack(np.meshgrid(*(np.arange(m) for m in n), indexing="ij"), -1).reshape(-1, 3)
    cells = np.concatenate([
        np.stack([node(*(base + corner).T) for corner in corners], axis=1)
        for corners in _CELL_CORNERS[cell]])

    if np.any(min_corner_volume(cell, points, cells) <= 0):
        raise ValueError(f"perturb={perturb} inverts elements; use a smaller value")
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
    surfaces (True). Each box is the volume region `name`; its sides are the surface
    regions `<name>_xmin`, ... (just `xmin`, ... if prefix_surfaces is False).
    """
    points, blocks, regions = [], [], []  # regions: (name, dim, cell type, cells)
    offset = 0
    for spec in specs:
        spec = dict(spec)
        name, cell = spec.pop("name"), spec.pop("cell", "hex8")
        with_surfaces = spec.pop("surfaces", True)
        p, cells, sides = _box_arrays(spec.pop("lo"), spec.pop("hi"), spec.pop("n", (1, 1, 1)),
                                      cell, spec.pop("perturb", 0.0), spec.pop("seed", 0))
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


def _write_gmsh(path, points, regions):
    """Write regions as gmsh physical groups (one tag per region, unique over dims)."""
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
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)
