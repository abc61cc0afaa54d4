"""Meshes -> bodies, boundary faces and face labels (meshio + numpy, no PETSc).

A body is the union of the cells of some 3D regions of one mesh (a rigid body may be made of
surface regions instead), renumbered to its own compact node numbering: the cells' corners first
(the DMPlex's vertices), then tet10's midside nodes. Surfaces (2D regions) are matched to the
boundary faces of the bodies by their corners. Node sets (mesh point groups, any region's nodes,
the scene's geometric `node_sets`) are resolved per body.
"""
import contextlib
import io
import os
from dataclasses import dataclass, field

import numpy as np

from .cells import (CORNERS, FACES, LINEAR_TYPES, NODES, SURFACE_TYPES, TET10_EDGES, TO_PETSC, VOLUME_TYPES,
                    orient)
from .scene import InputError, note, warn

_DIMENSIONS = (("vertex", 0), ("line", 1), ("triangle", 2), ("quad", 2), ("polygon", 2),
               ("tetra", 3), ("hexahedron", 3), ("wedge", 3), ("pyramid", 3), ("polyhedron", 3))
# file extensions meshio does not map to its MED reader by itself (Code_Aster's test meshes)
_FORMATS = {".msh": "gmsh", ".med": "med", ".mmed": "med", ".rmed": "med"}
PAD = 6  # a face's nodes: at most a tri6's


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
    node_groups: dict = field(default_factory=dict)  # point group name -> mesh point indices (MED node groups)
    point_data: dict = field(default_factory=dict)   # name -> (n, k) point field of the file

    def describe(self):
        return f"mesh '{self.name}' ({self.path})"

    def region_list(self, dim):
        names = [n for n, r in self.regions.items() if r.dim == dim]
        return ", ".join(names) if names else "none"


def read_mesh(name, path, extrude=None):
    """A mesh file and its named regions; extrude (length, layers, linear): a 2D mesh in the xy plane made
    3D along z (extrude_mesh)."""
    import meshio  # slow import; only needed here

    if not os.path.isfile(path):
        raise InputError(f"meshes.{name}: mesh file not found: {path}")
    # .msh is also an ANSYS extension (meshio would try both and print the failures); .mmed, .rmed
    # are Code_Aster's names for MED files, unknown to meshio
    file_format = _FORMATS.get(os.path.splitext(path)[1].lower())
    chatter = io.StringIO()
    try:
        with contextlib.redirect_stdout(chatter), contextlib.redirect_stderr(chatter):
            mesh = meshio.read(path, file_format=file_format)
    except Exception as err:  # meshio raises many kinds of errors on bad files
        detail = " ".join(f"{chatter.getvalue()} {type(err).__name__} {err}".split())
        raise InputError(f"meshes.{name}: cannot read mesh file {path}: {detail}") from None
    points = np.asarray(mesh.points, dtype=float)
    if points.ndim != 2 or points.shape[1] > 3:
        raise InputError(f"meshes.{name}: {path}: points of dimension {points.shape[1:]}, expected 2 or 3")
    if points.shape[1] < 3:
        points = np.hstack([points, np.zeros((len(points), 3 - points.shape[1]))])
    regions = _regions(mesh)
    node_groups = _med_node_groups(mesh)
    if not regions and not node_groups:
        raise InputError(f"meshes.{name}: {path} has no named regions "
                         "(Gmsh physical names, MED groups or meshio cell sets)")
    fields = {k: np.asarray(v, dtype=float).reshape(len(points), -1) for k, v in mesh.point_data.items()
              if not k.endswith("point_tags") and np.asarray(v).dtype.kind in "fi" and len(v) == len(points)}
    out = MeshFile(name, path, points, regions, node_groups, fields)
    return extrude_mesh(out, *extrude) if extrude else out


_EXTRUDED = {"vertex": "line", "line": "quad", "triangle": "wedge", "quad": "hexahedron"}
# quadratic cells -> their linear cell and corner count (meshio's and MED's orders: corners first)
_LINEAR = {"line3": ("line", 2), "triangle6": ("triangle", 3), "triangle7": ("triangle", 3),
           "quad8": ("quad", 4), "quad9": ("quad", 4)}


def extrude_mesh(mesh, length, layers, linear=False):
    """A 2D mesh in the xy plane (z = 0) extruded along z over `length` in `layers` layers: triangles
    and quads become prisms and hexahedra, lines quads, points lines, node groups their nodes on
    every layer, point fields copied to every layer; every region keeps its name, one dimension up
    (a plane-strain model of another code as a slab: hold z on its nodes). linear: quadratic cells
    are taken by their corners first (there are no hex20 or wedge15), with a note."""
    where = f"meshes.{mesh.name}.extrude"
    if linear:
        dropped = {}
        for region in mesh.regions.values():
            for t in [t for t in region.blocks if t in _LINEAR]:
                kind, corners = _LINEAR[t]
                cells = region.blocks.pop(t)[:, :corners]
                region.blocks[kind] = np.concatenate([region.blocks[kind], cells]) if kind in region.blocks else cells
                dropped.setdefault(t, []).append(cells)
        if dropped:  # a cell in several groups counted once
            counts = {t: len(np.unique(np.concatenate(c), axis=0)) for t, c in dropped.items()}
            note(f"{where}.linear: " + ", ".join(f"{n} {t}" for t, n in counts.items()) + f" cells of {mesh.path} "
                 "taken by their corners (their midside nodes dropped)")
    if np.any(np.abs(mesh.points[:, 2]) > 1e-12 * max(1.0, np.abs(mesh.points).max())):
        raise InputError(f"{where}: {mesh.path} is not a 2D mesh in the xy plane (z != 0)")
    n = len(mesh.points)
    z = np.linspace(0.0, length, layers + 1)
    points = np.concatenate([mesh.points + [0, 0, zk] for zk in z])
    regions = {}
    for name, region in mesh.regions.items():
        if region.dim == 3:
            raise InputError(f"{where}: {mesh.path} has the volume region '{name}': only a 2D mesh is extruded")
        blocks = {}
        for t, cells in region.blocks.items():
            if t not in _EXTRUDED:
                raise InputError(f"{where}: region '{name}' has cells of type '{t}'; extruded are points, lines, "
                                 "triangles and quads" + ("; `linear: true` takes quadratic ones by their corners"
                                                          if t in _LINEAR else ""))
            out = []
            for k in range(layers):
                lo, hi = cells + k * n, cells + (k + 1) * n
                if t == "vertex":
                    out.append(np.column_stack([lo[:, 0], hi[:, 0]]))
                elif t == "line":
                    out.append(np.column_stack([lo[:, 0], lo[:, 1], hi[:, 1], hi[:, 0]]))
                else:
                    out.append(np.hstack([lo, hi]))
            blocks[_EXTRUDED[t]] = np.concatenate(out)
        regions[name] = Region(region.dim + 1, blocks)
    groups = {name: np.concatenate([pts + k * n for k in range(layers + 1)]) for name, pts in mesh.node_groups.items()}
    fields = {k: np.concatenate([v] * (layers + 1)) for k, v in mesh.point_data.items()}
    return MeshFile(mesh.name, mesh.path, points, regions, groups, fields)


def _regions(mesh):
    """Named regions: Gmsh physical groups (tag, dim), MED cell groups (families) and meshio cell sets."""
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
    families = mesh.cell_data.get("cell_tags")
    if families is not None and getattr(mesh, "cell_tags", None):
        # MED: a cell's family (a negative tag) belongs to one or more groups
        for block, tags in zip(mesh.cells, families):
            tags = np.asarray(tags)
            for tag, groups in mesh.cell_tags.items():
                chosen = block.data[tags == tag]
                for group in groups:
                    add(group, block.type, chosen)
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


def _med_node_groups(mesh):
    """MED node groups: point families (positive tags) -> group names -> points."""
    tags = mesh.point_data.get("point_tags")
    if tags is None or not getattr(mesh, "point_tags", None):
        return {}
    tags = np.asarray(tags)
    groups = {}
    for tag, names in mesh.point_tags.items():
        chosen = np.nonzero(tags == tag)[0]
        for group in names:
            if len(chosen):
                groups[group] = np.union1d(groups.get(group, np.zeros(0, dtype=np.int64)), chosen)
    return groups


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
        if body.element and "hex8" not in mesh.types:
            raise InputError(f"bodies.{body.name}.element: {body.element!r} is an element of hex cells; "
                             f"body '{body.name}' has {mesh.cell_type} cells (leave element out)")
    return built


@dataclass
class BodyMesh:
    name: str
    mesh: MeshFile
    cell_type: str            # "tet4" | "hex8" | "wedge6" | "pyr5" | "tet10" | "mixed" (linear types) | "surface" (a rigid surface)
    types: np.ndarray         # (nc,) mbcontact type of each cell
    cells: np.ndarray         # (nc, maxnodes) body node indices, Gmsh order, -1 padded
    coords: np.ndarray        # (nn, 3) the nodes: corners, then tet10's midside nodes
    num_vertices: int         # the corners (the DMPlex's vertices)
    vertex_map: np.ndarray    # mesh point -> body node, -1 if not in the body
    boundary_keys: np.ndarray   # (nb, 4) sorted corners of each boundary face, -1 padded
    boundary_faces: np.ndarray  # (nb, PAD) same faces, cyclic corners then midside nodes, -1 padded
    boundary_nv: np.ndarray     # (nb,) nodes of each boundary face (3, 4 or 6)
    dim: int = 3

    @property
    def surface(self):
        return self.dim == 2

    def petsc_cells(self):
        """The corners in PETSc's vertex order, -1 padded to 8 (a surface body's: its cells' own)."""
        out = np.full((len(self.cells), 8), -1, dtype=np.int32)
        for t in np.unique(self.types):
            rows = self.types == t
            perm = TO_PETSC.get(t, np.arange({"tri3": 3, "quad4": 4}.get(t, 0)))
            out[rows, :len(perm)] = self.cells[rows][:, perm]
        return out

    def midside(self):
        """tet10: the body's midside nodes as (corner a, corner b) of their edges, (nm, 2)."""
        nm = len(self.coords) - self.num_vertices
        edges = np.full((nm, 2), -1, dtype=np.int64)
        if self.cell_type == "tet10":
            for m, (a, b) in enumerate(TET10_EDGES):
                node = self.cells[:, 4 + m] - self.num_vertices
                edges[node] = np.sort(self.cells[:, [a, b]], axis=1)
        return edges

    def face_corners(self, faces, nv):
        """Corner count of faces of nv nodes (a tri6 has 3)."""
        return np.where(nv == 6, 3, nv)


def build_body(body, mesh):
    where = f"bodies.{body.name}.regions"
    blocks = []  # (region name, mbcontact type, cells)
    dims = set()
    for region_name in body.regions:
        region = mesh.regions.get(region_name)
        if region is None and region_name in mesh.node_groups:  # e.g. a beam model's GROUP_NO
            raise InputError(f"{where}: '{region_name}' is a node group (MED GROUP_NO) of {mesh.describe()}, "
                             "not a group of cells: a body is made of volume regions (there: "
                             f"{mesh.region_list(3)}; surface regions: {mesh.region_list(2)}; line regions: "
                             f"{mesh.region_list(1)}); node groups name nodes for dirichlet, initial, springs")
        if region is None:
            raise InputError(f"{where}: region '{region_name}' not found in {mesh.describe()}; "
                             f"volume regions there: {mesh.region_list(3)}; "
                             f"surface regions: {mesh.region_list(2)}")
        if region.dim != 3 and not (body.rigid is not None and region.dim == 2):
            raise InputError(f"{where}: region '{region_name}' of {mesh.describe()} is "
                             f"{region.dim}D, a body needs 3D (volume) regions: {mesh.region_list(3)}"
                             + ("" if body.rigid is not None else " (a rigid body may also be a surface: `rigid`)"))
        dims.add(region.dim)
        for meshio_type, cells in region.blocks.items():
            kind = VOLUME_TYPES.get(meshio_type) if region.dim == 3 else (
                {3: "tri3", 4: "quad4"}.get(SURFACE_TYPES.get(meshio_type)))
            if kind is None:
                raise InputError(f"{where}: region '{region_name}' of {mesh.describe()} has cells of "
                                 f"type '{meshio_type}'; supported: tet4 (tetra), hex8 (hexahedron), wedge6 "
                                 "(wedge), pyr5 (pyramid), tet10 (tetra10)"
                                 + ("; a rigid surface: triangle, quad" if body.rigid is not None else ""))
            blocks.append((region_name, kind, cells))
    if len(dims) > 1:
        raise InputError(f"{where}: body '{body.name}' mixes volume and surface regions")
    dim = dims.pop()
    types = sorted({t for _, t, _ in blocks})
    if "tet10" in types and len(types) > 1:
        raise InputError(f"{where}: body '{body.name}' mixes tet10 with {', '.join(t for t in types if t != 'tet10')} "
                         "cells; a tet10 body has tet10 cells only")
    oriented = []
    for region_name, kind, cells in blocks:
        oriented.append((region_name, kind, _check_cells(body.name, mesh, region_name, kind, cells)))
    blocks = oriented
    width = max(c.shape[1] for _, _, c in blocks)
    cells = np.concatenate([np.pad(c, ((0, 0), (0, width - c.shape[1])), constant_values=-1) for _, _, c in blocks])
    ctypes = np.concatenate([np.full(len(c), kind, dtype=object) for _, kind, c in blocks])
    keys = np.sort(cells, axis=1)
    if len(np.unique(keys, axis=0)) != len(cells):
        raise InputError(f"{where}: body '{body.name}' contains the same element twice "
                         "(do its regions overlap?)")

    # corners first (the DMPlex's vertices), then tet10's midside nodes, each by mesh point number
    corner = np.zeros(cells.shape, dtype=bool)
    for t in np.unique(ctypes):
        rows = ctypes == t
        ncorner = CORNERS[t] if t in CORNERS else SURFACE_TYPES[{"tri3": "triangle", "quad4": "quad"}[t]]
        corner[np.ix_(rows, np.arange(ncorner))] = True
    corners = np.unique(cells[corner])
    midside = np.setdiff1d(np.unique(cells[cells >= 0]), corners)
    vertex_map = np.full(len(mesh.points), -1, dtype=np.int64)
    vertex_map[corners] = np.arange(len(corners))
    vertex_map[midside] = len(corners) + np.arange(len(midside))
    cells = np.where(cells >= 0, vertex_map[np.maximum(cells, 0)], -1)
    cell_type = types[0] if len(types) == 1 else "mixed"
    if dim == 2:
        cell_type = "surface"
    nodes = np.concatenate([corners, midside])
    b = BodyMesh(body.name, mesh, cell_type, ctypes, cells, mesh.points[nodes], len(corners), vertex_map,
                 None, None, None, dim)
    if cell_type == "tet10":
        _check_tet10_edges(body.name, mesh, b)
    b.boundary_keys, b.boundary_faces, b.boundary_nv = _boundary(body.name, mesh, b)
    return b


def _check_cells(body_name, mesh, region_name, kind, cells):
    """Finite coordinates and positive volumes (Gmsh convention): cells mirrored as a whole (another
    code's vertex order, MED's as meshio reads it) are reordered and reported; cells inverted in
    part or degenerate are refused. Returns the cells in positive order."""
    coords = mesh.points[cells]
    bad = np.nonzero(~np.all(np.isfinite(coords), axis=(1, 2)))[0]
    if len(bad):
        node = cells[bad[0]][~np.all(np.isfinite(coords[bad[0]]), axis=1)][0]
        raise InputError(f"bodies.{body_name}: node {node + 1} (1-based, file order) of "
                         f"{mesh.describe()} has a non-finite coordinate")
    if kind in ("tri3", "quad4"):  # a rigid surface: oriented later, towards its couples
        return cells
    cells, mirrored, bad = orient(kind, mesh.points, cells)
    bad = np.nonzero(bad)[0]
    if len(bad):
        raise InputError(f"bodies.{body_name}: element {bad[0] + 1} of region '{region_name}' "
                         f"in {mesh.path} is inverted or degenerate (signed corner volumes of both signs "
                         f"or zero in the Gmsh vertex order{', or a midside node off its edge' if kind == 'tet10' else ''}; "
                         f"{len(bad)} such elements in that region; index is 1-based in file order within the region)")
    if mirrored.any():
        note(f"bodies.{body_name}: {np.count_nonzero(mirrored)} of the {len(cells)} {kind} cells of region "
             f"'{region_name}' in {mesh.path} are mirrored (the vertex order of another code, e.g. MED's) "
             "and were reordered")
    return cells


def _check_tet10_edges(body_name, mesh, b):
    """Every edge of a tet10 body has one midside node, the same in every cell around it."""
    pairs = np.concatenate([np.sort(b.cells[:, [e0, e1]], axis=1) for e0, e1 in TET10_EDGES])
    mids = np.concatenate([b.cells[:, 4 + m] for m in range(6)])
    key, inverse = np.unique(pairs, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    first = np.full(len(key), -1, dtype=np.int64)
    first[inverse[::-1]] = mids[::-1]
    if np.any(first[inverse] != mids):
        raise InputError(f"bodies.{body_name}: the tet10 cells of {mesh.describe()} do not share their midside "
                         "nodes: two cells put different nodes on one edge (a non-conforming mesh)")
    if len(key) != len(b.coords) - b.num_vertices:
        raise InputError(f"bodies.{body_name}: {mesh.describe()}: a midside node of the tet10 cells lies on "
                         "two edges")


def _boundary(body_name, mesh, b):
    """Faces on exactly one cell: (sorted corners, cyclic nodes, node counts), padded. A surface
    body's faces are its cells."""
    if b.surface:
        nv = np.where(b.types == "tri3", 3, 4)
        faces = np.full((len(b.cells), PAD), -1, dtype=np.int64)
        faces[:, :b.cells.shape[1]] = b.cells
        return _keys(faces, nv), faces, nv
    rows, nvs = [], []
    for t in np.unique(b.types):
        cells = b.cells[b.types == t]
        for local in FACES[t]:
            f = np.full((len(cells), PAD), -1, dtype=np.int64)
            f[:, :len(local)] = cells[:, local]
            rows.append(f)
            nvs.append(np.full(len(cells), len(local)))
    faces, nv = np.concatenate(rows), np.concatenate(nvs)
    keys = _keys(faces, nv)
    ukeys, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 2):
        raise InputError(f"bodies.{body_name}: {mesh.describe()} is not a valid volume mesh: "
                         "a face is shared by more than two elements")
    boundary = counts == 1
    return ukeys[boundary], faces[first[boundary]], nv[first[boundary]]


def _keys(faces, nv):
    """Sorted corners of faces, -1 padded to 4 (a tri6 is known by its 3 corners)."""
    corners = np.where(nv == 6, 3, nv)
    keys = np.where(np.arange(4)[None, :] < corners[:, None], faces[:, :4], -1)
    return np.sort(keys, axis=1)


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
        cells, nv = _surface_cells(mesh, name, used_in)
        matched = np.zeros(len(cells), dtype=bool)
        for i, body in enumerate(bodies):
            if body.mesh is not mesh:
                continue
            local = np.where(cells >= 0, body.vertex_map[np.maximum(cells, 0)], -1)
            inside = np.all((local >= 0) | (cells < 0), axis=1)
            index = np.full(len(cells), -1)
            index[inside] = row_index(body.boundary_keys, _keys(local[inside], nv[inside]))
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
    """Faces of a 2D region: (n, PAD) mesh vertices (-1 padded) and their node counts."""
    region = mesh.regions[name]
    if region.dim != 2:
        raise InputError(f"{used_in}: region '{name}' of {mesh.describe()} is {region.dim}D; "
                         f"a surface must be a 2D region ({mesh.region_list(2)})")
    rows, nvs = [], []
    for meshio_type, cells in region.blocks.items():
        if meshio_type not in SURFACE_TYPES:
            raise InputError(f"{used_in}: region '{name}' of {mesh.describe()} has cells of type "
                             f"'{meshio_type}'; surfaces must be tri3 (triangle), quad4 (quad) or tri6 (triangle6)")
        f = np.full((len(cells), PAD), -1, dtype=np.int64)
        f[:, :cells.shape[1]] = cells
        rows.append(f)
        nvs.append(np.full(len(cells), SURFACE_TYPES[meshio_type]))
    return np.concatenate(rows), np.concatenate(nvs)


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
    for i, b in enumerate(bodies):  # a rigid surface has no inside: its faces face its partners
        if b.surface:
            _orient_surface(scene, bodies, labels, i)
    return labels, counts


def _orient_surface(scene, bodies, labels, i):
    """The faces of rigid surface body i turned to face the other side of their couple: each
    face's normal towards the nearest node of that side's faces (as Code_Aster's ORIE_NORM_COQUE
    with a direction, found rather than given). A face in no couple keeps its winding."""
    b = bodies[i]
    for c in scene.couples:
        for column in (1, 2):
            mine = np.nonzero(labels[i][:, column] == c.k)[0]
            if not len(mine):
                continue
            other = 3 - column
            partner = []
            for j in range(len(bodies)):
                if j != i and np.any(labels[j][:, other] == c.k):
                    nodes = np.unique(bodies[j].boundary_faces[labels[j][:, other] == c.k])
                    partner.append(bodies[j].coords[nodes[nodes >= 0]])
            if not partner:
                continue
            pts = np.concatenate(partner)
            for f in mine:
                nv = b.boundary_nv[f]
                x = b.coords[b.boundary_faces[f, :nv]]
                centre = x.mean(axis=0)
                normal = np.zeros(3)
                for a in range(nv):
                    normal += np.cross(x[a], x[(a + 1) % nv])
                nearest = pts[np.argmin(np.linalg.norm(pts - centre, axis=1))]
                if np.dot(nearest - centre, normal) < 0:
                    b.boundary_faces[f, 1:nv] = b.boundary_faces[f, 1:nv][::-1]
    b.cells[:] = b.boundary_faces[:, :b.cells.shape[1]]  # a surface body's faces are its cells, in order


def _union_faces(names, faces):
    """Union of the faces of the named surfaces, per body."""
    union = {}
    for name in names:
        for i, index in faces[name].items():
            union[i] = np.union1d(union.get(i, []), index).astype(np.int64)
    return union


# ---------------------------------------------------------------- node sets

def region_nodes(name, bodies, where, node_sets=None, allow_volume=True, allow_empty=False):
    """The body nodes named by `name`, per body: {body index: sorted node indices}: a scene node
    set, a mesh node group (MED's GROUP_NO), or the nodes of a region of any dimension (a volume
    only when allow_volume). A name the bodies' meshes do not have is refused, listing theirs."""
    if node_sets and name in node_sets:
        return node_sets[name]
    meshes = {b.mesh.name: b.mesh for b in bodies}
    found = {}
    hit_mesh = False
    for mesh in meshes.values():
        if name in mesh.node_groups:
            points = mesh.node_groups[name]
        elif name in mesh.regions:
            region = mesh.regions[name]
            if region.dim == 3 and not allow_volume:
                raise InputError(f"{where}: region '{name}' of {mesh.describe()} is a volume; name the "
                                 "nodes by a node set, a line or a surface region")
            points = np.unique(np.concatenate([c[c >= 0].ravel() for c in region.blocks.values()]))
        else:
            continue
        hit_mesh = True
        for i, body in enumerate(bodies):
            if body.mesh is mesh:
                local = body.vertex_map[points]
                local = np.unique(local[local >= 0])
                if len(local):
                    found[i] = np.union1d(found.get(i, np.zeros(0, dtype=np.int64)), local).astype(np.int64)
    if not hit_mesh:
        lists = "; ".join(f"{m.describe()}: {', '.join(list(m.regions) + list(m.node_groups))}" for m in meshes.values())
        extra = f"; node sets: {', '.join(node_sets)}" if node_sets else ""
        raise InputError(f"{where}: '{name}' is no node set, node group or region of the meshes of the bodies ({lists}{extra})")
    if not found and not allow_empty:
        raise InputError(f"{where}: '{name}' has no node in any body")
    return found


def nodes_of(names, bodies, where, node_sets=None, allow_volume=True, allow_empty=False):
    """Union over names of region_nodes: {body index: nodes}."""
    out = {}
    for name in names:
        for i, nodes in region_nodes(name, bodies, where, node_sets, allow_volume, allow_empty).items():
            out[i] = np.union1d(out.get(i, np.zeros(0, dtype=np.int64)), nodes).astype(np.int64)
    return out


def pairs(per_body):
    """{body: nodes} -> (n, 2) int32 rows (body, node), sorted."""
    rows = [np.column_stack([np.full(len(v), i), v]) for i, v in sorted(per_body.items())]
    return np.concatenate(rows).astype(np.int32) if rows else np.zeros((0, 2), dtype=np.int32)


def build_node_sets(scene, bodies):
    """The scene's `node_sets`, in file order (a set may use the ones before it): per set
    {body index: nodes}."""
    sets = {}
    if scene.node_sets:
        corners = np.vstack([np.vstack([b.coords.min(axis=0), b.coords.max(axis=0)]) for b in bodies])
        extent = float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))
    for name, spec in scene.node_sets.items():
        where = f"node_sets.{name}"
        tolerance = 1e-6 * extent if spec.tolerance is None else spec.tolerance
        chosen = set(range(len(bodies))) if not spec.bodies else {
            i for i, b in enumerate(bodies) if b.name in spec.bodies}
        if spec.kind in ("union", "difference", "intersection"):
            parts = [nodes_of([n], bodies, f"{where}.{spec.kind}", sets, allow_empty=True) for n in spec.names]
            out = {}
            for i in chosen:
                arrays = [p.get(i, np.zeros(0, dtype=np.int64)) for p in parts]
                if spec.kind == "union":
                    v = np.unique(np.concatenate(arrays))
                elif spec.kind == "intersection":
                    v = arrays[0]
                    for a in arrays[1:]:
                        v = np.intersect1d(v, a)
                else:
                    v = arrays[0]
                    for a in arrays[1:]:
                        v = np.setdiff1d(v, a)
                if len(v):
                    out[i] = v.astype(np.int64)
        else:
            out = {}
            for i in chosen:
                x = bodies[i].coords
                if spec.kind == "plane":
                    d = np.abs((x - spec.point) @ spec.normal)
                    inside = d <= tolerance
                elif spec.kind == "sphere":
                    inside = np.linalg.norm(x - spec.point, axis=1) <= spec.radius + tolerance
                else:  # box
                    inside = np.all((x >= spec.lo - tolerance) & (x <= spec.hi + tolerance), axis=1)
                v = np.nonzero(inside)[0]
                if len(v):
                    out[i] = v.astype(np.int64)
        if not out:
            raise InputError(f"{where}: selects no node of the bodies")
        sets[name] = out
    return sets


def couple_exclusions(scene, bodies, labels, node_sets=None):
    """Per couple (in scene order), the master nodes its `exclude` regions take out of contact, as
    an (n, 2) int32 array of (body index, body vertex): the nodes of the named regions (of any
    dimension below 3: node sets, lines, surfaces) that are nodes of the couple's master faces."""
    out = []
    for ci, c in enumerate(scene.couples):
        rows = set()
        where = f"couples[{ci}].exclude (couple k={c.k})"
        for name in c.exclude:
            try:
                per_body = region_nodes(name, bodies, where, node_sets, allow_volume=False)
            except InputError as err:
                if "is no node set" in str(err):
                    raise InputError(str(err).replace(f"'{name}' is no node set, node group or region",
                                                      f"region '{name}' not found")) from None
                raise
            hit = 0
            for i, nodes in per_body.items():
                master = labels[i][:, 1] == c.k
                if not master.any():
                    continue
                faces = bodies[i].boundary_faces[master]
                chosen = np.intersect1d(nodes, faces[faces >= 0])
                rows.update((i, int(v)) for v in chosen)
                hit += len(chosen)
            if not hit:
                raise InputError(f"{where}: region '{name}' has no node on the couple's master surfaces "
                                 f"({', '.join(c.master)}); the contact points are the master nodes")
        out.append(np.array(sorted(rows), dtype=np.int32).reshape(-1, 2))
    return out


def line_weights(names, bodies, where):
    """A line load's nodal weights int N_i ds over the edges of line regions (line: 1/2 of the
    length at each end; line3: 1/6, 1/6 and 2/3), per body: {body: (nodes, weights)}."""
    meshes = {b.mesh.name: b.mesh for b in bodies}
    out = {}
    for name in names:
        found = [m for m in meshes.values() if name in m.regions]
        if not found:
            lists = "; ".join(f"{m.describe()}: {m.region_list(1)}" for m in meshes.values())
            raise InputError(f"{where}: line region '{name}' not found in the meshes of the bodies (line regions: {lists})")
        for mesh in found:
            region = mesh.regions[name]
            if region.dim != 1:
                raise InputError(f"{where}: region '{name}' of {mesh.describe()} is {region.dim}D; a line load "
                                 f"acts on a line (1D) region ({mesh.region_list(1)})")
            for meshio_type, cells in region.blocks.items():
                if meshio_type == "line":
                    share = np.array([0.5, 0.5])
                elif meshio_type == "line3":
                    share = np.array([1 / 6, 1 / 6, 2 / 3])
                else:
                    raise InputError(f"{where}: region '{name}' has cells of type '{meshio_type}' (line or line3)")
                length = np.linalg.norm(mesh.points[cells[:, 1]] - mesh.points[cells[:, 0]], axis=1)
                for i, body in enumerate(bodies):
                    if body.mesh is not mesh:
                        continue
                    local = body.vertex_map[cells]
                    keep = np.all(local >= 0, axis=1)
                    if not keep.any():
                        continue
                    w = np.zeros(len(body.coords))
                    for k in range(cells.shape[1]):
                        np.add.at(w, local[keep, k], share[k] * length[keep])
                    nodes, acc = out.get(i, (np.zeros(0, dtype=np.int64), np.zeros(len(body.coords))))
                    acc = acc + w
                    out[i] = (np.nonzero(acc)[0], acc)
    result = {i: (nodes, acc[nodes]) for i, (nodes, acc) in out.items()}
    if not result:
        raise InputError(f"{where}: the line regions {', '.join(names)} lie on no body")
    return result
