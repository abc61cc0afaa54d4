"""Write the body meshes of a scene as DMPlexes into a new HDF5 file (petsc4py).

Run by mbcontact-prep as a subprocess:

    python3 -m mbcontact._writemesh BODIES.npz OUT.h5

petsc4py links PETSc's MPI HDF5 and h5py links serial HDF5; the two libraries must
never be loaded into one process, so this module imports no h5py (and prep.py no
petsc4py). It creates OUT.h5 (mode "w"); prep.py adds the metadata afterwards.

BODIES.npz holds `names` (body names, in order) and for body i:
  cells<i>   int32 (ncells, 8)    0-based vertex indices, PETSc vertex order, -1 padded
  types<i>   str (ncells,)        mbcontact cell type of each cell (tet4, hex8, wedge6, pyr5, tet10, tri3, quad4)
  dim<i>     int                  3, or 2 for a rigid surface
  coords<i>  float64 (nvertices, 3)
  faces<i>   int32 (nfaces, 4)    labelled boundary faces, corners in cyclic order, -1 padded
  facenv<i>  int32 (nfaces,)      their corners
  faceidx<i> int64 (nfaces,)      their index among the body's boundary faces (a surface's: its cells)
  labels<i>  int32 (nfaces, 3)    values for LABELS, 0 = not in that label
"""
import sys

import numpy as np

LABELS = ("Face Sets", "contact_master", "contact_slave")


def main(argv):
    npz_path, h5_path = argv
    import petsc4py
    petsc4py.init([])
    from petsc4py import PETSc

    data = np.load(npz_path)
    PETSc.Options().setValue("dm_plex_view_hdf5_storage_version", "2.0.0")
    viewer = PETSc.Viewer().createHDF5(h5_path, "w", comm=PETSc.COMM_SELF)
    # Only the /topologies part DMLoad reads: the default format also writes an
    # XDMF view to the fixed path /viz, which the second body of a different size
    # cannot overwrite (H5Dset_extent fails).
    viewer.pushFormat(PETSc.Viewer.Format.HDF5_PETSC)
    for i, name in enumerate(data["names"]):
        dm = body_dm(PETSc, str(name), data[f"cells{i}"], data[f"types{i}"], int(data[f"dim{i}"]), data[f"coords{i}"],
                     data[f"faces{i}"], data[f"facenv{i}"], data[f"faceidx{i}"], data[f"labels{i}"])
        dm.view(viewer)
        dm.destroy()
    viewer.destroy()
    return 0


POLYTOPE = {"tet4": "TETRAHEDRON", "tet10": "TETRAHEDRON", "hex8": "HEXAHEDRON", "wedge6": "TRI_PRISM",
            "pyr5": "PYRAMID", "tri3": "TRIANGLE", "quad4": "QUADRILATERAL"}
CORNERS = {"tet4": 4, "tet10": 4, "hex8": 8, "wedge6": 6, "pyr5": 5, "tri3": 3, "quad4": 4}


def body_dm(PETSc, name, cells, types, dim, coords, faces, facenv, faceidx, values):
    """Interpolated DMPlex of one body with its three face labels."""
    kinds = set(str(t) for t in types)
    if dim == 3 and len(kinds) == 1 and kinds <= {"tet4", "tet10", "hex8"}:
        ncorner = CORNERS[kinds.pop()]
        dm = PETSc.DMPlex().createFromCellList(3, cells[:, :ncorner].astype(PETSc.IntType), coords,
                                               interpolate=True, comm=PETSc.COMM_SELF)
    else:
        dm = mixed_dm(PETSc, cells, types, dim, coords)
    dm.setName(name)
    if dim == 3:
        check_geometry(PETSc, dm, name)
        points = face_points(dm, faces, facenv).astype(PETSc.IntType)
    else:
        points = faceidx.astype(PETSc.IntType)  # the cells themselves, points 0 .. ncells - 1
    for column, label_name in enumerate(LABELS):
        dm.createLabel(label_name)  # all three, though DMView skips empty labels
        label = dm.getLabel(label_name)
        for value in np.unique(values[:, column]):
            if value > 0:
                stratum = points[values[:, column] == value]
                label.setStratumIS(int(value), PETSc.IS().createGeneral(stratum, comm=PETSc.COMM_SELF))
    return dm


def mixed_dm(PETSc, cells, types, dim, coords):
    """A DMPlex of cells of several types (or a surface in 3D) built point by point, as PETSc's own
    readers of such meshes do: cells 0 .. nc-1, vertices nc .. nc+nv-1 (the numbering
    createFromCellList gives), each cell's polytope set before the interpolation (the cone size
    alone makes 6 vertices a tensor prism, a cohesive cell)."""
    nc, nv = len(cells), len(coords)
    corners = [CORNERS[str(t)] for t in types]
    dm = PETSc.DMPlex().create(comm=PETSc.COMM_SELF)
    dm.setChart(0, nc + nv)
    for c in range(nc):
        dm.setConeSize(c, corners[c])
    dm.setDimension(dim)
    dm.setUp()
    for c in range(nc):
        dm.setCone(c, [int(v) + nc for v in cells[c, :corners[c]]])
    dm.symmetrize()
    dm.stratify()
    label = dm.getCellTypeLabel()
    for c in range(nc):
        label.clearValue(c, dm.getCellType(c))
        dm.setCellType(c, getattr(PETSc.DM.PolytopeType, POLYTOPE[str(types[c])]))
    dm.interpolate()
    dm.setCoordinateDim(3)
    section = PETSc.Section().create(comm=PETSc.COMM_SELF)
    section.setNumFields(1)
    section.setFieldComponents(0, 3)
    vstart, vend = dm.getDepthStratum(0)
    section.setChart(vstart, vend)
    for v in range(vstart, vend):
        section.setDof(v, 3)
        section.setFieldDof(v, 0, 3)
    section.setUp()
    dm.getCoordinateDM().setSection(section)
    x = PETSc.Vec().createSeq(3 * nv, comm=PETSc.COMM_SELF)
    x.setArray(np.ascontiguousarray(coords, dtype=float).ravel())
    dm.setCoordinatesLocal(x)
    return dm


def face_points(dm, faces, facenv=None):
    """DMPlex point of each face given by its corners (cyclic order).

    Two consecutive edges determine the face: face = join(join(a, b), join(b, c)).
    """
    vstart = dm.getDepthStratum(0)[0]
    fstart, fend = dm.getHeightStratum(1)
    points = np.empty(len(faces), dtype=np.int64)
    for n, (a, b, c) in enumerate((faces[:, :3] + vstart).tolist()):
        edge1, edge2 = dm.getJoin([a, b]), dm.getJoin([b, c])
        join = dm.getJoin([edge1[0], edge2[0]]) if len(edge1) == len(edge2) == 1 else []
        if len(join) != 1 or not fstart <= join[0] < fend or dm.getSupportSize(join[0]) != 1:
            raise RuntimeError(f"{dm.getName()}: face {faces[n].tolist()} is not a boundary face")
        points[n] = join[0]
    return points


def check_geometry(PETSc, dm, name):
    """Run PETSc's DMPlexCheckGeometry (every cell |J| > 0) on a clone of dm.

    Guards the Gmsh -> PETSc vertex permutation; prep.py has already rejected
    inverted cells, so a failure here is an internal error.
    """
    prefix = "mbcontact_prep_check_"
    PETSc.Options().setValue(prefix + "dm_plex_check_geometry", True)
    clone = dm.clone()
    clone.setOptionsPrefix(prefix)
    try:
        clone.setFromOptions()
    except PETSc.Error as err:
        raise RuntimeError(f"body {name}: PETSc finds inverted cells ({err})") from None
    finally:
        clone.destroy()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
