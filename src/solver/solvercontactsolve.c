/* The multipliers of a step (the set-up and the distribution: solvercontact.c): q from every
   body's free increment, the PGS on the rows of each rank, dU += A^-1 H lambda. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/multiplierimpl.h>

/* -mbc_fclib_write FILE at step -mbc_fclib_write_step: the scaled problem (W = D / dscale,
   r = dscale lambda) and its solution as an FCLIB local problem in rank order, gathered to and
   written by rank 0. */
static PetscErrorCode SolverContactWriteFclib(MBCSolver s)
{
  MBCContact         c = s->contact;
  PetscMPIInt        rank;
  PetscInt           m = s->coff[s->ncontact];
  IS                 is;
  Mat               *W0;
  Vec                v[3], v0[3];
  VecScatter         sc;
  MBCFrictionProblem fp0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(ISCreateStride(PETSC_COMM_SELF, rank ? 0 : m, 0, 1, &is));
  PetscCall(MatCreateSubMatrices(s->fp.W, 1, &is, &is, MAT_INITIAL_MATRIX, &W0));
  PetscCall(ISDestroy(&is));
  v[0] = s->fp.q, v[1] = s->lambda, v[2] = s->ucontact;
  for (PetscInt i = 0; i < 3; i++) {
    PetscCall(VecScatterCreateToZero(v[i], &sc, &v0[i]));
    PetscCall(VecScatterBegin(sc, v[i], v0[i], INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, v[i], v0[i], INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterDestroy(&sc));
  }
  if (!rank) {
    PetscInt *dims;
    PetscCall(PetscMemzero(&fp0, sizeof(fp0)));
    fp0.nc = s->ncontact;
    fp0.W  = W0[0];
    fp0.q  = v0[0];
    PetscCall(PetscMalloc2(fp0.nc + 1, &fp0.mu, fp0.nc + 1, &dims));
    for (PetscInt p = 0; p < fp0.nc; p++) {
      fp0.mu[p] = c->couples[s->kcouple[s->order[p]]].mu;
      dims[p]   = s->poff[p + 1] - s->poff[p];
    }
    PetscCall(MBCFrictionProblemSetBlocks(&fp0, dims));
    PetscCall(PetscSNPrintf(fp0.title, sizeof(fp0.title), "%s, step %" PetscInt_FMT, s->scene->filename, s->step));
    PetscCall(MBCFclibWriteLocal(s->fclib_file, &fp0, v0[1], v0[2]));
    PetscCall(PetscFree(fp0.off));
    PetscCall(PetscFree2(fp0.mu, dims));
  }
  for (PetscInt i = 0; i < 3; i++) PetscCall(VecDestroy(&v0[i]));
  PetscCall(MatDestroySubMatrices(1, &W0));
  PetscCallMPI(MPI_Barrier(s->comm));
  PetscFunctionReturn(0);
}

/* A static contact solve with free bodies that failed: is the load on some free body beyond
   what friction can hold? Per body its load's resultant F (this step's), the mean normal n of
   the contact points that touch it and the largest mu of its couples: a tangential load
   |F - (F.n) n| above mu |F.n| has no static equilibrium, an input error named here. */
static PetscErrorCode SolverContactFrictionCapacity(MBCSolver s)
{
  MBCContact c = s->contact;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscReal F[4] = {0, 0, 0, 0}, n[3] = {0, 0, 0}, mu = 0, fn = 0, ft[3], T = 0, N;
    PetscInt  cnt = 0;
    if (s->bodies[b]) { /* F and whether the body is free, from its first rank */
      PetscMPIInt brank;
      PetscCallMPI(MPI_Comm_rank(s->bodies[b]->comm, &brank));
      if (!brank && s->bodies[b]->nrigid) {
        for (PetscInt d = 0; d < 3; d++) F[d] = s->bodies[b]->fres[d];
        F[3] = 1;
      }
    }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, F, 4, MPIU_REAL, MPIU_SUM, s->comm));
    if (!F[3]) continue;
    for (PetscInt k = 0; k < s->ncontact; k++) { /* the points touching b (replicated bookkeeping) */
      const MBCCouple *cp = &c->couples[s->kcouple[k]];
      const PetscInt   j  = s->kpoint[k];
      if (!MBCSolverPointTouches(cp, j, b)) continue;
      for (PetscInt d = 0; d < 3; d++) n[d] += s->frames[9 * k + d];
      mu = PetscMax(mu, cp->mu);
      cnt++;
    }
    N = PetscSqrtReal(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!cnt || !(N > 0)) continue;
    for (PetscInt d = 0; d < 3; d++) n[d] /= N, fn += F[d] * n[d];
    for (PetscInt d = 0; d < 3; d++) ft[d] = F[d] - fn * n[d], T += ft[d] * ft[d];
    T = PetscSqrtReal(T);
    PetscCheck(!(T > mu * PetscAbsReal(fn)), s->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: body '%s' carries a tangential load of %g along (%.3f, %.3f, %.3f) against a friction capacity mu N = %g x %g = %g on its contact surfaces (T / mu N = %.4f); a static state needs T <= mu N: lower the load, prescribe a displacement that holds the body, or run a dynamic analysis", s->step, (double)s->time, s->scene->bodies[b].name, (double)T, (double)(ft[0] / T), (double)(ft[1] / T), (double)(ft[2] / T), (double)mu, (double)PetscAbsReal(fn), (double)(mu * PetscAbsReal(fn)), (double)(T / (mu * PetscAbsReal(fn))));
  }
  PetscFunctionReturn(0);
}

/* Coulomb's law in a static load step holds for the slip over the whole step: the equilibrium
   iterations after the first only correct it, so their tangential rates start from the slip the
   step's earlier iterations made (else a point that slid in the first iteration and not in the
   next would be taken to stick, its traction inside the cone while the block slides). */
static PetscErrorCode SolverContactAddStepSlip(MBCSolver s, Vec q)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(q, &rstart, NULL));
  PetscCall(VecGetArray(q, &a));
  for (PetscInt p = s->pfirst; p < s->plast; p++) {
    const PetscInt k = s->order[p];
    if (s->coff[k + 1] - s->coff[k] == 3)
      for (PetscInt d = 1; d < 3; d++) a[s->poff[p] + d - rstart] += s->stepslip[3 * k + d];
  }
  PetscCall(VecRestoreArray(q, &a));
  PetscFunctionReturn(0);
}

/* A static load step begins: its slip counts from here. */
PetscErrorCode MBCSolverContactStepBegin(MBCSolver s)
{
  PetscFunctionBegin;
  if (s->stepslip) PetscCall(PetscArrayzero(s->stepslip, 3 * s->ncontact));
  PetscFunctionReturn(0);
}

/* A static load step is abandoned (to be cut): the slip it made is undone. */
PetscErrorCode MBCSolverContactStepAbandon(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; s->stepslip && i < 3 * s->ncontact; i++) s->slip[i] -= s->stepslip[i];
  PetscCall(MBCSolverContactStepBegin(s));
  PetscFunctionReturn(0);
}

/* Given every body's free increment in body->du, solves for the multipliers and adds
   A^-1 H lambda. */
PetscErrorCode MBCSolverContactSolve(MBCSolver s)
{
  const PetscInt nc = s->ncontact;

  PetscFunctionBegin;
  if (!nc) PetscFunctionReturn(0);
  if (s->contact_may_fail) { /* the warm start, for a retry with a smaller step */
    if (!s->lamsave) PetscCall(VecDuplicate(s->lambda, &s->lamsave)); /* freed with the layout it has */
    PetscCall(VecCopy(s->lambda, s->lamsave));
  }
  PetscCall(MBCSolverContactGapRate(s, s->fp.q));
  if (s->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverContactAddStepSlip(s, s->fp.q));
  if (s->carry != 0) { /* q' = q - c D lambda_n (scaled: W = D / dscale) */
    Vec t;
    PetscCall(VecDuplicate(s->lamprev, &t));
    PetscCall(VecAXPBY(t, s->dscale, 0.0, s->lamprev));
    PetscCall(MatMult(s->fp.W, t, s->ucontact));
    PetscCall(VecAXPY(s->fp.q, -s->carry, s->ucontact));
    PetscCall(VecDestroy(&t));
  }
  { /* solve with q scaled to unit norm: the FCLIB merit |r - proj(..)| / (1 + |q|) then is
       relative, and -mbc_pgs_rtol means the same in m or mm (absolute in the scene's length
       unit, 1e-8 would be 10 nm in m and 10 pm in mm) */
    PetscReal L;
    PetscCall(VecNorm(s->fp.q, NORM_2, &L));
    if (!(L > 0)) L = 1;
    PetscCall(MBCSolverContactRigidRHS(s));
    if (s->fp.G) PetscCall(VecZeroEntries(s->fp.alpha)); /* the rigid motion of this increment */
    PetscCall(VecScale(s->fp.q, 1 / L));
    PetscCall(VecScale(s->lambda, 1 / L));
    if (s->fp.G) {
      PetscCall(VecScale(s->fp.e, 1 / L));
      PetscCall(VecScale(s->fp.alpha, 1 / L));
    }
    PetscCall(MBCMultiplierSetProblem(s->mult, &s->fp));
    PetscCall(MBCMultiplierSolve(s->mult, s->lambda, s->ucontact)); /* warm start: r of the last step */
    PetscCall(VecScale(s->fp.q, L));
    PetscCall(VecScale(s->lambda, L));
    PetscCall(VecScale(s->ucontact, L));
    if (s->fp.G) {
      PetscCall(VecScale(s->fp.e, L));
      PetscCall(VecScale(s->fp.alpha, L));
    }
  }
  if (s->fclib_step == s->step && s->fclib_file[0]) PetscCall(SolverContactWriteFclib(s));
  if (s->mult->reason < 0 && s->fp.G) PetscCall(SolverContactFrictionCapacity(s));
  if (s->mult->reason < 0 && s->contact_may_fail) { /* the caller cuts the step: nothing changed */
    PetscCall(VecCopy(s->lamsave, s->lambda));
    s->contact_failed = PETSC_TRUE;
    PetscFunctionReturn(0);
  }
  PetscCheck(s->mult->reason > 0, s->comm, PETSC_ERR_NOT_CONVERGED, "Contact multipliers at step %" PetscInt_FMT " (t = %g): %s solve %s after %" PetscInt_FMT " iterations, FCLIB merit %g > -mbc_multiplier_rtol %g", s->step, (double)s->time, ((PetscObject)s->mult)->type_name, MBCMultiplierConvergedReasonName(s->mult->reason), s->mult->its, (double)s->mult->merit, (double)s->mult->rtol);
  PetscCall(VecAXPBY(s->lamprev, 1.0 / s->dscale, -s->carry, s->lambda)); /* lambda_n+1 = r - c lambda_n (physical) */
  PetscCall(MBCSolverContactGather(s, s->lambda, s->rall));
  PetscCall(MBCSolverContactGather(s, s->ucontact, s->uall));
  /* u = D lambda_n+1 + H^T du_free (+ gap) is H^T du: its tangential part is the step's slip
     (H's master weight is 1, so in length units); in a static step it counts from the step's
     start (SolverContactAddStepSlip), and this iteration moved the points by u_t - stepslip */
  for (PetscInt k = 0; k < nc; k++)
    if (s->coff[k + 1] - s->coff[k] == 3)
      for (PetscInt d = 1; d < 3; d++) {
        s->slip[3 * k + d] += s->uall[s->coff[k] + d] - s->stepslip[3 * k + d];
        if (s->analysis == MBC_ANALYSIS_STATIC) s->stepslip[3 * k + d] = s->uall[s->coff[k] + d];
      }
  PetscCall(MBCSolverContactToBodies(s, s->lamprev));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    if (!body || !s->H[b]) continue;
    PetscCall(MatMult(s->H[b], s->lam[b], s->Hl[b]));
    PetscCall(MBCBodyZeroHeldRows(body, s->Hl[b], NULL));
    PetscCall(KSPSolve(body->ksp, s->Hl[b], s->Xl[b]));
    PetscCall(VecAXPY(body->du, 1.0, s->Xl[b]));
  }
  if (s->fp.G) PetscCall(MBCSolverContactRigidMotion(s));
  PetscFunctionReturn(0);
}

/* Per contact point (in couple order): its state and the step's mean contact force z = theta r
   (in the frame n, t1, t2; tangents 0 where frictionless); counts of each state. state and
   lambda may be NULL. The same on every rank. */
PetscErrorCode MBCSolverContactStates(MBCSolver s, PetscInt count[3], PetscInt state[], PetscReal lambda[])
{
  MBCContact c = s->contact;

  PetscFunctionBegin;
  count[0] = count[1] = count[2] = 0;
  if (!s->ncontact) PetscFunctionReturn(0);
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const PetscInt o = s->coff[k], dim = s->coff[k + 1] - o;
      PetscReal      lam[3] = {0, 0, 0}, rt;
      PetscInt       st;
      for (PetscInt d = 0; d < dim; d++) lam[d] = s->theta * s->rall[o + d] / s->dscale;
      rt = PetscSqrtReal(lam[1] * lam[1] + lam[2] * lam[2]);
      if (!(lam[0] > 0)) st = MBC_CONTACT_SEPARATED;
      else if (dim == 3 && rt < c->couples[i].mu * lam[0] * (1 - 1e-6)) st = MBC_CONTACT_STICK;
      else st = MBC_CONTACT_SLIP;
      count[st]++;
      if (state) state[k] = st;
      if (lambda)
        for (PetscInt d = 0; d < 3; d++) lambda[3 * k + d] = lam[d];
    }
  PetscFunctionReturn(0);
}
