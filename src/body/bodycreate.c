/* A body: its DMPlex, loaded and distributed by PETSc from the scene file, on its own communicator. */
#include <mbc/private/bodyimpl.h>
#include <mbc/private/element.h>
#include <petscsf.h>

/* Every cell must have a positive Jacobian determinant at every quadrature point of its element,
   and not vanishingly small next to the cube of its longest edge. A rigid surface has no volume. */
static PetscErrorCode BodyCheckGeometry(MBCBody body)
{
  Vec                coords;
  const PetscScalar *x;
  PetscInt           cStart, cEnd, bad = -1, badq = -1;
  PetscReal          worst = 0, worstq = 0;
  IS                 cellNumbering;
  const PetscInt    *gnum;

  PetscFunctionBegin;
  if (body->surface) PetscFunctionReturn(0);
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetCellNumbering(body->dm, &cellNumbering));
  PetscCall(ISGetIndices(cellNumbering, &gnum));
  for (PetscInt c = cStart; c < cEnd && bad < 0 && badq < 0; c++) {
    PetscReal X[3 * MBC_MAX_CELL_NODES], L, det;
    PetscInt  idx[3 * MBC_MAX_CELL_NODES], nv;
    PetscCall(MBCBodyCellVertices(body, c, x, X, idx, &nv));
    det = MBCElementMinJacobian(nv, X, &L);
    /* a cell stretched far beyond its volume (one vertex moved 1e9 away) is not inverted but no
       mesh: detJ / L^3 is 1e-6 for a sliver of aspect 1000, 1e-18 for that one */
    if (!(det > 0)) bad = gnum[c - cStart] < 0 ? -(gnum[c - cStart] + 1) : gnum[c - cStart], worst = det;
    else if (det < 1e-12 * L * L * L) badq = gnum[c - cStart] < 0 ? -(gnum[c - cStart] + 1) : gnum[c - cStart], worstq = det / (L * L * L);
  }
  PetscCall(ISRestoreIndices(cellNumbering, &gnum));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCheck(bad < 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Scene file %s: body '%s': cell %" PetscInt_FMT " is inverted or degenerate (Jacobian determinant %g at a quadrature point)", body->scene->filename, body->name, bad, (double)worst);
  PetscCheck(badq < 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Scene file %s: body '%s': cell %" PetscInt_FMT " is degenerate (its Jacobian determinant is %g times the cube of its longest edge)", body->scene->filename, body->name, badq, (double)worstq);
  PetscFunctionReturn(0);
}

/* Scene index of every local vertex and cell from sfXC, the SF from the file's point numbers
   (roots, in chunks over the body's ranks) to this rank's points (leaves). mbcontact-prep writes
   each body serially from its cell list: cells are points 0..nc-1 and vertices nc..nc+nv-1, both
   in the scene's order (docs/scene-h5.md); anything else is not a scene file of ours. */
static PetscErrorCode BodySceneNumbering(MBCBody body, PetscSF sfXC)
{
  const PetscInt     nc = body->desc.num_cells, nv = body->desc.num_vertices;
  const PetscInt    *ilocal;
  const PetscSFNode *iremote;
  PetscInt           nroots, nleaves, cStart, cEnd, vStart, vEnd, *offset, bad = -1;
  PetscMPIInt        size;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(body->comm, &size));
  PetscCall(PetscSFGetGraph(sfXC, &nroots, &nleaves, &ilocal, &iremote));
  PetscCall(PetscMalloc1(size + 1, &offset));
  offset[0] = 0;
  PetscCallMPI(MPI_Allgather(&nroots, 1, MPIU_INT, offset + 1, 1, MPIU_INT, body->comm));
  for (PetscMPIInt r = 0; r < size; r++) offset[r + 1] += offset[r];
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  PetscCall(PetscMalloc2(vEnd - vStart, &body->vnum, cEnd - cStart, &body->cnum));
  for (PetscInt v = vStart; v < vEnd; v++) body->vnum[v - vStart] = -1;
  for (PetscInt c = cStart; c < cEnd; c++) body->cnum[c - cStart] = -1;
  for (PetscInt l = 0; l < nleaves; l++) {
    const PetscInt p = ilocal ? ilocal[l] : l, x = offset[iremote[l].rank] + iremote[l].index;
    if (p >= cStart && p < cEnd) {
      body->cnum[p - cStart] = x;
      if (x < 0 || x >= nc) bad = x;
    } else if (p >= vStart && p < vEnd) {
      body->vnum[p - vStart] = x - nc;
      if (x < nc || x >= nc + nv) bad = x;
    }
  }
  for (PetscInt v = vStart; v < vEnd && bad < 0; v++)
    if (body->vnum[v - vStart] < 0) bad = PETSC_MAX_INT;
  for (PetscInt c = cStart; c < cEnd && bad < 0; c++)
    if (body->cnum[c - cStart] < 0) bad = PETSC_MAX_INT;
  PetscCall(PetscFree(offset));
  PetscCheck(bad < 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s': the mesh does not number its %" PetscInt_FMT " cells first and then its %" PetscInt_FMT " vertices (point %" PetscInt_FMT "), as mbcontact-prep writes it; make the scene file again with mbcontact-prep", body->scene->filename, body->name, nc, nv, bad);
  PetscFunctionReturn(0);
}

/* The mesh as DMLoad reads it, in its steps (PETSc's DMPlexTopologyLoad, DMPlexCoordinatesLoad,
   DMPlexLabelsLoad): the topology, its distribution inside the body's communicator, then
   coordinates and labels straight onto the distributed mesh, through the SF from the file's
   point numbers to the distributed points, which also gives every point its scene index. */
static PetscErrorCode BodyLoadMesh(MBCBody body)
{
  PetscViewer viewer;
  PetscSF     sfXC;
  PetscMPIInt size;

  PetscFunctionBegin;
  PetscCall(DMCreate(body->comm, &body->dm));
  PetscCall(DMSetType(body->dm, DMPLEX));
  PetscCall(PetscObjectSetName((PetscObject)body->dm, body->name));
  PetscCall(PetscViewerHDF5Open(body->comm, body->scene->filename, FILE_MODE_READ, &viewer));
  PetscCall(DMPlexTopologyLoad(body->dm, viewer, &sfXC));
  PetscCallMPI(MPI_Comm_size(body->comm, &size));
  if (size > 1) {
    DM      dmDist = NULL;
    PetscSF sfBC   = NULL, sfXB = sfXC;
    PetscCall(DMPlexDistribute(body->dm, 0, &sfBC, &dmDist));
    if (dmDist) {
      PetscCall(PetscSFCompose(sfXB, sfBC, &sfXC));
      PetscCall(PetscSFDestroy(&sfXB));
      PetscCall(DMDestroy(&body->dm));
      body->dm = dmDist;
      PetscCall(PetscObjectSetName((PetscObject)body->dm, body->name));
    }
    PetscCall(PetscSFDestroy(&sfBC));
  }
  PetscCall(DMPlexCoordinatesLoad(body->dm, viewer, sfXC));
  PetscCall(DMPlexLabelsLoad(body->dm, viewer, sfXC));
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(BodySceneNumbering(body, sfXC));
  PetscCall(PetscSFDestroy(&sfXC));
  PetscFunctionReturn(0);
}

const char *const MBCElementTypes[] = {"tet4", "hex8", "hex8i", "hex8b", "tet10", "mixed", "rigid", "MBCElementType", "MBC_ELEMENT_", NULL};

/* The element of the body's hex cells: -body_<name>_element (or -body_element, copied to every
   body by the solver), else the scene's body key `element`, else hex8i (issue 12: as accurate on
   the Hertz cylinders as hex8 for ~2 % more time, free of hex8's shear locking in bending;
   docs/performance.md). A body without hexes has its cells' own elements (the choice is ignored). */
static PetscErrorCode BodyChooseElement(MBCBody body, const char prefix[])
{
  char      value[64] = "";
  PetscBool set       = PETSC_FALSE, hex = PETSC_FALSE, other = PETSC_FALSE;
  PetscInt  cStart, cEnd;

  PetscFunctionBegin;
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; c++) {
    if (MBCBodyCellType(body, c) == MBC_CELL_HEX8) hex = PETSC_TRUE;
    else if (MBCBodyCellType(body, c) != MBC_CELL_TET4) other = PETSC_TRUE;
  }
  { /* the same on every rank of the body */
    PetscBool l[2] = {hex, other}, g[2];
    PetscCall(MPIU_Allreduce(l, g, 2, MPIU_BOOL, MPI_LOR, body->comm));
    hex = g[0], other = g[1];
  }
  body->element = body->desc.rigid ? MBC_ELEMENT_RIGID : body->enode ? MBC_ELEMENT_TET10 : hex ? MBC_ELEMENT_HEX8I : other ? MBC_ELEMENT_MIXED : MBC_ELEMENT_TET4;
  if (!hex || body->desc.rigid) PetscFunctionReturn(0);
  if (body->desc.element[0]) PetscCall(PetscStrncpy(value, body->desc.element, sizeof(value)));
  PetscCall(PetscOptionsGetString(NULL, prefix, "-element", value, sizeof(value), &set));
  if (!value[0]) PetscFunctionReturn(0);
  for (PetscInt e = MBC_ELEMENT_HEX8; e <= MBC_ELEMENT_HEX8B; e++) {
    PetscBool match;
    PetscCall(PetscStrcmp(value, MBCElementTypes[e], &match));
    if (match) {
      body->element = (MBCElementType)e;
      PetscFunctionReturn(0);
    }
  }
  if (set) SETERRQ(PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "-%selement %s (or -body_element): unknown element for body '%s'; use hex8, hex8i or hex8b", prefix, value, body->name);
  SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has element '%s', not hex8, hex8i or hex8b", body->scene->filename, body->name, value);
}

/* Body index of the scene on comm; its options are -<prefix>body_<name>_* (prefix: the solver's, or NULL). */
PetscErrorCode MBCBodyCreate(MPI_Comm comm, MBCScene scene, PetscInt index, const char solverprefix[], MBCBody *newbody)
{
  MBCBody     body;
  char        prefix[MBC_NAME_LEN + 8];
  const char *bodyprefix;

  PetscFunctionBegin;
  PetscCall(PetscHeaderCreate(body, MBC_BODY_CLASSID, "MBCBody", "mbcontact body", "MBCBody", comm, MBCBodyDestroy, MBCBodyView));
  body->comm  = comm;
  body->scene = scene;
  PetscCall(PetscObjectReference((PetscObject)scene));
  body->index = index;
  body->desc  = scene->bodies[index];
  PetscCall(PetscStrncpy(body->name, body->desc.name, sizeof(body->name)));
  PetscCall(PetscObjectSetName((PetscObject)body, body->name));
  body->lambda = body->desc.E * body->desc.nu / ((1 + body->desc.nu) * (1 - 2 * body->desc.nu));
  body->mu     = body->desc.E / (2 * (1 + body->desc.nu));

  PetscCall(PetscLogEventBegin(MBC_BodyLoad, 0, 0, 0, 0));
  PetscCall(BodyLoadMesh(body));
  PetscCall(PetscLogEventEnd(MBC_BodyLoad, 0, 0, 0, 0));

  PetscCall(MBCBodyLayoutSetUp(body)); /* the DOFs on the nodes, the stress per cell, the cells' nodes */
  PetscCall(PetscSNPrintf(prefix, sizeof(prefix), "body_%s_", body->name));
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)body, solverprefix));
  PetscCall(PetscObjectAppendOptionsPrefix((PetscObject)body, prefix));
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)body, &bodyprefix));
  PetscCall(BodyChooseElement(body, bodyprefix));
  PetscCall(BodyCheckGeometry(body));
  *newbody = body;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyDestroy(MBCBody *body)
{
  MBCBody  b = *body;
  MPI_Comm comm;

  PetscFunctionBegin;
  if (!b) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(b, MBC_BODY_CLASSID, 1);
  if (--((PetscObject)b)->refct > 0) {
    *body = NULL;
    PetscFunctionReturn(0);
  }
  for (PetscInt i = 0; i < b->nloads; i++) PetscCall(VecDestroy(&b->load[i]));
  PetscCall(PetscFree2(b->load, b->load_index));
  if (b->bc_rows_held) { /* bc_rows points at one of the two sets */
    PetscCall(PetscFree2(b->bc_rows_held, b->bc_entry_held));
    b->bc_rows = b->bc_rows_free, b->bc_entry = b->bc_entry_free;
  }
  PetscCall(PetscFree2(b->bc_rows, b->bc_entry));
  PetscCall(VecDestroy(&b->fhold));
  PetscCall(MatDestroy(&b->Ainv));
  PetscCall(VecDestroy(&b->fheld));
  PetscCall(MBCBodyRigidModesDestroy(b));
  PetscCall(MatDestroy(&b->K));
  PetscCall(MatDestroy(&b->M));
  PetscCall(MatDestroy(&b->Kbc));
  PetscCall(MatDestroy(&b->Mbc));
  PetscCall(MatDestroy(&b->Cb));
  PetscCall(MatDestroy(&b->Cin));
  PetscCall(VecDestroy(&b->envelope));
  PetscCall(MatDestroy(&b->A));
  PetscCall(KSPDestroy(&b->ksp));
  for (PetscInt l = 0; l < MBC_MAX_CUTS; l++) {
    PetscCall(KSPDestroy(&b->kspcut[l]));
    PetscCall(MatDestroy(&b->Acut[l]));
  }
  PetscCall(VecDestroy(&b->ustart));
  PetscCall(VecDestroy(&b->u));
  PetscCall(VecDestroy(&b->u0));
  PetscCall(VecDestroy(&b->v0));
  PetscCall(VecDestroy(&b->v));
  PetscCall(VecDestroy(&b->a));
  PetscCall(VecDestroy(&b->du));
  PetscCall(VecDestroy(&b->rhs));
  PetscCall(VecDestroy(&b->f));
  PetscCall(VecDestroy(&b->fold));
  PetscCall(VecDestroy(&b->g));
  PetscCall(VecDestroy(&b->work));
  PetscCall(VecDestroy(&b->work2));
  PetscCall(DMDestroy(&b->dmStress));
  PetscCall(DMDestroy(&b->dm));
  PetscCall(PetscFree2(b->vnum, b->cnum));
  PetscCall(MBCBodyLayoutDestroy(b));
  PetscCall(MBCBodyRigidDestroy(b));
  PetscCall(MBCSceneDestroy(&b->scene));
  comm = b->comm; /* split by the solver for this body: freed after the header lets go of it */
  PetscCall(PetscHeaderDestroy(body));
  if (comm != MPI_COMM_NULL) PetscCallMPI(MPI_Comm_free(&comm));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyView(MBCBody b, PetscViewer viewer)
{
  PetscBool   ascii;
  PetscMPIInt size;
  PetscInt    n;

  PetscFunctionBegin;
  if (!b) PetscFunctionReturn(0); /* NULL on ranks outside the body */
  PetscValidHeaderSpecific(b, MBC_BODY_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)b), &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(b->comm, &size));
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)b, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  n = 0;
  if (b->u) PetscCall(VecGetSize(b->u, &n));
  PetscCall(PetscViewerASCIIPrintf(viewer, "%" PetscInt_FMT " %s cells (element %s), %" PetscInt_FMT " vertices, %" PetscInt_FMT " DOFs on %d ranks; E %g nu %g density %g\n", b->desc.num_cells, b->desc.cell_type, MBCElementTypes[b->element], b->desc.num_vertices, n, size, (double)b->desc.E, (double)b->desc.nu, (double)b->desc.density));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetName(MBCBody body, const char **name)
{
  PetscFunctionBegin;
  *name = body ? body->name : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetDM(MBCBody body, DM *dm)
{
  PetscFunctionBegin;
  *dm = body ? body->dm : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetDisplacement(MBCBody body, Vec *u)
{
  PetscFunctionBegin;
  *u = body ? body->u : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetKSP(MBCBody body, KSP *ksp)
{
  PetscFunctionBegin;
  *ksp = body ? body->ksp : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetOperators(MBCBody body, Mat *K, Mat *M, Mat *Cb)
{
  PetscFunctionBegin;
  if (K) *K = body ? body->K : NULL;
  if (M) *M = body ? body->M : NULL;
  if (Cb) *Cb = body ? body->Cb : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetVelocity(MBCBody body, Vec *v)
{
  PetscFunctionBegin;
  *v = body ? body->v : NULL;
  PetscFunctionReturn(0);
}

/* The cellwise stress (xx yy zz xy yz xz) of the current displacement, in a new Vec on the
   body's stress DM (MBCBodyGetStressDM): the solver keeps none between outputs. */
PetscErrorCode MBCBodyCreateStress(MBCBody body, Vec *stress)
{
  PetscFunctionBegin;
  *stress = NULL;
  if (!body) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(body, MBC_BODY_CLASSID, 1);
  PetscCheck(body->u, body->comm, PETSC_ERR_ARG_WRONGSTATE, "Body '%s' is not set up: call MBCSolverSetUp() first", body->name);
  PetscCall(DMCreateGlobalVector(body->dmStress, stress));
  PetscCall(PetscObjectSetName((PetscObject)*stress, "stress"));
  PetscCall(MBCBodyComputeStress(body, body->u, *stress));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetStressDM(MBCBody body, DM *dm)
{
  PetscFunctionBegin;
  *dm = body ? body->dmStress : NULL;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetComm(MBCBody body, MPI_Comm *comm)
{
  PetscFunctionBegin;
  *comm = body->comm;
  PetscFunctionReturn(0);
}

/* The body's position in the scene. */
PetscErrorCode MBCBodyGetIndex(MBCBody body, PetscInt *index)
{
  PetscFunctionBegin;
  *index = body->index;
  PetscFunctionReturn(0);
}

/* The element of the body's cells; *rigid: a rigid body (no element, six DOFs). */
PetscErrorCode MBCBodyGetElement(MBCBody body, MBCElementType *element, PetscBool *rigid)
{
  PetscFunctionBegin;
  if (element) *element = body->element;
  if (rigid) *rigid = body->desc.rigid;
  PetscFunctionReturn(0);
}

/* The prescribed rows this rank owns (global, sorted): those the body's factor holds to their
   values. */
PetscErrorCode MBCBodyGetPrescribedRows(MBCBody body, PetscInt *n, const PetscInt **rows)
{
  PetscFunctionBegin;
  *n = body->nbc;
  if (rows) *rows = body->bc_rows;
  PetscFunctionReturn(0);
}

/* For each prescribed row (MBCBodyGetPrescribedRows) the scene's dirichlet entry that prescribes it
   (-1: an absorbing surface held in a static state). */
PetscErrorCode MBCBodyGetPrescribedEntries(MBCBody body, const PetscInt **entry)
{
  PetscFunctionBegin;
  *entry = body->bc_entry;
  PetscFunctionReturn(0);
}

/* The rows K^+ holds at 0 where a static body floats (owned, sorted; none otherwise). */
PetscErrorCode MBCBodyGetHeldRows(MBCBody body, PetscInt *n, const PetscInt **rows)
{
  PetscFunctionBegin;
  *n = body->nfix;
  if (rows) *rows = body->fix_rows;
  PetscFunctionReturn(0);
}

/* The free rigid modes of a static body (orthonormal, 0 on the prescribed DOFs; none where it is
   held or the stage is dynamic). */
PetscErrorCode MBCBodyGetRigidModes(MBCBody body, PetscInt *n, const Vec **modes)
{
  PetscFunctionBegin;
  *n = body->nrigid;
  if (modes) *modes = body->rigid;
  PetscFunctionReturn(0);
}

/* Of the static iterate (MBCBodyStaticIncrement), per free mode: e = -R^T (F - K u) and the load
   R^T F it carries, the rounding left in e, and the load's resultant and moment about the origin. */
PetscErrorCode MBCBodyGetRigidEquilibrium(MBCBody body, const PetscReal **e, const PetscReal **f, PetscReal *eround, const PetscReal **fres)
{
  PetscFunctionBegin;
  if (e) *e = body->erigid;
  if (f) *f = body->frigid;
  if (eround) *eround = body->erigid_round;
  if (fres) *fres = body->fres;
  PetscFunctionReturn(0);
}

/* The step's increment du (read it only: MBCBodyAddIncrement adds to it). */
PetscErrorCode MBCBodyGetIncrement(MBCBody body, Vec *du)
{
  PetscFunctionBegin;
  *du = body->du;
  PetscFunctionReturn(0);
}

/* du += x: the response to the contact forces. */
PetscErrorCode MBCBodyAddIncrement(MBCBody body, Vec x)
{
  PetscFunctionBegin;
  PetscCall(VecAXPY(body->du, 1.0, x));
  PetscFunctionReturn(0);
}

/* du += R alpha: the free modes' motion the rigid equilibrium asks for. */
PetscErrorCode MBCBodyAddRigidIncrement(MBCBody body, const PetscReal alpha[])
{
  PetscFunctionBegin;
  for (PetscInt j = 0; j < body->nrigid; j++) PetscCall(VecAXPY(body->du, alpha[j], body->rigid[j]));
  PetscFunctionReturn(0);
}

/* The resultant and moment about the origin of the scene's load l on the body, for a unit time
   factor; *acts: l acts on the body. Collective on the body. */
PetscErrorCode MBCBodySceneLoadResultant(MBCBody body, PetscInt l, PetscReal r[6], PetscBool *acts)
{
  PetscFunctionBegin;
  *acts = PETSC_FALSE;
  for (PetscInt i = 0; i < body->nloads; i++)
    if (body->load_index[i] == l) {
      PetscCall(MBCBodyLoadResultant(body, body->load[i], r));
      *acts = PETSC_TRUE;
    }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyGetAcceleration(MBCBody body, Vec *a)
{
  PetscFunctionBegin;
  *a = body ? body->a : NULL;
  PetscFunctionReturn(0);
}

/* The external work and the damping dissipation so far (dynamic). */
PetscErrorCode MBCBodyGetWork(MBCBody body, PetscReal *wext, PetscReal *wdamp)
{
  PetscFunctionBegin;
  *wext  = body->wext;
  *wdamp = body->wdamp;
  PetscFunctionReturn(0);
}

/* A restart's: the work and dissipation the checkpoint held. */
PetscErrorCode MBCBodySetWork(MBCBody body, PetscReal wext, PetscReal wdamp)
{
  PetscFunctionBegin;
  body->wext  = wext;
  body->wdamp = wdamp;
  PetscFunctionReturn(0);
}

/* A dynamic restart's at its time t: the load F(t), where the next step's trapezoidal work starts. */
PetscErrorCode MBCBodyRestartLoad(MBCBody body, PetscReal t)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyExternalForce(body, t, PETSC_FALSE, body->fold));
  PetscFunctionReturn(0);
}

/* The scene index (the order mbcontact-prep wrote) of each local vertex (vStart-based) and cell. */
PetscErrorCode MBCBodyGetSceneNumbering(MBCBody body, const PetscInt **vnum, const PetscInt **cnum)
{
  PetscFunctionBegin;
  if (vnum) *vnum = body->vnum;
  if (cnum) *cnum = body->cnum;
  PetscFunctionReturn(0);
}

/* Local cell c (from the first cell): its nodes (points) in its kernel's order and its MBCCellType. */
PetscErrorCode MBCBodyGetCellNodes(MBCBody body, PetscInt c, PetscInt *nv, const PetscInt **v, MBCCellType *type)
{
  PetscFunctionBegin;
  *nv = body->cellvoff[c + 1] - body->cellvoff[c];
  *v  = &body->cellv[body->cellvoff[c]];
  if (type) *type = (MBCCellType)body->celltype[c];
  PetscFunctionReturn(0);
}
