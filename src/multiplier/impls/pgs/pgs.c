/* MBCMULTIPLIERPGS: the paper's projected Gauss-Seidel. Each contact's 3x3 problem, with the
   other contacts' current r on the right side, is solved exactly (separation, stick, or slip
   found by a 1D root search over the slip direction, MBCContactLocalSolve), so normal-tangent
   coupling of the diagonal block is honoured: no solve-then-clamp. Optional active-set
   (semismooth Newton) steps every -mbc_pgs_active_set sweeps. Options: -mbc_pgs_omega,
   -mbc_pgs_active_set, -mbc_pgs_local_sweeps, -mbc_pgs_merit_every. */
#include <mbc/private/multiplierimpl.h>

typedef struct {
  PetscReal omega;
  PetscInt  active_set;
  PetscInt  sweeps_local; /* Gauss-Seidel sweeps over a rank's contacts between exchanges */
  PetscInt  merit_every;  /* the merit (a product with W) every this many sweeps, or when a sweep changed r by less than the tolerance */
  /* per W: its diagonal and off-diagonal parts (MPIAIJ), the other ranks' r it needs */
  Mat        Ad, Ao;
  Vec        rg, cg, eg; /* ghost values of r, of the active-set column map and coefficients */
  VecScatter gsc;
  PetscReal *diag;
  /* the last factor of the active-set step with no contact slipping, kept for the next steps */
  KSP       ksp;
  PetscInt *luS, lun;
  PetscBool kept;
  PetscReal shift; /* the diagonal shift of the kept factor */
} MBC_PGS;

static PetscErrorCode MBCMultiplierSetFromOptions_PGS(MBCMultiplier m, PetscOptionItems *PetscOptionsObject)
{
  MBC_PGS *pgs = (MBC_PGS *)m->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "Projected Gauss-Seidel (-mbc_multiplier_type pgs)");
  PetscCall(PetscOptionsReal("-pgs_omega", "Relaxation factor (0, 2)", "MBCMultiplierSetFromOptions", pgs->omega, &pgs->omega, NULL));
  PetscCall(PetscOptionsInt("-pgs_active_set", "Every this many sweeps, try the direct solve on the contacts in contact (0: never)", "MBCMultiplierSetFromOptions", pgs->active_set, &pgs->active_set, NULL));
  PetscCall(PetscOptionsInt("-pgs_local_sweeps", "Gauss-Seidel sweeps over a rank's own contacts between two exchanges of the others' (parallel)", "MBCMultiplierSetFromOptions", pgs->sweeps_local, &pgs->sweeps_local, NULL));
  PetscCall(PetscOptionsInt("-pgs_merit_every", "Compute the merit (one product with W) every this many sweeps, and whenever a sweep changed r by less than the tolerance", "MBCMultiplierSetFromOptions", pgs->merit_every, &pgs->merit_every, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(pgs->omega > 0 && pgs->omega < 2, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_omega %g must lie in (0, 2)", (double)pgs->omega);
  PetscCheck(pgs->active_set >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_active_set %" PetscInt_FMT " must be >= 0", pgs->active_set);
  PetscCheck(pgs->sweeps_local >= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_local_sweeps %" PetscInt_FMT " must be at least 1", pgs->sweeps_local);
  PetscCheck(pgs->merit_every >= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_merit_every %" PetscInt_FMT " must be at least 1", pgs->merit_every);
  PetscFunctionReturn(0);
}

/* The parts of W a rank sweeps with: its diagonal block Ad (its rows and columns), the
   off-diagonal block Ao (its rows, the other ranks' columns, compacted) and the scatter of
   those columns of r; the diagonal 3x3 (1x1) blocks of its contacts. Kept while W is. */
static PetscErrorCode MBCMultiplierSetUp_PGS(MBCMultiplier m)
{
  MBC_PGS            *pgs = (MBC_PGS *)m->data;
  MBCFrictionProblem *fp  = m->fp;
  PetscBool           mpi;

  PetscFunctionBegin;
  PetscCheck(!fp->G, PetscObjectComm((PetscObject)m), PETSC_ERR_SUP, "The projected Gauss-Seidel cannot impose the equilibrium of bodies free in a static analysis; use -mbc_multiplier_type newton");
  PetscCheck(!fp->Winv, PetscObjectComm((PetscObject)m), PETSC_ERR_SUP, "The projected Gauss-Seidel needs the rows of D, which -mbc_d_route matfree does not store; use -mbc_multiplier_type newton, or another -mbc_d_route");
  PetscCall(PetscObjectBaseTypeCompare((PetscObject)fp->W, MATMPIAIJ, &mpi));
  if (mpi) {
    const PetscInt *garray;
    PetscInt        ng;
    IS              is;
    Vec             r;
    PetscCall(MatMPIAIJGetSeqAIJ(fp->W, &pgs->Ad, &pgs->Ao, &garray));
    PetscCall(MatGetSize(pgs->Ao, NULL, &ng));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ng, garray, PETSC_COPY_VALUES, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, ng, &pgs->rg));
    PetscCall(VecDuplicate(pgs->rg, &pgs->cg));
    PetscCall(VecDuplicate(pgs->rg, &pgs->eg));
    PetscCall(MatCreateVecs(fp->W, &r, NULL));
    PetscCall(VecScatterCreate(r, is, pgs->rg, NULL, &pgs->gsc));
    PetscCall(VecDestroy(&r));
    PetscCall(ISDestroy(&is));
  } else pgs->Ad = fp->W, pgs->Ao = NULL;
  PetscCall(MBCMultiplierDiagonalBlocks(fp, pgs->Ad, &pgs->diag));
  PetscFunctionReturn(0);
}


/* Row grow of the active-set system: the sum over row `row` (local) of W of coef_j W_row,j into
   the columns col_j >= 0 (the column map and coefficients of this rank's slots in c, e, of the
   others' in cg, eg); cols, vals: work space of W's row length. */
static PetscErrorCode ActiveSetRow(MBC_PGS *pgs, PetscInt row, PetscInt grow, const PetscScalar c[], const PetscScalar e[], const PetscScalar cg[], const PetscScalar eg[], PetscInt acols[], PetscScalar avals[], Mat A)
{
  Mat      parts[2] = {pgs->Ad, pgs->Ao};
  PetscInt n = 0, nu = 0;

  PetscFunctionBegin;
  for (PetscInt k = 0; k < 2; k++) {
    const PetscScalar *cc = k ? cg : c, *ee = k ? eg : e;
    PetscInt           ncols;
    const PetscInt    *cols;
    const PetscScalar *vals;
    if (!parts[k]) continue;
    PetscCall(MatGetRow(parts[k], row, &ncols, &cols, &vals));
    for (PetscInt j = 0; j < ncols; j++) {
      const PetscInt col = (PetscInt)PetscRealPart(cc[cols[j]]);
      if (col >= 0 && vals[j] != 0.0) acols[n] = col, avals[n++] = ee[cols[j]] * vals[j];
    }
    PetscCall(MatRestoreRow(parts[k], row, &ncols, &cols, &vals));
  }
  PetscCall(PetscSortIntWithScalarArray(n, acols, avals));
  for (PetscInt j = 0; j < n; j++) { /* a slipping contact's three slots share its column */
    if (nu && acols[nu - 1] == acols[j]) avals[nu - 1] += avals[j];
    else acols[nu] = acols[j], avals[nu++] = avals[j];
  }
  PetscCall(MatSetValues(A, 1, &grow, nu, acols, avals, INSERT_VALUES));
  PetscFunctionReturn(0);
}

/* Active-set step: with the contacts split by the current iterate (and q) into separated (r = 0),
   sticking (u = 0: all components unknown) and slipping (u_n = 0, r_t = mu r_n d with the
   friction direction d frozen: r_n unknown), the problem is linear. A sparse direct solve
   (KSP prefix -mbc_pgs_, MUMPS LU by default; rows and unknowns of a contact on its rank) solves
   it; the result, projected onto the cones, is kept only if it lowers the merit, so a wrong
   guess costs a factorization, never accuracy. Gauss-Seidel alone creeps on strongly coupled D
   (large time steps; bodies held only by contact in a static analysis): thousands of sweeps.
   Each W slot j of a contact in contact maps to a column col_j with a coefficient e_j: (k, 1)
   for the k-th unknown of a sticking contact, (k, 1), (k, mu d1), (k, mu d2) for the slots of a
   slipping one, (-1, 0) otherwise; the other ranks' maps arrive with the scatter of r. */
static PetscErrorCode ActiveSetStep(MBCMultiplier m, MBC_PGS *pgs, MBCFrictionProblem *fp, Vec r, Vec u, PetscBool closed, PetscReal *error)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)fp->W);
  PetscInt          *S, *first, *contact, ns = 0, nin = 0, n = 0, nstart = 0, N, tot[2];
  PetscReal         *dir, dmax = 0, shift;
  PetscScalar       *rv, *cv, *ev;
  const PetscScalar *qv, *uv, *cgv = NULL, *egv = NULL;
  PetscBool          slips = PETSC_FALSE, reuse = PETSC_FALSE;
  Vec                colv, coefv, x, b;
  KSP                ksp;
  KSPConvergedReason reason;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(fp->off[fp->nc] + 1, &S, fp->nc + 1, &first, fp->nc + 1, &contact, 2 * fp->nc + 1, &dir));
  PetscCall(VecGetArray(r, &rv));
  PetscCall(VecGetArrayRead(u, &uv));
  PetscCall(VecGetArrayRead(fp->q, &qv));
  for (PetscInt i = 0; i < fp->nc; i++) { /* in contact (r_n - u_n > 0: pressed, or penetrating; with closed, also q_n < 0, and all sticking): S lists their rows; dir != 0 marks slip */
    const PetscInt  o = fp->off[i], dim = fp->off[i + 1] - o;
    const PetscReal rn = PetscRealPart(rv[o]);
    PetscReal       rt = 0;
    if (!(rn - PetscRealPart(uv[o]) > 0) && !(closed && PetscRealPart(qv[o]) < 0)) continue;
    if (dim == 3) rt = PetscSqrtReal(PetscSqr(PetscRealPart(rv[o + 1])) + PetscSqr(PetscRealPart(rv[o + 2])));
    contact[nin] = i;
    first[nin]   = ns;
    if (!closed && dim == 3 && fp->mu[i] > 0 && rn > 0 && rt >= fp->mu[i] * rn * (1 - 1e-6)) {
      dir[2 * nin]     = PetscRealPart(rv[o + 1]) / rt;
      dir[2 * nin + 1] = PetscRealPart(rv[o + 2]) / rt;
      n += 1;
      slips = PETSC_TRUE;
    } else {
      dir[2 * nin] = dir[2 * nin + 1] = 0;
      n += dim;
    }
    for (PetscInt d = 0; d < dim; d++) S[ns++] = o + d;
    nin++;
  }
  PetscCall(VecRestoreArrayRead(fp->q, &qv));
  PetscCall(VecRestoreArrayRead(u, &uv));
  PetscCall(VecRestoreArray(r, &rv));
  tot[0] = n, tot[1] = slips;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, tot, 2, MPIU_INT, MPI_SUM, comm));
  N = tot[0], slips = (PetscBool)(tot[1] > 0);
  if (!N) {
    PetscCall(PetscFree4(S, first, contact, dir));
    PetscFunctionReturn(0);
  }
  PetscCallMPI(MPI_Exscan(&n, &nstart, 1, MPIU_INT, MPI_SUM, comm));
  {
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_rank(comm, &rank));
    if (!rank) nstart = 0;
  }
  /* no contact slips: the system is W_SS itself. Its factor is kept and reused while S and W
     stay the same (a sticking steady state then costs one triangular solve per step). */
  if (!slips && pgs->kept) {
    PetscBool same = (PetscBool)(pgs->lun == ns);
    if (same) PetscCall(PetscArraycmp(S, pgs->luS, ns, &same));
    PetscCallMPI(MPI_Allreduce(&same, &reuse, 1, MPIU_BOOL, MPI_LAND, comm));
  }
  PetscCall(VecCreateMPI(comm, n, N, &b));
  PetscCall(VecDuplicate(b, &x));
  PetscCall(VecGetArrayRead(fp->q, &qv));
  PetscCall(VecGetArray(b, &cv));
  for (PetscInt j = 0, e = 0; j < nin; j++) { /* right side -q of the equations: u = 0 (stick), u_n = 0 (slip) */
    const PetscInt neq = (dir[2 * j] != 0 || dir[2 * j + 1] != 0) ? 1 : fp->off[contact[j] + 1] - fp->off[contact[j]];
    for (PetscInt d = 0; d < neq; d++) cv[e++] = -qv[S[first[j] + d]];
  }
  PetscCall(VecRestoreArray(b, &cv));
  PetscCall(VecRestoreArrayRead(fp->q, &qv));
  if (!reuse) {
    Mat       A;
    PC        pc;
    PetscInt    *nnz, *onz, *acols, rowmax = 0;
    PetscScalar *avals;
    PetscCall(VecDuplicate(r, &colv));
    PetscCall(VecDuplicate(r, &coefv));
    PetscCall(VecSet(colv, -1.0));
    PetscCall(VecZeroEntries(coefv));
    PetscCall(VecGetArray(colv, &cv));
    PetscCall(VecGetArray(coefv, &ev));
    for (PetscInt k = 0, c = nstart; k < nin; k++) {
      const PetscInt i = contact[k], o = fp->off[i], dim = fp->off[i + 1] - o;
      if (dir[2 * k] != 0 || dir[2 * k + 1] != 0) {
        cv[o] = cv[o + 1] = cv[o + 2] = (PetscScalar)c++;
        ev[o] = 1, ev[o + 1] = fp->mu[i] * dir[2 * k], ev[o + 2] = fp->mu[i] * dir[2 * k + 1];
      } else
        for (PetscInt d = 0; d < dim; d++) cv[o + d] = (PetscScalar)c++, ev[o + d] = 1;
    }
    PetscCall(VecRestoreArray(coefv, &ev));
    PetscCall(VecRestoreArray(colv, &cv));
    if (pgs->gsc) {
      PetscCall(VecScatterBegin(pgs->gsc, colv, pgs->cg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(pgs->gsc, colv, pgs->cg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterBegin(pgs->gsc, coefv, pgs->eg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(pgs->gsc, coefv, pgs->eg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecGetArrayRead(pgs->cg, &cgv));
      PetscCall(VecGetArrayRead(pgs->eg, &egv));
    }
    PetscCall(PetscMalloc2(n + 1, &nnz, n + 1, &onz));
    for (PetscInt j = 0, e = 0; j < nin; j++) { /* preallocation: at most the row lengths of W (also bounded by n and N - n) */
      const PetscInt neq = (dir[2 * j] != 0 || dir[2 * j + 1] != 0) ? 1 : fp->off[contact[j] + 1] - fp->off[contact[j]];
      for (PetscInt d = 0; d < neq; d++, e++) {
        PetscInt nd, no = 0, t; /* MatRestoreRow() zeroes the count */
        PetscCall(MatGetRow(pgs->Ad, S[first[j] + d], &nd, NULL, NULL));
        t = nd;
        PetscCall(MatRestoreRow(pgs->Ad, S[first[j] + d], &t, NULL, NULL));
        if (pgs->Ao) {
          PetscCall(MatGetRow(pgs->Ao, S[first[j] + d], &no, NULL, NULL));
          t = no;
          PetscCall(MatRestoreRow(pgs->Ao, S[first[j] + d], &t, NULL, NULL));
        }
        nnz[e] = PetscMin(nd, n) + 1, onz[e] = PetscMin(no, N - n);
        rowmax = PetscMax(rowmax, nd + no);
      }
    }
    PetscCall(PetscMalloc2(rowmax + 1, &acols, rowmax + 1, &avals));
    PetscCall(MatCreateAIJ(comm, n, n, N, N, 0, nnz, 0, onz, &A));
    PetscCall(MatSetOption(A, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
    PetscCall(PetscFree2(nnz, onz));
    PetscCall(VecGetArrayRead(colv, (const PetscScalar **)&cv));
    PetscCall(VecGetArrayRead(coefv, (const PetscScalar **)&ev));
    for (PetscInt j = 0, e = nstart; j < nin; j++) {
      const PetscInt neq = (dir[2 * j] != 0 || dir[2 * j + 1] != 0) ? 1 : fp->off[contact[j] + 1] - fp->off[contact[j]];
      for (PetscInt d = 0; d < neq; d++, e++) {
        PetscScalar w;
        PetscCall(ActiveSetRow(pgs, S[first[j] + d], e, cv, ev, cgv, egv, acols, avals, A));
        PetscCall(MatGetValues(pgs->Ad, 1, &S[first[j] + d], 1, &S[first[j] + d], &w));
        dmax = PetscMax(dmax, PetscAbsScalar(w));
      }
    }
    PetscCall(PetscFree2(acols, avals));
    PetscCall(VecRestoreArrayRead(coefv, (const PetscScalar **)&ev));
    PetscCall(VecRestoreArrayRead(colv, (const PetscScalar **)&cv));
    if (cgv) {
      PetscCall(VecRestoreArrayRead(pgs->cg, &cgv));
      PetscCall(VecRestoreArrayRead(pgs->eg, &egv));
    }
    /* W_SS may be singular: tangential forces along directions prescribed on both sides (a
       roller under a roller) have no flexibility. A shift of 1e-10 of the largest diagonal picks
       the solution with those forces near zero and leaves the others to 1e-10. */
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPIU_REAL, MPIU_MAX, comm));
    PetscCall(MatAssemblyBegin(A, MAT_FLUSH_ASSEMBLY)); /* rows inserted, the shift added */
    PetscCall(MatAssemblyEnd(A, MAT_FLUSH_ASSEMBLY));
    for (PetscInt e = nstart; e < nstart + n; e++) PetscCall(MatSetValue(A, e, e, 1e-10 * dmax, ADD_VALUES));
    shift = 1e-10 * dmax;
    PetscCall(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    PetscCall(VecDestroy(&colv));
    PetscCall(VecDestroy(&coefv));
    { /* a new KSP each time: the system's size changes with the active set */
      PetscBool   mumps;
      const char *mprefix;
      PetscCall(KSPCreate(comm, &ksp));
      PetscCall(PetscObjectGetOptionsPrefix((PetscObject)m, &mprefix));
      PetscCall(KSPSetOptionsPrefix(ksp, mprefix));
      PetscCall(KSPAppendOptionsPrefix(ksp, "pgs_"));
      PetscCall(KSPSetType(ksp, KSPPREONLY));
      PetscCall(KSPGetPC(ksp, &pc));
      PetscCall(PCSetType(pc, PCLU));
      PetscCall(PetscHasExternalPackage("mumps", &mumps));
      if (mumps) PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
      PetscCall(KSPSetErrorIfNotConverged(ksp, PETSC_FALSE));
      PetscCall(KSPSetFromOptions(ksp));
    }
    PetscCall(KSPSetOperators(ksp, A, A));
    PetscCall(MatDestroy(&A));
    PetscCall(KSPSetUp(ksp));
    if (!slips) { /* keep this factor (one with slipping contacts is used once) */
      PetscCall(KSPDestroy(&pgs->ksp));
      pgs->ksp = ksp;
      PetscCall(PetscFree(pgs->luS));
      PetscCall(PetscMalloc1(ns + 1, &pgs->luS));
      PetscCall(PetscArraycpy(pgs->luS, S, ns));
      pgs->lun   = ns;
      pgs->kept  = PETSC_TRUE;
      pgs->shift = shift;
    }
  } else ksp = pgs->ksp, shift = pgs->shift;
  PetscCall(KSPSolve(ksp, b, x));
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  if (reason >= 0) { /* one step of refinement towards the unshifted system: x += A~^-1 (b - (A~ - shift I) x);
                        the shift's 1e-10 would otherwise floor the merit near 1e-11 */
    Mat Ash;
    Vec res, dx;
    PetscCall(KSPGetOperators(ksp, &Ash, NULL));
    PetscCall(VecDuplicate(b, &res));
    PetscCall(VecDuplicate(b, &dx));
    PetscCall(MatMult(Ash, x, res));
    PetscCall(VecAYPX(res, -1.0, b));
    PetscCall(VecAXPY(res, shift, x));
    PetscCall(KSPSolve(ksp, res, dx));
    PetscCall(VecAXPY(x, 1.0, dx));
    PetscCall(VecDestroy(&res));
    PetscCall(VecDestroy(&dx));
  } else if (ksp == pgs->ksp) pgs->kept = PETSC_FALSE;
  if (slips) PetscCall(KSPDestroy(&ksp));
  if (reason >= 0) { /* the new iterate, projected onto the cones; the caller keeps the best one */
    const PetscScalar *xv;
    const PetscReal    before = *error;
    PetscCall(VecZeroEntries(r));
    PetscCall(VecGetArray(r, &rv));
    PetscCall(VecGetArrayRead(x, &xv));
    for (PetscInt k = 0, c = 0; k < nin; k++) {
      const PetscInt i = contact[k], o = fp->off[i], dim = fp->off[i + 1] - o;
      PetscReal      y[3], p[3];
      if (dir[2 * k] != 0 || dir[2 * k + 1] != 0) {
        y[0] = PetscRealPart(xv[c++]);
        y[1] = fp->mu[i] * y[0] * dir[2 * k];
        y[2] = fp->mu[i] * y[0] * dir[2 * k + 1];
      } else
        for (PetscInt d = 0; d < dim; d++) y[d] = PetscRealPart(xv[c++]);
      if (dim == 1) rv[o] = PetscMax(0, y[0]); /* keep it in the cone */
      else {
        MBCProjectCone(y, fp->mu[i], p);
        for (PetscInt d = 0; d < 3; d++) rv[o + d] = p[d];
      }
    }
    PetscCall(VecRestoreArrayRead(x, &xv));
    PetscCall(VecRestoreArray(r, &rv));
    PetscCall(MBCFrictionVelocity(fp, r, u));
    PetscCall(MBCFrictionMerit(fp, r, u, error));
    PetscCall(PetscInfo(NULL, "active set%s: %" PetscInt_FMT " unknowns, merit %g -> %g\n", reuse ? " (kept factor)" : "", N, (double)before, (double)*error));
  }
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(PetscFree4(S, first, contact, dir));
  PetscFunctionReturn(0);
}

/* One Gauss-Seidel sweep over this rank's contacts, the others' r as last exchanged (in parallel
   a block Jacobi between ranks, Gauss-Seidel inside each). Adds the squared change of r and
   the squared new r to dr2, r2: the sweep's own estimate of convergence, at no cost. */
static PetscErrorCode PGSLocalSweep(MBC_PGS *pgs, MBCFrictionProblem *fp, Vec r, PetscReal *dr2, PetscReal *r2)
{
  PetscScalar       *rv;
  const PetscScalar *qv, *gv = NULL;

  PetscFunctionBegin;
  PetscCall(VecGetArray(r, &rv));
  PetscCall(VecGetArrayRead(fp->q, &qv));
  if (pgs->rg) PetscCall(VecGetArrayRead(pgs->rg, &gv));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    PetscReal      b[3], rnew[3];
    for (PetscInt d = 0; d < dim; d++) { /* b = q_i + (W r)_i - W_ii r_i */
      const PetscInt     row = o + d;
      PetscInt           ncols;
      const PetscInt    *cols;
      const PetscScalar *vals;
      b[d] = PetscRealPart(qv[row]);
      PetscCall(MatGetRow(pgs->Ad, row, &ncols, &cols, &vals));
      for (PetscInt k = 0; k < ncols; k++) b[d] += PetscRealPart(vals[k] * rv[cols[k]]);
      PetscCall(MatRestoreRow(pgs->Ad, row, &ncols, &cols, &vals));
      if (pgs->Ao) {
        PetscCall(MatGetRow(pgs->Ao, row, &ncols, &cols, &vals));
        for (PetscInt k = 0; k < ncols; k++) b[d] += PetscRealPart(vals[k] * gv[cols[k]]);
        PetscCall(MatRestoreRow(pgs->Ao, row, &ncols, &cols, &vals));
      }
      for (PetscInt e = 0; e < dim; e++) b[d] -= pgs->diag[9 * i + dim * d + e] * PetscRealPart(rv[o + e]);
    }
    if (dim == 1) rnew[0] = (b[0] >= 0 || !(pgs->diag[9 * i] > 0)) ? 0 : -b[0] / pgs->diag[9 * i];
    else PetscCall(MBCContactLocalSolve(&pgs->diag[9 * i], b, fp->mu[i], rnew));
    if (pgs->omega != 1) { /* over-relaxation may leave the cone: project back */
      PetscReal x[3];
      for (PetscInt d = 0; d < dim; d++) x[d] = pgs->omega * rnew[d] + (1 - pgs->omega) * PetscRealPart(rv[o + d]);
      if (dim == 1) rnew[0] = PetscMax(0, x[0]);
      else MBCProjectCone(x, fp->mu[i], rnew);
    }
    for (PetscInt d = 0; d < dim; d++) {
      *dr2 += PetscSqr(rnew[d] - PetscRealPart(rv[o + d]));
      *r2 += PetscSqr(rnew[d]);
      rv[o + d] = rnew[d];
    }
  }
  if (gv) PetscCall(VecRestoreArrayRead(pgs->rg, &gv));
  PetscCall(VecRestoreArrayRead(fp->q, &qv));
  PetscCall(VecRestoreArray(r, &rv));
  PetscFunctionReturn(0);
}

/* Sweeps over the contacts; r holds the warm start on entry, the solution on exit; u = W r + q.
   Stops when the merit falls below rtol. The merit costs a product with W, as much as a sweep:
   it is computed every merit_every sweeps, and whenever a sweep changed r by less than rtol
   relative (the sweep's own estimate), so a converging solve stops at once. On several ranks
   each rank sweeps its own contacts (-mbc_pgs_local_sweeps times) with the others' r of the
   last exchange. */
static PetscErrorCode MBCMultiplierSolve_PGS(MBCMultiplier m, Vec r, Vec u)
{
  MBC_PGS            *pgs = (MBC_PGS *)m->data;
  MBCFrictionProblem *fp  = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  PetscReal           change[2] = {0, 0};
  PetscBool           fresh = PETSC_TRUE; /* m->merit belongs to the current r */

  PetscFunctionBegin;
  PetscCall(MBCFrictionVelocity(fp, r, u));
  PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
  for (m->its = 0;; m->its++) {
    const PetscBool due = (PetscBool)(m->its % pgs->merit_every == 0 || change[0] <= PetscSqr(m->rtol) * change[1]);
    if (m->its > 0 && due) {
      PetscCall(MBCFrictionVelocity(fp, r, u));
      PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      fresh = PETSC_TRUE;
    }
    /* every active_set sweeps, and at once when a factor of the last solve is kept (warm start
       of a step like the last): a few active-set (semismooth Newton) steps while they pay; the
       first also counts the contacts closed in q as active */
    if (fresh && pgs->active_set && ((m->its > 0 && m->its % pgs->active_set == 0) || (m->its == 0 && pgs->kept)) && m->merit >= m->rtol) {
      Vec       rbest;
      PetscReal ebest = m->merit;
      PetscCall(VecDuplicate(r, &rbest));
      PetscCall(VecCopy(r, rbest));
      for (PetscInt k = 0, stale = 0; k < 10 && stale < 3 && ebest >= m->rtol; k++) {
        PetscCall(ActiveSetStep(m, pgs, fp, r, u, (PetscBool)(k == 0 && m->its > 0), &m->merit));
        if (m->merit < 0.5 * ebest) {
          ebest = m->merit, stale = 0;
          PetscCall(VecCopy(r, rbest));
        } else stale++;
      }
      PetscCall(VecCopy(rbest, r));
      PetscCall(VecDestroy(&rbest));
      PetscCall(MBCFrictionVelocity(fp, r, u));
      PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
    }
    if (fresh) {
      PetscCall(MBCMultiplierMonitorMerit(m, m->its, m->merit, NULL));
      if (PetscIsInfOrNanReal(m->merit)) m->reason = MBC_MULTIPLIER_DIVERGED_NANORINF;
      else if (m->merit < m->rtol) m->reason = MBC_MULTIPLIER_CONVERGED_RTOL;
    }
    if (m->reason == MBC_MULTIPLIER_ITERATING && m->its >= m->max_it) {
      if (!fresh) {
        PetscCall(MBCFrictionVelocity(fp, r, u));
        PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      }
      m->reason = m->merit < m->rtol ? MBC_MULTIPLIER_CONVERGED_RTOL : MBC_MULTIPLIER_DIVERGED_ITS;
    }
    if (m->reason != MBC_MULTIPLIER_ITERATING) break;
    if (pgs->gsc) { /* the other ranks' r */
      PetscCall(VecScatterBegin(pgs->gsc, r, pgs->rg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(pgs->gsc, r, pgs->rg, INSERT_VALUES, SCATTER_FORWARD));
    }
    change[0] = change[1] = 0;
    for (PetscInt k = 0; k < (pgs->gsc ? pgs->sweeps_local : 1); k++) PetscCall(PGSLocalSweep(pgs, fp, r, &change[0], &change[1]));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, change, 2, MPIU_REAL, MPIU_SUM, comm));
    fresh = PETSC_FALSE;
  }
  PetscFunctionReturn(0);
}

/* Frees what belongs to one W: its parts, the ghost scatter, the kept active-set factor. */
static PetscErrorCode MBCMultiplierReset_PGS(MBCMultiplier m)
{
  MBC_PGS *pgs = (MBC_PGS *)m->data;

  PetscFunctionBegin;
  pgs->Ad = pgs->Ao = NULL;
  PetscCall(VecDestroy(&pgs->rg));
  PetscCall(VecDestroy(&pgs->cg));
  PetscCall(VecDestroy(&pgs->eg));
  PetscCall(VecScatterDestroy(&pgs->gsc));
  PetscCall(PetscFree(pgs->diag));
  PetscCall(KSPDestroy(&pgs->ksp));
  PetscCall(PetscFree(pgs->luS));
  pgs->lun  = 0;
  pgs->kept = PETSC_FALSE;
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierDestroy_PGS(MBCMultiplier m)
{
  PetscFunctionBegin;
  PetscCall(MBCMultiplierReset_PGS(m));
  PetscCall(PetscFree(m->data));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierView_PGS(MBCMultiplier m, PetscViewer viewer)
{
  MBC_PGS *pgs = (MBC_PGS *)m->data;

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "relaxation %g, active-set step every %" PetscInt_FMT " sweeps, merit every %" PetscInt_FMT " sweeps, %" PetscInt_FMT " local sweeps between exchanges\n", (double)pgs->omega, pgs->active_set, pgs->merit_every, pgs->sweeps_local));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierCreate_PGS(MBCMultiplier m)
{
  MBC_PGS *pgs;

  PetscFunctionBegin;
  PetscCall(PetscNew(&pgs));
  pgs->omega        = 1.0;
  pgs->active_set   = 20;
  pgs->sweeps_local = 1;
  pgs->merit_every  = 10;
  m->data           = pgs;
  if (m->max_it < 0) m->max_it = 1000;
  m->ops->setfromoptions = MBCMultiplierSetFromOptions_PGS;
  m->ops->setup          = MBCMultiplierSetUp_PGS;
  m->ops->solve          = MBCMultiplierSolve_PGS;
  m->ops->reset          = MBCMultiplierReset_PGS;
  m->ops->destroy        = MBCMultiplierDestroy_PGS;
  m->ops->view           = MBCMultiplierView_PGS;
  PetscFunctionReturn(0);
}

/* The active-set step every n sweeps (0: never): the Newton type's warm-start sweeps use none. */
PetscErrorCode MBCMultiplierPGSSetActiveSet(MBCMultiplier m, PetscInt n)
{
  PetscBool pgs;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)m, MBCMULTIPLIERPGS, &pgs));
  if (pgs) ((MBC_PGS *)m->data)->active_set = n;
  PetscFunctionReturn(0);
}
