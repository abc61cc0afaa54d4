"""Meshes -> bodies, boundary faces and face labels (meshio + numpy, no PETSc).

A body is the union of the cells of some 3D regions of one mesh, renumbered to its
own compact vertex numbering. Surfaces (2D regions) are matched to the boundary
faces of the bodies by their sorted vertex sets.
"""
import contextlib
import io
import os
from dataclasses import dataclass

import numpy as np

from .cells import FACES, SURFACE_TYPES, TO_PETSC, VOLUME_TYPES, min_corner_volume
from .scene import InputError, warn

_DIMENSIONS = (("vertex", 0), ("line", 1), ("triangle", 2), ("quad", 2), ("polygon", 2),
               ("tetra", 3), ("hexahedron", 3), ("wedge", 3), ("pyramid", 3), ("polyhedron", 3))


def cell_dimension(cell_type):
    for prefix, dim in _DIMENSIONS:
        if cell_type.startswith(prefix):
            return dim
    return -1


@dataclass
class Region:
    dim: int
    blocks: dict  # meshio cell type -> cells (mesh vertex indices), in file order


@dataclass
class MeshFile:
    name: str
    path: str
    points: np.ndarray  # (n, 3)
    regions: dict       # region name -> Region

    def describe(self):
        return f"mesh '{self.name}' ({self.path})"

    def region_list(self, dim):
        names = [n for n, r in self.regions.items() if r.dim == dim]
        return ", ".join(names) if names else "none"


def read_mesh(name, path):
    import meshio  # slow import; only needed here

    if not os.path.isfile(path):
        raise InputError(f"meshes.{name}: mesh file not found: {path}")
    # .msh is also an ANSYS extension; meshio would try both and print the failures
    file_format = "gmsh" if path.lower().endswith(".msh") else None
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter):
            mesh = meshio.read(path, file_format=file_format)
    except Exception as err:  # meshio raises many kinds of errors on bad files
        detail = " ".join(f"{chatter.getvalue()} {err}".split())
        raise InputError(f"meshes.{name}: cannot read mesh file {path}: {detail}") from None
    points = np.asarray(mesh.points, dtype=float)
    if points.shape[1] < 3:
        points = np.hstack([points, np.zeros((len(points), 3 - points.shape[1]))])
    regions = _regions(mesh)
    if not regions:
        raise InputError(f"meshes.{name}: {path} has no named regions "
                         "(Gmsh physical names or meshio cell sets)")
    return MeshFile(name, path, points, regions)


def _regions(mesh):
    """Named regions: Gmsh physical groups (tag, dim) and meshio cell sets."""
    found = {}  # name -> {cell type: [arrays]}

    def add(name, cell_type, cells):
        if len(cells):
            found.setdefault(name, {}).setdefault(cell_type, []).append(cells)

    physical = mesh.cell_data.get("gmsh:physical")
    if physical is not None:
        for name, (tag, dim) in ((n, v[:2]) for n, v in mesh.field_data.items()):
            for block, tags in zip(mesh.cells, physical):
                if cell_dimension(block.type) == dim:
                    add(name, block.type, block.data[tags == tag])
    for name, per_block in mesh.cell_sets.items():
        if name in found or name.startswith("gmsh:"):
            continue
        for block, index in zip(mesh.cells, per_block):
            if index is not None:
                add(name, block.type, block.data[np.asarray(index, dtype=int)])

    regions = {}
    for name, blocks in found.items():
        dim = max(cell_dimension(t) for t in blocks)  # lower-dim cells in a set are ignored
        regions[name] = Region(dim, {t: np.concatenate(c) for t, c in blocks.items()
                                     if cell_dimension(t) == dim})
    return regions


# ---------------------------------------------------------------- bodies

def build_bodies(scene, meshes):
    """BodyMesh of every scene body; meshes: mesh name -> MeshFile."""
    owners = {}  # (mesh, region) -> body
    for body in scene.bodies:
        for region in body.regions:
            other = owners.setdefault((body.mesh, region), body.name)
            if other != body.name:
                raise InputError(f"bodies.{body.name}.regions: region '{region}' of mesh "
                                 f"'{body.mesh}' is already used by body '{other}'")
    built = [build_body(body, meshes[body.mesh]) for body in scene.bodies]
    for body, mesh in zip(scene.bodies, built):
        if body.element and mesh.cell_type != "hex8":
            raise InputError(f"bodies.{body.name}.element: {body.element!r} is an element of hex bodies; "
                             f"body '{body.name}' has {mesh.cell_type} cells (leave element out)")
    return built


@dataclass
class BodyMesh:
    name: str
    mesh: MeshFile
    cell_type: str            # "tet4" | "hex8"
    cells: np.ndarray         # (nc, 4|8) body vertex indices, Gmsh order
    coords: np.ndarray        # (nv, 3)
    vertex_map: np.ndarray    # mesh vertex -> body vertex, -1 if not in the body
    boundary_keys: np.ndarray   # (nb, 3|4) sorted vertices of each boundary face
    boundary_faces: np.ndarray  # (nb, 3|4) same faces, cyclic order

    def petsc_cells(self):
        return self.cells[:, TO_PETSC[self.cell_type]].astype(np.int32)


def build_body(body, mesh):
    where = f"bodies.{body.name}.regions"
    blocks = []  # (region name, cell type, cells)
    for region_name in body.regions:
        region = mesh.regions.get(region_name)
        if region is None:
            raise InputError(f"{where}: region '{region_name}' not found in {mesh.describe()}; "
                             f"volume regions there: {mesh.region_list(3)}; "
                             f"surface regions: {mesh.region_list(2)}")
        if region.dim != 3:
            raise InputError(f"{where}: region '{region_name}' of {mesh.describe()} is "
                             f"{region.dim}D, a body needs 3D (volume) regions: {mesh.region_list(3)}")
        for meshio_type, cells in region.blocks.items():
            if meshio_type not in VOLUME_TYPES:
                raise InputError(f"{where}: region '{region_name}' of {mesh.describe()} has cells of "
                                 f"type '{meshio_type}'; only tet4 (tetra) and hex8 (hexahedron) "
                                 "are supported")
            blocks.append((region_name, VOLUME_TYPES[meshio_type], cells))

    types = sorted({t for _, t, _ in blocks})
    if len(types) > 1:
        raise InputError(f"{where}: body '{body.name}' mixes {' and '.join(types)} cells; "
                         "use one body per cell type")
    cell_type = types[0]
    for region_name, _, cells in blocks:
        _check_cells(body.name, mesh, region_name, cell_type, cells)
    cells = np.concatenate([c for _, _, c in blocks])
    if len(np.unique(np.sort(cells, axis=1), axis=0)) != len(cells):
        raise InputError(f"{where}: body '{body.name}' contains the same element twice "
                         "(do its regions overlap?)")

    vertices = np.unique(cells)
    vertex_map = np.full(len(mesh.points), -1, dtype=np.int64)
    vertex_map[vertices] = np.arange(len(vertices))
    cells = vertex_map[cells]
    keys, faces = _boundary(body.name, mesh, cell_type, cells)
    return BodyMesh(body.name, mesh, cell_type, cells, mesh.points[vertices], vertex_map, keys, faces)


def _check_cells(body_name, mesh, region_name, cell_type, cells):
    """Finite coordinates and positive volumes (Gmsh convention)."""
    coords = mesh.points[cells]
    bad = np.nonzero(~np.all(np.isfinite(coords), axis=(1, 2)))[0]
    if len(bad):
        node = cells[bad[0]][~np.all(np.isfinite(coords[bad[0]]), axis=1)][0]
        raise InputError(f"bodies.{body_name}: node {node + 1} (1-based, file order) of "
                         f"{mesh.describe()} has a non-finite coordinate")
    bad = np.nonzero(min_corner_volume(cell_type, mesh.points, cells) <= 0)[0]
    if len(bad):
        raise InputError(f"bodies.{body_name}: element {bad[0] + 1} of region '{region_name}' "
                         f"in {mesh.path} is inverted or degenerate (signed volume <= 0 in the "
                         f"Gmsh vertex order; {len(bad)} such elements in that region; "
                         "index is 1-based in file order within the region)")


def _boundary(body_name, mesh, cell_type, cells):
    """Faces that belong to exactly one cell: (sorted keys, cyclic vertex lists)."""
    local = FACES[cell_type]
    faces = cells[:, local].reshape(-1, local.shape[1])
    keys, first, counts = np.unique(np.sort(faces, axis=1), axis=0,
                                    return_index=True, return_counts=True)
    if np.any(counts > 2):
        raise InputError(f"bodies.{body_name}: {mesh.describe()} is not a valid volume mesh: "
                         "a face is shared by more than two elements")
    boundary = counts == 1
    return keys[boundary], faces[first[boundary]]


def row_index(table, rows):
    """Index in `table` (rows unique) of each row of `rows`; -1 where absent."""
    if len(table) == 0 or len(rows) == 0:
        return np.full(len(rows), -1)
    _, inverse = np.unique(np.concatenate([table, rows]), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    position = np.full(inverse.max() + 1, -1)
    position[inverse[:len(table)]] = np.arange(len(table))
    return position[inverse[len(table):]]


# ---------------------------------------------------------------- surfaces

def surface_faces(name, references, bodies):
    """Boundary faces of each body lying on surface `name`: {body index: face indices}.

    references: where the surface is used (for messages).
    """
    used_in = f"surface '{name}' (used in {', '.join(references)})"
    meshes = {b.mesh.name: b.mesh for b in bodies}
    found = [m for m in meshes.values() if name in m.regions]
    if not found:
        lists = "; ".join(f"{m.describe()}: {m.region_list(2)}" for m in meshes.values())
        raise InputError(f"{used_in}: no such region in the meshes of the bodies "
                         f"(surface regions: {lists})")
    result, total, unmatched = {}, 0, 0
    for mesh in found:
        faces = _surface_cells(mesh, name, used_in)
        for nv, cells in faces.items():
            matched = np.zeros(len(cells), dtype=bool)
            for i, body in enumerate(bodies):
                if body.mesh is not mesh or body.boundary_keys.shape[1] != nv:
                    continue
                local = body.vertex_map[cells]
                inside = np.all(local >= 0, axis=1)
                index = np.full(len(cells), -1)
                index[inside] = row_index(body.boundary_keys, np.sort(local[inside], axis=1))
                hit = np.unique(index[index >= 0])
                if len(hit):
                    result[i] = np.union1d(result.get(i, []), hit).astype(np.int64)
                matched |= index >= 0
            total += len(cells)
            unmatched += np.count_nonzero(~matched)
    if not result:
        raise InputError(f"{used_in}: none of its {total} faces lies on the boundary of a body")
    if unmatched:
        warn(f"{used_in}: {unmatched} of {total} faces lie on no body boundary and are ignored")
    return result


def _surface_cells(mesh, name, used_in):
    """Faces of a 2D region, grouped by vertex count: {3|4: (n, 3|4) mesh vertices}."""
    region = mesh.regions[name]
    if region.dim != 2:
        raise InputError(f"{used_in}: region '{name}' of {mesh.describe()} is {region.dim}D; "
                         f"a surface must be a 2D region ({mesh.region_list(2)})")
    faces = {}
    for meshio_type, cells in region.blocks.items():
        if meshio_type not in SURFACE_TYPES:
            raise InputError(f"{used_in}: region '{name}' of {mesh.describe()} has cells of type "
                             f"'{meshio_type}'; surfaces must be tri3 (triangle) or quad4 (quad)")
        faces[SURFACE_TYPES[meshio_type]] = cells
    return faces


# ---------------------------------------------------------------- labels

LABEL_COLUMNS = {"Face Sets": 0, "contact_master": 1, "contact_slave": 2}


def face_labels(scene, bodies):
    """Per body, the label values (nb, 3) of its boundary faces (0 = unset).

    Also returns the number of faces of each surface (over all bodies).
    """
    labels = [np.zeros((len(b.boundary_keys), 3), dtype=np.int32) for b in bodies]
    surface_ids = {name: i + 1 for i, name in enumerate(scene.surfaces)}
    faces = {name: surface_faces(name, refs, bodies) for name, refs in scene.surfaces.items()}
    names = {sid: name for name, sid in surface_ids.items()}

    for name, per_body in faces.items():
        for i, index in per_body.items():
            clash = labels[i][index, 0]
            if np.any(clash):
                other = names[clash[clash > 0][0]]
                raise InputError(f"surfaces '{other}' and '{name}' overlap on body '{bodies[i].name}' "
                                 f"({np.count_nonzero(clash)} shared faces); a face can carry only "
                                 "one surface id in Face Sets")
            labels[i][index, 0] = surface_ids[name]

    for c in scene.couples:
        sides = {}
        for column, side in ((1, "master"), (2, "slave")):
            sides[side] = _union_faces(getattr(c, side), faces)
            for i, index in sides[side].items():
                taken = labels[i][index, column]
                if np.any(taken):
                    raise InputError(f"couples: faces of body '{bodies[i].name}' are {side} faces of "
                                     f"both couple k={taken[taken > 0][0]} and couple k={c.k}")
                labels[i][index, column] = c.k
        for i, index in sides["master"].items():
            shared = np.intersect1d(index, sides["slave"].get(i, []))
            if len(shared):
                raise InputError(f"couple k={c.k}: {len(shared)} faces of body '{bodies[i].name}' are "
                                 f"both master ({', '.join(c.master)}) and slave "
                                 f"({', '.join(c.slave)})")
    counts = {name: sum(len(ix) for ix in per_body.values()) for name, per_body in faces.items()}
    return labels, counts


def _union_faces(names, faces):
    """Union of the faces of the named surfaces, per body."""
    union = {}
    for name in names:
        for i, index in faces[name].items():
            union[i] = np.union1d(union.get(i, []), index).astype(np.int64)
    return union


def couple_exclusions(scene, bodies, labels):
    """Per couple (in scene order), the master nodes its `exclude` regions take out of contact, as
    an (n, 2) int32 array of (body index, body vertex): the vertices of the named regions (of
    any dimension below 3: node sets, lines, surfaces) that are nodes of the couple's master faces."""
    meshes = {b.mesh.name: b.mesh for b in bodies}
    out = []
    for ci, c in enumerate(scene.couples):
        pairs = set()
        for name in c.exclude:
            where = f"couples[{ci}].exclude (couple k={c.k})"
            found = [m for m in meshes.values() if name in m.regions]
            if not found:
                lists = "; ".join(f"{m.describe()}: {', '.join(m.regions)}" for m in meshes.values())
                raise InputError(f"{where}: region '{name}' not found in the meshes of the bodies ({lists})")
            hit = 0
            for mesh in found:
                region = mesh.regions[name]
                if region.dim == 3:
                    raise InputError(f"{where}: region '{name}' of {mesh.describe()} is a volume; name the "
                                     "nodes by a node set, a line or a surface region")
                vertices = np.unique(np.concatenate([cells.ravel() for cells in region.blocks.values()]))
                for i, body in enumerate(bodies):
                    master = labels[i][:, 1] == c.k
                    if body.mesh is not mesh or not master.any():
                        continue
                    local = body.vertex_map[vertices]
                    chosen = np.intersect1d(local[local >= 0], body.boundary_faces[master])
                    pairs.update((i, int(v)) for v in chosen)
                    hit += len(chosen)
            if not hit:
                raise InputError(f"{where}: region '{name}' has no node on the couple's master surfaces "
                                 f"({', '.join(c.master)}); the contact points are the master nodes")
        out.append(np.array(sorted(pairs), dtype=np.int32).reshape(-1, 2))
    return out
