/* PCMBCMIXEDLU ("mbcmixedlu"): a dense LU in single precision whose solves are refined in double,
   LAPACK's dsgesv with the factor kept for several solves. On one rank a MATSEQDENSE (LAPACK), on
   several a MATSCALAPACK (ScaLAPACK's psgetrf on its block-cyclic array; the residual by its own
   product, in double).
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
#if defined(PETSC_HAVE_SCALAPACK)
  #include <petsc/private/petscscalapack.h>
PETSC_EXTERN void psgetrf_(const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, PetscBLASInt *, PetscBLASInt *);
PETSC_EXTERN void psgetrs_(const char *, const PetscBLASInt *, const PetscBLASInt *, const float *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, PetscBLASInt *);
#endif

PETSC_EXTERN void sgetrf_(const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, PetscBLASInt *, PetscBLASInt *);
PETSC_EXTERN void sgetrs_(const char *, const PetscBLASInt *, const PetscBLASInt *, const float *, const PetscBLASInt *, const PetscBLASInt *, float *, const PetscBLASInt *, PetscBLASInt *);

PetscLogEvent MBC_MixedLUFactor;

typedef struct {
  PetscBLASInt  n, *piv;
  float        *slu; /* J's single-precision factor (NULL once the double one replaced it) */
  PetscScalar  *dlu; /* J's double factor, made where the refinement failed */
  float        *sw;  /* a right side in single precision */
  Vec           rv, sv; /* the residual, a correction */
  /* on several ranks: slu, dlu and piv are this rank's block-cyclic parts (J's descriptor); a
     right side goes from J's row layout (xdesc) to a column of the process grid (x2desc, x2d) */
  PetscBool     dist;
  PetscBLASInt  xdesc[9], x2desc[9], lszx;
  PetscScalar  *x2d;
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
  PetscCall(PetscFree2(lu->piv, lu->sw));
  PetscCall(PetscFree(lu->x2d));
  PetscCall(VecDestroy(&lu->rv));
  PetscCall(VecDestroy(&lu->sv));
  lu->n    = 0;
  lu->dist = PETSC_FALSE;
  PetscFunctionReturn(0);
}

#if defined(PETSC_HAVE_SCALAPACK)
/* a LAPACK info reduced over the ranks by op (MPI_MIN, MPI_MAX) */
static PetscErrorCode InfoReduce(MPI_Comm comm, MPI_Op op, PetscBLASInt *info)
{
  PetscMPIInt v = (PetscMPIInt)*info;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_INT, op, comm));
  *info = (PetscBLASInt)v;
  PetscFunctionReturn(0);
}

/* J's double factor over the ranks in place of the single one; *zero as MixedLUDouble's */
static PetscErrorCode MixedLUDistDouble(PC pc, PetscBLASInt *zero)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;
  Mat_ScaLAPACK *a  = (Mat_ScaLAPACK *)pc->pmat->data;
  PetscBLASInt   one = 1, info;
  const size_t   nloc = (size_t)a->lld * a->locc;

  PetscFunctionBegin;
  PetscCall(PetscFree(lu->slu));
  PetscCall(PetscMalloc1(nloc + 1, &lu->dlu));
  PetscCall(PetscArraycpy(lu->dlu, a->loc, nloc));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("SCALAPACKgetrf", SCALAPACKgetrf_(&a->M, &a->N, lu->dlu, &one, &one, a->desc, lu->piv, &info));
  PetscCall(PetscFPTrapPop());
  PetscCall(InfoReduce(PetscObjectComm((PetscObject)pc), MPI_MAX, &info));
  lu->doubles++;
  if (info > 0) PetscCall(PetscFree(lu->dlu));
  *zero = info;
  PetscFunctionReturn(0);
}

/* J (MATSCALAPACK) factored over the ranks: ScaLAPACK's psgetrf on a float copy of this rank's
   block-cyclic array, J's own descriptor */
static PetscErrorCode MixedLUDistSetUp(PC pc)
{
  PC_MBCMixedLU  *lu = (PC_MBCMixedLU *)pc->data;
  Mat_ScaLAPACK  *a  = (Mat_ScaLAPACK *)pc->pmat->data;
  MPI_Comm        comm = PetscObjectComm((PetscObject)pc);
  const size_t    nloc = (size_t)a->lld * a->locc;
  const PetscInt *ranges;
  PetscBLASInt    one = 1, zero = 0, nb, xlld, info = 0;
  PetscBool       fits = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCheck(a->M == a->N, comm, PETSC_ERR_ARG_SIZ, "PC %s needs a square matrix, not %d x %d", PCMBCMIXEDLU, (int)a->M, (int)a->N);
  lu->dist = PETSC_TRUE;
  lu->n    = a->M;
  /* a right side: J's rows in blocks of rank 0's count (ScaLAPACK's layout of a MATSCALAPACK's
     vectors), and a column of the process grid */
  PetscCall(PetscLayoutGetRanges(pc->pmat->rmap, &ranges));
  PetscCall(PetscBLASIntCast(ranges[1], &nb));
  xlld = PetscMax(1, pc->pmat->rmap->n);
  PetscCallBLAS("SCALAPACKdescinit", SCALAPACKdescinit_(lu->xdesc, &a->M, &one, &nb, &one, &zero, &zero, &a->grid->ictxcol, &xlld, &info));
  PetscCheckScaLapackInfo("descinit", info);
  lu->lszx = SCALAPACKnumroc_(&a->M, &a->mb, &a->grid->myrow, &a->rsrc, &a->grid->nprow);
  xlld     = PetscMax(1, lu->lszx);
  PetscCallBLAS("SCALAPACKdescinit", SCALAPACKdescinit_(lu->x2desc, &a->M, &one, &a->mb, &one, &zero, &zero, &a->grid->ictxt, &xlld, &info));
  PetscCheckScaLapackInfo("descinit", info);
  PetscCall(PetscMalloc2(a->locr + a->mb, &lu->piv, lu->lszx + 1, &lu->sw));
  PetscCall(PetscMalloc1(lu->lszx + 1, &lu->x2d));
  PetscCall(MatCreateVecs(pc->pmat, &lu->rv, &lu->sv));
  PetscCall(MatNorm(pc->pmat, NORM_INFINITY, &lu->jnorm));
  PetscCall(PetscMalloc1(nloc + 1, &lu->slu));
  PetscCall(PetscLogEventBegin(MBC_MixedLUFactor, pc, 0, 0, 0));
  for (size_t i = 0; i < nloc; i++) {
    const PetscReal v = PetscRealPart(a->loc[i]);
    if (!(PetscAbsReal(v) <= FLT_MAX)) fits = PETSC_FALSE; /* also NaN */
    lu->slu[i] = (float)v;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &fits, 1, MPIU_BOOL, MPI_LAND, comm));
  if (fits) {
    PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
    psgetrf_(&a->M, &a->N, lu->slu, &one, &one, a->desc, lu->piv, &info);
    PetscCall(PetscFPTrapPop());
    PetscCall(InfoReduce(comm, MPI_MIN, &info)); /* an illegal argument first */
    PetscCheck(info >= 0, comm, PETSC_ERR_LIB, "ScaLAPACK psgetrf: argument %d illegal", (int)-info);
    PetscCall(InfoReduce(comm, MPI_MAX, &info));
  }
  if (!fits || info > 0) {
    PetscCall(PetscInfo(pc, "%s single-precision LU of %d rows over the ranks: %s; factored in double\n", PCMBCMIXEDLU, (int)lu->n, fits ? "a zero pivot" : "entries out of range"));
    PetscCall(MixedLUDistDouble(pc, &info));
  }
  PetscCall(PetscLogEventEnd(MBC_MixedLUFactor, pc, 0, 0, 0));
  PetscCheck(!info, comm, PETSC_ERR_MAT_LU_ZRPVT, "Zero pivot in row %d of the dense LU", (int)info - 1);
  PetscCall(PetscLogFlops(2.0 / 3.0 * lu->n * lu->n * lu->n / (a->grid->nprow * a->grid->npcol)));
  PetscFunctionReturn(0);
}

/* out = J^-1 in by the factor held (single or double), in J's row layout */
static PetscErrorCode MixedLUDistSolve(PC pc, Vec in, Vec out)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;
  Mat_ScaLAPACK *a  = (Mat_ScaLAPACK *)pc->pmat->data;
  PetscScalar   *v;
  PetscBLASInt   one = 1, info = 0;

  PetscFunctionBegin;
  PetscCall(VecCopy(in, out));
  PetscCall(VecGetArray(out, &v));
  PetscCallBLAS("SCALAPACKgemr2d", SCALAPACKgemr2d_(&a->M, &one, v, &one, &one, lu->xdesc, lu->x2d, &one, &one, lu->x2desc, &a->grid->ictxcol));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  if (lu->slu) {
    for (PetscBLASInt i = 0; i < lu->lszx; i++) lu->sw[i] = (float)PetscRealPart(lu->x2d[i]);
    psgetrs_("N", &a->M, &one, lu->slu, &one, &one, a->desc, lu->piv, lu->sw, &one, &one, lu->x2desc, &info);
    for (PetscBLASInt i = 0; i < lu->lszx; i++) lu->x2d[i] = lu->sw[i];
  } else PetscCallBLAS("SCALAPACKgetrs", SCALAPACKgetrs_("N", &a->M, &one, lu->dlu, &one, &one, a->desc, lu->piv, lu->x2d, &one, &one, lu->x2desc, &info));
  PetscCall(PetscFPTrapPop());
  PetscCheckScaLapackInfo("getrs", info);
  PetscCallBLAS("SCALAPACKgemr2d", SCALAPACKgemr2d_(&a->M, &one, lu->x2d, &one, &one, lu->x2desc, v, &one, &one, lu->xdesc, &a->grid->ictxcol));
  PetscCall(VecRestoreArray(out, &v));
  PetscFunctionReturn(0);
}

#endif

static PetscErrorCode PCSetUp_MBCMixedLU(PC pc)
{
  PC_MBCMixedLU     *lu = (PC_MBCMixedLU *)pc->data;
  const PetscScalar *a;
  PetscInt           m, n, lda;
  PetscBool          seq, fits = PETSC_TRUE;
  PetscBLASInt       info = 0;
  PetscReal         *rowsum;

  PetscFunctionBegin;
  PetscCall(PCReset_MBCMixedLU(pc));
  PetscCall(PCSetFailedReason(pc, PC_NOERROR)); /* a new factor: a solve of the last one may have failed */
#if defined(PETSC_HAVE_SCALAPACK)
  {
    PetscBool dist;
    PetscCall(PetscObjectTypeCompare((PetscObject)pc->pmat, MATSCALAPACK, &dist));
    if (dist) {
      PetscCall(MixedLUDistSetUp(pc));
      PetscFunctionReturn(0);
    }
  }
#endif
  PetscCall(PetscObjectTypeCompare((PetscObject)pc->pmat, MATSEQDENSE, &seq));
  PetscCheck(seq, PetscObjectComm((PetscObject)pc), PETSC_ERR_SUP, "PC %s factors a MATSEQDENSE (one rank) or a MATSCALAPACK, not a %s", PCMBCMIXEDLU, ((PetscObject)pc->pmat)->type_name);
  PetscCall(MatGetSize(pc->pmat, &m, &n));
  PetscCheck(m == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "PC %s needs a square matrix, not %" PetscInt_FMT " x %" PetscInt_FMT, PCMBCMIXEDLU, m, n);
  PetscCall(PetscBLASIntCast(n, &lu->n));
  PetscCall(PetscMalloc2(n + 1, &lu->piv, n + 1, &lu->sw));
  PetscCall(MatCreateVecs(pc->pmat, &lu->rv, &lu->sv));
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

/* out = J^-1 in by the factor held (single or double) */
static PetscErrorCode MixedLUFactorSolve(PC pc, Vec in, Vec out)
{
  PC_MBCMixedLU     *lu  = (PC_MBCMixedLU *)pc->data;
  const PetscBLASInt one = 1;
  PetscScalar       *v;
  PetscBLASInt       info;

  PetscFunctionBegin;
#if defined(PETSC_HAVE_SCALAPACK)
  if (lu->dist) {
    PetscCall(MixedLUDistSolve(pc, in, out));
    PetscFunctionReturn(0);
  }
#endif
  PetscCall(VecCopy(in, out));
  PetscCall(VecGetArray(out, &v));
  if (lu->slu) {
    for (PetscInt i = 0; i < lu->n; i++) lu->sw[i] = (float)PetscRealPart(v[i]);
    sgetrs_("N", &lu->n, &one, lu->slu, &lu->n, lu->piv, lu->sw, &lu->n, &info);
    for (PetscInt i = 0; i < lu->n; i++) v[i] = lu->sw[i];
  } else PetscCallBLAS("LAPACKgetrs", LAPACKgetrs_("N", &lu->n, &one, lu->dlu, &lu->n, lu->piv, v, &lu->n, &info));
  PetscCall(VecRestoreArray(out, &v));
  PetscFunctionReturn(0);
}

/* x = J^-1 b: x += LU_s^-1 (b - J x) with the residual in double until dsgesv's test holds; where
   that stalls, J factored in double solves; singular in double, a failed solve */
static PetscErrorCode PCApply_MBCMixedLU(PC pc, Vec b, Vec x)
{
  PC_MBCMixedLU *lu = (PC_MBCMixedLU *)pc->data;
  PetscReal      rprev = PETSC_MAX_REAL, tol = PETSC_MACHINE_EPSILON * PetscSqrtReal((PetscReal)lu->n) * lu->jnorm;
  PetscBool      done  = PETSC_FALSE;
  PetscInt       steps = 0; /* this solve's refinement steps */
  PetscBLASInt   info;
  PetscMPIInt    size;

  PetscFunctionBegin;
  lu->solves++;
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  if (lu->slu) {
    PetscCall(VecSet(x, 0));
    PetscCall(VecCopy(b, lu->rv));
    for (PetscInt k = 0; k < lu->maxit && !done; k++) {
      PetscReal rn, xn;
      PetscCall(MixedLUFactorSolve(pc, lu->rv, lu->sv));
      PetscCall(VecAXPY(x, 1.0, lu->sv));
      PetscCall(MatMult(pc->pmat, x, lu->rv)); /* r = b - J x */
      PetscCall(VecAYPX(lu->rv, -1.0, b));
      steps++;
      PetscCall(VecNorm(lu->rv, NORM_INFINITY, &rn));
      PetscCall(VecNorm(x, NORM_INFINITY, &xn));
      if (rn <= tol * xn) done = PETSC_TRUE;
      else if (!(rn <= 0.5 * rprev)) break; /* stalls (or NaN): cond(J) too large for single precision */
      rprev = rn;
    }
  }
  PetscCall(PetscFPTrapPop());
  lu->steps += steps;
  if (!done) {
    if (lu->slu) {
      PetscCall(PetscInfo(pc, "%s: the refinement of a solve stalled at step %" PetscInt_FMT "; J factored in double\n", PCMBCMIXEDLU, steps));
#if defined(PETSC_HAVE_SCALAPACK)
      if (lu->dist) PetscCall(MixedLUDistDouble(pc, &info));
      else
#endif
        PetscCall(MixedLUDouble(pc, &info));
      if (info) PetscCall(PetscInfo(pc, "%s: zero pivot in row %d of the LU in double (not in single precision)\n", PCMBCMIXEDLU, (int)info - 1));
    }
    if (lu->dlu) {
      PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
      PetscCall(MixedLUFactorSolve(pc, b, x));
      PetscCall(PetscFPTrapPop());
    } else { /* singular in double although not in single: a failed solve, as a singular J is at
                set-up (the Newton step falls back), not an error that ends the run */
      PetscCall(PCSetFailedReason(pc, PC_FACTOR_NUMERIC_ZEROPIVOT));
      PetscCall(VecSet(x, PETSC_INFINITY));
    }
  }
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)pc), &size));
  PetscCall(PetscLogFlops(2.0 * lu->n * lu->n * (steps + (done ? 0 : 1)) / size)); /* the triangular solves (MatMult logs its own) */
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
