/* Assembly of a body's stiffness, mass and load vectors, and its constrained DOFs. */
#include <mbc/private/bodyimpl.h>

/* K and, for a dynamic analysis, M: consistent (rho int N_i N_j) or lumped (its row sums). */
static PetscErrorCode BodyAssembleOperators(MBCBody body, PetscBool mass, MBCMassType type)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyCreateOperator(body, &body->K));
  if (mass) PetscCall(MatDuplicate(body->K, MAT_DO_NOT_COPY_VALUES, &body->M));
  PetscCall(MBCBodyAssembleElasticity(body, body->K, body->M));
  PetscCall(MatSetOption(body->K, MAT_SYMMETRIC, PETSC_TRUE));
  if (mass && type == MBC_MASS_LUMPED) {
    Vec diag;
    PetscCall(MatCreateVecs(body->M, &diag, NULL));
    PetscCall(MatGetRowSum(body->M, diag));
    PetscCall(MatZeroEntries(body->M));
    PetscCall(MatDiagonalSet(body->M, diag, INSERT_VALUES));
    PetscCall(VecDestroy(&diag));
  }
  if (mass && body->desc.massless) PetscCall(MatZeroEntries(body->M)); /* no inertia: the pattern kept for A */
  if (mass) PetscCall(MBCBodyAddedMass(body));
  if (mass) PetscCall(MatSetOption(body->M, MAT_SYMMETRIC, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* Number of faces of a surface in this body, over the body's communicator. */
static PetscErrorCode BodySurfaceSize(MBCBody body, PetscInt id, PetscInt *n)
{
  DMLabel  label;
  PetscInt local = 0;

  PetscFunctionBegin;
  PetscCall(DMGetLabel(body->dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumSize(label, id, &local));
  PetscCall(MPIU_Allreduce(&local, n, 1, MPIU_INT, MPI_SUM, body->comm));
  PetscFunctionReturn(0);
}

/* F: vector times its weight at each of the load's nodes of this body that this rank owns (nodal
   and line forces). */
static PetscErrorCode BodyAssembleNodalLoad(MBCBody body, MBCLoadDesc *load, Vec F)
{
  PetscSection gsec;
  PetscScalar *f;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(F));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(VecGetOwnershipRange(F, &rstart, NULL));
  PetscCall(VecGetArray(F, &f));
  for (PetscInt k = 0; k < load->nnodes; k++) {
    PetscInt p, off;
    if (load->nodes[2 * k] != body->index) continue;
    PetscCall(MBCBodyNodePoint(body, load->nodes[2 * k + 1], &p));
    if (p < 0) continue;
    PetscCall(PetscSectionGetOffset(gsec, p, &off));
    if (off < 0) continue; /* owned by another rank */
    for (PetscInt c = 0; c < 3; c++) f[off + c - rstart] += load->weights[k] * load->vector[c];
  }
  PetscCall(VecRestoreArray(F, &f));
  PetscFunctionReturn(0);
}

/* The load vector of one scene load for a unit time factor: volume loads by their element
   weights, surface loads face by face (bodyfaceload.c, bodyhydrostatic.c), nodal loads at their
   nodes. */
static PetscErrorCode BodyAssembleLoad(MBCBody body, MBCLoadDesc *load, Vec F)
{
  PetscFunctionBegin;
  if (load->kind == MBC_LOAD_GROUND_ACCELERATION) { /* MBCBodyAssembleLoads assembles it */
    PetscBool applies;
    PetscCall(MBCBodyGroundLoad(body, load, F, &applies));
    PetscFunctionReturn(0);
  }
  if (load->kind == MBC_LOAD_HYDROSTATIC) { /* a linear field cut at the level: integrated by hand */
    PetscCall(MBCBodyAssembleHydrostatic(body, load, F));
    PetscFunctionReturn(0);
  }
  if (load->kind == MBC_LOAD_UPLIFT) { /* the dry joint; the solver updates it with the wet lengths (solveruplift.c) */
    PetscReal r[4], *w;
    PetscCall(PetscCalloc1(body->scene->couples[load->couple].uplift.nzones, &w));
    PetscCall(MBCBodyAssembleUplift(body, load, w, F, r));
    PetscCall(PetscFree(w));
    PetscFunctionReturn(0);
  }
  if (load->kind == MBC_LOAD_NODAL_FORCE || load->kind == MBC_LOAD_LINE_FORCE) {
    PetscCall(BodyAssembleNodalLoad(body, load, F));
    PetscFunctionReturn(0);
  }
  if (load->kind == MBC_LOAD_GRAVITY && body->desc.rigid) { /* through its mass about the reference point */
    PetscCall(MBCBodyRigidGravity(body, load->vector, F));
    PetscFunctionReturn(0);
  }
  PetscCheck(!(load->kind == MBC_LOAD_BODY_FORCE && body->surface), body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: a body force acts on the rigid surface '%s', which has no volume", body->scene->filename, body->name);
  if (load->kind == MBC_LOAD_GRAVITY || load->kind == MBC_LOAD_BODY_FORCE) { /* by hand, as K */
    PetscReal f[3];
    for (PetscInt d = 0; d < 3; d++) f[d] = PetscRealPart(load->vector[d]) * (load->kind == MBC_LOAD_GRAVITY ? body->desc.density : 1.0);
    PetscCall(MBCBodyAssembleVolumeLoad(body, f, F));
    PetscFunctionReturn(0);
  }
  PetscCall(MBCBodyAssembleFaceLoad(body, load, F));
  PetscFunctionReturn(0);
}

/* The scene loads acting on this body: volume loads naming it (or all bodies), surface loads on its faces. */
PetscErrorCode MBCBodyAssembleLoads(MBCBody body)
{
  MBCScene scene = body->scene;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(scene->nloads, &body->load, scene->nloads, &body->load_index));
  body->nloads = 0;
  for (PetscInt l = 0; l < scene->nloads; l++) {
    MBCLoadDesc *load = &scene->loads[l];
    PetscBool    applies;

    PetscCall(MBCLoadAppliesToBody(load, body->name, &applies));
    if (applies && load->surface_id >= 1) {
      PetscInt n;
      PetscCall(BodySurfaceSize(body, load->surface_id, &n));
      applies = (PetscBool)(n > 0);
    }
    if (applies && load->nnodes) { /* nodal and line forces: on the bodies their nodes are in */
      applies = PETSC_FALSE;
      for (PetscInt k = 0; k < load->nnodes && !applies; k++) applies = (PetscBool)(load->nodes[2 * k] == body->index);
    }
    if (applies && body->desc.rigid && (load->kind == MBC_LOAD_PRESSURE || load->kind == MBC_LOAD_TRACTION || load->kind == MBC_LOAD_HYDROSTATIC || load->kind == MBC_LOAD_UPLIFT) && body->surface)
      SETERRQ(body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: load %" PetscInt_FMT " (%s) acts on the rigid surface '%s', which has no faces of its own: load it by nodal forces", scene->filename, l, MBCLoadKinds[load->kind], body->name);
    if (applies && load->kind == MBC_LOAD_GROUND_ACCELERATION) applies = (PetscBool)(!body->scene->absolute || body->Cin); /* absolute motion: through the input surfaces only */
    if (!applies) continue;
    PetscCall(DMCreateGlobalVector(body->dm, &body->load[body->nloads]));
    PetscCall(BodyAssembleLoad(body, load, body->load[body->nloads]));
    body->load_index[body->nloads++] = l;
  }
  PetscFunctionReturn(0);
}

/* This rank's share of the resultant force and moment about the origin of the nodal forces F
   (a global Vec of the body): sums over the owned vertices, r = (F, x x F). */
PetscErrorCode MBCBodyLoadResultant(MBCBody body, Vec F, PetscReal r[6])
{
  DM                 cdm;
  PetscSection       csec, lsec, gsec;
  Vec                coords, Floc;
  const PetscScalar *x, *f;
  PetscInt           vStart, vEnd;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(r, 6));
  PetscCall(DMGetCoordinateDM(body->dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(DMGetLocalVector(body->dm, &Floc));
  PetscCall(DMGlobalToLocal(body->dm, F, INSERT_VALUES, Floc));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(VecGetArrayRead(Floc, &f));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  for (PetscInt v = vStart; v < vEnd; v++) {
    PetscInt goff, off, coff;
    PetscCall(PetscSectionGetOffset(gsec, v, &goff));
    if (goff < 0) continue; /* owned by another rank */
    PetscCall(PetscSectionGetOffset(lsec, v, &off));
    PetscCall(PetscSectionGetOffset(csec, v, &coff));
    {
      const PetscReal *X = (const PetscReal *)&x[coff], F[3] = {PetscRealPart(f[off]), PetscRealPart(f[off + 1]), PetscRealPart(f[off + 2])};
      for (PetscInt c = 0; c < 3; c++) r[c] += F[c];
      r[3] += X[1] * F[2] - X[2] * F[1];
      r[4] += X[2] * F[0] - X[0] * F[2];
      r[5] += X[0] * F[1] - X[1] * F[0];
    }
  }
  PetscCall(VecRestoreArrayRead(Floc, &f));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(DMRestoreLocalVector(body->dm, &Floc));
  PetscFunctionReturn(0);
}

/* Owned global rows of the DOFs prescribed by the scene's dirichlet entries; where entries
   overlap (an edge shared by two surfaces) the later entry wins. */
static PetscErrorCode BodySetUpConstraints(MBCBody body)
{
  MBCScene     scene = body->scene;
  DMLabel      label;
  PetscSection gsec, lsec;
  PetscInt     n = 0, cap = 0, *rows = NULL, *entry = NULL;
  PetscInt     local[3] = {0, 0, 0}, global[3];

  PetscFunctionBegin;
  PetscCall(DMGetLabel(body->dm, "Face Sets", &label));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  for (PetscInt e = 0; e < scene->ndirichlet; e++) {
    MBCDirichletDesc *d = &scene->dirichlet[e];
    IS                faceIS = NULL;
    const PetscInt   *faces;
    PetscInt          nfaces;

    for (PetscInt k = 0; k < d->nnodes; k++) { /* on nodes */
      PetscInt point, off;
      if (d->nodes[2 * k] != body->index) continue;
      PetscCall(MBCBodyNodePoint(body, d->nodes[2 * k + 1], &point));
      if (point < 0) continue;
      PetscCall(PetscSectionGetOffset(gsec, point, &off));
      if (off < 0) continue; /* owned by another rank */
      if (n == cap) {
        cap = 2 * cap + 64;
        PetscCall(PetscRealloc(cap * sizeof(PetscInt), &rows));
        PetscCall(PetscRealloc(cap * sizeof(PetscInt), &entry));
      }
      rows[n]    = off + d->component;
      entry[n++] = e;
    }
    if (label && d->surface_id >= 1) PetscCall(DMLabelGetStratumIS(label, d->surface_id, &faceIS));
    if (!faceIS) continue;
    PetscCall(ISGetLocalSize(faceIS, &nfaces));
    PetscCall(ISGetIndices(faceIS, &faces));
    for (PetscInt f = 0; f < nfaces; f++) {
      PetscInt *closure = NULL, nclosure;

      PetscCall(DMPlexGetTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
      for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
        PetscInt point = closure[p], off, dof;
        PetscCall(PetscSectionGetDof(lsec, point, &dof));
        if (!dof) continue; /* the face's nodes: its vertices (and a tet10's edges) */
        PetscCall(PetscSectionGetOffset(gsec, point, &off));
        if (off < 0) continue; /* owned by another rank */
        if (n == cap) {
          cap = 2 * cap + 64;
          PetscCall(PetscRealloc(cap * sizeof(PetscInt), &rows));
          PetscCall(PetscRealloc(cap * sizeof(PetscInt), &entry));
        }
        rows[n]    = off + d->component;
        entry[n++] = e;
      }
      PetscCall(DMPlexRestoreTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
    }
    PetscCall(ISRestoreIndices(faceIS, &faces));
    PetscCall(ISDestroy(&faceIS));
  }
  /* sort by row, keep the last entry of each row */
  PetscCall(PetscSortIntWithArray(n, rows, entry));
  PetscCall(PetscMalloc2(n, &body->bc_rows, n, &body->bc_entry));
  body->nbc = 0;
  for (PetscInt i = 0; i < n; i++) {
    if (body->nbc && body->bc_rows[body->nbc - 1] == rows[i]) {
      body->bc_entry[body->nbc - 1] = PetscMax(body->bc_entry[body->nbc - 1], entry[i]);
      continue;
    }
    body->bc_rows[body->nbc]  = rows[i];
    body->bc_entry[body->nbc] = entry[i];
    body->nbc++;
  }
  PetscCall(PetscFree(rows));
  PetscCall(PetscFree(entry));
  for (PetscInt i = 0; i < body->nbc; i++) local[scene->dirichlet[body->bc_entry[i]].component] = 1;
  PetscCall(MPIU_Allreduce(local, global, 3, MPIU_INT, MPI_MAX, body->comm));
  for (PetscInt c = 0; c < 3; c++) body->bc_component[c] = global[c] ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* dynamic: some analysis stage of the solver's run needs M, of type mass. The solver hands these
   over: the scene is shared by every solver on it and holds only what its file says. */
PetscErrorCode MBCBodySetUp(MBCBody body, PetscBool dynamic, MBCMassType mass)
{
  MBCScene scene = body->scene;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_BodyAssemble, 0, 0, 0, 0));
  if (body->desc.rigid) PetscCall(MBCBodyRigidSetUp(body, dynamic)); /* K = 0, M of its six DOFs */
  else PetscCall(BodyAssembleOperators(body, dynamic, mass));
  body->cM = body->desc.damping + body->desc.rayleigh_alpha;
  body->cK = body->desc.rayleigh_beta;
  PetscCall(BodySetUpConstraints(body));
  if (dynamic) PetscCall(MBCBodyAbsorbingSetUp(body)); /* before the loads: the input surfaces' loads use Cin */
  PetscCall(MBCBodySpringsSetUp(body, dynamic));
  PetscCall(MBCBodyAssembleLoads(body));
  PetscCall(DMCreateGlobalVector(body->dm, &body->u));
  PetscCall(PetscObjectSetName((PetscObject)body->u, "displacement"));
  PetscCall(VecDuplicate(body->u, &body->du));
  PetscCall(VecDuplicate(body->u, &body->rhs));
  PetscCall(VecDuplicate(body->u, &body->f));
  PetscCall(VecDuplicate(body->u, &body->g));
  PetscCall(VecDuplicate(body->u, &body->work));
  if (dynamic) {
    PetscCall(VecDuplicate(body->u, &body->v));
    PetscCall(VecDuplicate(body->u, &body->a));
    PetscCall(VecDuplicate(body->u, &body->fold));
    PetscCall(VecDuplicate(body->u, &body->work2));
  }
  PetscCall(PetscLogEventEnd(MBC_BodyAssemble, 0, 0, 0, 0));
  if (!dynamic && !scene->ncouples && !body->desc.rigid) {
    /* K alone: without inertia or contact, every component needs a prescribed DOF somewhere
       (with contact, the static solver stabilises such bodies: -mbc_static_stabilize). */
    PetscBool held[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
    MBCBodySpringHeld(body, held);
    for (PetscInt c = 0; c < 3; c++) PetscCheck(body->bc_component[c] || held[c], body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: body '%s' has no prescribed %c displacement: its static stiffness is singular (rigid-body motion); prescribe it on some surface, hold it by contact, or run a dynamic analysis", scene->filename, body->name, "xyz"[c]);
  }
  PetscFunctionReturn(0);
}
