/* PCMBCMIXEDLU ("mbcmixedlu"): a dense LU in single precision whose solves are refined in double,
   LAPACK's dsgesv with the factor kept for several solves. On one rank (MATSEQDENSE).
   Why: the contact Newton matrix of a dam is dense (every contact couples with every other through
   the bodies) and its LU is most of an earthquake step; single precision's LU runs at twice double's
   speed (OpenBLAS here: 27 against 14 GFlop/s at n = 2000), and a refinement step costs two passes
   of n^2. Each solve refines x += LU_s^-1 (b - J x), the residual in double, until LAPACK's dsgesv
   test ||b - J x||_inf <= ||x||_inf ||J||_inf eps sqrt(n) holds: double precision's backward
   error. Where it does not (the residual falls by less than half a step: cond(J) near
   1/eps_single), or single precision cannot hold J, J is factored in double and that factor
   solves from then on, so no answer is less accurate than PCLU's. */
#include <mbcmultiplier.h>
#include <petsc/private/pcimpl.h>
#include <petscblaslapack.h>
#include <float.h>

PETSC_EXTERN void sgetrf_(const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, PetscBLASInt *, PetscBLASInt *);
PETSC_EXTERN void sgetrs_(const char *, const PetscBLASInt *, const PetscBLASInt *, const float *, const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, PetscBLASInt *);

PetscLogEvent MBC_MixedLUFactor;

typedef struct {
  PetscBLASInt  n, *piv;
  float        *slu; /* J's single-precision factor (NULL once the double one replaced it) */
  PetscScalar  *dlu; /* J's double factor, made where the refinement failed */
  float        *sw;  /* a right side in single precision */
  PetscScalar  *r;   /* the residual */
  PetscReal     jnorm;
  PetscInt      maxit;
  PetscInt      solves, steps, doubles; /* solves, refinement steps, factors made in double */
} PC_MBCMixedLU;

/* J's double factor in place of the single one; *zero: the row of a zero pivot + 1 (0: none) */
static PetscErrorCode MixedLUDouble(PC pc, PetscBLASInt *zero)
{
  PC_MBCMixedLU     *lu = (PC_MBCMixedLU *)pc->data;
  const PetscScalar *a;
  PetscInt           lda;
  PetscBLASInt       info;

  PetscFunctionBegin;
  PetscCall(PetscFree(lu->slu));
  PetscCall(PetscMalloc1((size_t)lu->n * lu->n, &lu->dlu));
  PetscCall(MatDenseGetArrayRead(pc->pmat, &a));
  PetscCall(MatDenseGetLDA(pc->pmat, &lda));
  for (PetscInt c = 0; c < lu->n; c++) PetscCall(PetscArraycpy(lu->dlu + (size_t)c * lu->n, a + (size_t)c * lda, lu->n));
  PetscCall(MatDenseRestoreArrayRead(pc->pmat, &a));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&lu->n, &lu->n, lu->dlu, &lu->n, lu->piv, &info));
  PetscCall(PetscFPTrapPop());
  PetscCheck(info >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK getrf: argument %d illegal", (int)-info);
  lu->doubles++;
  if (info > 0) PetscCall(PetscFree(lu->dlu));
  *zero = info;
  PetscFunctionReturn(0);
}

static PetscErrorCode PCReset_MBCMixedLU(PC pc)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;

  PetscFunctionBegin;
  PetscCall(PetscFree(lu->slu));
  PetscCall(PetscFree(lu->dlu));
  PetscCall(PetscFree3(lu->piv, lu->sw, lu->r));
  lu->n = 0;
  PetscFunctionReturn(0);
}

static PetscErrorCode PCSetUp_MBCMixedLU(PC pc)
{
  PC_MBCMixedLU     *lu = (PC_MBCMixedLU *)pc->data;
  const PetscScalar *a;
  PetscInt           m, n, lda;
  PetscBool          seq, fits = PETSC_TRUE;
  PetscBLASInt       info = 0;
  PetscReal         *rowsum;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc->pmat, MATSEQDENSE, &seq));
  PetscCheck(seq, PetscObjectComm((PetscObject)pc), PETSC_ERR_SUP, "PC %s factors a MATSEQDENSE (one rank), not a %s", PCMBCMIXEDLU, ((PetscObject)pc->pmat)->type_name);
  PetscCall(MatGetSize(pc->pmat, &m, &n));
  PetscCheck(m == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "PC %s needs a square matrix, not %" PetscInt_FMT " x %" PetscInt_FMT, PCMBCMIXEDLU, m, n);
  PetscCall(PCReset_MBCMixedLU(pc));
  PetscCall(PCSetFailedReason(pc, PC_NOERROR)); /* a new factor: a solve of the last one may have failed */
  PetscCall(PetscBLASIntCast(n, &lu->n));
  PetscCall(PetscMalloc3(n + 1, &lu->piv, n + 1, &lu->sw, n + 1, &lu->r));
  PetscCall(PetscMalloc1((size_t)n * n + 1, &lu->slu));
  PetscCall(PetscLogEventBegin(MBC_MixedLUFactor, pc, 0, 0, 0));
  PetscCall(PetscCalloc1(n + 1, &rowsum));
  PetscCall(MatDenseGetArrayRead(pc->pmat, &a));
  PetscCall(MatDenseGetLDA(pc->pmat, &lda));
  for (PetscInt c = 0; c < n; c++)
    for (PetscInt i = 0; i < n; i++) {
      const PetscReal v = PetscRealPart(a[(size_t)c * lda + i]);
      if (!(PetscAbsReal(v) <= FLT_MAX)) fits = PETSC_FALSE; /* also NaN */
      lu->slu[(size_t)c * n + i] = (float)v;
      rowsum[i] += PetscAbsReal(v);
    }
  PetscCall(MatDenseRestoreArrayRead(pc->pmat, &a));
  lu->jnorm = 0;
  for (PetscInt i = 0; i < n; i++) lu->jnorm = PetscMax(lu->jnorm, rowsum[i]);
  PetscCall(PetscFree(rowsum));
  if (fits) {
    PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
    sgetrf_(&lu->n, &lu->n, lu->slu, &lu->n, lu->piv, &info);
    PetscCall(PetscFPTrapPop());
    PetscCheck(info >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK sgetrf: argument %d illegal", (int)-info);
  }
  if (!fits || info > 0) { /* out of single precision's range, or singular in it */
    PetscCall(PetscInfo(pc, "%s single-precision LU of %d rows: %s; factored in double\n", PCMBCMIXEDLU, (int)lu->n, fits ? "a zero pivot" : "entries out of range"));
    PetscCall(MixedLUDouble(pc, &info));
  }
  PetscCall(PetscLogEventEnd(MBC_MixedLUFactor, pc, 0, 0, 0));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_MAT_LU_ZRPVT, "Zero pivot in row %d of the dense LU", (int)info - 1);
  PetscCall(PetscLogFlops(2.0 / 3.0 * n * n * n));
  PetscFunctionReturn(0);
}

static PetscErrorCode PCApply_MBCMixedLU(PC pc, Vec b, Vec x)
{
  PC_MBCMixedLU     *lu  = (PC_MBCMixedLU *)pc->data;
  const PetscBLASInt one = 1;
  const PetscScalar *bv, *a;
  PetscScalar       *xv;
  PetscInt           lda;
  PetscBLASInt       info, ldab;
  PetscReal          rprev = PETSC_MAX_REAL, tol = PETSC_MACHINE_EPSILON * PetscSqrtReal((PetscReal)lu->n) * lu->jnorm;
  PetscBool          done = PETSC_FALSE;
  PetscInt           steps = 0; /* this solve's refinement steps: 4 n^2 flops each */

  PetscFunctionBegin;
  lu->solves++;
  PetscCall(VecGetArrayRead(b, &bv));
  PetscCall(VecGetArrayWrite(x, &xv));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  if (lu->slu) {
    const PetscScalar mone = -1, pone = 1;
    PetscCall(MatDenseGetArrayRead(pc->pmat, &a));
    PetscCall(MatDenseGetLDA(pc->pmat, &lda));
    PetscCall(PetscBLASIntCast(lda, &ldab));
    PetscCall(PetscArrayzero(xv, lu->n));
    PetscCall(PetscArraycpy(lu->r, bv, lu->n));
    for (PetscInt k = 0; k < lu->maxit && !done; k++) {
      PetscReal rn = 0, xn = 0;
      for (PetscInt i = 0; i < lu->n; i++) lu->sw[i] = (float)PetscRealPart(lu->r[i]);
      sgetrs_("N", &lu->n, &one, lu->slu, &lu->n, lu->piv, lu->sw, &lu->n, &info);
      for (PetscInt i = 0; i < lu->n; i++) xv[i] += lu->sw[i];
      PetscCall(PetscArraycpy(lu->r, bv, lu->n)); /* r = b - J x */
      BLASgemv_("N", &lu->n, &lu->n, &mone, a, &ldab, xv, &one, &pone, lu->r, &one);
      steps++;
      for (PetscInt i = 0; i < lu->n; i++) rn = PetscMax(rn, PetscAbsScalar(lu->r[i])), xn = PetscMax(xn, PetscAbsScalar(xv[i]));
      if (rn <= tol * xn) done = PETSC_TRUE;
      else if (!(rn <= 0.5 * rprev)) break; /* stalls (or NaN): cond(J) too large for single precision */
      rprev = rn;
    }
    PetscCall(MatDenseRestoreArrayRead(pc->pmat, &a));
  }
  PetscCall(PetscFPTrapPop());
  lu->steps += steps;
  if (!done) {
    if (lu->slu) {
      PetscCall(PetscInfo(pc, "%s: the refinement of a solve stalled at step %" PetscInt_FMT "; J factored in double\n", PCMBCMIXEDLU, steps));
      PetscCall(MixedLUDouble(pc, &info));
      if (info) PetscCall(PetscInfo(pc, "%s: zero pivot in row %d of the LU in double (not in single precision)\n", PCMBCMIXEDLU, (int)info - 1));
    }
    if (lu->dlu) {
      PetscCall(PetscArraycpy(xv, bv, lu->n));
      PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
      PetscCallBLAS("LAPACKgetrs", LAPACKgetrs_("N", &lu->n, &one, lu->dlu, &lu->n, lu->piv, xv, &lu->n, &info));
      PetscCall(PetscFPTrapPop());
    } else { /* singular in double although not in single: a failed solve, as a singular J is at
                set-up (the Newton step falls back), not an error that ends the run */
      PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
      for (PetscInt i = 0; i < lu->n; i++) xv[i] = PETSC_INFINITY;
    }
  }
  PetscCall(VecRestoreArrayWrite(x, &xv));
  PetscCall(VecRestoreArrayRead(b, &bv));
  PetscCall(PetscLogFlops(4.0 * lu->n * lu->n * steps + (done ? 0.0 : 2.0 * lu->n * lu->n)));
  PetscFunctionReturn(0);
}

static PetscErrorCode PCView_MBCMixedLU(PC pc, PetscViewer viewer)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;
  PetscBool      ascii;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (ascii)
    PetscCall(PetscViewerASCIIPrintf(viewer, "  dense LU in single precision refined in double: %" PetscInt_FMT " solves, %" PetscInt_FMT " refinement steps, %" PetscInt_FMT " factors made in double (refinement stalled)%s\n", lu->solves, lu->steps, lu->doubles, lu->dlu ? "; the current factor is double" : ""));
  PetscFunctionReturn(0);
}

static PetscErrorCode PCSetFromOptions_MBCMixedLU(PC pc, PetscOptionItems *PetscOptionsObject)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "Dense LU in single precision refined in double");
  PetscCall(PetscOptionsInt("-pc_mbcmixedlu_max_it", "Refinement steps of a solve before J is factored in double", "PCMBCMIXEDLU", lu->maxit, &lu->maxit, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(lu->maxit >= 1, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_OUTOFRANGE, "-pc_mbcmixedlu_max_it %" PetscInt_FMT " must be at least 1", lu->maxit);
  PetscFunctionReturn(0);
}

static PetscErrorCode PCDestroy_MBCMixedLU(PC pc)
{
  PetscFunctionBegin;
  PetscCall(PCReset_MBCMixedLU(pc));
  PetscCall(PetscFree(pc->data));
  PetscFunctionReturn(0);
}

PetscErrorCode PCCreate_MBCMixedLU(PC pc)
{
  PC_MBCMixedLU *lu;

  PetscFunctionBegin;
  PetscCall(PetscNew(&lu));
  lu->maxit               = 30; /* dsgesv's ITERMAX */
  pc->data                = lu;
  pc->ops->setup          = PCSetUp_MBCMixedLU;
  pc->ops->apply          = PCApply_MBCMixedLU;
  pc->ops->reset          = PCReset_MBCMixedLU;
  pc->ops->destroy        = PCDestroy_MBCMixedLU;
  pc->ops->view           = PCView_MBCMixedLU;
  pc->ops->setfromoptions = PCSetFromOptions_MBCMixedLU;
  PetscFunctionReturn(0);
}

/*@
  PCMBCMixedLUGetCounts - what the PC did since it was created: solves, refinement steps, and the
  factors it made in double because the refinement stalled or single precision could not hold J
@*/
PetscErrorCode PCMBCMixedLUGetCounts(PC pc, PetscInt *solves, PetscInt *steps, PetscInt *doubles)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;
  PetscBool      is;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMBCMIXEDLU, &is));
  PetscCheck(is, PetscObjectComm((PetscObject)pc), PETSC_ERR_ARG_WRONG, "PC is %s, not %s", ((PetscObject)pc)->type_name, PCMBCMIXEDLU);
  if (solves) *solves = lu->solves;
  if (steps) *steps = lu->steps;
  if (doubles) *doubles = lu->doubles;
  PetscFunctionReturn(0);
}
