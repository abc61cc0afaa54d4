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
static PetscErrorCode NodalBlockMatrix(MBCBody body, Mat *A)
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
  PetscCall(NodalBlockMatrix(body, &body->Cb));
  if (any[1]) PetscCall(NodalBlockMatrix(body, &body->Cin));
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
