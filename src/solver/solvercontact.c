/* Contact forces in the Newmark step (the paper's eqs. (2)-(9)): per body K~ dU = dF + H lambda,
   H mapping each contact point's frame (n, t1, t2) to the master node (+) and the slave face
   nodes (- weights). With dU_free = A^-1 dF and X = A^-1 H (one multi-right-hand-side solve per
   body with its factor), the multipliers solve u = D lambda + q in the Coulomb cone with
   D = sum_i H_i^T X_i, q = (gap, 0, 0) + sum_i H_i^T dU_free_i; then dU = dU_free + X lambda.
   A frictionless couple's points carry the normal multiplier only (fp.off gives each point's
   first column).

   Complementarity is imposed on the step's mean contact force z = theta lambda_n+1 +
   (1 - theta) lambda_n, theta = gamma (dynamic: the weights of Newmark's velocity update, so
   z dt is the contact impulse of the step) or 1 (static), not on lambda_n+1. With r = z / theta
   the problem keeps D: q' = q - c D lambda_n, c = (1 - theta) / theta, lambda_n+1 = r - c lambda_n.
   For the trapezoidal rule the contact work of a step is then z . (g_n+1 - g_n) = -z . g_n <= 0:
   a contact that opens gives back no energy. Imposed on lambda_n+1 itself it would be
   (lambda_n . g_n+1 - lambda_n+1 . g_n) / 2, an energy gain whenever a loaded contact opens (a
   bouncing block gains energy at every bounce). */
#include <mbc/private/solverimpl.h>
#include <mbc/private/pgsimpl.h>

/* Contact points of all couples in one list: (couple, point). */
static PetscInt NumContacts(MBCContact c)
{
  PetscInt n = 0;
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].npoints;
  return n;
}

/* H of one body: 3 columns per contact point (1 if frictionless), the point's frame times its
   master (+) and slave (-) node weights (MBCCoupleIntegrate); rows of constrained DOFs are
   zero (a prescribed DOF takes no contact force; the PGS treats a contact with no free DOF as
   inactive). */
static PetscErrorCode BodyContactMatrix(MBCSolver s, MBCBody body, Mat *H)
{
  MBCContact  c = s->contact;
  PetscMPIInt brank;
  PetscInt    ndof, nloc, k = 0;

  PetscFunctionBegin;
  PetscCall(VecGetSize(body->u, &ndof));
  PetscCall(VecGetLocalSize(body->u, &nloc));
  PetscCall(MatCreateAIJ(body->comm, nloc, PETSC_DECIDE, ndof, s->fp.off[s->fp.nc], 24, NULL, 24, NULL, H));
  PetscCall(MatSetOption(*H, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple  *cp = &c->couples[i];
    MBCSurface *m = &cp->master, *sl = &cp->slave;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscReal       *e[3] = {p->n, p->t1, p->t2};
      if (brank) continue; /* rank 0 of the body inserts; assembly sends rows to their owners */
      for (PetscInt a = 0; a < s->fp.off[k + 1] - s->fp.off[k]; a++) {
        const PetscInt col = s->fp.off[k] + a;
        for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++) {
          const PetscInt node = cp->mnode[l];
          if (m->nbody[node] != body->index) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, m->nrow[node] + d, col, cp->mw[l] * e[a][d], ADD_VALUES));
        }
        for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) {
          const PetscInt node = cp->snode[l];
          if (sl->nbody[node] != body->index) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, sl->nrow[node] + d, col, -cp->sw[l] * e[a][d], ADD_VALUES));
        }
      }
    }
  }
  PetscCall(MatAssemblyBegin(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatZeroRows(*H, body->nbc, body->bc_rows, 0.0, NULL, NULL));
  PetscFunctionReturn(0);
}

/* Per-body work of the contact step, rebuilt with H: H^T du, its copy on every rank of the
   body, the scatter between them, and lambda in X's column layout. */
static PetscErrorCode SolverContactReset(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscCall(MatDestroy(&s->H[b]));
    PetscCall(MatDestroy(&s->X[b]));
    PetscCall(VecDestroy(&s->Hu[b]));
    PetscCall(VecDestroy(&s->Hus[b]));
    PetscCall(VecDestroy(&s->lam[b]));
    PetscCall(VecScatterDestroy(&s->hsc[b]));
  }
  PetscCall(MBCFrictionProblemDestroy(&s->fp));
  PetscCall(VecDestroy(&s->lambda));
  PetscCall(VecDestroy(&s->ucontact));
  PetscCall(VecDestroy(&s->lamprev));
  PetscFunctionReturn(0);
}

/* Carries nf per-point 3-vector fields (components in each point's frame n, t1, t2; 1 component
   if frictionless) from the points of the last build to the new ones, matched by (couple, master
   node), through global coordinates. Points without a match get 0. */
static PetscErrorCode CarryFields(PetscInt nf, PetscInt nold, const PetscInt oldpairs[], const PetscReal oldframes[], const PetscInt oldoff[], const PetscReal *oldv[], PetscInt nnew, const PetscInt newpairs[], const PetscReal newframes[], const PetscInt newoff[], PetscReal *newv[])
{
  PetscInt *key, *perm;

  PetscFunctionBegin;
  for (PetscInt f = 0; f < nf; f++)
    for (PetscInt k = 0; k < newoff[nnew]; k++) newv[f][k] = 0;
  if (!nold) PetscFunctionReturn(0);
  PetscCall(PetscMalloc2(nold, &key, nold, &perm));
  for (PetscInt lo = 0, hi; lo < nold; lo = hi) { /* points are grouped by couple */
    for (hi = lo; hi < nold && oldpairs[MBC_PAIR_SIZE * hi] == oldpairs[MBC_PAIR_SIZE * lo]; hi++) {
      key[hi]  = oldpairs[MBC_PAIR_SIZE * hi + 1];
      perm[hi] = hi;
    }
    PetscCall(PetscSortIntWithArray(hi - lo, key + lo, perm + lo));
    for (PetscInt k = 0; k < nnew; k++) {
      PetscInt j, dim = newoff[k + 1] - newoff[k];
      if (newpairs[MBC_PAIR_SIZE * k] != oldpairs[MBC_PAIR_SIZE * lo]) continue;
      PetscCall(PetscFindInt(newpairs[MBC_PAIR_SIZE * k + 1], hi - lo, key + lo, &j));
      if (j < 0) continue;
      j = perm[lo + j];
      for (PetscInt fi = 0; fi < nf; fi++) {
        PetscReal f[3] = {0, 0, 0};
        for (PetscInt d = 0; d < oldoff[j + 1] - oldoff[j]; d++)
          for (PetscInt e = 0; e < 3; e++) f[e] += oldv[fi][oldoff[j] + d] * oldframes[9 * j + 3 * d + e];
        for (PetscInt d = 0; d < dim; d++) newv[fi][newoff[k] + d] = f[0] * newframes[9 * k + 3 * d] + f[1] * newframes[9 * k + 3 * d + 1] + f[2] * newframes[9 * k + 3 * d + 2];
      }
    }
  }
  PetscCall(PetscFree2(key, perm));
  PetscFunctionReturn(0);
}

/* lambda (replicated, s->lamprev) into the owned part of body b's column layout of H and X. */
static PetscErrorCode SolverLambdaToBody(MBCSolver s, PetscInt b)
{
  const PetscScalar *l;
  PetscScalar       *la;
  PetscInt           lo, hi;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(s->lam[b], &lo, &hi));
  PetscCall(VecGetArrayRead(s->lamprev, &l));
  PetscCall(VecGetArray(s->lam[b], &la));
  for (PetscInt i = lo; i < hi; i++) la[i - lo] = l[i];
  PetscCall(VecRestoreArray(s->lam[b], &la));
  PetscCall(VecRestoreArrayRead(s->lamprev, &l));
  PetscFunctionReturn(0);
}

/* The acceleration a_n holds M^-1 H_old lambda_n; the next step assumes M^-1 H_new lambda_n' with
   the carried lambda_n' (points that left the contact carry nothing). a += M^-1 (H_new lambda_n' -
   H_old lambda_n) keeps M a_n = F_n - K u_n + H lambda_n true (u and v, hence the energy, do not
   change), so the step stays the trapezoidal rule on the mean contact force. */
static PetscErrorCode SolverContactAccelerationUpdate(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody   body = s->bodies[b];
    PetscReal norm;
    if (!body) continue;
    PetscCall(VecScale(body->fcontact, -1.0));
    if (s->H[b]) {
      PetscCall(SolverLambdaToBody(s, b));
      PetscCall(MatMultAdd(s->H[b], s->lam[b], body->fcontact, body->fcontact));
    }
    PetscCall(VecNorm(body->fcontact, NORM_INFINITY, &norm));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &norm, 1, MPIU_REAL, MPIU_MAX, body->comm));
    if (norm == 0) continue;
    if (!body->kspM) PetscCall(MBCBodyFactor(body, 0.0, 1.0, &body->kspM, &body->Mc, "mass"));
    PetscCall(VecCopy(body->fcontact, body->rhs));
    PetscCall(MBCBodyConstrainedSolve(body, body->kspM, 0.0, 1.0, NULL, body->rhs, body->work));
    PetscCall(VecAXPY(body->a, 1.0, body->work));
  }
  PetscFunctionReturn(0);
}

/* H_i, X_i = A_i^-1 H_i and the per-body work vectors for every body, and W = D / dscale with
   D = sum_i H_i^T X_i (m x m), replicated on every rank. */
static PetscErrorCode SolverContactBuildD(MBCSolver s, PetscInt m)
{
  PetscScalar *Dl, *Dg;

  PetscFunctionBegin;
  PetscCall(PetscCalloc2(m * m, &Dl, m * m, &Dg));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody     body = s->bodies[b];
    Mat         Hd, D;
    PetscMPIInt brank;
    if (!body) continue;
    PetscCall(BodyContactMatrix(s, body, &s->H[b]));
    PetscCall(MatConvert(s->H[b], MATDENSE, MAT_INITIAL_MATRIX, &Hd));
    PetscCall(MatDuplicate(Hd, MAT_DO_NOT_COPY_VALUES, &s->X[b]));
    PetscCall(KSPMatSolve(body->ksp, Hd, s->X[b]));
    PetscCall(MatDestroy(&Hd));
    /* D_i = H^T X with H sparse (a dozen entries per column): the dense product would cost
       2 N m^2 flops, this one 2 nnz(H) m */
    PetscCall(MatTransposeMatMult(s->H[b], s->X[b], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &D));
    { /* D_i (m x m) to every rank of the body, then summed over bodies */
      Mat               *Dseq;
      IS                 all;
      const PetscScalar *a;
      PetscInt           lda;
      PetscCall(ISCreateStride(PETSC_COMM_SELF, m, 0, 1, &all));
      PetscCall(MatCreateSubMatrices(D, 1, &all, &all, MAT_INITIAL_MATRIX, &Dseq));
      PetscCall(ISDestroy(&all));
      PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
      PetscCall(MatDenseGetLDA(Dseq[0], &lda));
      PetscCall(MatDenseGetArrayRead(Dseq[0], &a));
      if (!brank)
        for (PetscInt i = 0; i < m; i++)
          for (PetscInt j = 0; j < m; j++) Dl[i * m + j] += a[i + j * lda]; /* row-major */
      PetscCall(MatDenseRestoreArrayRead(Dseq[0], &a));
      PetscCall(MatDestroySubMatrices(1, &Dseq));
    }
    PetscCall(MatDestroy(&D));
    PetscCall(MatCreateVecs(s->X[b], &s->lam[b], NULL));
    PetscCall(MatCreateVecs(s->H[b], &s->Hu[b], NULL));
    PetscCall(VecScatterCreateToAll(s->Hu[b], &s->hsc[b], &s->Hus[b]));
  }
  PetscCallMPI(MPI_Allreduce(Dl, Dg, (PetscMPIInt)(m * m), MPIU_SCALAR, MPIU_SUM, s->comm)); /* sum over bodies */
  { /* W = D / dbar as SeqAIJ, dbar the mean diagonal: r = dbar lambda has the units of u, so the
       FCLIB merit weighs forces and displacements alike; the same on every rank (the PGS runs
       redundantly, deterministically) */
    PetscInt *nnz;
    s->dscale = 0;
    for (PetscInt i = 0; i < m; i++) s->dscale += PetscRealPart(Dg[i * m + i]) / m;
    PetscCheck(s->dscale > 0, s->comm, PETSC_ERR_ARG_WRONG, "The contact flexibility matrix has no positive diagonal: every contact DOF is prescribed");
    for (PetscInt i = 0; i < m * m; i++) Dg[i] /= s->dscale;
    PetscCall(PetscCalloc1(m, &nnz));
    for (PetscInt i = 0; i < m; i++)
      for (PetscInt j = 0; j < m; j++) nnz[i] += Dg[i * m + j] != 0.0;
    PetscCall(MatCreateSeqAIJ(PETSC_COMM_SELF, m, m, 0, nnz, &s->fp.W));
    for (PetscInt i = 0; i < m; i++)
      for (PetscInt j = 0; j < m; j++)
        if (Dg[i * m + j] != 0.0) PetscCall(MatSetValue(s->fp.W, i, j, Dg[i * m + j], INSERT_VALUES));
    PetscCall(MatAssemblyBegin(s->fp.W, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(s->fp.W, MAT_FINAL_ASSEMBLY));
    PetscCall(PetscFree(nnz));
  }
  PetscCall(PetscFree2(Dl, Dg));
  PetscFunctionReturn(0);
}

/* Builds H, X = A^-1 H and D for the contact points of pairs (couple, master, face per point),
   and carries the last step's contact forces and the PGS warm start over to them. */
PetscErrorCode MBCSolverContactSetUp(MBCSolver s, PetscInt n, PetscInt pairs[])
{
  MBCContact   c  = s->contact;
  PetscInt     nc = NumContacts(c), m, *dims, nold = s->npairs_built, *oldpairs = s->pairs_built, *oldoff = NULL;
  PetscReal   *oldframes = s->frames, *oldlam = NULL, *oldr = NULL, *oldslip = s->slip;

  PetscFunctionBegin;
  PetscCheck(n == nc, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Contact pairs and points disagree");
  PetscCall(PetscLogEventBegin(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  if (nold && s->lamprev) { /* keep what the new points inherit */
    const PetscScalar *a, *l;
    PetscInt           mold = s->fp.off[nold];
    PetscCall(PetscMalloc3(nold + 1, &oldoff, mold, &oldlam, mold, &oldr));
    PetscCall(PetscArraycpy(oldoff, s->fp.off, nold + 1));
    PetscCall(VecGetArrayRead(s->lamprev, &a));
    PetscCall(VecGetArrayRead(s->lambda, &l));
    for (PetscInt i = 0; i < mold; i++) {
      oldlam[i] = PetscRealPart(a[i]);
      oldr[i]   = PetscRealPart(l[i]) / s->dscale;
    }
    PetscCall(VecRestoreArrayRead(s->lambda, &l));
    PetscCall(VecRestoreArrayRead(s->lamprev, &a));
  }
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) /* the contact force H lambda_n inside the acceleration */
    for (PetscInt b = 0; b < s->nbodies; b++) {
      MBCBody body = s->bodies[b];
      if (!body) continue;
      if (!body->fcontact) PetscCall(VecDuplicate(body->u, &body->fcontact));
      if (s->H[b]) PetscCall(MatMult(s->H[b], s->lam[b], body->fcontact));
      else PetscCall(VecZeroEntries(body->fcontact));
    }
  s->frames = NULL;
  s->slip   = NULL;
  PetscCall(SolverContactReset(s));
  s->pairs_built  = pairs;
  s->npairs_built = n;
  s->fp.nc = nc;
  PetscCall(PetscMalloc1(nc, &s->fp.mu));
  PetscCall(PetscMalloc1(nc, &dims));
  PetscCall(PetscMalloc1(9 * nc + 1, &s->frames));
  PetscCall(PetscCalloc1(3 * nc + 1, &s->slip));
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const MBCContactPoint *p = &c->couples[i].points[j];
      s->fp.mu[k] = c->couples[i].mu;
      dims[k]     = c->couples[i].mu > 0 ? 3 : 1;
      for (PetscInt e = 0; e < 3; e++) {
        s->frames[9 * k + e]     = p->n[e];
        s->frames[9 * k + 3 + e] = p->t1[e];
        s->frames[9 * k + 6 + e] = p->t2[e];
      }
    }
  PetscCall(MBCFrictionProblemSetBlocks(&s->fp, dims));
  PetscCall(PetscFree(dims));
  m = s->fp.off[nc];
  if (nc) {
    PetscReal *v[2];
    PetscCall(SolverContactBuildD(s, m));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, m, &s->fp.q));
    PetscCall(VecDuplicate(s->fp.q, &s->lambda));
    PetscCall(VecDuplicate(s->fp.q, &s->ucontact));
    PetscCall(VecDuplicate(s->fp.q, &s->lamprev));
    /* carry lambda_n and the warm start r (physical, then scaled) over to the new points */
    PetscCall(VecGetArray(s->lamprev, &v[0]));
    PetscCall(VecGetArray(s->lambda, &v[1]));
    {
      const PetscReal *old[2] = {oldlam, oldr};
      PetscCall(CarryFields(2, oldoff ? nold : 0, oldpairs, oldframes, oldoff, old, nc, pairs, s->frames, s->fp.off, v));
    }
    for (PetscInt i = 0; i < m; i++) v[1][i] *= s->dscale;
    PetscCall(VecRestoreArray(s->lambda, &v[1]));
    PetscCall(VecRestoreArray(s->lamprev, &v[0]));
    if (oldslip && nold) { /* the slip so far, (0, t1, t2) in each point's frame */
      PetscInt        *off3;
      const PetscReal *old[1] = {oldslip};
      PetscCall(PetscMalloc1(PetscMax(nold, nc) + 1, &off3));
      for (PetscInt i = 0; i <= PetscMax(nold, nc); i++) off3[i] = 3 * i;
      PetscCall(CarryFields(1, nold, oldpairs, oldframes, off3, old, nc, pairs, s->frames, off3, &s->slip));
      for (PetscInt k = 0; k < nc; k++) s->slip[3 * k] = 0;
      PetscCall(PetscFree(off3));
    }
  }
  PetscCall(PetscFree3(oldoff, oldlam, oldr));
  PetscCall(PetscFree(oldslip));
  PetscCall(PetscFree(oldframes));
  PetscCall(PetscFree(oldpairs));
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) PetscCall(SolverContactAccelerationUpdate(s)); /* also when no point is left */
  PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverContactDestroy(MBCSolver s)
{
  PetscFunctionBegin;
  if (!s->H) PetscFunctionReturn(0);
  PetscCall(SolverContactReset(s));
  PetscCall(PetscFree6(s->H, s->X, s->Hu, s->Hus, s->lam, s->hsc));
  PetscCall(PetscFree(s->frames));
  PetscCall(PetscFree(s->slip));
  PetscCall(PetscFree(s->pairs_built));
  PetscFunctionReturn(0);
}

/* -mbc_fclib_write FILE at step -mbc_fclib_write_step: the scaled problem (W = D / dscale,
   r = dscale lambda) and its solution as an FCLIB local problem, written by rank 0. */
static PetscErrorCode SolverContactWriteFclib(MBCSolver s)
{
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscSNPrintf(s->fp.title, sizeof(s->fp.title), "%s, step %" PetscInt_FMT, s->scene->filename, s->step));
  if (!rank) PetscCall(MBCFclibWriteLocal(s->fclib_file, &s->fp, s->lambda, s->ucontact));
  PetscCallMPI(MPI_Barrier(s->comm));
  PetscFunctionReturn(0);
}

/* Given every body's free increment in body->du, solves for the multipliers and adds X lambda. */
PetscErrorCode MBCSolverContactSolve(MBCSolver s)
{
  MBCContact   c  = s->contact;
  PetscInt     nc = s->fp.nc, m;
  PetscScalar *ql, *qg, *q;

  PetscFunctionBegin;
  if (!nc) PetscFunctionReturn(0);
  m = s->fp.off[nc];
  PetscCall(PetscCalloc2(m, &ql, m, &qg));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody            body = s->bodies[b];
    PetscMPIInt        brank;
    const PetscScalar *a;
    if (!body) continue;
    PetscCall(MatMultTranspose(s->H[b], body->du, s->Hu[b]));
    PetscCall(VecScatterBegin(s->hsc[b], s->Hu[b], s->Hus[b], INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(s->hsc[b], s->Hu[b], s->Hus[b], INSERT_VALUES, SCATTER_FORWARD));
    PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
    PetscCall(VecGetArrayRead(s->Hus[b], &a));
    if (!brank)
      for (PetscInt i = 0; i < m; i++) ql[i] += a[i];
    PetscCall(VecRestoreArrayRead(s->Hus[b], &a));
  }
  PetscCallMPI(MPI_Allreduce(ql, qg, (PetscMPIInt)m, MPIU_SCALAR, MPIU_SUM, s->comm)); /* sum over bodies */
  PetscCall(VecGetArray(s->fp.q, &q));
  for (PetscInt i = 0; i < m; i++) q[i] = qg[i];
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) q[s->fp.off[k]] += c->couples[i].igap[j];
  PetscCall(VecRestoreArray(s->fp.q, &q));
  PetscCall(PetscFree2(ql, qg));
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
    PetscCall(VecScale(s->fp.q, 1 / L));
    PetscCall(VecScale(s->lambda, 1 / L));
    PetscCall(MBCPGSSolve(&s->pgs, &s->fp, s->lambda, s->ucontact)); /* warm start: r of the last step */
    PetscCall(VecScale(s->fp.q, L));
    PetscCall(VecScale(s->lambda, L));
    PetscCall(VecScale(s->ucontact, L));
  }
  if (s->fclib_step == s->step && s->fclib_file[0]) PetscCall(SolverContactWriteFclib(s));
  PetscCheck(s->pgs.reason > 0, s->comm, PETSC_ERR_NOT_CONVERGED, "Contact multipliers at step %" PetscInt_FMT " (t = %g): projected Gauss-Seidel %s after %" PetscInt_FMT " sweeps, FCLIB error %g > -mbc_pgs_rtol %g", s->step, (double)s->time, MBCPGSReasonName(s->pgs.reason), s->pgs.its, (double)s->pgs.error, (double)s->pgs.rtol);
  PetscCall(VecAXPBY(s->lamprev, 1.0 / s->dscale, -s->carry, s->lambda)); /* lambda_n+1 = r - c lambda_n (physical) */
  { /* u = D lambda_n+1 + H^T du_free (+ gap) is H^T du: its tangential part is the step's slip
       (H's master weight is 1, so in length units) */
    const PetscScalar *u;
    PetscCall(VecGetArrayRead(s->ucontact, &u));
    for (PetscInt k = 0; k < nc; k++)
      if (s->fp.off[k + 1] - s->fp.off[k] == 3)
        for (PetscInt d = 1; d < 3; d++) s->slip[3 * k + d] += PetscRealPart(u[s->fp.off[k] + d]);
    PetscCall(VecRestoreArrayRead(s->ucontact, &u));
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    if (!body) continue;
    PetscCall(SolverLambdaToBody(s, b));
    PetscCall(MatMultAdd(s->X[b], s->lam[b], body->du, body->du));
  }
  PetscFunctionReturn(0);
}

/* Per contact point (in couple order): its state and the step's mean contact force z = theta r
   (in the frame n, t1, t2; tangents 0 where frictionless); counts of each state. state and
   lambda may be NULL. */
PetscErrorCode MBCSolverContactStates(MBCSolver s, PetscInt count[3], PetscInt state[], PetscReal lambda[])
{
  const PetscScalar *l;

  PetscFunctionBegin;
  count[0] = count[1] = count[2] = 0;
  if (!s->fp.nc) PetscFunctionReturn(0);
  PetscCall(VecGetArrayRead(s->lambda, &l));
  for (PetscInt i = 0; i < s->fp.nc; i++) {
    const PetscInt o = s->fp.off[i], dim = s->fp.off[i + 1] - o;
    PetscReal      lam[3] = {0, 0, 0}, rt;
    PetscInt       st;
    for (PetscInt d = 0; d < dim; d++) lam[d] = s->theta * PetscRealPart(l[o + d]) / s->dscale;
    rt = PetscSqrtReal(lam[1] * lam[1] + lam[2] * lam[2]);
    if (!(lam[0] > 0)) st = MBC_CONTACT_SEPARATED;
    else if (dim == 3 && rt < s->fp.mu[i] * lam[0] * (1 - 1e-6)) st = MBC_CONTACT_STICK;
    else st = MBC_CONTACT_SLIP;
    count[st]++;
    if (state) state[i] = st;
    if (lambda)
      for (PetscInt d = 0; d < 3; d++) lambda[3 * i + d] = lam[d];
  }
  PetscCall(VecRestoreArrayRead(s->lambda, &l));
  PetscFunctionReturn(0);
}
