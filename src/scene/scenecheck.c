/* Validates the bodies' meshes in a scene file (docs/scene-h5.md) with the HDF5 C API before
   PETSc's DMPlex loaders see them: those trust their input, and a bad cone entry, offset or
   label index makes them write out of bounds or loop for ever (DMPlexStratify). A scene file is
   not trusted to come from mbcontact-prep: every dataset the loaders read is checked here for
   its type, shape and values, and the meshes against the metadata. Every rank checks the whole
   file (the meshes are small next to the solve), so every rank reports the same error. */
#include <mbc/private/sceneimpl.h>
#include <hdf5.h>

/* The point classes of an interpolated 3D mesh, by depth. */
enum { P_CELL, P_VERTEX, P_FACE, P_EDGE, P_BAD };

/* Coordinates beyond this magnitude square to overflow in the geometry; no mesh has them. */
#define MBC_MAX_COORD 1e15

typedef struct {
  const char *file, *body;
  hid_t       grp; /* /topologies/<body> */
  char        where[MBC_NAME_LEN + 32];
} MeshCtx;

/* Opens dataset path under m->grp, checks its class (integer or float) and that it is 1D or
   (n, 1) (or any shape when anyshape), and returns its number of values. */
static PetscErrorCode DsetOpen(MeshCtx *m, const char *path, H5T_class_t cls, PetscBool anyshape, hid_t *dset, PetscInt *n)
{
  hid_t    space, type;
  int      ndims;
  hsize_t  dims[8];
  hssize_t npts;

  PetscFunctionBegin;
  PetscCheck(H5Lexists(m->grp, path, H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s is missing", m->file, m->where, path);
  *dset = H5Dopen2(m->grp, path, H5P_DEFAULT);
  PetscCheck(*dset >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s is not a dataset", m->file, m->where, path);
  type = H5Dget_type(*dset);
  PetscCheck(H5Tget_class(type) == cls, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s must hold %s", m->file, m->where, path, cls == H5T_INTEGER ? "integers" : "floating-point numbers");
  H5Tclose(type);
  space = H5Dget_space(*dset);
  ndims = H5Sget_simple_extent_ndims(space);
  PetscCheck(ndims >= 0 && ndims <= 8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s has %d dimensions", m->file, m->where, path, ndims);
  H5Sget_simple_extent_dims(space, dims, NULL);
  npts = H5Sget_simple_extent_npoints(space);
  H5Sclose(space);
  PetscCheck(anyshape || ndims == 1 || (ndims == 2 && dims[1] == 1), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s must have shape (n,) or (n, 1), not %d-dimensional with %llu columns", m->file, m->where, path, ndims, ndims > 1 ? (unsigned long long)dims[1] : 1ULL);
  PetscCheck(npts >= 0 && npts < PETSC_MAX_INT / 8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s has %lld values, more than this build of PETSc can index", m->file, m->where, path, (long long)npts);
  *n = (PetscInt)npts;
  PetscFunctionReturn(0);
}

/* An integer dataset of n values (n < 0: any length, returned in *n). */
static PetscErrorCode ReadInts(MeshCtx *m, const char *path, PetscInt *n, PetscInt64 **v)
{
  hid_t    dset;
  PetscInt len;

  PetscFunctionBegin;
  PetscCall(DsetOpen(m, path, H5T_INTEGER, PETSC_FALSE, &dset, &len));
  PetscCheck(*n < 0 || len == *n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s has %" PetscInt_FMT " values, expected %" PetscInt_FMT, m->file, m->where, path, len, *n);
  PetscCall(PetscMalloc1(len + 1, v));
  PetscCheck(len == 0 || H5Dread(dset, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, *v) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read dataset %s/%s (truncated file?)", m->file, m->where, path);
  H5Dclose(dset);
  *n = len;
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadIntAttr(MeshCtx *m, hid_t obj, const char *objpath, const char *name, PetscInt64 *value)
{
  hid_t     attr, space;
  long long v;

  PetscFunctionBegin;
  PetscCheck(H5Aexists(obj, name) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s/%s is missing", m->file, name, m->where, objpath);
  attr  = H5Aopen(obj, name, H5P_DEFAULT);
  space = H5Aget_space(attr);
  PetscCheck(H5Sget_simple_extent_npoints(space) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s/%s must be one integer", m->file, name, m->where, objpath);
  H5Sclose(space);
  PetscCheck(H5Aread(attr, H5T_NATIVE_LLONG, &v) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s/%s is not an integer", m->file, name, m->where, objpath);
  H5Aclose(attr);
  *value = v;
  PetscFunctionReturn(0);
}

static PetscErrorCode CheckIntAttr(MeshCtx *m, const char *objpath, const char *name, PetscInt64 expected)
{
  hid_t      obj;
  PetscInt64 v;

  PetscFunctionBegin;
  obj = H5Oopen(m->grp, objpath, H5P_DEFAULT);
  PetscCheck(obj >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s is missing", m->file, m->where, objpath);
  PetscCall(ReadIntAttr(m, obj, objpath, name, &v));
  H5Oclose(obj);
  PetscCheck(v == expected, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s/%s is %lld, expected %lld", m->file, name, m->where, objpath, (long long)v, (long long)expected);
  PetscFunctionReturn(0);
}

static PetscErrorCode CheckStringAttr(const char *file, hid_t obj, const char *objpath, const char *name, const char *expected)
{
  hid_t     attr, type, mtype;
  char      buf[64] = "";
  size_t    size;
  PetscBool same;

  PetscFunctionBegin;
  PetscCheck(H5Aexists(obj, name) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is missing", file, name, objpath);
  attr = H5Aopen(obj, name, H5P_DEFAULT);
  type = H5Aget_type(attr);
  size = H5Tget_size(type);
  PetscCheck(H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0 && size < sizeof(buf) - 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s must be the fixed-length string '%s'", file, name, objpath, expected);
  mtype = H5Tcopy(H5T_C_S1);
  H5Tset_size(mtype, size + 1);
  PetscCheck(H5Aread(attr, mtype, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: cannot read attribute %s of %s", file, name, objpath);
  H5Tclose(mtype);
  H5Tclose(type);
  H5Aclose(attr);
  PetscCall(PetscStrcmp(buf, expected, &same));
  PetscCheck(same, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is '%s', expected '%s'", file, name, objpath, buf, expected);
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt    N, nc, nv;
  PetscInt    dim;     /* 3, or 2: a rigid surface (cells of edges, no faces) */
  PetscInt64 *cones, *cells, *orient, *off; /* off[p]: start of p's cone in cells */
  char       *cls;
  PetscInt   *support; /* faces: number of cells around */
  PetscInt   *nverts;  /* cells: their vertices */
} Topo;

/* Cone sizes (faces) and vertex counts a cell of the body's type may have: tet4 and tet10 (4, 4),
   hex8 (6, 8), wedge6 (5, 6), pyr5 (5, 5), mixed any of these; a surface's cells (3, 3) or (4, 4). */
static PetscBool CellShapeAllowed(const char *type, PetscInt64 cone, PetscInt nv)
{
  const PetscBool tet = (PetscBool)(cone == 4 && nv == 4), hex = (PetscBool)(cone == 6 && nv == 8), wedge = (PetscBool)(cone == 5 && nv == 6), pyr = (PetscBool)(cone == 5 && nv == 5);
  if (!strcmp(type, "tet4") || !strcmp(type, "tet10")) return tet;
  if (!strcmp(type, "hex8")) return hex;
  if (!strcmp(type, "wedge6")) return wedge;
  if (!strcmp(type, "pyr5")) return pyr;
  if (!strcmp(type, "mixed")) return (PetscBool)(tet || hex || wedge || pyr);
  if (!strcmp(type, "surface")) return (PetscBool)((cone == 3 && nv == 3) || (cone == 4 && nv == 4));
  return PETSC_FALSE;
}

/* The DAG: cells 0..nc-1 (cone of faces, or of edges for a surface), vertices nc..nc+nv-1 (empty
   cone), then faces (cone of edges) and edges (cone of two vertices); every cone entry one depth
   down and distinct, every orientation in the range of its polytope, faces (and a surface's cells)
   closed cycles of edges, cells closed surfaces of faces with the vertex count of their type, every
   vertex in a cell. */
static PetscErrorCode CheckTopology(MeshCtx *m, const char *type, Topo *t)
{
  PetscInt    n = -1, ncells = -1, no, *seen, *used, nlocal, vlist[128];
  PetscInt64 *order, total = 0;

  PetscFunctionBegin;
  t->dim = strcmp(type, "surface") ? 3 : 2;
  PetscCall(ReadInts(m, "topology/cones", &n, &t->cones));
  t->N = n;
  PetscCheck(t->N >= t->nc + t->nv, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cones has %" PetscInt_FMT " points, fewer than the body's %" PetscInt_FMT " cells and %" PetscInt_FMT " vertices", m->file, m->where, t->N, t->nc, t->nv);
  PetscCall(ReadInts(m, "topology/order", &n, &order));
  for (PetscInt p = 0; p < t->N; p++) PetscCheck(order[p] == p, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/order[%" PetscInt_FMT "] = %lld: the points must be numbered 0, 1, ... in file order, as mbcontact-prep writes them", m->file, m->where, p, (long long)order[p]);
  PetscCall(PetscFree(order));
  PetscCall(CheckIntAttr(m, "topology/cells", "cell_dim", t->dim));
  PetscCall(PetscMalloc2(t->N + 1, &t->off, t->N, &t->cls));
  for (PetscInt p = 0; p < t->N; p++) {
    PetscInt64 c = t->cones[p];
    PetscCheck(c >= 0 && c <= 8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cones[%" PetscInt_FMT "] = %lld is not a cone size of a 3D mesh", m->file, m->where, p, (long long)c);
    t->off[p] = total;
    total += c;
    if (p < t->nc) {
      PetscCheck(t->dim == 3 ? (c >= 4 && c <= 6) : (c == 3 || c == 4), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cones[%" PetscInt_FMT "] = %lld: cell %" PetscInt_FMT " of a %s body needs %s", m->file, m->where, p, (long long)c, p, type, t->dim == 3 ? "4 to 6 faces" : "3 or 4 edges");
      t->cls[p] = P_CELL;
    } else if (p < t->nc + t->nv) {
      PetscCheck(c == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cones[%" PetscInt_FMT "] = %lld: point %" PetscInt_FMT " is a vertex (the body has %" PetscInt_FMT " cells, then %" PetscInt_FMT " vertices) and has no cone", m->file, m->where, p, (long long)c, p, t->nc, t->nv);
      t->cls[p] = P_VERTEX;
    } else {
      PetscCheck(c == 2 || (t->dim == 3 && (c == 3 || c == 4)), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cones[%" PetscInt_FMT "] = %lld: after the cells and vertices come %s", m->file, m->where, p, (long long)c, t->dim == 3 ? "faces (3 or 4 edges) and edges (2 vertices)" : "edges (2 vertices)");
      t->cls[p] = c == 2 ? P_EDGE : P_FACE;
    }
  }
  t->off[t->N] = total;
  ncells = (PetscInt)total;
  no     = (PetscInt)total;
  PetscCall(ReadInts(m, "topology/cells", &ncells, &t->cells));
  PetscCall(ReadInts(m, "topology/orientation", &no, &t->orient));
  for (PetscInt p = 0; p < t->N; p++) {
    const PetscInt64 *cone = &t->cells[t->off[p]], *ori = &t->orient[t->off[p]];
    const int         want = t->cls[p] == P_CELL ? (t->dim == 3 ? P_FACE : P_EDGE) : t->cls[p] == P_FACE ? P_EDGE : P_VERTEX;
    for (PetscInt i = 0; i < t->cones[p]; i++) {
      const PetscInt64 q = cone[i], o = ori[i];
      PetscInt64       narr;
      PetscCheck(q >= 0 && q < t->N && t->cls[q] == want, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cells[%lld] = %lld: the cone of %s %" PetscInt_FMT " must hold %s (points numbered 0 to %" PetscInt_FMT ")", m->file, m->where, (long long)(t->off[p] + i), (long long)q,
                 t->cls[p] == P_CELL ? "cell" : t->cls[p] == P_FACE ? "face" : "edge", p, want == P_FACE ? "faces" : want == P_EDGE ? "edges" : "vertices", t->N - 1);
      narr = want == P_FACE ? 2 * t->cones[q] : want == P_EDGE ? 2 : 1;
      for (PetscInt j = 0; j < i; j++) PetscCheck(cone[j] != q, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/cells[%lld] = %lld repeats an entry of the cone of point %" PetscInt_FMT, m->file, m->where, (long long)(t->off[p] + i), (long long)q, p);
      PetscCheck(narr == 1 ? o == 0 : (o >= -narr / 2 && o < narr / 2), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology/orientation[%lld] = %lld is outside [%lld, %lld)", m->file, m->where, (long long)(t->off[p] + i), (long long)o, narr == 1 ? 0LL : (long long)(-narr / 2), narr == 1 ? 1LL : (long long)(narr / 2));
    }
  }
  /* closed cycles and surfaces, vertex counts, supports */
  PetscCall(PetscCalloc2(t->N, &seen, t->N, &used));
  PetscCall(PetscCalloc2(t->N, &t->support, t->nc + 1, &t->nverts));
  for (PetscInt p = 0; p < t->N; p++) {
    if (t->cls[p] != P_FACE && t->cls[p] != P_CELL) continue;
    nlocal = 0;
    if (t->cls[p] == P_FACE || t->dim == 2) { /* every vertex of the polygon's edges in two of them */
      for (PetscInt i = 0; i < t->cones[p]; i++) {
        const PetscInt64 e = t->cells[t->off[p] + i];
        used[e] = 1;
        if (t->dim == 2) t->support[e]++;
        for (PetscInt k = 0; k < 2; k++) {
          const PetscInt v = (PetscInt)t->cells[t->off[e] + k];
          used[v] = 1;
          if (!seen[v]++) vlist[nlocal++] = v;
        }
      }
      for (PetscInt i = 0; i < nlocal; i++) {
        PetscCheck(seen[vlist[i]] == 2 && nlocal == t->cones[p], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: the edges of %s %" PetscInt_FMT " do not form a closed polygon (topology/cells[%lld...])", m->file, m->where, t->cls[p] == P_FACE ? "face" : "cell", p, (long long)t->off[p]);
      }
      for (PetscInt i = 0; i < nlocal; i++) seen[vlist[i]] = 0;
      if (t->cls[p] == P_CELL) {
        t->nverts[p] = nlocal;
        PetscCheck(CellShapeAllowed(type, t->cones[p], nlocal), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: cell %" PetscInt_FMT " has %" PetscInt_FMT " edges, no cell of a %s body", m->file, m->where, p, nlocal, type);
      }
    } else { /* every edge of the cell's faces in two of them; the vertices its type has */
      PetscInt nv = 0, ntri = 0;
      for (PetscInt i = 0; i < t->cones[p]; i++) {
        const PetscInt64 f = t->cells[t->off[p] + i];
        t->support[f]++;
        used[f] = 1;
        if (t->cones[f] == 3) ntri++;
        for (PetscInt k = 0; k < t->cones[f]; k++) {
          const PetscInt e = (PetscInt)t->cells[t->off[f] + k];
          used[e] = 1;
          if (!seen[e]++) vlist[nlocal++] = e;
          for (PetscInt l = 0; l < 2; l++) {
            const PetscInt v = (PetscInt)t->cells[t->off[e] + l];
            used[v] = 1;
            if (seen[v] >= 0) { seen[v] = -1; nv++; vlist[nlocal++] = v; }
          }
        }
      }
      for (PetscInt i = 0; i < nlocal; i++) {
        const PetscInt q = vlist[i];
        PetscCheck(t->cls[q] == P_VERTEX || seen[q] == 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: the faces of cell %" PetscInt_FMT " do not close (edge %" PetscInt_FMT " is on %" PetscInt_FMT " of them)", m->file, m->where, p, q, seen[q]);
      }
      PetscCheck(CellShapeAllowed(type, t->cones[p], nv), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: cell %" PetscInt_FMT " has %" PetscInt_FMT " faces and %" PetscInt_FMT " vertices, no cell of a %s body", m->file, m->where, p, (PetscInt)t->cones[p], nv, type);
      /* the faces' shapes: a tet's 4 triangles, a hex's 6 quads, a prism's 2 triangles, a pyramid's 4 */
      PetscCheck(ntri == (nv == 4 ? 4 : nv == 8 ? 0 : nv == 6 ? 2 : 4), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: cell %" PetscInt_FMT " of %" PetscInt_FMT " vertices has %" PetscInt_FMT " triangular faces", m->file, m->where, p, nv, ntri);
      t->nverts[p] = nv;
      for (PetscInt i = 0; i < nlocal; i++) seen[vlist[i]] = 0;
    }
  }
  for (PetscInt p = 0; p < t->N; p++) {
    PetscCheck(t->cls[p] != P_FACE || t->support[p] <= 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: face %" PetscInt_FMT " is on %" PetscInt_FMT " cells (at most 2)", m->file, m->where, p, t->support[p]);
    PetscCheck(t->cls[p] != P_VERTEX || used[p], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/topology: vertex %" PetscInt_FMT " (point %" PetscInt_FMT ") is in no cell", m->file, m->where, p - t->nc, p);
  }
  PetscCall(PetscFree2(seen, used));
  PetscFunctionReturn(0);
}

/* coordinateDM: its point list, section (3 dofs per vertex, distinct offsets) and the coordinates. */
static PetscErrorCode CheckCoordinates(MeshCtx *m, Topo *t)
{
  PetscInt    n = t->nv, ncoord = 3 * t->nv;
  PetscInt64 *order, *dof, *off;
  PetscInt   *seen;
  hid_t       dset, grp;
  double     *x;
  const char *secs[] = {"dms/coordinateDM/section", "dms/coordinateDM/section/field0"};

  PetscFunctionBegin;
  grp = H5Gopen2(m->grp, ".", H5P_DEFAULT);
  PetscCall(CheckStringAttr(m->file, grp, m->where, "coordinateDMName", "coordinateDM"));
  PetscCall(CheckStringAttr(m->file, grp, m->where, "coordinatesName", "coordinates"));
  H5Gclose(grp);
  PetscCall(ReadInts(m, "dms/coordinateDM/order", &n, &order));
  PetscCall(PetscCalloc1(ncoord + 1, &seen));
  for (PetscInt i = 0; i < t->nv; i++) {
    const PetscInt64 p = order[i];
    PetscCheck(p >= t->nc && p < t->nc + t->nv && !seen[p - t->nc], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/dms/coordinateDM/order[%" PetscInt_FMT "] = %lld is not a vertex (points %" PetscInt_FMT " to %" PetscInt_FMT ") or repeats one", m->file, m->where, i, (long long)p, t->nc, t->nc + t->nv - 1);
    seen[p - t->nc] = 1;
  }
  PetscCall(PetscFree(order));
  PetscCall(CheckIntAttr(m, secs[0], "numFields", 1));
  PetscCall(CheckIntAttr(m, secs[1], "fieldComponents", 3));
  for (int s = 0; s < 2; s++) {
    char dpath[96], opath[96];
    PetscCall(CheckIntAttr(m, secs[s], "hasConstraints", 0));
    PetscCall(PetscSNPrintf(dpath, sizeof(dpath), "%s/atlasDof", secs[s]));
    PetscCall(PetscSNPrintf(opath, sizeof(opath), "%s/atlasOff", secs[s]));
    n = t->nv;
    PetscCall(ReadInts(m, dpath, &n, &dof));
    n = t->nv;
    PetscCall(ReadInts(m, opath, &n, &off));
    PetscCall(PetscArrayzero(seen, ncoord + 1));
    for (PetscInt i = 0; i < t->nv; i++) {
      PetscCheck(dof[i] == 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] = %lld, expected 3 coordinates per vertex", m->file, m->where, dpath, i, (long long)dof[i]);
      PetscCheck(off[i] >= 0 && off[i] % 3 == 0 && off[i] < ncoord && !seen[off[i]], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] = %lld is not a distinct multiple of 3 below %" PetscInt_FMT, m->file, m->where, opath, i, (long long)off[i], ncoord);
      seen[off[i]] = 1;
    }
    PetscCall(PetscFree(dof));
    PetscCall(PetscFree(off));
  }
  PetscCall(PetscFree(seen));
  PetscCall(CheckIntAttr(m, "dms/coordinateDM/vecs/coordinates", "blockSize", 3));
  PetscCall(DsetOpen(m, "dms/coordinateDM/vecs/coordinates/coordinates", H5T_FLOAT, PETSC_TRUE, &dset, &n));
  PetscCheck(n == ncoord, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/dms/coordinateDM/vecs/coordinates/coordinates has %" PetscInt_FMT " values, expected 3 x %" PetscInt_FMT " vertices", m->file, m->where, n, t->nv);
  PetscCall(PetscMalloc1(ncoord + 1, &x));
  PetscCheck(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, x) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read the coordinates of %s (truncated file?)", m->file, m->where);
  H5Dclose(dset);
  for (PetscInt i = 0; i < ncoord; i++) PetscCheck(PetscIsNormalReal(x[i]) || x[i] == 0 ? PetscAbsReal(x[i]) <= MBC_MAX_COORD : PETSC_FALSE, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s': coordinate %c of vertex %" PetscInt_FMT " is %g (not finite, or beyond %g)", m->file, m->body, "xyz"[i % 3], i / 3, x[i], MBC_MAX_COORD);
  PetscCall(PetscFree(x));
  PetscFunctionReturn(0);
}

typedef struct {
  MeshCtx  *m;
  MBCScene  s;
  Topo     *t;
  PetscInt *faces;  /* per surface id: faces in Face Sets */
  PetscInt *cfaces; /* per couple: master and slave faces */
  char     *unknown; /* the first contact label value of no couple */
  PetscErrorCode err;
} LabelCtx;

/* One stratum /labels/<label>/<value>: its indices in range, and for ours faces on the boundary
   with a value the metadata knows. */
static PetscErrorCode CheckStratum(LabelCtx *c, const char *label, const char *valname)
{
  MeshCtx    *m = c->m;
  Topo       *t = c->t;
  char        path[2 * MBC_NAME_LEN], *end;
  PetscInt    n = -1;
  PetscInt64 *idx;
  long        value;
  PetscBool   facesets, master, slave, celltype;

  PetscFunctionBegin;
  value = strtol(valname, &end, 10);
  PetscCheck(valname[0] && !*end && value > PETSC_MIN_INT && value < PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/labels/%s/%s: a label value must be an integer", m->file, m->where, label, valname);
  PetscCall(PetscSNPrintf(path, sizeof(path), "labels/%s/%s/indices", label, valname));
  PetscCall(ReadInts(m, path, &n, &idx));
  PetscCall(PetscStrcmp(label, "Face Sets", &facesets));
  PetscCall(PetscStrcmp(label, "contact_master", &master));
  PetscCall(PetscStrcmp(label, "contact_slave", &slave));
  PetscCall(PetscStrcmp(label, "celltype", &celltype));
  if (facesets) PetscCheck(value >= 1 && value <= c->s->nsurfaces, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/labels/Face Sets/%s: surface id %ld is not one of the scene's %" PetscInt_FMT " surfaces", m->file, m->where, valname, value, c->s->nsurfaces);
  if (master || slave) { /* reported after the couples without faces, the likelier cause */
    PetscInt k;
    for (k = 0; k < c->s->ncouples && c->s->couples[k].k != value; k++) { }
    if (k < c->s->ncouples) c->cfaces[2 * k + (slave ? 1 : 0)] += n;
    else if (!c->unknown[0]) PetscCall(PetscSNPrintf(c->unknown, sizeof(c->unknown), "%s/labels/%s/%s: no couple has k = %ld", m->where, label, valname, value));
  }
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt64 p = idx[i];
    PetscCheck(p >= 0 && p < t->N, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] = %lld is not a point (0 to %" PetscInt_FMT ")", m->file, m->where, path, i, (long long)p, t->N - 1);
    if (facesets || master || slave) PetscCheck(t->dim == 2 ? t->cls[p] == P_CELL : (t->cls[p] == P_FACE && t->support[p] == 1), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] = %lld is not a boundary face", m->file, m->where, path, i, (long long)p);
    if (celltype) {
      /* DMPolytopeType: segment 1, triangle 3, quadrilateral 4, tetrahedron 6, hexahedron 7, prism 8, pyramid 11 */
      const PetscInt nvc  = t->cls[p] == P_CELL ? t->nverts[p] : 0;
      const int      want = t->cls[p] == P_VERTEX ? 0 : t->cls[p] == P_EDGE ? 1 : (t->cls[p] == P_FACE || t->dim == 2) ? (t->cones[p] == 3 ? 3 : 4) : (nvc == 4 ? 6 : nvc == 8 ? 7 : nvc == 6 ? 8 : 11);
      PetscCheck(value == want, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] = %lld: point of cell type %d labelled %ld", m->file, m->where, path, i, (long long)p, want, value);
    }
  }
  if (facesets) c->faces[value - 1] += n;
  PetscCall(PetscFree(idx));
  PetscFunctionReturn(0);
}

static herr_t StratumIter(hid_t g, const char *name, const H5L_info_t *info, void *ctx)
{
  LabelCtx *c = (LabelCtx *)ctx;
  char      label[MBC_NAME_LEN];
  ssize_t   len = H5Iget_name(g, label, sizeof(label));
  char     *base;

  if (len <= 0 || len >= (ssize_t)sizeof(label)) {
    c->err = PetscError(PETSC_COMM_SELF, __LINE__, PETSC_FUNCTION_NAME, __FILE__, PETSC_ERR_FILE_UNEXPECTED, PETSC_ERROR_INITIAL, "Scene file %s: %s: a label name is too long", c->m->file, c->m->where);
    return -1;
  }
  base    = strrchr(label, '/') + 1;
  c->err  = CheckStratum(c, base, name);
  return c->err ? -1 : 0;
}

static herr_t LabelIter(hid_t g, const char *name, const H5L_info_t *info, void *ctx)
{
  LabelCtx *c = (LabelCtx *)ctx;
  hid_t     lg;
  herr_t    r;

  if (strlen(name) >= MBC_NAME_LEN) {
    c->err = PetscError(PETSC_COMM_SELF, __LINE__, PETSC_FUNCTION_NAME, __FILE__, PETSC_ERR_FILE_UNEXPECTED, PETSC_ERROR_INITIAL, "Scene file %s: %s/labels: a label name is longer than %d characters", c->m->file, c->m->where, MBC_NAME_LEN - 1);
    return -1;
  }
  lg = H5Gopen2(g, name, H5P_DEFAULT);
  if (lg < 0) {
    c->err = PetscError(PETSC_COMM_SELF, __LINE__, PETSC_FUNCTION_NAME, __FILE__, PETSC_ERR_FILE_UNEXPECTED, PETSC_ERROR_INITIAL, "Scene file %s: %s/labels/%s is not a group", c->m->file, c->m->where, name);
    return -1;
  }
  r = H5Literate(lg, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, StratumIter, ctx);
  H5Gclose(lg);
  if (r < 0 && !c->err) c->err = PetscError(PETSC_COMM_SELF, __LINE__, PETSC_FUNCTION_NAME, __FILE__, PETSC_ERR_FILE_UNEXPECTED, PETSC_ERROR_INITIAL, "Scene file %s: cannot read label %s/labels/%s", c->m->file, c->m->where, name);
  return r;
}

static PetscErrorCode CheckLabels(MeshCtx *m, MBCScene s, Topo *t, PetscInt *faces, PetscInt *cfaces, char *unknown)
{
  LabelCtx c = {m, s, t, faces, cfaces, unknown, 0};
  hid_t    lg;
  herr_t   r;

  PetscFunctionBegin;
  if (H5Lexists(m->grp, "labels", H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  lg = H5Gopen2(m->grp, "labels", H5P_DEFAULT);
  PetscCheck(lg >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/labels is not a group", m->file, m->where);
  r = H5Literate(lg, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, LabelIter, &c);
  H5Gclose(lg);
  if (c.err) PetscFunctionReturn(c.err);
  PetscCheck(r >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: cannot read the labels of %s", m->file, m->where);
  PetscFunctionReturn(0);
}

static PetscErrorCode TopoFree(Topo *t)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(t->cones));
  PetscCall(PetscFree(t->cells));
  PetscCall(PetscFree(t->orient));
  PetscCall(PetscFree2(t->off, t->cls));
  PetscCall(PetscFree2(t->support, t->nverts));
  PetscFunctionReturn(0);
}

/* Every body's mesh, then the surfaces the conditions use against the faces the meshes carry. */
PetscErrorCode MBCSceneCheckMeshes(MBCScene s, hid_t file)
{
  PetscInt *faces, *cfaces;
  char      unknown[2 * MBC_NAME_LEN] = "";

  PetscFunctionBegin;
  PetscCall(CheckStringAttr(s->filename, file, "/", "dmplex_storage_version", "2.0.0"));
  PetscCheck(H5Lexists(file, "topologies", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: group /topologies (the meshes) is missing", s->filename);
  PetscCall(PetscCalloc2(s->nsurfaces + 1, &faces, 2 * s->ncouples + 1, &cfaces));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBodyDesc   *d = &s->bodies[b];
    MeshCtx        m;
    Topo           t;
    PetscErrorCode ierr;
    htri_t         exists;

    PetscCall(PetscMemzero(&t, sizeof(t)));
    m.file = s->filename;
    m.body = d->name;
    PetscCall(PetscSNPrintf(m.where, sizeof(m.where), "/topologies/%s", d->name));
    exists = H5Lexists(file, m.where, H5P_DEFAULT);
    PetscCheck(exists > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has no mesh (group %s is missing)", s->filename, d->name, m.where);
    m.grp = H5Gopen2(file, m.where, H5P_DEFAULT);
    PetscCheck(m.grp >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s is not a group", s->filename, m.where);
    t.nc = d->num_cells;
    t.nv = d->num_vertices;
    ierr = CheckTopology(&m, d->cell_type, &t);
    if (!ierr) ierr = CheckCoordinates(&m, &t);
    if (!ierr) ierr = CheckLabels(&m, s, &t, faces, cfaces, unknown);
    H5Gclose(m.grp);
    PetscCall(TopoFree(&t));
    PetscCall(ierr);
  }
  for (PetscInt i = 0; i < s->nsurfaces; i++) {
    PetscBool used = PETSC_FALSE;
    for (PetscInt k = 0; k < s->ndirichlet; k++) used = (PetscBool)(used || s->dirichlet[k].surface_id == i + 1);
    for (PetscInt k = 0; k < s->nloads; k++) used = (PetscBool)(used || s->loads[k].surface_id == i + 1);
    PetscCheck(!used || faces[i] > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: surface '%s' (id %" PetscInt_FMT ") carries a condition or load but no face of any mesh is in its Face Sets stratum", s->filename, s->surfaces[i].name, i + 1);
    PetscCheck(s->surfaces[i].num_faces <= 0 || s->surfaces[i].num_faces == faces[i], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: surface '%s' has num_faces = %" PetscInt_FMT " but the meshes label %" PetscInt_FMT " faces with its id %" PetscInt_FMT, s->filename, s->surfaces[i].name, s->surfaces[i].num_faces, faces[i], i + 1);
  }
  for (PetscInt k = 0; k < s->ncouples; k++) PetscCheck(cfaces[2 * k] > 0 && cfaces[2 * k + 1] > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT " (master %s, slave %s) has %" PetscInt_FMT " master and %" PetscInt_FMT " slave faces in the meshes' contact_master/contact_slave labels; both sides need faces", s->filename, s->couples[k].k, s->couples[k].master, s->couples[k].slave, cfaces[2 * k], cfaces[2 * k + 1]);
  PetscCheck(!unknown[0], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s", s->filename, unknown);
  PetscCall(PetscFree2(faces, cfaces));
  PetscFunctionReturn(0);
}

/* The stages as the prep writes them (docs/scene-h5.md): each from where the one before ends, a
   positive step that fits its length, stable Newmark parameters, one mass matrix, at most
   MBC_MAX_STEPS steps in all; the file may have been written by hand. */
PetscErrorCode MBCSceneCheckStages(MBCScene s)
{
  PetscReal steps = 0;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < s->nstages; i++) {
    const MBCStageDesc *st = &s->stages[i];
    const PetscReal     start = i ? s->stages[i - 1].final_time : 0, length = st->final_time - st->start_time;
    PetscCheck(st->start_time == start, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: stage %" PetscInt_FMT " '%s' starts at t = %g, not where the stage before ends (%g)", s->filename, i, st->name, (double)st->start_time, (double)start);
    PetscCheck(st->dt > 0 && PetscIsNormalReal(st->dt) && PetscIsNormalReal(length) && length >= st->dt * (1 - 1e-12), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: stage %" PetscInt_FMT " '%s': dt %g and final_time %g (from t = %g) must be finite, dt > 0 and at least one step", s->filename, i, st->name, (double)st->dt, (double)st->final_time, (double)st->start_time);
    steps += length / st->dt;
    PetscCheck(steps <= MBC_MAX_STEPS, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: the stages up to stage %" PetscInt_FMT " '%s' make %.3g steps, more than %g", s->filename, i, st->name, (double)steps, (double)MBC_MAX_STEPS);
    PetscCheck(st->mass == s->stages[0].mass, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: stage %" PetscInt_FMT " '%s' has %s mass, stage 0 %s: every stage uses one mass matrix", s->filename, i, st->name, MBCMassTypes[st->mass], MBCMassTypes[s->stages[0].mass]);
    if (st->analysis == MBC_ANALYSIS_DYNAMIC) PetscCheck(st->newmark_gamma >= 0.5 && st->newmark_beta >= 0.25 * (0.5 + st->newmark_gamma) * (0.5 + st->newmark_gamma) * (1 - 1e-12), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: stage %" PetscInt_FMT " '%s': Newmark beta %g, gamma %g are not unconditionally stable (need gamma >= 1/2, beta >= (1/2 + gamma)^2 / 4)", s->filename, i, st->name, (double)st->newmark_beta, (double)st->newmark_gamma);
  }
  PetscFunctionReturn(0);
}
