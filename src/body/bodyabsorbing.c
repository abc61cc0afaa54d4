/* Absorbing boundaries and the ground motion's loads (docs/scene.md, absorbing and
   ground_acceleration).

   Lysmer-Kuhlemeyer dashpots: a truncated boundary with outward normal n takes the traction
   -rho (c_p n n^T + c_s (I - n n^T)) v, c_p and c_s the body's own wave speeds, lumped at the nodes
   (Cb, part of the damping matrix: C = (c + alpha) M + beta K + Cb, and of Newmark's operator
   K + a0 M + a1 C, factored once per step size). A plane wave leaving along n goes out without
   reflection; it is exact for a vertically propagating wave at a horizontal base.

   The quiet base's input: a wave of velocity v_i(t) coming in through the boundary is the
   traction 2 rho c v_i (the dashpot's own -rho c v takes what goes out), so the record enters
   as the load Cin e v_g(t), Cin the dashpots of the input surfaces weighted 2 (the record is the
   incident wave) or 1 (the record is the outcrop motion, twice the incident wave), e the record's
   direction. Such a scene is in absolute motion: no body gets the relative form's -M a_g. */
#include <mbc/private/bodyimpl.h>

/* w_i = integral of N_i dA: 2 x 2 Gauss on the bilinear quad (exact on any planar quad, and on a
   triangle as the quad with a repeated vertex). */
static PetscErrorCode AreaWeights(PetscInt nv, const PetscReal X[4][3], void *ctx, PetscReal w[4])
{
  static const PetscReal sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1}, g = 0.57735026918962576451;
  PetscReal              Q[4][3];

  PetscFunctionBegin;
  for (PetscInt v = 0; v < 4; v++) {
    w[v] = 0;
    for (PetscInt k = 0; k < 3; k++) Q[v][k] = X[PetscMin(v, nv - 1)][k];
  }
  for (PetscInt q = 0; q < 4; q++) {
    const PetscReal xi = sx[q] * g, eta = sy[q] * g;
    PetscReal       dxi[3] = {0, 0, 0}, deta[3] = {0, 0, 0}, c[3], J;
    for (PetscInt v = 0; v < 4; v++)
      for (PetscInt k = 0; k < 3; k++) {
        dxi[k] += 0.25 * sx[v] * (1 + sy[v] * eta) * Q[v][k];
        deta[k] += 0.25 * sy[v] * (1 + sx[v] * xi) * Q[v][k];
      }
    c[0] = dxi[1] * deta[2] - dxi[2] * deta[1];
    c[1] = dxi[2] * deta[0] - dxi[0] * deta[2];
    c[2] = dxi[0] * deta[1] - dxi[1] * deta[0];
    J    = PetscSqrtReal(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (PetscInt v = 0; v < 4; v++) w[PetscMin(v, nv - 1)] += 0.25 * (1 + sx[v] * xi) * (1 + sy[v] * eta) * J;
  }
  PetscFunctionReturn(0);
}

/* A matrix of nodal 3 x 3 blocks with the layout and local numbering of K. */
PetscErrorCode MBCBodyNodalBlockMatrix(MBCBody body, Mat *A)
{
  ISLocalToGlobalMapping rl2g, cl2g;
  PetscInt               m, n, M, N;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(body->K, &m, &n));
  PetscCall(MatGetSize(body->K, &M, &N));
  PetscCall(MatGetLocalToGlobalMapping(body->K, &rl2g, &cl2g));
  PetscCall(MatCreate(body->comm, A));
  PetscCall(MatSetSizes(*A, m, n, M, N));
  PetscCall(MatSetType(*A, MATAIJ));
  PetscCall(MatSeqAIJSetPreallocation(*A, 3, NULL));
  PetscCall(MatMPIAIJSetPreallocation(*A, 3, NULL, 3, NULL));
  PetscCall(MatSetLocalToGlobalMapping(*A, rl2g, cl2g));
  PetscCall(MatSetOption(*A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* The constrained set of the static states: the Dirichlet rows and every DOF of the absorbing
   surfaces (entry -1: held at 0), sorted; the Dirichlet set alone is kept for the dynamic ones. */
static PetscErrorCode BodyAbsorbingHeldSet(MBCBody body)
{
  MBCScene     scene = body->scene;
  DMLabel      label;
  PetscSection gsec;
  PetscInt     vStart, vEnd, n = 0, cap = body->nbc + 64, *rows, *entry;

  PetscFunctionBegin;
  PetscCall(DMGetLabel(body->dm, "Face Sets", &label));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  PetscCall(PetscMalloc1(cap, &rows));
  PetscCall(PetscMalloc1(cap, &entry));
  for (PetscInt i = 0; label && i < scene->nabsorbing; i++) {
    IS              faceIS;
    const PetscInt *faces;
    PetscInt        nfaces;
    PetscCall(DMLabelGetStratumIS(label, scene->absorbing[i].surface_id, &faceIS));
    if (!faceIS) continue;
    PetscCall(ISGetLocalSize(faceIS, &nfaces));
    PetscCall(ISGetIndices(faceIS, &faces));
    for (PetscInt f = 0; f < nfaces; f++) {
      PetscInt *closure = NULL, nclosure;
      PetscCall(DMPlexGetTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
      for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
        PetscInt off;
        if (closure[p] < vStart || closure[p] >= vEnd) continue;
        PetscCall(PetscSectionGetOffset(gsec, closure[p], &off));
        if (off < 0) continue; /* owned by another rank */
        if (n + 3 > cap) {
          cap = 2 * cap;
          PetscCall(PetscRealloc(cap * sizeof(PetscInt), &rows));
          PetscCall(PetscRealloc(cap * sizeof(PetscInt), &entry));
        }
        for (PetscInt c = 0; c < 3; c++) rows[n] = off + c, entry[n++] = -1;
      }
      PetscCall(DMPlexRestoreTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
    }
    PetscCall(ISRestoreIndices(faceIS, &faces));
    PetscCall(ISDestroy(&faceIS));
  }
  if (n + body->nbc > cap) {
    cap = n + body->nbc;
    PetscCall(PetscRealloc(cap * sizeof(PetscInt), &rows));
    PetscCall(PetscRealloc(cap * sizeof(PetscInt), &entry));
  }
  for (PetscInt i = 0; i < body->nbc; i++) rows[n] = body->bc_rows[i], entry[n++] = body->bc_entry[i];
  PetscCall(PetscSortIntWithArray(n, rows, entry));
  body->nbc_free      = body->nbc;
  body->bc_rows_free  = body->bc_rows;
  body->bc_entry_free = body->bc_entry;
  PetscCall(PetscMalloc2(n, &body->bc_rows_held, n, &body->bc_entry_held));
  body->nbc_held = 0;
  for (PetscInt i = 0; i < n; i++) { /* one per row; a Dirichlet entry wins over the hold */
    if (body->nbc_held && body->bc_rows_held[body->nbc_held - 1] == rows[i]) {
      body->bc_entry_held[body->nbc_held - 1] = PetscMax(body->bc_entry_held[body->nbc_held - 1], entry[i]);
      continue;
    }
    body->bc_rows_held[body->nbc_held]    = rows[i];
    body->bc_entry_held[body->nbc_held++] = entry[i];
  }
  PetscCall(PetscFree(rows));
  PetscCall(PetscFree(entry));
  PetscFunctionReturn(0);
}

/* A static state (a static stage, the initial state of a dynamic analysis) holds the absorbing
   surfaces: a truncated foundation has no other support under the dam's weight. */
PetscErrorCode MBCBodyAbsorbingHold(MBCBody body)
{
  PetscFunctionBegin;
  if (!body->bc_rows_held || body->held) PetscFunctionReturn(0);
  body->nbc      = body->nbc_held;
  body->bc_rows  = body->bc_rows_held;
  body->bc_entry = body->bc_entry_held;
  body->held     = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* A dynamic stage frees them and puts the reactions they carried at time t, K u - F on their
   rows, as a constant load in their place (as FLAC and 3DEC do when a quiet boundary replaces a
   support): the static state stays in equilibrium and the dashpots see only the motion. */
PetscErrorCode MBCBodyAbsorbingRelease(MBCBody body, PetscReal t)
{
  const PetscScalar *r;
  PetscScalar       *h;
  PetscInt           rstart;

  PetscFunctionBegin;
  if (!body->held) PetscFunctionReturn(0);
  if (!body->fhold) PetscCall(VecDuplicate(body->u, &body->fhold));
  PetscCall(MBCBodyExternalForce(body, t, PETSC_FALSE, body->work));
  PetscCall(VecScale(body->work, -1.0));
  PetscCall(MatMultAdd(body->K, body->u, body->work, body->work)); /* K u - F */
  PetscCall(VecZeroEntries(body->fhold));
  PetscCall(VecGetOwnershipRange(body->u, &rstart, NULL));
  PetscCall(VecGetArrayRead(body->work, &r));
  PetscCall(VecGetArray(body->fhold, &h));
  for (PetscInt i = 0; i < body->nbc_held; i++)
    if (body->bc_entry_held[i] < 0) h[body->bc_rows_held[i] - rstart] = r[body->bc_rows_held[i] - rstart];
  PetscCall(VecRestoreArray(body->fhold, &h));
  PetscCall(VecRestoreArrayRead(body->work, &r));
  body->nbc      = body->nbc_free;
  body->bc_rows  = body->bc_rows_free;
  body->bc_entry = body->bc_entry_free;
  body->held     = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* Cb and Cin of the body's absorbing surfaces (none: both NULL). Collective on the body. After
   the constraints: a prescribed DOF takes no dashpot force (its rows and columns are zeroed, so
   that Newmark's right side needs no Cb g term). */
PetscErrorCode MBCBodyAbsorbingSetUp(MBCBody body)
{
  MBCScene        scene = body->scene;
  const PetscReal rho   = body->desc.density;
  PetscReal       cp, cs;
  PetscInt        any[2] = {0, 0};

  PetscFunctionBegin;
  if (!scene->nabsorbing) PetscFunctionReturn(0);
  { /* does any absorbing (input) surface have faces on this body? */
    DMLabel label;
    PetscCall(DMGetLabel(body->dm, "Face Sets", &label));
    for (PetscInt i = 0; label && i < scene->nabsorbing; i++) {
      PetscInt n;
      PetscCall(DMLabelGetStratumSize(label, scene->absorbing[i].surface_id, &n));
      if (n) any[0] = 1;
      if (n && scene->absorbing[i].input != MBC_INPUT_NONE) any[1] = 1;
    }
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, any, 2, MPIU_INT, MPI_MAX, body->comm));
  }
  if (!any[0]) PetscFunctionReturn(0);
  PetscCheck(rho > 0 && !body->desc.massless, body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: body '%s' has an absorbing boundary but no mass: its dashpots rho c would be 0 (a massless body radiates nothing)", scene->filename, body->name);
  cp = PetscSqrtReal((body->lambda + 2 * body->mu) / rho);
  cs = PetscSqrtReal(body->mu / rho);
  PetscCall(MBCBodyNodalBlockMatrix(body, &body->Cb));
  if (any[1]) PetscCall(MBCBodyNodalBlockMatrix(body, &body->Cin));
  for (PetscInt i = 0; i < scene->nabsorbing; i++) {
    const MBCAbsorbingDesc *a = &scene->absorbing[i];
    PetscCall(MBCBodySurfaceBlocks(body, a->surface_id, AreaWeights, NULL, rho * cp, rho * cs, body->Cb));
    if (a->input != MBC_INPUT_NONE) {
      const PetscReal f = a->input == MBC_INPUT_INCIDENT ? 2.0 : 1.0;
      PetscCall(MBCBodySurfaceBlocks(body, a->surface_id, AreaWeights, NULL, f * rho * cp, f * rho * cs, body->Cin));
    }
  }
  PetscCall(MatAssemblyBegin(body->Cb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(body->Cb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatZeroRowsColumns(body->Cb, body->nbc, body->bc_rows, 0.0, NULL, NULL));
  PetscCall(BodyAbsorbingHeldSet(body));
  PetscCall(MatSetOption(body->Cb, MAT_SYMMETRIC, PETSC_TRUE));
  if (body->Cin) {
    PetscCall(MatAssemblyBegin(body->Cin, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(body->Cin, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(0);
}

/* The load vector of a ground acceleration for a unit record value: -(M + M_a) e (relative
   motion) or, in a scene in absolute motion, Cin e on a body with input surfaces (its time
   function is then the record's velocity, MBCBodyExternalForce); *applies false where the load
   does nothing to this body (absolute motion, no input surface). Collective on the body. */
PetscErrorCode MBCBodyGroundLoad(MBCBody body, MBCLoadDesc *load, Vec F, PetscBool *applies)
{
  Vec          e;
  PetscScalar *ev;
  PetscInt     n;

  PetscFunctionBegin;
  *applies = PETSC_TRUE;
  if (body->scene->absolute && !body->Cin) {
    *applies = PETSC_FALSE;
    PetscFunctionReturn(0);
  }
  PetscCheck(body->scene->absolute || body->M, body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: a ground acceleration acts on body '%s' through its mass, which a static analysis does not have", body->scene->filename, body->name);
  PetscCall(VecDuplicate(F, &e));
  PetscCall(VecGetLocalSize(e, &n));
  PetscCall(VecGetArray(e, &ev));
  for (PetscInt i = 0; i < n; i++) ev[i] = load->vector[i % 3]; /* 3 DOFs per vertex, interlaced */
  PetscCall(VecRestoreArray(e, &ev));
  if (body->scene->absolute) PetscCall(MatMult(body->Cin, e, F));
  else {
    PetscCall(MatMult(body->M, e, F));
    PetscCall(VecScale(F, -1.0));
  }
  PetscCall(VecDestroy(&e));
  PetscFunctionReturn(0);
}

PetscBool MBCBodyDamped(MBCBody body)
{
  return (PetscBool)(body->cM != 0 || body->cK != 0 || body->Cb);
}

/* x += scale C y, C = cM M + cK K + Cb (never formed). */
PetscErrorCode MBCBodyAddDamping(MBCBody body, PetscReal scale, Vec y, Vec x)
{
  PetscFunctionBegin;
  if (body->cM != 0) {
    PetscCall(MatMult(body->M, y, body->work));
    PetscCall(VecAXPY(x, scale * body->cM, body->work));
  }
  if (body->cK != 0) {
    PetscCall(MatMult(body->K, y, body->work));
    PetscCall(VecAXPY(x, scale * body->cK, body->work));
  }
  if (body->Cb) {
    PetscCall(MatMult(body->Cb, y, body->work));
    PetscCall(VecAXPY(x, scale, body->work));
  }
  PetscFunctionReturn(0);
}
