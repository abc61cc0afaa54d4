"""The 3D cell types of a body in Gmsh/VTK vertex order (the order meshio uses), their faces,
orientation and PETSc's vertex order.

Pure numpy: shared by the preprocessor and the mesh generators.
"""
import numpy as np

# meshio cell type -> mbcontact cell type
VOLUME_TYPES = {"tetra": "tet4", "hexahedron": "hex8", "wedge": "wedge6", "pyramid": "pyr5",
                "tetra10": "tet10"}
# meshio cell type -> number of vertices of a surface face
SURFACE_TYPES = {"triangle": 3, "quad": 4, "triangle6": 6}
# the linear types a body may mix; a tet10 body has tet10 cells only
LINEAR_TYPES = ("tet4", "hex8", "wedge6", "pyr5")
NODES = {"tet4": 4, "hex8": 8, "wedge6": 6, "pyr5": 5, "tet10": 10}
# the corners of a cell (its DMPlex vertices): all its nodes but tet10's midside nodes
CORNERS = {"tet4": 4, "hex8": 8, "wedge6": 6, "pyr5": 5, "tet10": 4}
# tet10's midside nodes 4..9 on the edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3) (Gmsh, VTK, MED)
TET10_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])

# Faces of a cell, vertices in cyclic order, outward normal (right-hand rule) for a positively
# oriented cell; a tet10 face is a tri6: its corners, then the midside nodes of the edges
# (c0, c1), (c1, c2), (c2, c0).
FACES = {
    "tet4": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    "hex8": [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]],
    "wedge6": [[0, 2, 1], [3, 4, 5], [0, 1, 4, 3], [1, 2, 5, 4], [2, 0, 3, 5]],
    "pyr5": [[0, 3, 2, 1], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
    "tet10": [[0, 2, 1, 6, 5, 4], [0, 1, 3, 4, 8, 7], [0, 3, 2, 7, 9, 6], [1, 2, 3, 5, 9, 8]],
}

# Vertex permutation Gmsh -> PETSc of the corners: cells_petsc = cells_gmsh[:, TO_PETSC[t]].
# PETSc's reference cells wind their first face the other way (DMPlexInvertCell: swap vertices
# 0, 1 of a tet, 1, 3 of a hex); its prism has the top face over (0, 2, 1) and its pyramid the
# base reversed. Checked with petsc4py 3.18: the unit tet and hex pass DMPlexCheckGeometry only
# after this permutation, and DMPlexComputeCellGeometryFVM gives the unit prism and pyramid their
# volume and centroid with it (the prism's top in Gmsh order gives a volume of 0).
TO_PETSC = {
    "tet4": np.array([1, 0, 2, 3]),
    "hex8": np.array([0, 3, 2, 1, 4, 5, 6, 7]),
    "wedge6": np.array([0, 2, 1, 3, 4, 5]),
    "pyr5": np.array([0, 3, 2, 1, 4]),
    "tet10": np.array([1, 0, 2, 3]),
}

# Corner tetrahedra (corner, its three edge neighbours, right-handed). A cell is valid when all
# of them have positive volume, mirrored when all are negative (another code's convention, e.g.
# MED's, which meshio reads without reordering).
CORNER_TETS = {
    "tet4": np.array([[0, 1, 2, 3]]),
    "hex8": np.array([[0, 1, 3, 4], [1, 2, 0, 5], [2, 3, 1, 6], [3, 0, 2, 7],
                      [4, 7, 5, 0], [5, 4, 6, 1], [6, 5, 7, 2], [7, 6, 4, 3]]),
    "wedge6": np.array([[0, 1, 2, 3], [1, 2, 0, 4], [2, 0, 1, 5], [3, 5, 4, 0], [4, 3, 5, 1], [5, 4, 3, 2]]),
    "pyr5": np.array([[0, 1, 3, 4], [1, 2, 0, 4], [2, 3, 1, 4], [3, 0, 2, 4]]),
    "tet10": np.array([[0, 1, 2, 3]]),
}

# The mirror image of a cell with the same vertices: turns a negatively oriented cell positive.
MIRROR = {
    "tet4": np.array([0, 2, 1, 3]),
    "hex8": np.array([0, 3, 2, 1, 4, 7, 6, 5]),
    "wedge6": np.array([0, 2, 1, 3, 5, 4]),
    "pyr5": np.array([0, 3, 2, 1, 4]),
    "tet10": np.array([0, 2, 1, 3, 6, 5, 4, 7, 9, 8]),
}

# XDMF topology of each type (the result file's index)
XDMF = {"tet4": "Tetrahedron", "hex8": "Hexahedron", "wedge6": "Wedge", "pyr5": "Pyramid",
        "tet10": "Tetrahedron_10"}


def corner_volumes(cell_type, points, cells):
    """Signed corner-tet volumes (times 6) of each cell, (ncells, ncorners), Gmsh convention."""
    dets = []
    for a, b, c, d in CORNER_TETS[cell_type]:
        x0 = points[cells[:, a]]
        edges = np.stack([points[cells[:, b]] - x0, points[cells[:, c]] - x0,
                          points[cells[:, d]] - x0], axis=1)
        dets.append(np.linalg.det(edges))
    return np.stack(dets, axis=1)


def min_corner_volume(cell_type, points, cells):
    """Smallest signed corner-tet volume (times 6) of each cell, Gmsh convention."""
    return corner_volumes(cell_type, points, cells).min(axis=1)


def orient(cell_type, points, cells):
    """Cells with every corner volume negative (mirrored) reordered by MIRROR; returns the cells,
    the mask of those reordered and that of the cells neither way valid (inverted in part,
    degenerate or twisted)."""
    v = corner_volumes(cell_type, points, cells)
    mirrored = np.all(v < 0, axis=1)
    bad = ~(np.all(v > 0, axis=1) | mirrored)
    if cell_type == "tet10":  # its midside nodes must lie near their edges' midpoints
        bad |= _tet10_curved_too_far(points, cells)
    out = cells.copy()
    out[mirrored] = cells[mirrored][:, MIRROR[cell_type]]
    return out, mirrored, bad


def _tet10_curved_too_far(points, cells):
    """A midside node farther from its edge's midpoint than a quarter of the edge's length makes
    the quadratic map fold over (its Jacobian vanishes at the corner): refused."""
    bad = np.zeros(len(cells), dtype=bool)
    for m, (a, b) in enumerate(TET10_EDGES):
        pa, pb, pm = points[cells[:, a]], points[cells[:, b]], points[cells[:, 4 + m]]
        length = np.linalg.norm(pb - pa, axis=1)
        bad |= np.linalg.norm(pm - 0.5 * (pa + pb), axis=1) > 0.25 * length
    return bad
