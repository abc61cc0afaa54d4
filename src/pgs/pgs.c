/* Projected Gauss-Seidel for u = W r + q, r in the Coulomb cone K (|r_t| <= mu r_n), with the
   De Saxce complementarity K* ∋ u + mu |u_t| e_n ⟂ r. Each contact's 3x3 problem, with the
   other contacts' current r on the right side, is solved exactly (separation, stick, or slip
   found by a 1D root search over the slip direction), so normal-tangent coupling of the
   diagonal block is honoured: no solve-then-clamp. */
#include <mbc/private/pgsimpl.h>
#include <petscblaslapack.h>

PetscLogEvent MBC_PGSSolve, MBC_FlexibilityAssemble;

const char *MBCPGSReasonName(MBCPGSReason r)
{
  switch (r) {
  case MBC_PGS_CONVERGED_RTOL:
    return "CONVERGED_RTOL";
  case MBC_PGS_DIVERGED_ITS:
    return "DIVERGED_ITS";
  case MBC_PGS_DIVERGED_NANORINF:
    return "DIVERGED_NANORINF";
  default:
    return "ITERATING";
  }
}

/* Projection onto K_mu = {|x_t| <= mu x_n}. */
static void ProjectCone(const PetscReal x[3], PetscReal mu, PetscReal p[3])
{
  const PetscReal t = PetscSqrtReal(x[1] * x[1] + x[2] * x[2]);
  if (t <= mu * x[0]) {
    p[0] = x[0], p[1] = x[1], p[2] = x[2];
  } else if (mu * t <= -x[0]) {
    p[0] = p[1] = p[2] = 0;
  } else {
    const PetscReal a = (x[0] + mu * t) / (1 + mu * mu);
    p[0] = a;
    p[1] = mu * a * x[1] / t;
    p[2] = mu * a * x[2] / t;
  }
}

/* Natural-map residual of one contact with De Saxce's modified velocity. */
static PetscReal ContactResidual2(const PetscReal r[3], const PetscReal u[3], PetscReal mu)
{
  const PetscReal ut = PetscSqrtReal(u[1] * u[1] + u[2] * u[2]);
  PetscReal       x[3], p[3], e = 0;
  x[0] = r[0] - (u[0] + mu * ut);
  x[1] = r[1] - u[1];
  x[2] = r[2] - u[2];
  ProjectCone(x, mu, p);
  for (int d = 0; d < 3; d++) e += (r[d] - p[d]) * (r[d] - p[d]);
  return e;
}

/* FCLIB merit: sqrt(sum over contacts of |r - proj_K(r - (u + mu |u_t| e_n))|^2) / (1 + |q|);
   a frictionless 1-block contributes (r_n - max(0, r_n - u_n))^2, the same value its 3-block
   with mu = 0 and r_t = 0 would. Sums over the ranks. */
PetscErrorCode MBCFrictionError(MBCFrictionProblem *fp, Vec r, Vec u, PetscReal *error)
{
  const PetscScalar *rv, *uv;
  PetscReal          e = 0, qn;

  PetscFunctionBegin;
  PetscCall(MatMult(fp->W, r, u));
  PetscCall(VecAXPY(u, 1.0, fp->q));
  PetscCall(VecGetArrayRead(r, &rv));
  PetscCall(VecGetArrayRead(u, &uv));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i];
    if (fp->off[i + 1] - o == 1) { /* frictionless: r_n - max(0, r_n - u_n) */
      const PetscReal p = PetscMax(0, PetscRealPart(rv[o] - uv[o]));
      e += PetscSqr(PetscRealPart(rv[o]) - p);
    } else e += ContactResidual2(&rv[o], &uv[o], fp->mu[i]);
  }
  PetscCall(VecRestoreArrayRead(u, &uv));
  PetscCall(VecRestoreArrayRead(r, &rv));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &e, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)fp->W)));
  PetscCall(VecNorm(fp->q, NORM_2, &qn));
  *error = PetscSqrtReal(e) / (1 + qn);
  PetscFunctionReturn(0);
}

/* Slip: r = rn (1, mu cos f, mu sin f) with u_n = 0 gives rn(f) = -b_n / den(f); the tangential
   velocity must point against the friction direction d(f): u_t(f) x d(f) = 0, u_t . d <= 0.
   Multiplied by den, G(f) = den u_t x d = ((-b_n A_tn + A_nn b_t) + M d) x d is a trigonometric
   polynomial of degree 2 (at most 4 roots) without the poles of rn: sign changes bracket them. */
static PetscReal SlipResidual(const PetscReal A[9], const PetscReal b[3], PetscReal mu, PetscReal f, PetscReal r[3], PetscReal *along, PetscReal *den)
{
  const PetscReal c = PetscCosReal(f), s = PetscSinReal(f);
  PetscReal       w[2]; /* den * u_t */
  *den = A[0] + mu * (A[1] * c + A[2] * s);
  w[0] = -b[0] * (A[3] + mu * (A[4] * c + A[5] * s)) + *den * b[1];
  w[1] = -b[0] * (A[6] + mu * (A[7] * c + A[8] * s)) + *den * b[2];
  r[0] = -b[0] / *den, r[1] = mu * r[0] * c, r[2] = mu * r[0] * s;
  *along = (w[0] * c + w[1] * s) / *den; /* u_t . d */
  return w[0] * s - w[1] * c;
}

/* Exact solution of one contact: u = A r + b (A row-major 3x3, the diagonal block of W). */
PetscErrorCode MBCContactLocalSolve(const PetscReal A[9], const PetscReal b[3], PetscReal mu, PetscReal r[3])
{
  PetscReal Ai[9], det;

  PetscFunctionBegin;
  if (b[0] >= 0 || !(A[0] > 0)) { /* separation, or no free DOF along the normal (all prescribed) */
    r[0] = r[1] = r[2] = 0;
    PetscFunctionReturn(0);
  }
  if (mu == 0) { /* frictionless: only the normal component */
    r[0] = -b[0] / A[0];
    r[1] = r[2] = 0;
    PetscFunctionReturn(0);
  }
  r[0] = r[1] = r[2] = 0;
  det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
  if (det != 0) { /* stick: u = 0 */
    Ai[0] = (A[4] * A[8] - A[5] * A[7]) / det, Ai[1] = (A[2] * A[7] - A[1] * A[8]) / det, Ai[2] = (A[1] * A[5] - A[2] * A[4]) / det;
    Ai[3] = (A[5] * A[6] - A[3] * A[8]) / det, Ai[4] = (A[0] * A[8] - A[2] * A[6]) / det, Ai[5] = (A[2] * A[3] - A[0] * A[5]) / det;
    Ai[6] = (A[3] * A[7] - A[4] * A[6]) / det, Ai[7] = (A[1] * A[6] - A[0] * A[7]) / det, Ai[8] = (A[0] * A[4] - A[1] * A[3]) / det;
    for (int i = 0; i < 3; i++) r[i] = -(Ai[3 * i] * b[0] + Ai[3 * i + 1] * b[1] + Ai[3 * i + 2] * b[2]);
    if (r[0] >= 0 && PetscSqrtReal(r[1] * r[1] + r[2] * r[2]) <= mu * r[0] * (1 + 1e-14)) PetscFunctionReturn(0);
  }
  { /* slip: sample G over the direction, bisect its sign changes, keep valid roots (den > 0,
       u_t . d <= 0); among several, the one whose friction force is closest to the stick trial's */
    const int N = 72;
    PetscReal best[3] = {0, 0, 0}, bestScore = PETSC_MAX_REAL, f0 = 0, G0, along, den, rr[3];
    G0 = SlipResidual(A, b, mu, f0, rr, &along, &den);
    for (int k = 1; k <= N; k++) {
      PetscReal f1 = 2 * PETSC_PI * k / N, G1 = SlipResidual(A, b, mu, f1, rr, &along, &den);
      if ((G0 <= 0 && G1 >= 0) || (G0 >= 0 && G1 <= 0)) {
        PetscReal lo = f0, hi = f1, Glo = G0, fm = f0;
        for (int it = 0; it < 200 && hi - lo > 4 * PETSC_MACHINE_EPSILON; it++) {
          PetscReal Gm;
          fm = 0.5 * (lo + hi);
          Gm = SlipResidual(A, b, mu, fm, rr, &along, &den);
          if ((Glo <= 0 && Gm <= 0) || (Glo >= 0 && Gm >= 0)) lo = fm, Glo = Gm;
          else hi = fm;
        }
        (void)SlipResidual(A, b, mu, fm, rr, &along, &den);
        if (den > 0 && along <= 0) {
          const PetscReal score = PetscSqr(rr[1] - r[1]) + PetscSqr(rr[2] - r[2]);
          if (score < bestScore) {
            bestScore = score;
            best[0] = rr[0], best[1] = rr[1], best[2] = rr[2];
          }
        }
      }
      f0 = f1, G0 = G1;
    }
    if (bestScore < PETSC_MAX_REAL) {
      r[0] = best[0], r[1] = best[1], r[2] = best[2];
      PetscFunctionReturn(0);
    }
  }
  /* no exact slip state (a singular or strongly non-symmetric block): projected fixed point */
  {
    PetscReal rho = 1.0 / PetscMax(PetscMax(A[0], A[4]), A[8]), x[3], u[3];
    for (int it = 0; it < 200; it++) {
      for (int i = 0; i < 3; i++) u[i] = A[3 * i] * r[0] + A[3 * i + 1] * r[1] + A[3 * i + 2] * r[2] + b[i];
      x[0] = r[0] - rho * (u[0] + mu * PetscSqrtReal(u[1] * u[1] + u[2] * u[2]));
      x[1] = r[1] - rho * u[1];
      x[2] = r[2] - rho * u[2];
      ProjectCone(x, mu, r);
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCPGSSetFromOptions(MBCPGS *pgs)
{
  PetscFunctionBegin;
  pgs->rtol         = 1e-8;
  pgs->omega        = 1.0;
  pgs->max_it       = 1000;
  pgs->active_set   = 20;
  pgs->sweeps_local = 1;
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "Projected Gauss-Seidel for the contact multipliers", "MBCPGS");
  PetscCall(PetscOptionsReal("-mbc_pgs_rtol", "Tolerance on the FCLIB merit (in a simulation: of the step problem scaled to |q| = 1, so relative)", "MBCPGSSetFromOptions", pgs->rtol, &pgs->rtol, NULL));
  PetscCall(PetscOptionsInt("-mbc_pgs_max_it", "Maximum sweeps", "MBCPGSSetFromOptions", pgs->max_it, &pgs->max_it, NULL));
  PetscCall(PetscOptionsReal("-mbc_pgs_omega", "Relaxation factor (0, 2)", "MBCPGSSetFromOptions", pgs->omega, &pgs->omega, NULL));
  PetscCall(PetscOptionsInt("-mbc_pgs_active_set", "Every this many sweeps, try the direct solve on the contacts in contact (0: never)", "MBCPGSSetFromOptions", pgs->active_set, &pgs->active_set, NULL));
  PetscCall(PetscOptionsInt("-mbc_pgs_local_sweeps", "Gauss-Seidel sweeps over a rank's own contacts between two exchanges of the others' (parallel)", "MBCPGSSetFromOptions", pgs->sweeps_local, &pgs->sweeps_local, NULL));
  PetscCall(PetscOptionsBool("-mbc_pgs_monitor", "Print the merit every sweep", "MBCPGSSetFromOptions", pgs->monitor, &pgs->monitor, NULL));
  PetscOptionsEnd();
  PetscCheck(pgs->rtol > 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_rtol %g must be positive", (double)pgs->rtol);
  PetscCheck(pgs->max_it > 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_max_it %" PetscInt_FMT " must be positive", pgs->max_it);
  PetscCheck(pgs->omega > 0 && pgs->omega < 2, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_omega %g must lie in (0, 2)", (double)pgs->omega);
  PetscCheck(pgs->active_set >= 0, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_active_set %" PetscInt_FMT " must be >= 0", pgs->active_set);
  PetscCheck(pgs->sweeps_local >= 1, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_pgs_local_sweeps %" PetscInt_FMT " must be at least 1", pgs->sweeps_local);
  PetscFunctionReturn(0);
}

/* The parts of W a rank sweeps with: its diagonal block Ad (its rows and columns), the
   off-diagonal block Ao (its rows, the other ranks' columns, compacted) and the scatter of
   those columns of r; the diagonal 3x3 (1x1) blocks of its contacts. Kept while W is. */
static PetscErrorCode PGSSetUpW(MBCPGS *pgs, MBCFrictionProblem *fp, Vec r)
{
  PetscBool mpi;

  PetscFunctionBegin;
  if (pgs->Wc == fp->W) PetscFunctionReturn(0);
  PetscCall(MBCPGSReset(pgs));
  PetscCall(PetscObjectReference((PetscObject)fp->W));
  pgs->Wc = fp->W;
  PetscCall(PetscObjectBaseTypeCompare((PetscObject)fp->W, MATMPIAIJ, &mpi));
  if (mpi) {
    const PetscInt *garray;
    PetscInt        ng;
    IS              is;
    PetscCall(MatMPIAIJGetSeqAIJ(fp->W, &pgs->Ad, &pgs->Ao, &garray));
    PetscCall(MatGetSize(pgs->Ao, NULL, &ng));
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, ng, garray, PETSC_COPY_VALUES, &is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, ng, &pgs->rg));
    PetscCall(VecDuplicate(pgs->rg, &pgs->cg));
    PetscCall(VecDuplicate(pgs->rg, &pgs->eg));
    PetscCall(VecScatterCreate(r, is, pgs->rg, NULL, &pgs->gsc));
    PetscCall(ISDestroy(&is));
  } else pgs->Ad = fp->W, pgs->Ao = NULL;
  PetscCall(PetscMalloc1(9 * fp->nc + 1, &pgs->diag));
  for (PetscInt i = 0; i < fp->nc; i++) { /* diagonal blocks, row-major dim x dim */
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o, idx[3] = {o, o + 1, o + 2};
    PetscScalar    v[9];
    PetscCall(MatGetValues(pgs->Ad, dim, idx, dim, idx, v));
    for (PetscInt k = 0; k < dim * dim; k++) pgs->diag[9 * i + k] = PetscRealPart(v[k]);
  }
  PetscFunctionReturn(0);
}

/* Row grow of the active-set system: the sum over row `row` (local) of W of coef_j W_row,j into
   the columns col_j >= 0 (the column map and coefficients of this rank's slots in c, e, of the
   others' in cg, eg); cols, vals: work space of W's row length. */
static PetscErrorCode ActiveSetRow(MBCPGS *pgs, PetscInt row, PetscInt grow, const PetscScalar c[], const PetscScalar e[], const PetscScalar cg[], const PetscScalar eg[], PetscInt acols[], PetscScalar avals[], Mat A)
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
static PetscErrorCode ActiveSetStep(MBCPGS *pgs, MBCFrictionProblem *fp, Vec r, Vec u, PetscBool closed, PetscReal *error)
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
    PetscCall(MatCreate(comm, &A));
    PetscCall(MatSetSizes(A, n, n, N, N));
    PetscCall(MatSetType(A, MATAIJ));
    PetscCall(MatSeqAIJSetPreallocation(A, 0, nnz));
    PetscCall(MatMPIAIJSetPreallocation(A, 0, nnz, 0, onz));
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
      PetscBool mumps;
      PetscCall(KSPCreate(comm, &ksp));
      PetscCall(KSPSetOptionsPrefix(ksp, "mbc_pgs_"));
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
        ProjectCone(y, fp->mu[i], p);
        for (PetscInt d = 0; d < 3; d++) rv[o + d] = p[d];
      }
    }
    PetscCall(VecRestoreArrayRead(x, &xv));
    PetscCall(VecRestoreArray(r, &rv));
    PetscCall(MBCFrictionError(fp, r, u, error));
    PetscCall(PetscInfo(NULL, "active set%s: %" PetscInt_FMT " unknowns, merit %g -> %g\n", reuse ? " (kept factor)" : "", N, (double)before, (double)*error));
  }
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&b));
  PetscCall(PetscFree4(S, first, contact, dir));
  PetscFunctionReturn(0);
}

/* One Gauss-Seidel sweep over this rank's contacts, the others' r as last exchanged (in parallel
   a block Jacobi between ranks, Gauss-Seidel inside each). */
static PetscErrorCode PGSLocalSweep(MBCPGS *pgs, MBCFrictionProblem *fp, Vec r)
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
      else ProjectCone(x, fp->mu[i], rnew);
    }
    for (PetscInt d = 0; d < dim; d++) rv[o + d] = rnew[d];
  }
  if (gv) PetscCall(VecRestoreArrayRead(pgs->rg, &gv));
  PetscCall(VecRestoreArrayRead(fp->q, &qv));
  PetscCall(VecRestoreArray(r, &rv));
  PetscFunctionReturn(0);
}

/* Sweeps over the contacts; r holds the warm start on entry, the solution on exit; u = W r + q.
   Stops when the merit falls below rtol. On several ranks each rank sweeps its own contacts
   (-mbc_pgs_local_sweeps times) with the others' r of the last exchange. */
PetscErrorCode MBCPGSSolve(MBCPGS *pgs, MBCFrictionProblem *fp, Vec r, Vec u)
{
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_PGSSolve, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(PGSSetUpW(pgs, fp, r));
  pgs->reason = MBC_PGS_ITERATING;
  for (pgs->its = 0; pgs->reason == MBC_PGS_ITERATING; pgs->its++) {
    PetscCall(MBCFrictionError(fp, r, u, &pgs->error));
    /* every active_set sweeps, and at once when a factor of the last solve is kept (warm start
       of a step like the last) */
    if (pgs->active_set && ((pgs->its > 0 && pgs->its % pgs->active_set == 0) || (pgs->its == 0 && pgs->kept)) && pgs->error >= pgs->rtol) {
      /* a few active-set (semismooth Newton) steps while they pay; the first also counts the
         contacts closed in q as active: with a body held only by contact (static), D has a huge
         rigid-mode part and the Gauss-Seidel iterate leaves most of them unloaded */
      /* semismooth Newton: each step's split comes from the last step's iterate, not only from
         improving ones (an active set that slips a few heel contacts may first raise the merit);
         the best iterate is kept, and the steps stop after 3 without a new best */
      Vec       rbest;
      PetscReal ebest = pgs->error;
      PetscCall(VecDuplicate(r, &rbest));
      PetscCall(VecCopy(r, rbest));
      for (PetscInt k = 0, stale = 0; k < 10 && stale < 3 && ebest >= pgs->rtol; k++) {
        PetscCall(ActiveSetStep(pgs, fp, r, u, (PetscBool)(k == 0 && pgs->its > 0), &pgs->error));
        if (pgs->error < 0.5 * ebest) {
          ebest = pgs->error, stale = 0;
          PetscCall(VecCopy(r, rbest));
        } else stale++;
      }
      PetscCall(VecCopy(rbest, r));
      PetscCall(VecDestroy(&rbest));
      PetscCall(MBCFrictionError(fp, r, u, &pgs->error));
    }
    if (pgs->monitor) PetscCall(PetscPrintf(PetscObjectComm((PetscObject)fp->W), "  PGS sweep %4" PetscInt_FMT " FCLIB error %.6e\n", pgs->its, (double)pgs->error));
    if (PetscIsInfOrNanReal(pgs->error)) pgs->reason = MBC_PGS_DIVERGED_NANORINF;
    else if (pgs->error < pgs->rtol) pgs->reason = MBC_PGS_CONVERGED_RTOL;
    else if (pgs->its >= pgs->max_it) pgs->reason = MBC_PGS_DIVERGED_ITS;
    if (pgs->reason != MBC_PGS_ITERATING) break;
    if (pgs->gsc) { /* the other ranks' r */
      PetscCall(VecScatterBegin(pgs->gsc, r, pgs->rg, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(pgs->gsc, r, pgs->rg, INSERT_VALUES, SCATTER_FORWARD));
    }
    for (PetscInt k = 0; k < (pgs->gsc ? pgs->sweeps_local : 1); k++) PetscCall(PGSLocalSweep(pgs, fp, r));
  }
  PetscCall(PetscTime(&t1));
  pgs->time = t1 - t0;
  PetscCall(PetscLogEventEnd(MBC_PGSSolve, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Block layout: dims[i] rows (1 or 3) for contact i, or 3 each when dims is NULL. */
PetscErrorCode MBCFrictionProblemSetBlocks(MBCFrictionProblem *fp, const PetscInt dims[])
{
  PetscFunctionBegin;
  PetscCall(PetscFree(fp->off));
  PetscCall(PetscMalloc1(fp->nc + 1, &fp->off));
  fp->off[0] = 0;
  for (PetscInt i = 0; i < fp->nc; i++) fp->off[i + 1] = fp->off[i] + (dims ? dims[i] : 3);
  PetscFunctionReturn(0);
}

/* Frees what belongs to one W: its parts, the ghost scatter, the kept active-set factor. */
PetscErrorCode MBCPGSReset(MBCPGS *pgs)
{
  PetscFunctionBegin;
  PetscCall(MatDestroy(&pgs->Wc));
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

PetscErrorCode MBCFrictionProblemDestroy(MBCFrictionProblem *fp)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(fp->off));
  PetscCall(MatDestroy(&fp->W));
  PetscCall(VecDestroy(&fp->q));
  PetscCall(PetscFree(fp->mu));
  PetscFunctionReturn(0);
}
