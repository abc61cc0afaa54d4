/* The bodies in the result file, in the scene's order whatever the rank count: each body's
   vertices (reference coordinates) and cells once, its displacement and cellwise stress at every
   output. A body's mesh is distributed over its own ranks; every local vertex and cell knows its
   scene index (MBCBody vnum, cnum, from the load), so a star forest per body brings the values of
   the owned points to contiguous blocks of rows in the scene's order, and each rank of the body
   writes its block in one collective HDF5 write. Ranks off the body take part in every creation
   and write, selecting no rows. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>
#include <petscsf.h>

/* Node permutation from a cell's kernel order (MBCBodyCellVertices: PETSc's closure, then tet10's
   midside nodes) to XDMF's (VTK's, Gmsh's, the scene's), per MBCCellType (python/mbcontact/cells.py,
   TO_PETSC), and XDMF's name of each. */
static const PetscInt ToXdmf[7][10] = {
  {1, 0, 2, 3},                   /* tet4 */
  {0, 3, 2, 1, 4, 5, 6, 7},       /* hex8 */
  {0, 2, 1, 3, 4, 5},             /* wedge6 */
  {0, 3, 2, 1, 4},                /* pyr5 */
  {1, 0, 2, 3, 4, 6, 5, 8, 7, 9}, /* tet10 */
  {0, 1, 2},                      /* tri3 */
  {0, 1, 2, 3}                    /* quad4 */
};
static const char *const XdmfName[7] = {"Tetrahedron", "Hexahedron", "Wedge", "Pyramid", "Tetrahedron_10", "Triangle", "Quadrilateral"};

/* Component c of XDMF's Tensor6 (xx xy xz yy yz zz, what ParaView shows) is Voigt component
   VoigtOfTensor6[c] of the stress field (xx yy zz xy yz xz, bodypointwise.c): the file stores the
   tensor in XDMF's order, so the .xmf points at the dataset as it is. */
static const PetscInt VoigtOfTensor6[6] = {0, 3, 5, 1, 4, 2};

/* Rows [*start, *start + *n) of N for this rank of comm: blocks in rank order. */
static PetscErrorCode SplitRows(MPI_Comm comm, PetscInt N, PetscInt *start, PetscInt *n)
{
  PetscInt    nn = PETSC_DECIDE, s = 0;
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCall(PetscSplitOwnership(comm, &nn, &N));
  PetscCallMPI(MPI_Exscan(&nn, &s, 1, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  *start = rank ? s : 0; /* MPI_Exscan leaves rank 0's undefined */
  *n     = nn;
  PetscFunctionReturn(0);
}

/* Star forest on comm from the bs values of each of nleaves entities (leaves, in order) to the bs
   values of its row row[i] (global; this rank holds nrows rows). Every row must get exactly one
   entity: checked, as it is what makes the file independent of the distribution. */
static PetscErrorCode RowSFCreate(MPI_Comm comm, PetscInt nrows, PetscInt nleaves, const PetscInt row[], PetscInt bs, const char *body, const char *what, PetscSF *sf)
{
  PetscLayout     map;
  PetscInt       *remote, bad = 0;
  const PetscInt *degree;

  PetscFunctionBegin;
  PetscCall(PetscLayoutCreate(comm, &map));
  PetscCall(PetscLayoutSetLocalSize(map, nrows * bs));
  PetscCall(PetscLayoutSetUp(map));
  PetscCall(PetscMalloc1(nleaves * bs, &remote));
  for (PetscInt i = 0; i < nleaves; i++)
    for (PetscInt c = 0; c < bs; c++) remote[i * bs + c] = row[i] * bs + c;
  PetscCall(PetscSFCreate(comm, sf));
  PetscCall(PetscSFSetGraphLayout(*sf, map, nleaves * bs, NULL, PETSC_OWN_POINTER, remote));
  PetscCall(PetscFree(remote));
  PetscCall(PetscLayoutDestroy(&map));
  PetscCall(PetscSFSetUp(*sf));
  PetscCall(PetscSFComputeDegreeBegin(*sf, &degree));
  PetscCall(PetscSFComputeDegreeEnd(*sf, &degree));
  for (PetscInt r = 0; r < nrows * bs; r += bs)
    if (degree[r] != 1) bad++;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_SUM, comm));
  PetscCheck(!bad, comm, PETSC_ERR_PLIB, "Result file: body '%s': %" PetscInt_FMT " %s rows would not be written exactly once", body, bad, what);
  PetscFunctionReturn(0);
}

/* The points of [pStart, pEnd) this rank owns in dm's global section: the point, its local row
   in dm's global Vecs, its scene index. */
static PetscErrorCode OwnedPoints(DM dm, PetscInt pStart, PetscInt pEnd, const PetscInt num[], PetscInt *n, PetscInt **point, PetscInt **row, PetscInt **scene)
{
  PetscSection gsec;
  PetscInt     off;

  PetscFunctionBegin;
  PetscCall(DMGetGlobalSection(dm, &gsec));
  PetscCall(PetscMalloc1(pEnd - pStart, point));
  PetscCall(PetscMalloc1(pEnd - pStart, row));
  PetscCall(PetscMalloc1(pEnd - pStart, scene));
  *n = 0;
  for (PetscInt p = pStart; p < pEnd; p++) {
    PetscInt dof;
    if (num[p - pStart] < 0) continue; /* no node, no DOFs */
    PetscCall(PetscSectionGetDof(gsec, p, &dof));
    PetscCall(PetscSectionGetOffset(gsec, p, &off));
    if (off < 0 || dof <= 0) continue;
    (*point)[*n] = p;
    (*row)[*n]   = off;
    (*scene)[*n] = num[p - pStart];
    (*n)++;
  }
  { /* offsets are global rows; the local ones start at the Vec's ownership range */
    Vec      g;
    PetscInt lo;
    PetscCall(DMGetGlobalVector(dm, &g));
    PetscCall(VecGetOwnershipRange(g, &lo, NULL));
    PetscCall(DMRestoreGlobalVector(dm, &g));
    for (PetscInt i = 0; i < *n; i++) (*row)[i] -= lo;
  }
  PetscFunctionReturn(0);
}

/* Reference coordinates of the owned vertices and the cells by scene vertex index (XDMF order),
   brought to their rows. Collective on the body's communicator. */
static PetscErrorCode BodyGeometry(MBCBody body, MBCBodyOutput *o, const PetscInt vpoint[], const PetscInt vscene[], const PetscInt cpoint[], const PetscInt cscene[], PetscReal *x, int *cells)
{
  Vec                coords;
  const PetscScalar *xa;
  PetscReal         *xl;
  PetscInt          *cl, *cr, cStart;
  PetscSF            sf;
  DM                 bdm;
  MPI_Comm           bcomm;
  const char        *bname;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetDM(body, &bdm));
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetName(body, &bname));
  (void)vscene;
  PetscCall(DMGetCoordinatesLocal(bdm, &coords));
  PetscCall(VecGetArrayRead(coords, &xa));
  PetscCall(PetscMalloc1(3 * o->nvown, &xl));
  for (PetscInt i = 0; i < o->nvown; i++) PetscCall(MBCBodyPointCoordinates(body, vpoint[i], xa, &xl[3 * i]));
  PetscCall(VecRestoreArrayRead(coords, &xa));
  PetscCall(PetscSFReduceBegin(o->vsf, MPIU_REAL, xl, x, MPI_REPLACE));
  PetscCall(PetscSFReduceEnd(o->vsf, MPIU_REAL, xl, x, MPI_REPLACE));
  PetscCall(PetscFree(xl));

  PetscCall(DMPlexGetHeightStratum(bdm, 0, &cStart, NULL));
  PetscCall(PetscMalloc2(o->nvpc * o->ncown, &cl, o->nvpc * o->ncrows, &cr));
  for (PetscInt i = 0; i < o->ncown; i++) {
    const PetscInt *v;
    PetscInt        nv;
    MBCCellType     t;
    PetscCall(MBCBodyGetCellNodes(body, cpoint[i] - cStart, &nv, &v, &t));
    PetscCheck(nv <= o->nvpc, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Body '%s': cell %" PetscInt_FMT " has %" PetscInt_FMT " nodes, more than %" PetscInt_FMT, bname, cscene[i], nv, o->nvpc);
    for (PetscInt j = 0; j < o->nvpc; j++) cl[o->nvpc * i + j] = j < nv ? MBCBodyPointNode(body, v[ToXdmf[t][j]]) : -1;
  }
  PetscCall(RowSFCreate(bcomm, o->ncrows, o->ncown, cscene, o->nvpc, bname, "cell", &sf));
  PetscCall(PetscSFReduceBegin(sf, MPIU_INT, cl, cr, MPI_REPLACE));
  PetscCall(PetscSFReduceEnd(sf, MPIU_INT, cl, cr, MPI_REPLACE));
  PetscCall(PetscSFDestroy(&sf));
  for (PetscInt i = 0; i < o->nvpc * o->ncrows; i++) cells[i] = (int)cr[i];
  PetscCall(PetscFree2(cl, cr));
  PetscFunctionReturn(0);
}

/* The vertex map of a body this rank is in (o->nv set): vstart, nvrows, nvown, vrow and vsf;
   the owned vertices' points and scene indices if asked. Also the checkpoint's
   (solvercheckpoint.c), which stores the state in the scene's order. */
PetscErrorCode MBCBodyVertexMapCreate(MBCBody body, MBCBodyOutput *o, PetscInt **vpoint, PetscInt **vscene)
{
  PetscInt    pStart, pEnd, *vp, *vs, *num;
  MPI_Comm    bcomm;
  DM          bdm;
  const char *bname;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetDM(body, &bdm));
  PetscCall(MBCBodyGetName(body, &bname));
  PetscCall(SplitRows(bcomm, o->nv, &o->vstart, &o->nvrows));
  PetscCall(DMPlexGetChart(bdm, &pStart, &pEnd));
  PetscCall(PetscMalloc1(pEnd - pStart + 1, &num));
  for (PetscInt p = pStart; p < pEnd; p++) num[p - pStart] = MBCBodyPointNode(body, p); /* the nodes: vertices, tet10's edges */
  PetscCall(OwnedPoints(bdm, pStart, pEnd, num, &o->nvown, &vp, &o->vrow, &vs));
  PetscCall(PetscFree(num));
  PetscCall(RowSFCreate(bcomm, o->nvrows, o->nvown, vs, 3, bname, "vertex", &o->vsf));
  if (vpoint) *vpoint = vp;
  else PetscCall(PetscFree(vp));
  if (vscene) *vscene = vs;
  else PetscCall(PetscFree(vs));
  PetscFunctionReturn(0);
}

/* The maps of a body this rank is in, and its vertices and cells in this rank's rows. */
static PetscErrorCode BodyOutputSetUp(MBCBody body, MBCBodyOutput *o, PetscReal **x, int **cells)
{
  PetscInt        cStart, cEnd, *vpoint, *vscene, *cpoint, *cscene;
  const PetscInt *cnum;
  DM              dmStress;
  MPI_Comm        bcomm;
  DM              bdm;
  const char     *bname;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetDM(body, &bdm));
  PetscCall(MBCBodyGetName(body, &bname));
  PetscCall(MBCBodyVertexMapCreate(body, o, &vpoint, &vscene));
  PetscCall(SplitRows(bcomm, o->nc, &o->cstart, &o->ncrows));
  PetscCall(DMPlexGetHeightStratum(bdm, 0, &cStart, &cEnd));
  PetscCall(MBCBodyGetStressDM(body, &dmStress));
  PetscCall(MBCBodyGetSceneNumbering(body, NULL, &cnum));
  PetscCall(OwnedPoints(dmStress, cStart, cEnd, cnum, &o->ncown, &cpoint, &o->crow, &cscene));
  PetscCall(RowSFCreate(bcomm, o->ncrows, o->ncown, cscene, 6, bname, "cell", &o->csf));
  PetscCall(PetscMalloc2(6 * PetscMax(o->nvown, o->ncown), &o->leaf, 3 * o->nvrows + 6 * o->ncrows, &o->root));
  PetscCall(PetscMalloc1(3 * o->nvrows, x));
  PetscCall(PetscMalloc1(o->nvpc * o->ncrows, cells));
  PetscCall(BodyGeometry(body, o, vpoint, vscene, cpoint, cscene, *x, *cells));
  PetscCall(PetscFree(vpoint));
  PetscCall(PetscFree(vscene));
  PetscCall(PetscFree(cpoint));
  PetscCall(PetscFree(cscene));
  PetscFunctionReturn(0);
}

/* A body of several cell types (mixed, a surface of triangles and quads): /bodies/<name>/topology,
   XDMF's Mixed topology (per cell its type code and its nodes), this rank's rows at their offset.
   Collective on the solver's communicator. */
static PetscErrorCode BodyMixedTopology(MBCSolver s, PetscInt b, hid_t g, const int cells[])
{
  MBCBodyOutput *o = &s->bout[b];
  const char    *t = s->scene->bodies[b].cell_type;
  int           *flat = NULL;
  PetscInt       n = 0, off = 0, total = 0;

  PetscFunctionBegin;
  if (strcmp(t, "mixed") && strcmp(t, "surface")) PetscFunctionReturn(0);
  if (s->bodies[b]) {
    PetscCall(PetscMalloc1((o->nvpc + 1) * o->ncrows + 1, &flat));
    for (PetscInt i = 0; i < o->ncrows; i++) {
      PetscInt nv = 0;
      while (nv < o->nvpc && cells[o->nvpc * i + nv] >= 0) nv++;
      flat[n++] = !strcmp(t, "surface") ? (nv == 3 ? 4 : 5) : (nv == 4 ? 6 : nv == 5 ? 7 : nv == 6 ? 8 : 9);
      for (PetscInt j = 0; j < nv; j++) flat[n++] = cells[o->nvpc * i + j];
    }
  }
  PetscCallMPI(MPI_Exscan(&n, &off, 1, MPIU_INT, MPI_SUM, s->comm));
  PetscCallMPI(MPI_Allreduce(&n, &total, 1, MPIU_INT, MPI_SUM, s->comm));
  {
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
    if (!rank) off = 0;
  }
  o->ntopo = total;
  PetscCall(MBCH5WriteRows(g, "topology", H5T_NATIVE_INT, total, 1, off, n, flat));
  PetscCall(PetscFree(flat));
  PetscFunctionReturn(0);
}

/* The maps of every body, then /bodies/<name>/vertices and cells: first every rank sets up its
   bodies (in parallel), then all write body after body. Collective on the solver's communicator. */
PetscErrorCode MBCSolverOutputBodiesOpen(MBCSolver s)
{
  MBCScene    scene = s->scene;
  hid_t       bodies;
  int         count = (int)s->nbodies, **cells;
  PetscReal **x;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(s->nbodies, &s->bout));
  PetscCall(PetscCalloc2(s->nbodies, &x, s->nbodies, &cells));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBodyOutput *o = &s->bout[b];
    const char *t = scene->bodies[b].cell_type;
    o->nv   = scene->bodies[b].num_nodes;
    o->nc   = scene->bodies[b].num_cells;
    o->nvpc = !strcmp(t, "tet4") ? 4 : !strcmp(t, "pyr5") ? 5 : !strcmp(t, "wedge6") ? 6 : !strcmp(t, "tet10") ? 10 : !strcmp(t, "surface") ? 4 : 8;
    PetscCheck(o->nv < PETSC_MAX_INT / 8 && o->nc < PETSC_MAX_INT / 8, s->comm, PETSC_ERR_SUP, "Body '%s': too large for the 32-bit cell indices of the result file", scene->bodies[b].name);
    if (s->bodies[b]) PetscCall(BodyOutputSetUp(s->bodies[b], o, &x[b], &cells[b]));
  }
  PetscCall(MBCH5GroupCreate((hid_t)s->h5, "bodies", PETSC_TRUE, &bodies));
  PetscCall(MBCH5WriteAttribute(bodies, "count", H5T_NATIVE_INT, 1, &count));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBodyOutput *o     = &s->bout[b];
    int            index = (int)b;
    hid_t          g;
    PetscCall(MBCH5GroupCreate(bodies, scene->bodies[b].name, PETSC_FALSE, &g));
    PetscCall(MBCH5WriteAttributeString(g, "cell_type", scene->bodies[b].cell_type));
    PetscCall(MBCH5WriteAttribute(g, "index", H5T_NATIVE_INT, 1, &index));
    PetscCall(MBCH5WriteRows(g, "vertices", H5T_NATIVE_DOUBLE, o->nv, 3, o->vstart, o->nvrows, x[b]));
    PetscCall(MBCH5WriteRows(g, "cells", H5T_NATIVE_INT, o->nc, o->nvpc, o->cstart, o->ncrows, cells[b]));
    PetscCall(BodyMixedTopology(s, b, g, cells[b]));
    PetscCall(MBCH5GroupClose(&g));
    PetscCall(PetscFree(x[b]));
    PetscCall(PetscFree(cells[b]));
  }
  PetscCall(MBCH5GroupClose(&bodies));
  PetscCall(PetscFree2(x, cells));
  PetscFunctionReturn(0);
}

/* Displacement and stress of the bodies this rank is in, in its rows (o->root: displacement,
   then stress). */
static PetscErrorCode BodyFields(MBCScene scene, MBCBody body, MBCBodyOutput *o)
{
  Vec bu;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetDisplacement(body, &bu));
  if (scene->output_displacement) {
    const PetscScalar *u;
    PetscCall(VecGetArrayRead(bu, &u));
    for (PetscInt i = 0; i < o->nvown; i++)
      for (PetscInt c = 0; c < 3; c++) o->leaf[3 * i + c] = PetscRealPart(u[o->vrow[i] + c]);
    PetscCall(VecRestoreArrayRead(bu, &u));
    PetscCall(PetscSFReduceBegin(o->vsf, MPIU_REAL, o->leaf, o->root, MPI_REPLACE));
    PetscCall(PetscSFReduceEnd(o->vsf, MPIU_REAL, o->leaf, o->root, MPI_REPLACE));
  }
  if (scene->output_stress) {
    const PetscScalar *sa;
    Vec                stress;
    DM                 dmStress;
    PetscCall(MBCBodyGetStressDM(body, &dmStress));
    PetscCall(DMGetGlobalVector(dmStress, &stress));
    PetscCall(MBCBodyComputeStress(body, bu, stress));
    PetscCall(VecGetArrayRead(stress, &sa));
    for (PetscInt i = 0; i < o->ncown; i++) /* Voigt (xx yy zz xy yz xz) into XDMF's Tensor6 order (xx xy xz yy yz zz) */
      for (PetscInt c = 0; c < 6; c++) o->leaf[6 * i + c] = PetscRealPart(sa[o->crow[i] + VoigtOfTensor6[c]]);
    PetscCall(VecRestoreArrayRead(stress, &sa));
    PetscCall(DMRestoreGlobalVector(dmStress, &stress));
    PetscCall(PetscSFReduceBegin(o->csf, MPIU_REAL, o->leaf, o->root + 3 * o->nvrows, MPI_REPLACE));
    PetscCall(PetscSFReduceEnd(o->csf, MPIU_REAL, o->leaf, o->root + 3 * o->nvrows, MPI_REPLACE));
  }
  PetscFunctionReturn(0);
}

/* The envelope of the bodies this rank is in (MBCBodyEnvelopeUpdate), in its cell rows: the
   largest principal stress in env[b][0 .. ncrows), its time in env[b][ncrows .. 2 ncrows). */
static PetscErrorCode BodyEnvelope(MBCBody body, MBCBodyOutput *o, PetscReal **env)
{
  const PetscScalar *ea;
  PetscReal         *rows;
  Vec                envelope;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(2 * o->ncrows, env));
  PetscCall(PetscMalloc1(6 * o->ncrows, &rows));
  PetscCall(MBCBodyGetEnvelope(body, &envelope));
  PetscCall(VecGetArrayRead(envelope, &ea));
  for (PetscInt i = 0; i < o->ncown; i++)
    for (PetscInt c = 0; c < 6; c++) o->leaf[6 * i + c] = PetscRealPart(ea[o->crow[i] + c]);
  PetscCall(VecRestoreArrayRead(envelope, &ea));
  PetscCall(PetscSFReduceBegin(o->csf, MPIU_REAL, o->leaf, rows, MPI_REPLACE));
  PetscCall(PetscSFReduceEnd(o->csf, MPIU_REAL, o->leaf, rows, MPI_REPLACE));
  for (PetscInt i = 0; i < o->ncrows; i++) {
    (*env)[i]             = rows[6 * i];
    (*env)[o->ncrows + i] = rows[6 * i + 1];
  }
  PetscCall(PetscFree(rows));
  PetscFunctionReturn(0);
}

/* /bodies/<name>/step_<k>/displacement and stress of output k = s->noutputs: every rank computes
   its bodies' rows, then all write body after body. Collective. */
PetscErrorCode MBCSolverOutputBodiesStep(MBCSolver s)
{
  MBCScene    scene = s->scene;
  int         step  = (int)s->step;
  PetscReal **env  = NULL;

  PetscFunctionBegin;
  if (scene->output_envelope) PetscCall(PetscCalloc1(s->nbodies, &env));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) {
      PetscCall(BodyFields(scene, s->bodies[b], &s->bout[b]));
      if (env) PetscCall(BodyEnvelope(s->bodies[b], &s->bout[b], &env[b]));
    }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBodyOutput *o = &s->bout[b];
    char           path[MBC_NAME_LEN + 64];
    hid_t          g;

    PetscCall(PetscSNPrintf(path, sizeof(path), "bodies/%s/step_%" PetscInt_FMT, scene->bodies[b].name, s->noutputs));
    PetscCall(MBCH5GroupCreate((hid_t)s->h5, path, PETSC_FALSE, &g));
    PetscCall(MBCH5WriteAttribute(g, "time", H5T_NATIVE_DOUBLE, 1, &s->time));
    PetscCall(MBCH5WriteAttribute(g, "step", H5T_NATIVE_INT, 1, &step));
    if (scene->output_displacement) PetscCall(MBCH5WriteRows(g, "displacement", H5T_NATIVE_DOUBLE, o->nv, 3, o->vstart, o->nvrows, o->root));
    if (scene->output_stress) PetscCall(MBCH5WriteRows(g, "stress", H5T_NATIVE_DOUBLE, o->nc, 6, o->cstart, o->ncrows, o->root ? o->root + 3 * o->nvrows : NULL));
    if (env) {
      PetscCall(MBCH5WriteRows(g, "max_principal_stress", H5T_NATIVE_DOUBLE, o->nc, 1, o->cstart, o->ncrows, env[b]));
      PetscCall(MBCH5WriteRows(g, "max_principal_stress_time", H5T_NATIVE_DOUBLE, o->nc, 1, o->cstart, o->ncrows, env[b] ? env[b] + o->ncrows : NULL));
      PetscCall(PetscFree(env[b]));
    }
    PetscCall(MBCH5GroupClose(&g));
  }
  PetscCall(PetscFree(env));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputBodiesClose(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; s->bout && b < s->nbodies; b++) {
    MBCBodyOutput *o = &s->bout[b];
    PetscCall(PetscSFDestroy(&o->vsf));
    PetscCall(PetscSFDestroy(&o->csf));
    PetscCall(PetscFree(o->vrow));
    PetscCall(PetscFree(o->crow));
    PetscCall(PetscFree2(o->leaf, o->root));
  }
  PetscCall(PetscFree(s->bout));
  PetscFunctionReturn(0);
}

/* The bodies of output k as uniform grids of the XDMF index (rank 0). */
PetscErrorCode MBCSolverOutputBodiesXdmf(MBCSolver s, FILE *fp, PetscInt k)
{
  MBCScene    scene = s->scene;
  const char *h5 = strrchr(s->h5file, '/') ? strrchr(s->h5file, '/') + 1 : s->h5file;

  PetscFunctionBegin;
  for (PetscInt b = 0; s->bout && b < s->nbodies; b++) {
    const MBCBodyOutput *o    = &s->bout[b];
    const char          *name = scene->bodies[b].name;
    fprintf(fp, "      <Grid Name=\"%s\" GridType=\"Uniform\">\n", name);
    if (o->ntopo) {
      fprintf(fp, "        <Topology TopologyType=\"Mixed\" NumberOfElements=\"%" PetscInt_FMT "\">\n", o->nc);
      fprintf(fp, "          <DataItem Dimensions=\"%" PetscInt_FMT "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">%s:/bodies/%s/topology</DataItem>\n        </Topology>\n", o->ntopo, h5, name);
    } else {
      const char *t = scene->bodies[b].cell_type;
      const PetscInt type = !strcmp(t, "tet4") ? MBC_CELL_TET4 : !strcmp(t, "pyr5") ? MBC_CELL_PYR5 : !strcmp(t, "wedge6") ? MBC_CELL_WEDGE6 : !strcmp(t, "tet10") ? MBC_CELL_TET10 : MBC_CELL_HEX8;
      fprintf(fp, "        <Topology TopologyType=\"%s\" NumberOfElements=\"%" PetscInt_FMT "\">\n", XdmfName[type], o->nc);
      fprintf(fp, "          <DataItem Dimensions=\"%" PetscInt_FMT " %" PetscInt_FMT "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">%s:/bodies/%s/cells</DataItem>\n        </Topology>\n", o->nc, o->nvpc, h5, name);
    }
    fprintf(fp, "        <Geometry GeometryType=\"XYZ\">\n          <DataItem Dimensions=\"%" PetscInt_FMT " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/bodies/%s/vertices</DataItem>\n        </Geometry>\n", o->nv, h5, name);
    if (scene->output_displacement) fprintf(fp, "        <Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">\n          <DataItem Dimensions=\"%" PetscInt_FMT " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/bodies/%s/step_%" PetscInt_FMT "/displacement</DataItem>\n        </Attribute>\n", o->nv, h5, name, k);
    if (scene->output_envelope)
      for (PetscInt i = 0; i < 2; i++) fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Cell\">\n          <DataItem Dimensions=\"%" PetscInt_FMT "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/bodies/%s/step_%" PetscInt_FMT "/%s</DataItem>\n        </Attribute>\n", i ? "max_principal_stress_time" : "max_principal_stress", o->nc, h5, name, k, i ? "max_principal_stress_time" : "max_principal_stress");
    if (scene->output_stress) fprintf(fp, "        <Attribute Name=\"stress\" AttributeType=\"Tensor6\" Center=\"Cell\">\n          <DataItem Dimensions=\"%" PetscInt_FMT " 6\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/bodies/%s/step_%" PetscInt_FMT "/stress</DataItem>\n        </Attribute>\n", o->nc, h5, name, k);
    fprintf(fp, "      </Grid>\n");
  }
  PetscFunctionReturn(0);
}
