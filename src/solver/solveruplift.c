/* Uplift (docs/scene.md, couples' `uplift`): the solver's part. Before every step it finds, per
   couple with penetration, the wet length from the heel, from the contact points of the last
   step (s->cpts, the same on every rank): the joint is open from the heel up to its first point
   along the uplift's direction whose contact pressure exceeds the threshold, the water filling it
   (Abaqus' pressure penetration from the reservoir side, along one direction: the wet front is
   one line across the whole couple). Where a wet length changed, the bodies assemble their
   uplift loads again (bodyuplift.c); their factored operators are untouched. */
#include <mbc/private/solverimpl.h>

/* The wet length of couple i from the last step's points: 0 before the first step. */
static PetscReal UpliftWetLength(MBCSolver s, PetscInt i)
{
  const MBCUpliftDesc *u = &s->scene->couples[i].uplift;
  const PetscInt       k = s->scene->couples[i].k;
  PetscReal            w = u->length;
  PetscBool            any = PETSC_FALSE;

  if (!u->penetration || !s->cpts.x0) return 0;
  for (PetscInt p = 0; p < s->cpts.n; p++) {
    const PetscReal *x = &s->cpts.x0[3 * p];
    PetscReal        sp;
    if (s->cpts.couple[p] != k) continue;
    any = PETSC_TRUE;
    sp  = (x[0] - u->origin[0]) * u->direction[0] + (x[1] - u->origin[1]) * u->direction[1] + (x[2] - u->origin[2]) * u->direction[2];
    if (sp < 0 || sp > u->length) continue;
    if (s->cpts.pressure[p] > u->threshold) w = PetscMin(w, sp); /* closed: the water stops here */
  }
  return any ? w : 0;
}

PetscErrorCode MBCSolverUpliftUpdate(MBCSolver s)
{
  MBCScene  scene = s->scene;
  PetscBool changed;

  PetscFunctionBegin;
  if (!s->uplift.set) {
    for (PetscInt i = 0; i < scene->ncouples; i++) s->uplift.on = (PetscBool)(s->uplift.on || scene->couples[i].uplift.on);
    if (!s->uplift.on) PetscFunctionReturn(0);
    PetscCall(PetscCalloc2(scene->ncouples, &s->uplift.wet, 4 * scene->ncouples, &s->uplift.r));
  }
  if (!s->uplift.on) PetscFunctionReturn(0);
  changed = (PetscBool)!s->uplift.set;
  for (PetscInt i = 0; i < scene->ncouples; i++) { /* the same on every rank: s->cpts is replicated */
    const PetscReal w = scene->couples[i].uplift.on ? UpliftWetLength(s, i) : 0;
    if (w == s->uplift.wet[i]) continue;
    changed = PETSC_TRUE;
    if (s->monitor) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " uplift: couple %" PetscInt_FMT " wet length %g -> %g of %g\n", s->step, scene->couples[i].k, (double)s->uplift.wet[i], (double)w, (double)scene->couples[i].uplift.length));
    s->uplift.wet[i] = w;
  }
  s->uplift.set = PETSC_TRUE;
  if (!changed) PetscFunctionReturn(0);
  PetscCall(PetscArrayzero(s->uplift.r, 4 * scene->ncouples));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyUpliftUpdate(s->bodies[b], s->uplift.wet, s->uplift.r)); /* each rank its owned faces */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s->uplift.r, (PetscMPIInt)(4 * scene->ncouples), MPIU_REAL, MPIU_SUM, s->comm));
  PetscFunctionReturn(0);
}

/* Couple i at the current time: r[0] = int p dA on its master side, r[1..3] the point of action
   (NaN without uplift), r[4] the wet length. */
PetscErrorCode MBCSolverUpliftResultant(MBCSolver s, PetscInt i, PetscReal r[5])
{
  PetscReal factor = 0;

  PetscFunctionBegin;
  r[0] = 0, r[1] = r[2] = r[3] = NAN, r[4] = 0;
  if (!s->uplift.on || !s->uplift.set || !s->scene->couples[i].uplift.on) PetscFunctionReturn(0);
  for (PetscInt l = 0; l < s->scene->nloads; l++) { /* the time factor of its loads (one for both sides) */
    const MBCLoadDesc *load = &s->scene->loads[l];
    if (load->kind == MBC_LOAD_UPLIFT && load->couple == i) {
      PetscCall(MBCTimeFactor(s->scene, load->time, load->time_function, s->time, &factor));
      break;
    }
  }
  r[0] = factor * s->uplift.r[4 * i];
  if (s->uplift.r[4 * i] > 0)
    for (PetscInt c = 0; c < 3; c++) r[1 + c] = s->uplift.r[4 * i + 1 + c] / s->uplift.r[4 * i];
  r[4] = s->uplift.wet[i];
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverUpliftDestroy(MBCSolver s)
{
  PetscFunctionBegin;
  PetscCall(PetscFree2(s->uplift.wet, s->uplift.r));
  s->uplift.on = s->uplift.set = PETSC_FALSE;
  PetscFunctionReturn(0);
}
