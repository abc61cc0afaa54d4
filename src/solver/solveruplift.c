/* Uplift (docs/scene.md, couples' `uplift`): the solver's part. Before every step it finds, per
   couple with penetration and per zone of it (a master body's range across the direction: a
   monolith's base), the wet length from the heel, from the contact points of the last step
   (s->cpts, the same on every rank): the joint is open from the heel up to its first point along
   the uplift's direction whose contact pressure exceeds the threshold or whose bond holds (a
   bonded couple's, docs/dam.md), the water filling it
   (Abaqus' pressure penetration from the reservoir side, along one direction: one front per
   zone). Where a wet length changed, the bodies assemble their uplift loads again (bodyuplift.c);
   their factored operators are untouched. */
#include <mbc/private/solverimpl.h>

/* The wet lengths w[] of couple i's zones from the last step's points (each point in the zone of
   its master node's body): 0 before the first step; false where the points are not those written
   (w[] untouched: the caller keeps the wet lengths it has). */
static PetscBool UpliftWetLengths(MBCSolver s, PetscInt i, PetscReal w[])
{
  const MBCUpliftDesc *u = &s->scene->couples[i].uplift;
  MBCContact           c = s->contact;
  PetscInt             total = 0;

  for (PetscInt ci = 0; c && ci < c->ncouples; ci++) total += c->couples[ci].npoints;
  if (u->penetration && c && s->cpts.x0 && total != s->cpts.n) return PETSC_FALSE; /* the points changed since they were written */
  for (PetscInt z = 0; z < u->nzones; z++) w[z] = 0;
  if (!u->penetration || !c || !s->cpts.x0) return PETSC_TRUE;
  for (PetscInt z = 0; z < u->nzones; z++) w[z] = -1; /* a zone without points stays dry */
  for (PetscInt ci = 0, k = 0; ci < c->ncouples; ci++) {
    const MBCCouple *cp = &c->couples[ci];
    if (cp->k != s->scene->couples[i].k) {
      k += cp->npoints;
      continue;
    }
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const PetscReal *x = &s->cpts.x0[3 * k];
      const PetscInt   z = u->zone_of_body[cp->master.nbody[cp->points[j].master]];
      const PetscReal  sp = MBCUpliftAlong(u, u->direction, x);
      if (z < 0) continue;
      if (w[z] < 0) w[z] = u->length;
      if (sp < 0 || sp > u->length || !(s->cpts.pressure[k] > u->threshold || (s->cpts.bonded && s->cpts.bonded[k]))) continue;
      w[z] = PetscMin(w[z], sp); /* closed, or bonded (a joint law's bond holds, in tension too: interfacejoint.c): the water stops here */
    }
  }
  for (PetscInt z = 0; z < u->nzones; z++) w[z] = PetscMax(w[z], 0);
  return PETSC_TRUE;
}

/* the zones' arrays, once */
static PetscErrorCode UpliftInit(MBCSolver s)
{
  MBCScene scene = s->scene;
  PetscInt n     = 0;

  PetscFunctionBegin;
  if (s->uplift.off) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < scene->ncouples; i++) s->uplift.on = (PetscBool)(s->uplift.on || scene->couples[i].uplift.on);
  if (!s->uplift.on) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(scene->ncouples + 1, &s->uplift.off));
  for (PetscInt i = 0; i < scene->ncouples; i++) {
    s->uplift.off[i] = n;
    n += scene->couples[i].uplift.on ? scene->couples[i].uplift.nzones : 0;
  }
  s->uplift.off[scene->ncouples] = n;
  PetscCall(PetscCalloc3(n + 1, &s->uplift.wet, n + 1, &s->uplift.w, 4 * scene->ncouples, &s->uplift.r));
  PetscFunctionReturn(0);
}

/* The wet lengths the next step takes (from the last step's points), for a checkpoint: *n of them
   (0 without uplift) in *w, valid until the next update */
PetscErrorCode MBCSolverUpliftNext(MBCSolver s, PetscInt *n, const PetscReal **w)
{
  PetscFunctionBegin;
  *n = 0, *w = NULL;
  if (!s->uplift.on || !s->uplift.set) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < s->scene->ncouples; i++) {
    const PetscInt off = s->uplift.off[i], nz = s->uplift.off[i + 1] - off;
    if (nz && !UpliftWetLengths(s, i, &s->uplift.w[off])) PetscCall(PetscArraycpy(&s->uplift.w[off], &s->uplift.wet[off], nz));
  }
  *n = s->uplift.off[s->scene->ncouples], *w = s->uplift.w;
  PetscFunctionReturn(0);
}

/* A restart: the wet lengths its checkpoint's step left (MBCSolverUpliftNext), which the first
   step takes, as the uninterrupted run's did (the points they came from are not written) */
PetscErrorCode MBCSolverUpliftRestore(MBCSolver s, PetscInt n, const PetscReal w[])
{
  PetscFunctionBegin;
  PetscCall(UpliftInit(s));
  PetscCheck(s->uplift.on && n == s->uplift.off[s->scene->ncouples], s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s: %" PetscInt_FMT " uplift zones, the scene has %" PetscInt_FMT, s->restart, n, s->uplift.on ? s->uplift.off[s->scene->ncouples] : 0);
  PetscCall(PetscArraycpy(s->uplift.wet, w, n));
  s->uplift.restored = PETSC_TRUE;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverUpliftUpdate(MBCSolver s)
{
  MBCScene  scene = s->scene;
  PetscBool changed;

  PetscFunctionBegin;
  PetscCall(UpliftInit(s));
  if (!s->uplift.on) PetscFunctionReturn(0);
  changed = (PetscBool)(!s->uplift.set || s->uplift.restored);
  for (PetscInt i = 0; i < scene->ncouples && !s->uplift.restored; i++) { /* the same on every rank: s->cpts is replicated */
    const PetscInt off = s->uplift.off[i], nz = s->uplift.off[i + 1] - off;
    PetscReal      before = 0, after = 0;
    if (!nz) continue;
    if (!UpliftWetLengths(s, i, &s->uplift.w[off])) PetscCall(PetscArraycpy(&s->uplift.w[off], &s->uplift.wet[off], nz));
    for (PetscInt z = 0; z < nz; z++) {
      if (s->uplift.w[off + z] != s->uplift.wet[off + z]) changed = PETSC_TRUE;
      before = PetscMax(before, s->uplift.wet[off + z]), after = PetscMax(after, s->uplift.w[off + z]);
    }
    if (s->monitor && before != after) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " uplift: couple %" PetscInt_FMT " wet length %g -> %g of %g (the largest of its %" PetscInt_FMT " zones)\n", s->step, scene->couples[i].k, (double)before, (double)after, (double)scene->couples[i].uplift.length, nz));
    PetscCall(PetscArraycpy(&s->uplift.wet[off], &s->uplift.w[off], nz));
  }
  s->uplift.set      = PETSC_TRUE;
  s->uplift.restored = PETSC_FALSE;
  if (!changed) PetscFunctionReturn(0);
  PetscCall(PetscArrayzero(s->uplift.r, 4 * scene->ncouples));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyUpliftUpdate(s->bodies[b], s->uplift.wet, s->uplift.off, s->uplift.r)); /* each rank its owned faces */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, s->uplift.r, (PetscMPIInt)(4 * scene->ncouples), MPIU_REAL, MPIU_SUM, s->comm));
  PetscFunctionReturn(0);
}

/* Couple i at the current time: r[0] = int p dA on its master side, r[1..3] the point of action
   (NaN without uplift), r[4] the largest wet length of its zones. */
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
  for (PetscInt z = s->uplift.off[i]; z < s->uplift.off[i + 1]; z++) r[4] = PetscMax(r[4], s->uplift.wet[z]);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverUpliftDestroy(MBCSolver s)
{
  PetscFunctionBegin;
  PetscCall(PetscFree3(s->uplift.wet, s->uplift.w, s->uplift.r));
  PetscCall(PetscFree(s->uplift.off));
  s->uplift.on = s->uplift.set = s->uplift.restored = PETSC_FALSE;
  PetscFunctionReturn(0);
}
