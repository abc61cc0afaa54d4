"""The two supported 3D cell types in Gmsh/VTK vertex order (the order meshio uses).

Pure numpy: shared by the preprocessor and the mesh generators.
"""
import numpy as np

# meshio cell type -> mbcontact cell type
VOLUME_TYPES = {"tetra": "tet4", "hexahedron": "hex8"}
# meshio cell type -> number of vertices of a surface face
SURFACE_TYPES = {"triangle": 3, "quad": 4}

# Faces of a cell, vertices in cyclic order, outward normal (right-hand rule)
# for a positively oriented cell.
FACES = {
    "tet4": np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]),
    "hex8": np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4],
                      [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]),
}

# Vertex permutation Gmsh -> PETSc: cells_petsc = cells_gmsh[:, TO_PETSC[t]].
# This is what PETSc's own Gmsh reader does (DMPlexInvertCell: swap vertices 0,1
# of a tet, 1,3 of a hex). Checked with petsc4py 3.18: the unit tet/hex in Gmsh order
# passes DMPlexCheckGeometry (|J| > 0) only after this permutation, and fails
# ("cell is inverted, |J| = -0.125") without it.
TO_PETSC = {
    "tet4": np.array([1, 0, 2, 3]),
    "hex8": np.array([0, 3, 2, 1, 4, 5, 6, 7]),
}

# Corner tetrahedra (corner, its three edge neighbours, right-handed). A cell is
# valid when all of them have positive volume. For the tet: the cell itself.
CORNER_TETS = {
    "tet4": np.array([[0, 1, 2, 3]]),
    "hex8": np.array([[0, 1, 3, 4], [1, 2, 0, 5], [2, 3, 1, 6], [3, 0, 2, 7],
                      [4, 7, 5, 0], [5, 4, 6, 1], [6, 5, 7, 2], [7, 6, 4, 3]]),
}


def min_corner_volume(cell_type, points, cells):
    """Smallest signed corner-tet volume (times 6) of each cell, Gmsh convention."""
    dets = []
    for a, b, c, d in CORNER_TETS[cell_type]:
        x0 = points[cells[:, a]]
        edges = np.stack([points[cells[:, b]] - x0, points[cells[:, c]] - x0,
                          points[cells[:, d]] - x0], axis=1)
        dets.append(np.linalg.det(edges))
    return np.min(dets, axis=0)
