/* A body's own part of a time or load step: the static increment and its out-of-balance force,
   Newmark's predictor and corrector, the factor of each step size, the energies. The solver
   orders these over the bodies and the contact solve between them. */
#include <mbc/private/bodyimpl.h>

/* What this rank may hold (-mbc_memory_mb, MB; 0: no check): a factor beyond it goes out of core. */
PetscErrorCode MBCBodySetMemoryLimit(MBCBody body, PetscReal mb)
{
  PetscFunctionBegin;
  body->memory_mb = mb;
  PetscFunctionReturn(0);
}

/* The analysis stage under way: loads of later stages do not act yet. */
PetscErrorCode MBCBodySetStage(MBCBody body, PetscInt stage)
{
  PetscFunctionBegin;
  body->stage = stage;
  PetscFunctionReturn(0);
}

/* kinetic 1/2 v^T M v, strain 1/2 u^T K u, the external work and the damping dissipation so far.
   Collective on the body. */
PetscErrorCode MBCBodyEnergy(MBCBody body, PetscReal energy[4])
{
  PetscScalar vMv = 0, uKu;

  PetscFunctionBegin;
  PetscCall(MatMult(body->K, body->u, body->work));
  PetscCall(VecDot(body->u, body->work, &uKu));
  if (body->v) {
    PetscCall(MatMult(body->M, body->v, body->work));
    PetscCall(VecDot(body->v, body->work, &vMv));
  }
  energy[0] = 0.5 * PetscRealPart(vMv);
  energy[1] = 0.5 * PetscRealPart(uKu);
  energy[2] = body->wext;
  energy[3] = body->wdamp;
  PetscFunctionReturn(0);
}

/* A static stage's set-up of the body before anything is factored: the absorbing surfaces held,
   the free rigid modes (exact, FETI), unless a spring stabilize diag(K) to the last iterate is
   asked for (stabilize > 0): *stabilized where the spring holds the body, *floating where its free
   modes remain. */
PetscErrorCode MBCBodyStaticBegin(MBCBody body, PetscReal stabilize, PetscBool *stabilized, PetscBool *floating)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyAbsorbingHold(body)); /* a truncated foundation's support in a static state */
  PetscCall(MBCBodyRigidModes(body));
  body->stab = (stabilize > 0 && body->nrigid) ? stabilize : 0.0;
  if (body->stab > 0) PetscCall(MBCBodyRigidModesDestroy(body));
  *stabilized = (PetscBool)(body->stab > 0);
  *floating   = (PetscBool)(body->nrigid > 0);
  PetscFunctionReturn(0);
}

/* The static stiffness factored (a dynamic stage's factor dropped); no inertia from here on. */
PetscErrorCode MBCBodyStaticFactor(MBCBody body)
{
  PetscFunctionBegin;
  PetscCall(KSPDestroy(&body->ksp)); /* a dynamic stage's (a reference) */
  PetscCall(MatDestroy(&body->A));
  PetscCall(MBCBodyFactor(body, 1.0, 0.0, &body->ksp, &body->A, "static stiffness"));
  body->aK = 1.0;
  body->aM = 0.0;
  if (body->v) PetscCall(VecZeroEntries(body->v)); /* after a dynamic stage: a static one has no inertia */
  if (body->a) PetscCall(VecZeroEntries(body->a));
  PetscFunctionReturn(0);
}

/* A static iterate's free increment du = A^+ (F(t) - K u) with the prescribed increment, and
   what the rigid modes' equilibrium G lambda = e needs of a floating body: the load on each
   mode, e = -R^T (F - K u) and its rounding, the load's resultant and moment. */
PetscErrorCode MBCBodyStaticIncrement(MBCBody body, PetscReal t)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyExternalForce(body, t, PETSC_FALSE, body->rhs));
  for (PetscInt j = 0; j < body->nrigid; j++) { /* the load on each free mode */
    PetscScalar d;
    PetscCall(VecDot(body->rhs, body->rigid[j], &d));
    body->frigid[j] = PetscRealPart(d);
  }
  if (body->nrigid) { /* and its resultant and moment */
    PetscCall(MBCBodyLoadResultant(body, body->rhs, body->fres));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, body->fres, 6, MPIU_REAL, MPIU_SUM, body->comm));
  }
  PetscCall(MatMult(body->K, body->u, body->work));
  PetscCall(VecAXPY(body->rhs, -1.0, body->work));
  body->erigid_round = 0;
  for (PetscInt j = 0; j < body->nrigid; j++) { /* the equilibrium's right side -R^T (F - K u) */
    PetscScalar d;
    PetscReal   knorm, unorm, rnorm;
    PetscCall(VecDot(body->rhs, body->rigid[j], &d));
    body->erigid[j] = -PetscRealPart(d);
    PetscCall(MatNorm(body->K, NORM_INFINITY, &knorm));
    PetscCall(VecNorm(body->u, NORM_INFINITY, &unorm));
    PetscCall(VecNorm(body->rigid[j], NORM_1, &rnorm));
    body->erigid_round = PetscMax(body->erigid_round, PETSC_MACHINE_EPSILON * knorm * unorm * rnorm);
  }
  PetscCall(MBCBodyPrescribedIncrement(body, t, body->g));
  PetscCall(MBCBodyConstrainedSolve(body, body->ksp, 1.0, 0.0, body->g, body->rhs, body->du));
  PetscFunctionReturn(0);
}

/* u += du after the contact solve; on this rank: norm[0] the out-of-balance force max|A du|,
   norm[1] max|K u|, norm[2] the rounding of K u, eps |K|_inf |u|_inf (where the body moves
   rigidly, as in a load step that closes a gap, K u is that rounding and so is the force). */
PetscErrorCode MBCBodyStaticUpdate(MBCBody body, PetscReal t, PetscReal norm[3])
{
  PetscReal n, knorm;

  PetscFunctionBegin;
  PetscCall(MBCBodyCheckFinite(body, body->du, "displacement increment", t));
  if (body->nrigid) { /* K du off the prescribed rows: A du is not the force of a rigid motion */
    PetscCall(MatMult(body->K, body->du, body->work));
    PetscCall(MBCBodySetConstrainedRows(body, NULL, body->work));
  } else PetscCall(MatMult(body->A, body->du, body->work));
  PetscCall(VecNorm(body->work, NORM_INFINITY, &norm[0]));
  PetscCall(VecAXPY(body->u, 1.0, body->du));
  PetscCall(MatMult(body->K, body->u, body->work));
  PetscCall(VecNorm(body->work, NORM_INFINITY, &norm[1]));
  PetscCall(MatNorm(body->K, NORM_INFINITY, &knorm));
  PetscCall(VecNorm(body->u, NORM_INFINITY, &n));
  norm[2] = PETSC_MACHINE_EPSILON * knorm * n;
  PetscFunctionReturn(0);
}

/* u kept where a step that may be cut begins (MBCBodyStepRestore goes back to it). */
PetscErrorCode MBCBodyStepSave(MBCBody body)
{
  PetscFunctionBegin;
  if (!body->ustart) PetscCall(VecDuplicate(body->u, &body->ustart));
  PetscCall(VecCopy(body->u, body->ustart));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyStepRestore(MBCBody body)
{
  PetscFunctionBegin;
  PetscCall(VecCopy(body->ustart, body->u));
  PetscFunctionReturn(0);
}

/* The acceleration the forces at time t give the body in its state: M a = F(t) - K u - C v +
   fc on the free DOFs (fc: the contact force H lambda, or NULL); fold = F(t). */
PetscErrorCode MBCBodyAcceleration(MBCBody body, PetscReal t, Vec fc)
{
  PetscReal rnorm;
  KSP       ksp;
  Mat       A;

  PetscFunctionBegin;
  PetscCall(MBCBodyExternalForce(body, t, PETSC_FALSE, body->fold));
  PetscCall(VecCopy(body->fold, body->rhs));
  PetscCall(MatMult(body->K, body->u, body->work));
  PetscCall(VecAXPY(body->rhs, -1.0, body->work));
  if (MBCBodyDamped(body)) PetscCall(MBCBodyAddDamping(body, -1.0, body->v, body->rhs));
  if (fc) PetscCall(VecAXPY(body->rhs, 1.0, fc));
  PetscCall(MBCBodySetConstrainedRows(body, NULL, body->rhs));
  PetscCall(VecZeroEntries(body->a));
  if (body->desc.massless) PetscFunctionReturn(0); /* no inertia: its Newmark acceleration starts at 0 */
  PetscCall(VecNorm(body->rhs, NORM_INFINITY, &rnorm));
  if (rnorm > 0) {
    PetscCall(MBCBodyFactor(body, 0.0, 1.0, &ksp, &A, "mass"));
    PetscCall(MBCBodyConstrainedSolve(body, ksp, 0.0, 1.0, NULL, body->rhs, body->a));
    PetscCall(KSPDestroy(&ksp));
    PetscCall(MatDestroy(&A));
  }
  PetscFunctionReturn(0);
}

/* The external work counted from here as at a dynamic run's start: total = T + U - F.u stays
   0 for constant loads. */
PetscErrorCode MBCBodyWorkStart(MBCBody body)
{
  PetscFunctionBegin;
  PetscCall(VecDot(body->fold, body->u, &body->wext));
  PetscFunctionReturn(0);
}

/* Initial state of a dynamic analysis: the displacement and velocity given (the scene's
   `initial`, MBCBodySetInitialState), else the static equilibrium under the constant loads and the
   prescribed values at t = 0, at rest; the acceleration the forces at t = 0 give. */
PetscErrorCode MBCBodyDynamicInitialState(MBCBody body)
{
  PetscReal fnorm, gnorm;
  KSP       ksp;
  Mat       A;
  PetscBool hasu, hasv;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(body->u));
  PetscCall(VecZeroEntries(body->v));
  PetscCall(VecZeroEntries(body->a));
  PetscCall(MBCBodyAbsorbingHold(body));
  PetscCall(MBCBodyInitialState(body, &hasu, &hasv));
  PetscCall(MBCBodyExternalForce(body, 0.0, PETSC_TRUE, body->rhs));
  PetscCall(MBCBodyPrescribed(body, 0.0, body->g));
  PetscCall(VecNorm(body->rhs, NORM_INFINITY, &fnorm));
  PetscCall(VecNorm(body->g, NORM_INFINITY, &gnorm));
  if (!hasu && (fnorm > 0 || gnorm > 0)) {
    PetscCall(MBCBodyFactor(body, 1.0, 0.0, &ksp, &A, "initial static stiffness"));
    PetscCall(MBCBodyConstrainedSolve(body, ksp, 1.0, 0.0, body->g, body->rhs, body->u));
    PetscCall(KSPDestroy(&ksp));
    PetscCall(MatDestroy(&A));
  }
  PetscCall(MBCBodyAbsorbingRelease(body, 0.0)); /* the motion from here on through the dashpots */
  PetscCall(MBCBodyAcceleration(body, 0.0, NULL));
  PetscCall(MBCBodyWorkStart(body));
  if (hasu || hasv) { /* the energy the initial state holds counts as work done on the body before t = 0: total starts at 0 */
    PetscReal e[4];
    PetscCall(MBCBodyEnergy(body, e));
    body->wext = e[0] + e[1];
  }
  body->wdamp = 0;
  PetscFunctionReturn(0);
}

/* A dynamic stage begins at time t after another one: the static stage's free modes and spring
   go (the mass holds the body now), so do the factors of the stage before's step sizes; the
   velocities are 0 after a static stage; the absorbing surfaces are released. */
PetscErrorCode MBCBodyDynamicStageBegin(MBCBody body, PetscBool after_static, PetscReal t)
{
  PetscFunctionBegin;
  body->stab = 0;
  PetscCall(MBCBodyRigidModesDestroy(body));
  for (PetscInt l = 0; l < MBC_MAX_CUTS; l++) {
    PetscCall(KSPDestroy(&body->kspcut[l]));
    PetscCall(MatDestroy(&body->Acut[l]));
  }
  PetscCall(KSPDestroy(&body->ksp));
  PetscCall(MatDestroy(&body->A));
  if (after_static) PetscCall(VecZeroEntries(body->v));
  PetscCall(MBCBodyAbsorbingRelease(body, t));
  PetscFunctionReturn(0);
}

/* The operator of step level `level` (h = dt / 2^level, coefficients c) becomes the body's:
   factored once and kept for the stage, so a cut step and the steps after it refactor nothing. */
PetscErrorCode MBCBodyUseStepLevel(MBCBody body, PetscInt level, MBCTimeCoefficients c)
{
  PetscFunctionBegin;
  body->aK = 1 + c.a1 * body->cK;
  body->aM = c.aM + c.a1 * body->cM;
  body->aC = c.a1; /* the dashpots, if any */
  if (!body->kspcut[level]) PetscCall(MBCBodyFactor(body, body->aK, body->aM, &body->kspcut[level], &body->Acut[level], level ? "Newmark effective stiffness (cut step)" : "Newmark effective stiffness"));
  body->aC = 0;
  PetscCall(PetscObjectReference((PetscObject)body->kspcut[level]));
  PetscCall(PetscObjectReference((PetscObject)body->Acut[level]));
  PetscCall(KSPDestroy(&body->ksp));
  PetscCall(MatDestroy(&body->A));
  body->ksp = body->kspcut[level];
  body->A   = body->Acut[level];
  PetscFunctionReturn(0);
}

/* rhs: the right side of the step's increment (solvergenalpha.c) without the prescribed values'
   and the new multipliers' parts; f holds F_n+1, fold F_n. fc: H lambda_n (NULL: none). */
static PetscErrorCode BodyStepRHS(MBCBody body, MBCTimeCoefficients c, Vec fc)
{
  PetscFunctionBegin;
  PetscCall(VecCopy(body->f, body->rhs));
  if (c.cf != 0) PetscCall(VecAXPY(body->rhs, c.cf, body->fold));
  /* the vectors summed before the products: rhs += K (cK y - (1 + cf) u) + M (w + cM y) + Cb y with
     w = ((1 - am)(a2 v + a3 a) - am a) / (1 - af) and y = (a4 - cf) v + a5 a (Rayleigh's C =
     cM M + cK K + the dashpots' Cb): two products with the body's matrices a step, not four */
  PetscCall(VecAXPBY(body->work2, c.a2 * (1 - c.am) / (1 - c.af), 0.0, body->v));
  PetscCall(VecAXPY(body->work2, (c.a3 * (1 - c.am) - c.am) / (1 - c.af), body->a));
  PetscCall(VecSet(body->work, 0.0));
  if (MBCBodyDamped(body)) {
    PetscCall(VecAXPBY(body->work, c.a4 - c.cf, 0.0, body->v));
    PetscCall(VecAXPY(body->work, c.a5, body->a));
    if (body->Cb) PetscCall(MatMultAdd(body->Cb, body->work, body->rhs, body->rhs));
    if (body->cM != 0) PetscCall(VecAXPY(body->work2, body->cM, body->work));
    PetscCall(VecScale(body->work, body->cK));
  }
  PetscCall(VecAXPY(body->work, -(1 + c.cf), body->u));
  PetscCall(MatMultAdd(body->K, body->work, body->rhs, body->rhs));
  PetscCall(MatMultAdd(body->M, body->work2, body->rhs, body->rhs));
  if (fc && c.cf != 0) PetscCall(VecAXPY(body->rhs, c.cf, fc));
  PetscFunctionReturn(0);
}

/* The predictor of a dynamic step ending at t: the free increment du = K~^-1 (the step's right
   side) with the prescribed increment. fc: H lambda_n where the scheme averages the contact force
   (NULL: none); fr, with weight wr: the force of the points that left the contact set (NULL: none). */
PetscErrorCode MBCBodyDynamicIncrement(MBCBody body, PetscReal t, MBCTimeCoefficients c, Vec fc, PetscReal wr, Vec fr)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyExternalForce(body, t, PETSC_FALSE, body->f));
  PetscCall(BodyStepRHS(body, c, fc));
  if (fr) PetscCall(VecAXPY(body->rhs, wr, fr));
  PetscCall(MBCBodyPrescribedIncrement(body, t, body->g));
  PetscCall(MBCBodyConstrainedSolve(body, body->ksp, body->aK, body->aM, body->g, body->rhs, body->du));
  PetscFunctionReturn(0);
}

/* The corrector after the contact solve: u, v, a of the step's end from du, and the work of the
   loads (trapezoidal) and of the damping over the step. */
PetscErrorCode MBCBodyDynamicUpdate(MBCBody body, PetscReal t, MBCTimeCoefficients c)
{
  const PetscReal h = c.h, a0 = c.a0, a2 = c.a2, a3 = c.a3, a6 = c.a6, a7 = c.a7;
  PetscScalar     work, dv;

  PetscFunctionBegin;
  PetscCall(MBCBodyCheckFinite(body, body->du, "displacement increment", t));

  /* trapezoidal work of the external loads */
  PetscCall(VecAXPY(body->fold, 1.0, body->f));
  PetscCall(VecDot(body->fold, body->du, &work));
  body->wext += 0.5 * PetscRealPart(work);
  PetscCall(VecCopy(body->f, body->fold));

  /* a_new = a0 du - a2 v - a3 a (in work2); v_new = v + a6 a + a7 a_new */
  PetscCall(VecAXPBY(body->work2, a0, 0.0, body->du));
  PetscCall(VecAXPY(body->work2, -a2, body->v));
  PetscCall(VecAXPY(body->work2, -a3, body->a));
  PetscCall(VecAXPBYPCZ(body->v, a6, a7, 1.0, body->a, body->work2)); /* v = v + a6 a + a7 a_new */
  PetscCall(VecCopy(body->work2, body->a));
  PetscCall(VecAXPY(body->u, 1.0, body->du));
  /* damping dissipation with the mid-step velocity (v_n + v_n+1)/2 = du/dt for gamma = 1/2 */
  if (MBCBodyDamped(body)) {
    PetscCall(VecAXPBY(body->work2, 1.0 / h, 0.0, body->du));
    PetscCall(VecZeroEntries(body->rhs));
    PetscCall(MBCBodyAddDamping(body, 1.0, body->work2, body->rhs));
    PetscCall(VecDot(body->work2, body->rhs, &dv));
    body->wdamp += h * PetscRealPart(dv);
  }
  PetscFunctionReturn(0);
}
