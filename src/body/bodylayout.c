/* A body's nodes and DOF layout, by hand rather than from a PetscFE (a PetscFE has one cell type;
   a body may mix tets, hexes, prisms and pyramids, or be a rigid surface): 3 displacement DOFs on
   every vertex, and on every edge of a tet10 body (its midside node, whose position comes from the
   scene file, so curved tet10 edges stay curved); 6 stress components per cell. Each local cell's
   nodes are kept in the order its element kernel numbers them (element.h). */
#include <mbc/private/bodyimpl.h>
#include <mbc/private/element.h>
#include <petsc/private/hashmapij.h>
#include <petsc/private/hashmapi.h>

const char *const MBCCellTypes[] = {"tet4", "hex8", "wedge6", "pyr5", "tet10", "tri3", "quad4", "MBCCellType", "MBC_CELL_", NULL};

/* A section of ndof DOFs on the points [pStart, pEnd) of the strata given (depths or heights). */
static PetscErrorCode SectionOn(DM dm, PetscInt ncomp, const char *name, PetscInt nranges, const PetscInt ranges[], PetscSection *sec)
{
  PetscInt pStart, pEnd;

  PetscFunctionBegin;
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscSectionCreate(PetscObjectComm((PetscObject)dm), sec));
  PetscCall(PetscSectionSetNumFields(*sec, 1));
  PetscCall(PetscSectionSetFieldName(*sec, 0, name));
  PetscCall(PetscSectionSetFieldComponents(*sec, 0, ncomp));
  PetscCall(PetscSectionSetChart(*sec, pStart, pEnd));
  for (PetscInt r = 0; r < nranges; r++)
    for (PetscInt p = ranges[2 * r]; p < ranges[2 * r + 1]; p++) {
      PetscCall(PetscSectionSetDof(*sec, p, ncomp));
      PetscCall(PetscSectionSetFieldDof(*sec, p, 0, ncomp));
    }
  PetscCall(PetscSectionSetUp(*sec));
  PetscFunctionReturn(0);
}

/* tet10: the scene node and position of every local edge's midside node, from the scene's table of
   (vertex a, vertex b) pairs in scene numbering. */
static PetscErrorCode BodyMidsideSetUp(MBCBody body)
{
  const MBCBodyDesc *d  = &body->desc;
  const PetscInt     nm = d->num_nodes - d->num_vertices;
  PetscHMapIJ        map;
  PetscInt           eStart, eEnd, vStart, vEnd, missing = -1;

  PetscFunctionBegin;
  PetscCall(DMPlexGetDepthStratum(body->dm, 1, &eStart, &eEnd));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  PetscCall(PetscHMapIJCreate(&map));
  for (PetscInt m = 0; m < nm; m++) {
    PetscHashIJKey key = {PetscMin(d->midside[2 * m], d->midside[2 * m + 1]), PetscMax(d->midside[2 * m], d->midside[2 * m + 1])};
    PetscCall(PetscHMapIJSet(map, key, m));
  }
  PetscCall(PetscMalloc2(eEnd - eStart, &body->enode, 3 * (eEnd - eStart), &body->ecoord));
  for (PetscInt e = eStart; e < eEnd; e++) {
    const PetscInt *cone;
    PetscHashIJKey  key;
    PetscInt        m, a, b;
    PetscCall(DMPlexGetCone(body->dm, e, &cone));
    a   = body->vnum[cone[0] - vStart];
    b   = body->vnum[cone[1] - vStart];
    key = (PetscHashIJKey){PetscMin(a, b), PetscMax(a, b)};
    PetscCall(PetscHMapIJGet(map, key, &m));
    if (m < 0 && missing < 0) missing = e;
    body->enode[e - eStart] = m < 0 ? -1 : d->num_vertices + m;
    for (PetscInt c = 0; c < 3; c++) body->ecoord[3 * (e - eStart) + c] = m < 0 ? 0 : d->midside_x[3 * m + c];
  }
  PetscCall(PetscHMapIJDestroy(&map));
  PetscCheck(missing < 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s': an edge of its tet10 mesh has no midside node in the scene's table", body->scene->filename, body->name);
  PetscFunctionReturn(0);
}

/* Each local cell's type and nodes in its kernel's order: the closure's vertices (PETSc's order
   for that polytope), then for a tet10 the midside nodes of the edges (v0 v1) (v1 v2) (v2 v0)
   (v0 v3) (v1 v3) (v2 v3). */
static PetscErrorCode BodyCellNodesSetUp(MBCBody body)
{
  PetscInt cStart, cEnd, vStart, vEnd, eStart, eEnd, n = 0;

  PetscFunctionBegin;
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(body->dm, 1, &eStart, &eEnd));
  PetscCall(PetscMalloc3(cEnd - cStart + 1, &body->cellvoff, MBC_MAX_CELL_NODES * (cEnd - cStart) + 1, &body->cellv, cEnd - cStart + 1, &body->celltype));
  body->cellvoff[0] = 0;
  for (PetscInt c = cStart; c < cEnd; c++) {
    PetscInt       nv = 0, ne = 0, *closure = NULL, nclosure, v[8], edge[6];
    DMPolytopeType ct;
    PetscCall(DMPlexGetCellType(body->dm, c, &ct));
    PetscCall(DMPlexGetTransitiveClosure(body->dm, c, PETSC_TRUE, &nclosure, &closure));
    for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
      if (closure[p] >= vStart && closure[p] < vEnd && nv < 8) v[nv++] = closure[p];
      else if (body->enode && closure[p] >= eStart && closure[p] < eEnd && ne < 6) edge[ne++] = closure[p];
    }
    PetscCall(DMPlexRestoreTransitiveClosure(body->dm, c, PETSC_TRUE, &nclosure, &closure));
    switch (ct) {
    case DM_POLYTOPE_TETRAHEDRON: body->celltype[c - cStart] = body->enode ? MBC_CELL_TET10 : MBC_CELL_TET4; break;
    case DM_POLYTOPE_HEXAHEDRON: body->celltype[c - cStart] = MBC_CELL_HEX8; break;
    case DM_POLYTOPE_TRI_PRISM: body->celltype[c - cStart] = MBC_CELL_WEDGE6; break;
    case DM_POLYTOPE_PYRAMID: body->celltype[c - cStart] = MBC_CELL_PYR5; break;
    case DM_POLYTOPE_TRIANGLE: body->celltype[c - cStart] = MBC_CELL_TRI3; break;
    case DM_POLYTOPE_QUADRILATERAL: body->celltype[c - cStart] = MBC_CELL_QUAD4; break;
    default: SETERRQ(PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': cell %" PetscInt_FMT " of polytope %s: no element", body->name, c, DMPolytopeTypes[ct]);
    }
    for (PetscInt a = 0; a < nv; a++) body->cellv[n++] = v[a];
    if (body->celltype[c - cStart] == MBC_CELL_TET10) {
      static const PetscInt pairs[6][2] = {
        {0, 1},
        {1, 2},
        {2, 0},
        {0, 3},
        {1, 3},
        {2, 3}
      };
      PetscCheck(nv == 4 && ne == 6, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Body '%s': tet10 cell %" PetscInt_FMT " with %" PetscInt_FMT " vertices and %" PetscInt_FMT " edges", body->name, c, nv, ne);
      for (PetscInt k = 0; k < 6; k++) {
        PetscInt found = -1;
        for (PetscInt j = 0; j < 6 && found < 0; j++) {
          const PetscInt *cone;
          PetscCall(DMPlexGetCone(body->dm, edge[j], &cone));
          if ((cone[0] == v[pairs[k][0]] && cone[1] == v[pairs[k][1]]) || (cone[1] == v[pairs[k][0]] && cone[0] == v[pairs[k][1]])) found = edge[j];
        }
        PetscCheck(found >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Body '%s': tet10 cell %" PetscInt_FMT ": an edge is missing", body->name, c);
        body->cellv[n++] = found;
      }
    }
    body->cellvoff[c - cStart + 1] = n;
  }
  PetscFunctionReturn(0);
}

/* The displacement and stress layouts and the cells' nodes; a tet10 body's midside nodes. */
PetscErrorCode MBCBodyLayoutSetUp(MBCBody body)
{
  PetscSection sec;
  PetscInt     ranges[4], nranges = 1, dim;

  PetscFunctionBegin;
  PetscCall(DMGetDimension(body->dm, &dim));
  if (body->desc.num_nodes > body->desc.num_vertices) PetscCall(BodyMidsideSetUp(body));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &ranges[0], &ranges[1]));
  if (body->enode) {
    PetscCall(DMPlexGetDepthStratum(body->dm, 1, &ranges[2], &ranges[3]));
    nranges = 2;
  }
  PetscCall(DMClone(body->dm, &body->dmStress));
  PetscCall(SectionOn(body->dm, 3, "displacement", nranges, ranges, &sec));
  PetscCall(DMSetLocalSection(body->dm, sec));
  PetscCall(PetscSectionDestroy(&sec));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &ranges[0], &ranges[1]));
  PetscCall(SectionOn(body->dmStress, 6, "stress", 1, ranges, &sec));
  PetscCall(DMSetLocalSection(body->dmStress, sec));
  PetscCall(PetscSectionDestroy(&sec));
  PetscCall(BodyCellNodesSetUp(body));
  body->surface = (PetscBool)(dim == 2);
  PetscFunctionReturn(0);
}

/* The scene index of the node at local point p (a vertex, or a tet10 edge), -1 for other points. */
PetscInt MBCBodyPointNode(MBCBody body, PetscInt p)
{
  PetscInt vStart, vEnd, eStart, eEnd;
  if (DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd)) return -1;
  if (p >= vStart && p < vEnd) return body->vnum[p - vStart];
  if (!body->enode || DMPlexGetDepthStratum(body->dm, 1, &eStart, &eEnd)) return -1;
  return p >= eStart && p < eEnd ? body->enode[p - eStart] : -1;
}

/* The position of the node at point p (a vertex's from the local coordinates x, a midside
   node's from the scene). */
PetscErrorCode MBCBodyPointCoordinates(MBCBody body, PetscInt p, const PetscScalar x[], PetscReal X[3])
{
  PetscSection csec;
  PetscInt     vStart, vEnd, eStart, off;

  PetscFunctionBegin;
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  if (p >= vStart && p < vEnd) {
    PetscCall(DMGetCoordinateSection(body->dm, &csec));
    PetscCall(PetscSectionGetOffset(csec, p, &off));
    for (PetscInt i = 0; i < 3; i++) X[i] = PetscRealPart(x[off + i]);
    PetscFunctionReturn(0);
  }
  PetscCheck(body->enode, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Body '%s': point %" PetscInt_FMT " is no node", body->name, p);
  PetscCall(DMPlexGetDepthStratum(body->dm, 1, &eStart, NULL));
  for (PetscInt i = 0; i < 3; i++) X[i] = body->ecoord[3 * (p - eStart) + i];
  PetscFunctionReturn(0);
}

/* Cell c's nodes in its kernel's order: their coordinates X (3 each, vertices from the local
   coordinate array x), the local DOF offsets idx of the displacement (3 each); *nv their count,
   which tells the element: 4 tet4, 5 pyr5, 6 wedge6, 8 hex8, 10 tet10 (3 tri3 and 4 quad4 in a
   rigid surface, which has no element: see MBCBodyCellType). */
PetscErrorCode MBCBodyCellVertices(MBCBody body, PetscInt c, const PetscScalar x[], PetscReal X[], PetscInt idx[], PetscInt *nv)
{
  PetscSection lsec;
  PetscInt     cStart;

  PetscFunctionBegin;
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, NULL));
  *nv = body->cellvoff[c - cStart + 1] - body->cellvoff[c - cStart];
  for (PetscInt a = 0; a < *nv; a++) {
    const PetscInt p = body->cellv[body->cellvoff[c - cStart] + a];
    PetscInt       off;
    PetscCall(PetscSectionGetOffset(lsec, p, &off));
    PetscCall(MBCBodyPointCoordinates(body, p, x, &X[3 * a]));
    for (PetscInt i = 0; i < 3; i++) idx[3 * a + i] = off + i;
  }
  PetscFunctionReturn(0);
}

MBCCellType MBCBodyCellType(MBCBody body, PetscInt c)
{
  PetscInt cStart = 0;
  (void)DMPlexGetHeightStratum(body->dm, 0, &cStart, NULL);
  return (MBCCellType)body->celltype[c - cStart];
}

/* Winds a boundary face's nv corners pts (coordinates X) outward, away from its one cell, with
   its Newell normal n (twice its area times the unit normal, for a flat face); what names the
   face's surface in an error. */
static PetscErrorCode FaceWindOutward(MBCBody body, PetscInt face, const PetscScalar x[], const char what[], PetscInt pts[], PetscReal X[][3], PetscInt nv, PetscReal n[3])
{
  DM              dm = body->dm;
  PetscInt       *closure = NULL, nclosure, vStart, vEnd, ns, ncv = 0;
  const PetscInt *support;
  PetscReal       fc[3] = {0, 0, 0}, cc[3] = {0, 0, 0};

  PetscFunctionBegin;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  for (PetscInt v = 0; v < nv; v++)
    for (PetscInt c = 0; c < 3; c++) fc[c] += X[v][c] / nv;
  for (PetscInt c = 0; c < 3; c++) n[c] = 0;
  for (PetscInt v = 0; v < nv; v++) { /* Newell's normal */
    const PetscReal *p = X[v], *q = X[(v + 1) % nv];
    n[0] += (p[1] - q[1]) * (p[2] + q[2]);
    n[1] += (p[2] - q[2]) * (p[0] + q[0]);
    n[2] += (p[0] - q[0]) * (p[1] + q[1]);
  }
  PetscCall(DMPlexGetSupportSize(dm, face, &ns));
  PetscCall(DMPlexGetSupport(dm, face, &support));
  PetscCheck(ns == 1, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Body '%s': %s: a face is not on the body's boundary", body->name, what);
  PetscCall(DMPlexGetTransitiveClosure(dm, support[0], PETSC_TRUE, &nclosure, &closure));
  for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
    PetscReal y[3];
    if (closure[p] < vStart || closure[p] >= vEnd) continue;
    PetscCall(MBCBodyPointCoordinates(body, closure[p], x, y));
    for (PetscInt c = 0; c < 3; c++) cc[c] += y[c];
    ncv++;
  }
  PetscCall(DMPlexRestoreTransitiveClosure(dm, support[0], PETSC_TRUE, &nclosure, &closure));
  if (n[0] * (fc[0] - cc[0] / ncv) + n[1] * (fc[1] - cc[1] / ncv) + n[2] * (fc[2] - cc[2] / ncv) < 0) { /* outward winding */
    for (PetscInt i = 1, j = nv - 1; i < j; i++, j--) {
      PetscInt tv = pts[i];
      pts[i] = pts[j], pts[j] = tv;
      for (PetscInt c = 0; c < 3; c++) {
        PetscReal t = X[i][c];
        X[i][c] = X[j][c], X[j][c] = t;
      }
    }
    for (PetscInt c = 0; c < 3; c++) n[c] = -n[c];
  }
  PetscFunctionReturn(0);
}

/* The nodes of face `face` (a boundary face of a volume body, or a rigid surface's cell) with the
   outward winding: its corners in cyclic order seen from outside (the support cell's centroid
   behind it), then a tri6's midside nodes of the edges (c0 c1) (c1 c2) (c2 c0); their points,
   positions X (from the local coordinate array x) and count (3, 4 or 6), *ncorner the corners.
   A rigid surface's faces keep the winding the prep gave them (towards their couple's other side). */
PetscErrorCode MBCBodyFaceNodes(MBCBody body, PetscInt face, const PetscScalar x[], PetscInt pts[6], PetscReal X[6][3], PetscInt *nv, PetscInt *ncorner)
{
  DM              dm = body->dm;
  PetscInt       *closure = NULL, nclosure, vStart, vEnd, eStart, eEnd, ne = 0, edges[3];
  PetscReal       n[3];

  PetscFunctionBegin;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetDepthStratum(dm, 1, &eStart, &eEnd));
  *nv = 0;
  PetscCall(DMPlexGetTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure)); /* vertices in cyclic order */
  for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
    if (closure[p] >= vStart && closure[p] < vEnd && *nv < 4) pts[(*nv)++] = closure[p];
    else if (body->enode && closure[p] >= eStart && closure[p] < eEnd && ne < 3) edges[ne++] = closure[p];
  }
  PetscCall(DMPlexRestoreTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure));
  PetscCheck(*nv == 3 || *nv == 4, PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': a face with %" PetscInt_FMT " vertices", body->name, *nv);
  *ncorner = *nv;
  for (PetscInt v = 0; v < *nv; v++) PetscCall(MBCBodyPointCoordinates(body, pts[v], x, X[v]));
  if (!body->surface) PetscCall(FaceWindOutward(body, face, x, "a face of a surface", pts, X, *nv, n));
  if (ne == 3 && *nv == 3) { /* tri6: the midside nodes in the corners' order */
    for (PetscInt k = 0; k < 3; k++) {
      const PetscInt a = pts[k], b = pts[(k + 1) % 3];
      PetscInt       found = -1;
      for (PetscInt j = 0; j < 3 && found < 0; j++) {
        const PetscInt *cone;
        PetscCall(DMPlexGetCone(dm, edges[j], &cone));
        if ((cone[0] == a && cone[1] == b) || (cone[0] == b && cone[1] == a)) found = edges[j];
      }
      PetscCheck(found >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Body '%s': a tri6 face misses an edge", body->name);
      pts[3 + k] = found;
      PetscCall(MBCBodyPointCoordinates(body, found, x, X[3 + k]));
    }
    *nv = 6;
  }
  PetscFunctionReturn(0);
}

/* *p: the local point (vertex, or tet10 edge) of scene node `node` of this body, -1 where this rank
   does not have it. */
PetscErrorCode MBCBodyNodePoint(MBCBody body, PetscInt node, PetscInt *p)
{
  PetscFunctionBegin;
  if (!body->nodemap) {
    PetscHMapI map;
    PetscInt   pStart, pEnd;
    PetscCall(PetscHMapICreate(&map));
    PetscCall(DMPlexGetChart(body->dm, &pStart, &pEnd));
    for (PetscInt q = pStart; q < pEnd; q++) {
      const PetscInt n = MBCBodyPointNode(body, q);
      if (n >= 0) PetscCall(PetscHMapISet(map, n, q));
    }
    body->nodemap = (void *)map;
  }
  PetscCall(PetscHMapIGet((PetscHMapI)body->nodemap, node, p));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyLayoutDestroy(MBCBody body)
{
  PetscFunctionBegin;
  if (body->nodemap) {
    PetscHMapI map = (PetscHMapI)body->nodemap;
    PetscCall(PetscHMapIDestroy(&map));
    body->nodemap = NULL;
  }
  PetscCall(PetscFree3(body->cellvoff, body->cellv, body->celltype));
  PetscCall(PetscFree2(body->enode, body->ecoord));
  PetscFunctionReturn(0);
}

/* A boundary face's corner vertices vert (3 or 4) wound outward, away from its one cell, their
   coordinates X (from the local coordinates x) and the face's Newell normal n (twice its area
   times the outward unit normal, for a flat face); what names the surface in an error. */
PetscErrorCode MBCBodyFaceCorners(MBCBody body, PetscInt face, const PetscScalar x[], const char what[], PetscInt vert[4], PetscReal X[4][3], PetscInt *nv, PetscReal n[3])
{
  DM        dm = body->dm;
  PetscInt *closure = NULL, nclosure, vStart, vEnd;

  PetscFunctionBegin;
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  *nv = 0;
  PetscCall(DMPlexGetTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure)); /* vertices in cyclic order */
  for (PetscInt p = 0; p < 2 * nclosure; p += 2)
    if (closure[p] >= vStart && closure[p] < vEnd && *nv < 4) vert[(*nv)++] = closure[p];
  PetscCall(DMPlexRestoreTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure));
  PetscCheck(*nv == 3 || *nv == 4, PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': %s: a face with %" PetscInt_FMT " vertices", body->name, what, *nv);
  for (PetscInt v = 0; v < *nv; v++) PetscCall(MBCBodyPointCoordinates(body, vert[v], x, X[v]));
  PetscCall(FaceWindOutward(body, face, x, what, vert, X, *nv, n));
  PetscFunctionReturn(0);
}
