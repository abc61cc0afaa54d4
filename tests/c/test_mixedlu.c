/* PCMBCMIXEDLU (single-precision LU refined in double) against LAPACK's double LU (PCLU): the same
   backward error, LAPACK dsgesv's ||b - J x||_inf <= ||x||_inf ||J||_inf eps sqrt(n), on a
   well-conditioned matrix through refinement alone; a matrix with cond 1e10 (> 1/eps_single:
   the refinement cannot converge) and one out of single precision's range are factored in double
   and solved as accurately as PCLU; a singular matrix is a zero-pivot error, one singular in double
   only a failed solve; a sparse one is refused. On several ranks the same matrices as a
   MATSCALAPACK (ScaLAPACK's psgetrf), against ScaLAPACK's double LU. */
#include <mbcmultiplier.h>

#define N 240

/* J = Q1 diag(s) Q2 with Householder reflections Q (orthogonal): cond_2(J) = s_max / s_min */
static PetscErrorCode Conditioned(PetscRandom rnd, PetscReal cond, PetscReal scale, Mat *J)
{
  PetscReal    v[N], w[N], vv = 0, ww = 0, s[N], *a;
  PetscScalar *x;

  PetscFunctionBegin;
  for (int i = 0; i < N; i++) {
    PetscCall(PetscRandomGetValueReal(rnd, &v[i]));
    PetscCall(PetscRandomGetValueReal(rnd, &w[i]));
    vv += v[i] * v[i], ww += w[i] * w[i];
    s[i] = scale * PetscPowReal(cond, -(PetscReal)i / (N - 1));
  }
  PetscCall(PetscMalloc1(N * N, &a));
  for (int i = 0; i < N; i++) /* a = (I - 2 v v^T / vv) diag(s) (I - 2 w w^T / ww) */
    for (int j = 0; j < N; j++) {
      PetscReal t = 0;
      for (int k = 0; k < N; k++) t += ((i == k) - 2 * v[i] * v[k] / vv) * s[k] * ((k == j) - 2 * w[k] * w[j] / ww);
      a[i + N * j] = t;
    }
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, N, N, NULL, J));
  PetscCall(MatDenseGetArrayWrite(*J, &x));
  for (int k = 0; k < N * N; k++) x[k] = a[k];
  PetscCall(MatDenseRestoreArrayWrite(*J, &x));
  PetscCall(MatAssemblyBegin(*J, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*J, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree(a));
  PetscFunctionReturn(0);
}

/* J (a MATSEQDENSE, the same on every rank) as the PC sees it: itself on one rank, a MATSCALAPACK
   over the ranks on several */
static PetscErrorCode Distribute(Mat *J)
{
  PetscMPIInt        size;
  Mat                D;
  PetscInt           n, rs, re;
  const PetscScalar *a;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(MatGetSize(*J, &n, NULL));
  PetscCall(MatCreateDense(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, n, n, NULL, &D));
  PetscCall(MatGetOwnershipRange(D, &rs, &re));
  PetscCall(MatDenseGetArrayRead(*J, &a));
  for (PetscInt i = rs; i < re; i++)
    for (PetscInt j = 0; j < n; j++) PetscCall(MatSetValue(D, i, j, a[i + n * j], INSERT_VALUES));
  PetscCall(MatDenseRestoreArrayRead(*J, &a));
  PetscCall(MatAssemblyBegin(D, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(D, MAT_FINAL_ASSEMBLY));
  PetscCall(MatDestroy(J));
  PetscCall(MatConvert(D, MATSCALAPACK, MAT_INITIAL_MATRIX, J));
  PetscCall(MatDestroy(&D));
  PetscFunctionReturn(0);
}

/* a direct solve of J by the PC type (PCLU: ScaLAPACK's on a MATSCALAPACK) */
static PetscErrorCode DirectKSP(Mat J, PCType type, KSP *ksp, PC *pc)
{
  PetscBool dist;

  PetscFunctionBegin;
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)J), ksp));
  PetscCall(KSPSetType(*ksp, KSPPREONLY));
  PetscCall(KSPGetPC(*ksp, pc));
  PetscCall(PCSetType(*pc, type));
  PetscCall(PetscObjectTypeCompare((PetscObject)J, MATSCALAPACK, &dist));
  if (dist) PetscCall(PCFactorSetMatSolverType(*pc, MATSOLVERSCALAPACK));
  PetscCall(KSPSetOperators(*ksp, J, J));
  PetscFunctionReturn(0);
}

static PetscErrorCode Solve(Mat J, PCType type, Vec b, Vec x, PetscInt counts[3])
{
  KSP ksp;
  PC  pc;

  PetscFunctionBegin;
  PetscCall(DirectKSP(J, type, &ksp, &pc));
  PetscCall(KSPSolve(ksp, b, x));
  if (counts) PetscCall(PCMBCMixedLUGetCounts(pc, &counts[0], &counts[1], &counts[2]));
  PetscCall(KSPDestroy(&ksp));
  PetscFunctionReturn(0);
}

/* the error PCMBCMIXEDLU's set-up on J returns */
static PetscErrorCode SetUpError(Mat J, PetscErrorCode *ierr)
{
  KSP ksp;
  PC  pc;

  PetscFunctionBegin;
  PetscCall(DirectKSP(J, PCMBCMIXEDLU, &ksp, &pc));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  *ierr = KSPSetUp(ksp);
  PetscCall(PetscPopErrorHandler());
  PetscCall(KSPDestroy(&ksp));
  PetscFunctionReturn(0);
}

/* ||b - J x||_inf / (||J||_inf ||x||_inf) in units of eps sqrt(n) */
static PetscErrorCode Backward(Mat J, Vec b, Vec x, PetscReal *e)
{
  Vec       r;
  PetscReal rn, xn, jn;

  PetscFunctionBegin;
  PetscCall(VecDuplicate(b, &r));
  PetscCall(MatMult(J, x, r));
  PetscCall(VecAYPX(r, -1.0, b));
  PetscCall(VecNorm(r, NORM_INFINITY, &rn));
  PetscCall(VecNorm(x, NORM_INFINITY, &xn));
  PetscCall(MatNorm(J, NORM_INFINITY, &jn));
  *e = rn / (jn * xn) / (PETSC_MACHINE_EPSILON * PetscSqrtReal(N));
  PetscCall(VecDestroy(&r));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscRandom rnd;
  Vec         b, x, xlu;
  const struct {
    PetscReal cond, scale;
    PetscInt  doubles;
    const char *what;
  } cases[] = {
    {1e2, 1, 0, "cond 1e2"}, {1e5, 1e-3, 0, "cond 1e5"}, {1e10, 1, 1, "cond 1e10"}, {1e2, 1e40, 1, "entries 1e40"},
  };

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(MBCMultiplierInitializePackage());
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  for (size_t c = 0; c < sizeof(cases) / sizeof(cases[0]); c++) {
    Mat       J;
    PetscInt  counts[3];
    PetscReal e, elu, dx, nx;
    PetscCall(Conditioned(rnd, cases[c].cond, cases[c].scale, &J));
    PetscCall(Distribute(&J));
    PetscCall(MatCreateVecs(J, &x, &b));
    PetscCall(VecDuplicate(b, &xlu));
    PetscCall(VecSetRandom(b, rnd));
    PetscCall(Solve(J, PCMBCMIXEDLU, b, x, counts));
    PetscCall(Solve(J, PCLU, b, xlu, NULL));
    PetscCall(Backward(J, b, x, &e));
    PetscCall(Backward(J, b, xlu, &elu));
    PetscCall(VecAXPY(xlu, -1.0, x));
    PetscCall(VecNorm(xlu, NORM_INFINITY, &dx));
    PetscCall(VecNorm(x, NORM_INFINITY, &nx));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%-13s backward error %.3g (PCLU %.3g) eps sqrt(n), |x - x_LU| / |x| %.3g, %" PetscInt_FMT " refinement steps, %" PetscInt_FMT " factors in double\n", cases[c].what, (double)e, (double)elu, (double)(dx / nx), counts[1], counts[2]));
    PetscCheck(e <= 1 && e <= PetscMax(10 * elu, 0.1), PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: backward error %g eps sqrt(n) (PCLU's %g)", cases[c].what, (double)e, (double)elu);
    PetscCheck(counts[2] == cases[c].doubles, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: %" PetscInt_FMT " factors in double, expected %" PetscInt_FMT, cases[c].what, counts[2], cases[c].doubles);
    /* in single precision the first solve alone is at eps_single: refinement happened */
    PetscCheck(cases[c].doubles || counts[1] >= 2, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: %" PetscInt_FMT " refinement steps", cases[c].what, counts[1]);
    /* the forward errors of two backward-stable solves differ by at most ~cond eps */
    PetscCheck(dx <= 100 * cases[c].cond * PETSC_MACHINE_EPSILON * nx, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: |x - x_LU| / |x| = %g", cases[c].what, (double)(dx / nx));
    PetscCall(MatDestroy(&J));
    PetscCall(VecDestroy(&b));
    PetscCall(VecDestroy(&x));
    PetscCall(VecDestroy(&xlu));
  }
  { /* singular: a zero column is a zero pivot, reported as such */
    Mat            J;
    PetscErrorCode ierr;
    PetscCall(Conditioned(rnd, 10, 1, &J));
    PetscCall(MatZeroRowsColumns(J, 1, (PetscInt[]){7}, 0.0, NULL, NULL));
    PetscCall(Distribute(&J));
    PetscCall(SetUpError(J, &ierr));
    PetscCheck(ierr == PETSC_ERR_MAT_LU_ZRPVT, PETSC_COMM_SELF, PETSC_ERR_PLIB, "singular matrix: error %d, expected a zero pivot (%d)", (int)ierr, (int)PETSC_ERR_MAT_LU_ZRPVT);
    PetscCall(MatDestroy(&J));
  }
  { /* singular in double, not in single: row 3 = row 1 + row 2 exactly in double, while single
       precision's rounding of a and 1 + a leaves a pivot of 6e-8 (cond ~1e8: the refinement
       stalls). The factor made in the solve meets the zero pivot: a failed solve
       (KSP_DIVERGED_PC_FAILED, PC_FACTOR_NUMERIC_ZEROPIVOT) that the Newton step falls back from, not an
       error ending the run (the overturning block on the slab ended so); the next factor of a
       regular matrix by the same PC solves again. */
    const PetscReal a = 508082496.0 / 1073741824.0, c = 549564285.0 / 1073741824.0;
    const PetscReal rows[3][3] = {{1, a, 0}, {0, 1, c}, {1, 1 + a, c}};
    Mat                J;
    Vec                b3, x3;
    KSP                ksp;
    PC                 pc;
    KSPConvergedReason reason;
    PCFailedReason     pcr;
    PetscScalar       *v;
    PetscReal          xn;
    PetscInt           counts[3];
    PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, 3, 3, NULL, &J));
    PetscCall(MatDenseGetArrayWrite(J, &v));
    for (int i = 0; i < 3; i++)
      for (int j = 0; j < 3; j++) v[i + 3 * j] = rows[i][j];
    PetscCall(MatDenseRestoreArrayWrite(J, &v));
    PetscCall(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
    PetscCall(Distribute(&J));
    PetscCall(MatCreateVecs(J, &x3, &b3));
    {
      PetscInt rs, re;
      const PetscScalar bv[3] = {1.0, -2.0, 0.5};
      PetscCall(VecGetOwnershipRange(b3, &rs, &re));
      for (PetscInt i = rs; i < re; i++) PetscCall(VecSetValue(b3, i, bv[i], INSERT_VALUES));
    }
    PetscCall(VecAssemblyBegin(b3));
    PetscCall(VecAssemblyEnd(b3));
    PetscCall(DirectKSP(J, PCMBCMIXEDLU, &ksp, &pc));
    PetscCall(KSPSolve(ksp, b3, x3));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    PetscCall(PCGetFailedReasonRank(pc, &pcr));
    PetscCall(PCMBCMixedLUGetCounts(pc, &counts[0], &counts[1], &counts[2]));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "singular in double only: %s, %s, %" PetscInt_FMT " factors in double\n", KSPConvergedReasons[reason], PCFailedReasons[pcr], counts[2]));
    /* the KSP reports the PC's failure (KSPPREONLY reads the PC's failed reason): the Newton step's fallback reads that */
    PetscCheck(reason == KSP_DIVERGED_PC_FAILED && pcr == PC_FACTOR_NUMERIC_ZEROPIVOT && counts[2] == 1, PETSC_COMM_SELF, PETSC_ERR_PLIB, "singular in double only: %s, PC failed reason %s, %" PetscInt_FMT " factors in double", KSPConvergedReasons[reason], PCFailedReasons[pcr], counts[2]);
    PetscCall(MatShift(J, 1.0)); /* regular: the same PC factors and solves it */
    PetscCall(KSPSetOperators(ksp, J, J));
    PetscCall(KSPSolve(ksp, b3, x3));
    PetscCall(KSPGetConvergedReason(ksp, &reason));
    PetscCall(PCGetFailedReasonRank(pc, &pcr));
    PetscCall(VecNorm(x3, NORM_INFINITY, &xn));
    PetscCheck(reason > 0 && pcr == PC_NOERROR && xn < 10, PETSC_COMM_SELF, PETSC_ERR_PLIB, "after a failed solve, a regular matrix: %s, %s, |x| %g", KSPConvergedReasons[reason], PCFailedReasons[pcr], (double)xn);
    PetscCall(KSPDestroy(&ksp));
    PetscCall(VecDestroy(&b3));
    PetscCall(VecDestroy(&x3));
    PetscCall(MatDestroy(&J));
  }
  { /* a sparse matrix is refused */
    Mat            A;
    PetscErrorCode ierr;
    PetscInt rs, re;
    PetscCall(MatCreateAIJ(PETSC_COMM_WORLD, PETSC_DECIDE, PETSC_DECIDE, 4, 4, 1, NULL, 1, NULL, &A));
    PetscCall(MatGetOwnershipRange(A, &rs, &re));
    for (PetscInt i = rs; i < re; i++) PetscCall(MatSetValue(A, i, i, 1.0, INSERT_VALUES));
    PetscCall(MatAssemblyBegin(A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(A, MAT_FINAL_ASSEMBLY));
    PetscCall(SetUpError(A, &ierr));
    PetscCheck(ierr == PETSC_ERR_SUP, PETSC_COMM_SELF, PETSC_ERR_PLIB, "sparse matrix: error %d, expected PETSC_ERR_SUP", (int)ierr);
    PetscCall(MatDestroy(&A));
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(PetscFinalize());
  return 0;
}
