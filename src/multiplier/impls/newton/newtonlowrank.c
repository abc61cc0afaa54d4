/* The Newton step as a low-rank correction of a kept inverse (W assembled, no equilibrium
   constraints: every dynamic step). While W holds (the pairs do not change, dt is fixed: most of
   an earthquake stage) the Newton matrix of a reference state, J_ref (contacts separated in the
   reference: identity rows; the others sticking: rho W + sigma I, identity rows without
   flexibility), is the same at every Newton step of every time step; its inverse Z is computed
   once the direct steps with this W have cost as much, with the contacts separated then as the
   reference. A
   step's J differs from J_ref only in the rows C of the contacts whose state differs from the
   reference (the tangential rows of a slipping one, whose normal row sticks; every row of one
   separated or closed since): J = J_ref + E_C U^T with
     (U^T x)_r = alpha_r . x_c + beta_r . (W x)_c      (c: the rows of r's contact)
   and Sherman-Morrison-Woodbury gives J^-1 b = Z b - Z E_C M^-1 U^T Z b, M = I + U^T Z E_C: a
   pass over Z, its k = |C| columns, W's k rows and an LU of size k instead of one of the active
   rows ((W Z) on the rows separated in the reference is kept with Z for M). J_ref is diagonal on
   the rows separated in the reference and the frozen ones, so Z is the inverse of the other rows'
   block and a product (ReferenceBlocks), kept on those rows only. The
   step is checked by its residual against J and refined like the direct solve's; where it fails,
   or k is a large part of the active rows, the direct solve runs. A restart restores the
   reference (MBCMultiplierSetRestartState), so that its Z and its steps are the run's own. */
#include "newtonimpl.h"
#include <petscblaslapack.h>
#if defined(PETSC_HAVE_SCALAPACK)
  #include <petsc/private/petscscalapack.h>
PETSC_EXTERN void pdgetri_(const PetscBLASInt *, PetscScalar *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, const PetscBLASInt *, PetscScalar *, const PetscBLASInt *, PetscBLASInt *, const PetscBLASInt *, PetscBLASInt *);
#endif

/* contact i's rows differ from the reference's (its rows are in C) */
static inline PetscBool NewtonRowsDiffer(const MBC_Newton *nt, PetscInt i)
{
  return (PetscBool)(nt->active[i] ? !(nt->sticks[i] && !nt->refopen[i]) : !nt->refopen[i]);
}

/* the reference rows of contact i: row d is alpha . x + beta . (W x) over the contact's rows */
static void NewtonReferenceRow(const MBC_Newton *nt, PetscInt i, PetscInt o, PetscInt d, PetscReal sigma, PetscReal a[3], PetscReal b[3])
{
  for (PetscInt e = 0; e < 3; e++) a[e] = b[e] = 0;
  if (nt->refopen[i]) a[d] = 1;
  else if (nt->frozen[o + d]) a[d] = 1 + sigma;
  else a[d] = sigma, b[d] = nt->rho[2 * i + (d > 0)];
}

/* row d of contact i less its reference row: q[2 + e] on x_e, q[5 + e] on (W x)_e over the contact's
   rows; whether they differ at all (a slipping contact's normal row is the sticking reference's) */
static PetscBool NewtonRowDiff(const MBC_Newton *nt, PetscInt i, PetscInt o, PetscInt dim, PetscInt d, PetscReal sigma, PetscReal q[])
{
  PetscReal a[3], bb[3];
  PetscBool differs = PETSC_FALSE;

  NewtonReferenceRow(nt, i, o, d, sigma, a, bb);
  for (PetscInt e = 0; e < 3; e++) {
    PetscReal ac = 0, bc = 0; /* the current row */
    if (e < dim && nt->active[i]) ac = nt->A[9 * i + dim * d + e] + (d == e ? sigma : 0), bc = nt->B[9 * i + dim * d + e];
    else if (e == d) ac = 1;
    q[2 + e] = e < dim ? ac - a[e] : 0;
    q[5 + e] = e < dim ? bc - bb[e] : 0;
    if (q[2 + e] != 0 || q[5 + e] != 0) differs = PETSC_TRUE;
  }
  q[9] = bb[d];
  return differs;
}

/* B: A's rows (an MPIDense N x N) in another row layout, nl rows on this rank */
static PetscErrorCode DenseRelayout(Mat A, PetscInt nl, Mat *B)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)A);
  PetscInt           N, start = 0;
  IS                 rows, all;
  Mat               *sub;
  const PetscScalar *s;
  PetscScalar       *d;
  PetscInt           lds, ldd;

  PetscFunctionBegin;
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCallMPI(MPI_Exscan(&nl, &start, 1, MPIU_INT, MPI_SUM, comm));
  {
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_rank(comm, &rank));
    if (!rank) start = 0;
  }
  PetscCall(ISCreateStride(PETSC_COMM_SELF, nl, start, 1, &rows));
  PetscCall(ISCreateStride(PETSC_COMM_SELF, N, 0, 1, &all));
  PetscCall(MatCreateSubMatrices(A, 1, &rows, &all, MAT_INITIAL_MATRIX, &sub));
  PetscCall(MatCreateDense(comm, nl, nl, N, N, NULL, B));
  PetscCall(MatDenseGetArrayRead(sub[0], &s));
  PetscCall(MatDenseGetLDA(sub[0], &lds));
  PetscCall(MatDenseGetArrayWrite(*B, &d));
  PetscCall(MatDenseGetLDA(*B, &ldd));
  for (PetscInt c = 0; c < N; c++)
    for (PetscInt r = 0; r < nl; r++) d[c * ldd + r] = s[c * lds + r];
  PetscCall(MatDenseRestoreArrayWrite(*B, &d));
  PetscCall(MatDenseRestoreArrayRead(sub[0], &s));
  PetscCall(MatAssemblyBegin(*B, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*B, MAT_FINAL_ASSEMBLY));
  PetscCall(MatDestroySubMatrices(1, &sub));
  PetscCall(ISDestroy(&rows));
  PetscCall(ISDestroy(&all));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCNewtonRowsAllGather(MPI_Comm comm, PetscInt nl, const PetscInt rows[], PetscInt *n, PetscInt **all, PetscMPIInt **cnt, PetscMPIInt **dsp)
{
  PetscMPIInt size, kl;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMPIIntCast(nl, &kl));
  PetscCall(PetscMalloc2(size, cnt, size + 1, dsp));
  PetscCallMPI(MPI_Allgather(&kl, 1, MPI_INT, *cnt, 1, MPI_INT, comm));
  (*dsp)[0] = 0;
  for (PetscMPIInt p = 0; p < size; p++) (*dsp)[p + 1] = (*dsp)[p] + (*cnt)[p];
  *n = (*dsp)[size];
  PetscCall(PetscMalloc1(*n + 1, all));
  PetscCallMPI(MPI_Allgatherv(rows, kl, MPIU_INT, *all, *cnt, *dsp, MPIU_INT, comm));
  PetscFunctionReturn(0);
}

/* a[0 .. n) summed over the ranks, in place: arrays whose rows each rank filled only where it
   owns them (the others hold zeros there) */
static PetscErrorCode SumOverRanks(MPI_Comm comm, PetscScalar a[], PetscInt64 n)
{
  PetscMPIInt size, nm;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  if (size == 1 || !n) PetscFunctionReturn(0);
  PetscCall(PetscMPIIntCast(n, &nm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, a, nm, MPIU_SCALAR, MPIU_SUM, comm));
  PetscFunctionReturn(0);
}

/* W's rows `rows` (global, the same on every rank), dense on every rank: W is most of the time
   more than half full, and dense products run at BLAS's speed. Each rank writes the rows it owns
   straight from W's and a sum over the ranks completes them (every row has one owner, the others
   add zeros). MatCreateSubMatrices and MatConvert copied them twice: 2.4 s of the 49k dam's 90
   earthquake steps on one rank, 5.6 s on two. */
static PetscErrorCode WRowsDense(Mat W, IS rows, Mat *D)
{
  const PetscInt *idx;
  PetscInt        N, k, lda, rs, re;
  PetscScalar    *d;

  PetscFunctionBegin;
  PetscCall(MatGetSize(W, &N, NULL));
  PetscCall(MatGetOwnershipRange(W, &rs, &re));
  PetscCall(ISGetLocalSize(rows, &k));
  PetscCall(ISGetIndices(rows, &idx));
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, k, N, NULL, D));
  PetscCall(MatDenseGetLDA(*D, &lda));
  PetscCall(MatDenseGetArrayWrite(*D, &d)); /* zeroed by MatSeqDenseSetPreallocation */
  for (PetscInt r = 0; r < k; r++) {
    PetscInt           nc;
    const PetscInt    *cols;
    const PetscScalar *vals;
    if (idx[r] < rs || idx[r] >= re) continue;
    PetscCall(MatGetRow(W, idx[r], &nc, &cols, &vals));
    for (PetscInt j = 0; j < nc; j++) d[(size_t)cols[j] * lda + r] = vals[j];
    PetscCall(MatRestoreRow(W, idx[r], &nc, &cols, &vals));
  }
  PetscCheck(!k || lda == k, PETSC_COMM_SELF, PETSC_ERR_PLIB, "W's rows: a dense leading dimension %" PetscInt_FMT " for %" PetscInt_FMT " rows", lda, k);
  PetscCall(SumOverRanks(PetscObjectComm((PetscObject)W), d, (PetscInt64)k * N));
  PetscCall(MatDenseRestoreArrayWrite(*D, &d));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(MatAssemblyBegin(*D, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*D, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* Z's entries on the rows and columns `rows` (global, the same on every rank), k x k column-major
   on every rank: each rank copies its own rows of Z (its rows S stored by columns, every column on
   every rank; its diagonal on D), a sum over the ranks completes them; MatCreateSubMatrices on the
   MPI dense Z took 4 s of the 49k dam's 90 earthquake steps on two ranks. */
static PetscErrorCode ZRowsCols(const MBC_Newton *nt, IS rows, PetscScalar **zkk)
{
  const PetscInt    *idx;
  const PetscScalar *z;
  PetscInt           k, lda, rs, re, *zr;

  PetscFunctionBegin;
  PetscCall(MatGetOwnershipRangeColumn(nt->Z, &rs, &re)); /* W's rows */
  PetscCall(ISGetLocalSize(rows, &k));
  PetscCall(ISGetIndices(rows, &idx));
  PetscCall(PetscCalloc1((size_t)k * k + 1, zkk));
  PetscCall(MatDenseGetLDA(nt->Z, &lda));
  PetscCall(MatDenseGetArrayRead(nt->Z, &z));
  PetscCall(PetscMalloc1(k + 1, &zr));
  for (PetscInt r = 0; r < k; r++) { /* row r's row of Z; -1: not this rank's, -2: in D (the diagonal) */
    const PetscInt l = idx[r] - rs;
    zr[r]            = idx[r] < rs || idx[r] >= re ? -1 : (nt->zrow[l] < 0 ? -2 : nt->zrow[l]);
    if (zr[r] == -2) (*zkk)[(size_t)r * k + r] = nt->zdinv[l];
  }
  for (PetscInt c = 0; c < k; c++) { /* by Z's columns, each read where it is stored */
    const PetscScalar *zc = z + (size_t)idx[c] * lda;
    PetscScalar       *o  = *zkk + (size_t)c * k;
    for (PetscInt r = 0; r < k; r++)
      if (zr[r] >= 0) o[r] = zc[zr[r]];
  }
  PetscCall(PetscFree(zr));
  PetscCall(MatDenseRestoreArrayRead(nt->Z, &z));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(SumOverRanks(PetscObjectComm((PetscObject)nt->Z), *zkk, (PetscInt64)k * k));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCNewtonLowRankDestroyReference(MBC_Newton *nt)
{
  PetscFunctionBegin;
  PetscCall(MatDestroy(&nt->Z));
  PetscCall(VecDestroy(&nt->zx));
  PetscCall(PetscFree3(nt->zrow, nt->zsloc, nt->zdinv));
  PetscCall(PetscFree3(nt->WZ, nt->oidx, nt->wzcol));
  nt->nO = 0;
  PetscFunctionReturn(0);
}

/* J_ref by blocks: the rows D where it is diagonal (separated in the reference: 1; frozen:
   1 + sigma) and the others S (rho W + sigma I). In the order (D, S)
     J_ref = [D_DD 0; A_SD A_SS],  Z = J_ref^-1 = [D_DD^-1 0; -A_SS^-1 A_SD D_DD^-1  A_SS^-1],
   so Z costs the inverse of A_SS (2 |S|^3) and a product (2 |S|^2 |D|) instead of 2 N^3: in the
   strong shaking a third of the rows and more are separated in the reference. */
typedef struct {
  PetscInt     nlS, nlD, NS, ND;
  PetscInt    *sloc, *dloc; /* this rank's rows of S and D (local indices) */
  PetscInt    *gS, *gD;     /* the global rows of S and D, in that order (rank by rank) */
  PetscMPIInt *cntD, *dspD; /* D's rows per rank */
  PetscReal   *dval;        /* J_ref's diagonal on D, in gD's order */
  Mat          Zss, Zsd;    /* A_SS^-1 and -A_SS^-1 A_SD D_DD^-1, rows S in W's row layout */
} ReferenceBlocks;

static PetscErrorCode ReferenceBlocksDestroy(ReferenceBlocks *rb)
{
  PetscFunctionBegin;
  PetscCall(PetscFree2(rb->sloc, rb->dloc));
  PetscCall(PetscFree2(rb->gS, rb->gD));
  PetscCall(PetscFree3(rb->cntD, rb->dspD, rb->dval));
  PetscCall(MatDestroy(&rb->Zss));
  PetscCall(MatDestroy(&rb->Zsd));
  PetscFunctionReturn(0);
}

/* (W Z)_O, the rows of W Z on the contacts separated in the reference (O within D), on every
   rank: M's rows of the contacts closed since need (W Z)_{pC}, and a product W_{p:} Z_{:C} at
   every step cost more than the step (k ~ 1 500 of 3 384 rows in the 49k dam's strong shaking).
   From Z's blocks, W_O Z = [W_OS Z_SS, W_OS Z_SD + W_OD D_DD^-1]: this rank's rows of S and D,
   then a sum over the ranks; its columns in the order (S, D) (nt->wzcol). */
static PetscErrorCode NewtonLowRankWZ(MBCMultiplier m, const ReferenceBlocks *rb)
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  PetscInt            N, rs, re, nloc = 0, *orow, ldo, c0;
  PetscMPIInt        *cnt, *dsp, rank;
  IS                  isO;
  Mat                 wod = NULL;
  const PetscScalar  *w;
  PetscScalar        *ws = NULL, *wl = NULL; /* wl: W_O on this rank's columns, from W's dense copy */

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(MatGetSize(fp->W, &N, NULL));
  PetscCall(MatGetOwnershipRange(fp->W, &rs, &re));
  PetscCall(PetscMalloc1(fp->off[fp->nc] + 1, &orow));
  for (PetscInt i = 0; i < fp->nc; i++)
    if (nt->refopen[i])
      for (PetscInt d = fp->off[i]; d < fp->off[i + 1]; d++) orow[nloc++] = rs + d;
  {
    PetscInt *all;
    PetscCall(MBCNewtonRowsAllGather(comm, nloc, orow, &nt->nO, &all, &cnt, &dsp));
    PetscCall(PetscMalloc3((size_t)nt->nO * N + 1, &nt->WZ, N + 1, &nt->oidx, N + 1, &nt->wzcol));
    for (PetscInt r = 0; r < N; r++) nt->oidx[r] = -1;
    for (PetscInt o = 0; o < nt->nO; o++) nt->oidx[all[o]] = o;
    for (PetscInt j = 0; j < rb->NS; j++) nt->wzcol[rb->gS[j]] = j;
    for (PetscInt j = 0; j < rb->ND; j++) nt->wzcol[rb->gD[j]] = rb->NS + j;
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nt->nO, all, PETSC_OWN_POINTER, &isO));
  }
  PetscCall(PetscFree2(cnt, dsp));
  PetscCall(PetscFree(orow));
  if (!nt->nO) {
    PetscCall(ISDestroy(&isO));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscArrayzero(nt->WZ, (size_t)nt->nO * N));
  if (nt->Wprod != fp->W) { /* W_O on this rank's columns from the dense copy's rows O there (W
                               symmetric), not W's rows O gathered on every rank (|O| x N, summed) */
    const PetscScalar *a;
    const PetscInt    *oi;
    PetscInt           lda;
    PetscCall(PetscMalloc1((size_t)nt->nO * (re - rs) + 1, &wl));
    PetscCall(MatDenseGetLDA(nt->Wprod, &lda));
    PetscCall(MatDenseGetArrayRead(nt->Wprod, &a));
    PetscCall(ISGetIndices(isO, &oi));
    for (PetscInt o = 0; o < nt->nO; o++)
      for (PetscInt l = 0; l < re - rs; l++) wl[(size_t)l * nt->nO + o] = a[(size_t)oi[o] * lda + l];
    PetscCall(ISRestoreIndices(isO, &oi));
    PetscCall(MatDenseRestoreArrayRead(nt->Wprod, &a));
    w   = wl;
    ldo = nt->nO;
    c0  = 0;
  } else {
    PetscCall(WRowsDense(fp->W, isO, &wod));
    PetscCall(MatDenseGetArrayRead(wod, &w));
    PetscCall(MatDenseGetLDA(wod, &ldo));
    c0 = rs; /* its columns are W's */
  }
  if (rb->nlS) { /* W_OS on this rank's rows of S, times their rows of Z_SS and Z_SD */
    const Mat    zb[2]  = {rb->Zss, rb->Zsd};
    const size_t col[2] = {0, (size_t)rb->NS * nt->nO};
    PetscBLASInt bO, bk, bn, bldz;
    PetscScalar  one = 1, zero = 0;
    PetscCall(PetscMalloc1((size_t)nt->nO * rb->nlS, &ws));
    for (PetscInt s = 0; s < rb->nlS; s++) PetscCall(PetscArraycpy(ws + (size_t)s * nt->nO, w + (size_t)(c0 + rb->sloc[s]) * ldo, nt->nO));
    PetscCall(PetscBLASIntCast(nt->nO, &bO));
    PetscCall(PetscBLASIntCast(rb->nlS, &bk));
    for (PetscInt b = 0; b < 2; b++) {
      const PetscScalar *z;
      PetscInt           lda, n;
      if (!zb[b]) continue;
      PetscCall(MatGetSize(zb[b], NULL, &n));
      PetscCall(MatDenseGetLDA(zb[b], &lda));
      PetscCall(PetscBLASIntCast(n, &bn));
      PetscCall(PetscBLASIntCast(lda, &bldz));
      PetscCall(MatDenseGetArrayRead(zb[b], &z));
      PetscCallBLAS("BLASgemm", BLASgemm_("N", "N", &bO, &bn, &bk, &one, ws, &bO, z, &bldz, &zero, nt->WZ + col[b], &bO));
      PetscCall(MatDenseRestoreArrayRead(zb[b], &z));
    }
    PetscCall(PetscFree(ws));
  }
  for (PetscInt j = 0; j < rb->nlD; j++) { /* W_OD D_DD^-1 on this rank's rows of D */
    const PetscInt     g  = rb->dspD[rank] + j;
    const PetscScalar *wc = w + (size_t)(c0 + rb->dloc[j]) * ldo;
    PetscScalar       *c  = nt->WZ + (size_t)(rb->NS + g) * nt->nO;
    for (PetscInt o = 0; o < nt->nO; o++) c[o] += wc[o] / rb->dval[g];
  }
  if (wod) PetscCall(MatDenseRestoreArrayRead(wod, &w));
  PetscCall(MatDestroy(&wod));
  PetscCall(PetscFree(wl));
  PetscCall(SumOverRanks(comm, nt->WZ, (PetscInt64)nt->nO * N));
  PetscCall(ISDestroy(&isO));
  PetscFunctionReturn(0);
}

/* *Z = J0^-1 in place on one rank (LAPACK getrf + getri: one N x N array); NULL where singular */
static PetscErrorCode InverseLAPACK(Mat *J0, Mat *Z)
{
  PetscScalar *a, *work, wq;
  PetscBLASInt n, lda, *piv, info, lw = -1;
  PetscInt     N, ld;

  PetscFunctionBegin;
  *Z = NULL;
  PetscCall(MatGetSize(*J0, &N, NULL));
  PetscCall(MatDenseGetLDA(*J0, &ld));
  PetscCall(PetscBLASIntCast(N, &n));
  PetscCall(PetscBLASIntCast(ld, &lda));
  PetscCall(MatDenseGetArray(*J0, &a));
  PetscCall(PetscMalloc1(N + 1, &piv));
  PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&n, &n, a, &lda, piv, &info));
  if (!info) {
    PetscCallBLAS("LAPACKgetri", LAPACKgetri_(&n, a, &lda, piv, &wq, &lw, &info));
    PetscCall(PetscBLASIntCast((PetscInt)PetscRealPart(wq), &lw));
    PetscCall(PetscMalloc1(lw + 1, &work));
    PetscCallBLAS("LAPACKgetri", LAPACKgetri_(&n, a, &lda, piv, work, &lw, &info));
    PetscCall(PetscFree(work));
  }
  PetscCall(PetscFree(piv));
  PetscCall(MatDenseRestoreArray(*J0, &a));
  if (!info) {
    *Z  = *J0;
    *J0 = NULL;
  }
  PetscFunctionReturn(0);
}

/* *Z = J0^-1 over the ranks by ScaLAPACK (pdgetrf + pdgetri in place on J0's block-cyclic copy:
   the LU's solve with the identity took 2 N^3 flops and two more N x N arrays), in W's row layout
   (nl rows here); NULL where singular */
static PetscErrorCode InverseScaLAPACK(Mat J0, PetscInt nl, Mat *Z)
{
#if defined(PETSC_HAVE_SCALAPACK)
  MPI_Comm       comm = PetscObjectComm((PetscObject)J0);
  Mat            A, t;
  Mat_ScaLAPACK *a;
  PetscInt       N, nstd = PETSC_DECIDE;
  PetscBLASInt   one = 1, info, lwork = -1, liwork = -1, iwq = 0, *ipiv, *iwork;
  PetscScalar    wq = 0, *work;
  PetscMPIInt    bad;

  PetscFunctionBegin;
  *Z = NULL;
  PetscCall(MatGetSize(J0, &N, NULL));
  PetscCall(PetscSplitOwnership(comm, &nstd, &N)); /* ScaLAPACK from PETSc's own layout (W's may leave ranks without rows) */
  PetscCall(DenseRelayout(J0, nstd, &t));
  PetscCall(MatConvert(t, MATSCALAPACK, MAT_INITIAL_MATRIX, &A));
  PetscCall(MatDestroy(&t));
  a = (Mat_ScaLAPACK *)A->data;
  PetscCall(PetscMalloc1(a->locr + a->mb, &ipiv));
  PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
  PetscCallBLAS("SCALAPACKgetrf", SCALAPACKgetrf_(&a->M, &a->N, a->loc, &one, &one, a->desc, ipiv, &info));
  PetscCall(PetscFPTrapPop());
  bad = info ? 1 : 0; /* info > 0: a zero pivot */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, comm));
  if (!bad) {
    pdgetri_(&a->N, a->loc, &one, &one, a->desc, ipiv, &wq, &lwork, &iwq, &liwork, &info); /* the workspace's size */
    PetscCheckScaLapackInfo("getri", info);
    PetscCall(PetscBLASIntCast((PetscInt)PetscRealPart(wq), &lwork));
    liwork = PetscMax(iwq, 1);
    PetscCall(PetscMalloc2(lwork + 1, &work, liwork + 1, &iwork));
    PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
    pdgetri_(&a->N, a->loc, &one, &one, a->desc, ipiv, work, &lwork, iwork, &liwork, &info);
    PetscCall(PetscFPTrapPop());
    PetscCheckScaLapackInfo("getri", info);
    PetscCall(PetscFree2(work, iwork));
    PetscCall(MatConvert(A, MATDENSE, MAT_INITIAL_MATRIX, &t));
    PetscCall(DenseRelayout(t, nl, Z)); /* back in W's row layout */
    PetscCall(MatDestroy(&t));
  }
  PetscCall(PetscFree(ipiv));
  PetscCall(MatDestroy(&A));
  PetscFunctionReturn(0);
#else
  SETERRQ(PetscObjectComm((PetscObject)J0), PETSC_ERR_SUP, "The kept inverse over several ranks needs ScaLAPACK");
#endif
}

/* Zsd = -Zss B, B = A_SD D_DD^-1 (asd), both with the rows S in W's layout: B's rows gathered on
   every rank (|S| |D| entries, as B^T by columns), then this rank's rows by one GEMM. PETSc's
   MPIDense product ran on one rank (4.4 s against 0.27 on one rank, the 49k dam). */
static PetscErrorCode ZsdProduct(ReferenceBlocks *rb, Mat asd)
{
  MPI_Comm           comm = PetscObjectComm((PetscObject)asd);
  const PetscScalar *a, *zs;
  PetscScalar       *bt, *bl, *zd, mone = -1, zero = 0;
  PetscInt           lda, ldz, ldd;
  PetscMPIInt        size, *cnt, *dsp, nl;
  PetscBLASInt       m, n, k, bldz, bldd;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc2(size, &cnt, size + 1, &dsp));
  PetscCall(PetscMPIIntCast(rb->nlS * rb->ND, &nl));
  PetscCallMPI(MPI_Allgather(&nl, 1, MPI_INT, cnt, 1, MPI_INT, comm));
  dsp[0] = 0;
  for (PetscMPIInt p = 0; p < size; p++) PetscCall(PetscMPIIntCast((PetscInt64)dsp[p] + cnt[p], &dsp[p + 1]));
  PetscCall(PetscMalloc2((size_t)rb->NS * rb->ND + 1, &bt, (size_t)rb->nlS * rb->ND + 1, &bl));
  PetscCall(MatDenseGetLDA(asd, &lda));
  PetscCall(MatDenseGetArrayRead(asd, &a));
  for (PetscInt s = 0; s < rb->nlS; s++)
    for (PetscInt j = 0; j < rb->ND; j++) bl[(size_t)s * rb->ND + j] = a[(size_t)j * lda + s];
  PetscCall(MatDenseRestoreArrayRead(asd, &a));
  PetscCallMPI(MPI_Allgatherv(bl, nl, MPIU_SCALAR, bt, cnt, dsp, MPIU_SCALAR, comm));
  PetscCall(MatCreateDense(comm, rb->nlS, PETSC_DECIDE, rb->NS, rb->ND, NULL, &rb->Zsd));
  if (rb->nlS) {
    PetscCall(MatDenseGetLDA(rb->Zss, &ldz));
    PetscCall(MatDenseGetLDA(rb->Zsd, &ldd));
    PetscCall(PetscBLASIntCast(rb->nlS, &m));
    PetscCall(PetscBLASIntCast(rb->ND, &n));
    PetscCall(PetscBLASIntCast(rb->NS, &k));
    PetscCall(PetscBLASIntCast(ldz, &bldz));
    PetscCall(PetscBLASIntCast(ldd, &bldd));
    PetscCall(MatDenseGetArrayRead(rb->Zss, &zs));
    PetscCall(MatDenseGetArrayWrite(rb->Zsd, &zd));
    PetscCallBLAS("BLASgemm", BLASgemm_("N", "T", &m, &n, &k, &mone, zs, &bldz, bt, &n, &zero, zd, &bldd));
    PetscCall(MatDenseRestoreArrayWrite(rb->Zsd, &zd));
    PetscCall(MatDenseRestoreArrayRead(rb->Zss, &zs));
  }
  PetscCall(MatAssemblyBegin(rb->Zsd, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(rb->Zsd, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree2(bt, bl));
  PetscCall(PetscFree2(cnt, dsp));
  PetscFunctionReturn(0);
}

/* the blocks of J_ref (ReferenceBlocks): its rows split into D and S; A_SS^-1 (Zss) by LAPACK
   (one rank) or ScaLAPACK, and Zsd = -Zss A_SD D_DD^-1; n1 and z1, the 1-norms of J_ref and of Z
   (their columns' sums from the blocks'). Zss NULL where A_SS is singular. */
static PetscErrorCode ReferenceBlocksBuild(MBCMultiplier m, PetscBool scal, ReferenceBlocks *rb, PetscReal *n1, PetscReal *z1)
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  PetscInt            rs, re, nl, *grow, *all;
  PetscReal          *srho, *dl, *cs = NULL, *cd = NULL;
  PetscMPIInt        *cnt, *dsp;
  IS                  isS, isD;
  Mat                 ass, asd = NULL;

  PetscFunctionBegin;
  PetscCall(MatGetOwnershipRange(fp->W, &rs, &re));
  nl = re - rs;
  PetscCall(PetscMalloc2(nl + 1, &rb->sloc, nl + 1, &rb->dloc));
  PetscCall(PetscMalloc3(nl + 1, &grow, nl + 1, &srho, nl + 1, &dl));
  rb->nlS = rb->nlD = 0;
  for (PetscInt i = 0; i < fp->nc; i++)
    for (PetscInt d = fp->off[i]; d < fp->off[i + 1]; d++) {
      if (nt->refopen[i] || nt->frozen[d]) {
        dl[rb->nlD]        = nt->refopen[i] ? 1.0 : 1.0 + nt->zsigma;
        rb->dloc[rb->nlD++] = d;
      } else {
        srho[rb->nlS]       = nt->rho[2 * i + (d > fp->off[i])];
        rb->sloc[rb->nlS++] = d;
      }
    }
  for (PetscInt s = 0; s < rb->nlS; s++) grow[s] = rs + rb->sloc[s];
  PetscCall(MBCNewtonRowsAllGather(comm, rb->nlS, grow, &rb->NS, &rb->gS, &cnt, &dsp));
  PetscCall(ISCreateGeneral(comm, rb->nlS, grow, PETSC_COPY_VALUES, &isS));
  PetscCall(PetscFree2(cnt, dsp));
  for (PetscInt j = 0; j < rb->nlD; j++) grow[j] = rs + rb->dloc[j];
  PetscCall(MBCNewtonRowsAllGather(comm, rb->nlD, grow, &rb->ND, &all, &rb->cntD, &rb->dspD));
  PetscCall(ISCreateGeneral(comm, rb->nlD, grow, PETSC_COPY_VALUES, &isD));
  { /* rb->gD and rb->dval in one allocation pair with gS, cntD/dspD with dval */
    PetscInt    *gS = rb->gS;
    PetscMPIInt *c = rb->cntD, *o = rb->dspD, size;
    PetscCallMPI(MPI_Comm_size(comm, &size));
    PetscCall(PetscMalloc2(rb->NS + 1, &rb->gS, rb->ND + 1, &rb->gD));
    PetscCall(PetscArraycpy(rb->gS, gS, rb->NS));
    PetscCall(PetscArraycpy(rb->gD, all, rb->ND));
    PetscCall(PetscFree(gS));
    PetscCall(PetscFree(all));
    PetscCall(PetscMalloc3(size, &rb->cntD, size + 1, &rb->dspD, rb->ND + 1, &rb->dval));
    PetscCall(PetscArraycpy(rb->cntD, c, size));
    PetscCall(PetscArraycpy(rb->dspD, o, size + 1));
    PetscCall(PetscFree2(c, o));
    PetscCallMPI(MPI_Allgatherv(dl, (PetscMPIInt)rb->nlD, MPIU_REAL, rb->dval, rb->cntD, rb->dspD, MPIU_REAL, comm));
  }
  *n1 = *z1 = 0;
  for (PetscInt j = 0; j < rb->ND; j++) *n1 = PetscMax(*n1, rb->dval[j]), *z1 = PetscMax(*z1, 1 / rb->dval[j]);
  if (rb->NS) {
    Vec r, c;
    PetscCall(MatCreateSubMatrix(fp->W, isS, isS, MAT_INITIAL_MATRIX, &ass));
    PetscCall(MatConvert(ass, MATDENSE, MAT_INPLACE_MATRIX, &ass));
    {
      PetscScalar *rv;
      PetscCall(MatCreateVecs(ass, NULL, &r));
      PetscCall(VecGetArray(r, &rv));
      for (PetscInt s = 0; s < rb->nlS; s++) rv[s] = srho[s];
      PetscCall(VecRestoreArray(r, &rv));
    }
    PetscCall(MatDiagonalScale(ass, r, NULL));
    PetscCall(MatShift(ass, nt->zsigma));
    PetscCall(PetscMalloc2(rb->NS, &cs, rb->ND + 1, &cd));
    PetscCall(MatGetColumnNorms(ass, NORM_1, cs));
    for (PetscInt j = 0; j < rb->NS; j++) *n1 = PetscMax(*n1, cs[j]);
    if (rb->ND) {
      PetscScalar *cv;
      PetscCall(MatCreateSubMatrix(fp->W, isS, isD, MAT_INITIAL_MATRIX, &asd));
      PetscCall(MatConvert(asd, MATDENSE, MAT_INPLACE_MATRIX, &asd));
      PetscCall(MatDiagonalScale(asd, r, NULL));
      PetscCall(MatGetColumnNorms(asd, NORM_1, cd));
      for (PetscInt j = 0; j < rb->ND; j++) *n1 = PetscMax(*n1, rb->dval[j] + cd[j]);
      PetscCall(MatCreateVecs(asd, &c, NULL));
      PetscCall(VecGetArray(c, &cv));
      for (PetscInt j = 0; j < rb->nlD; j++) cv[j] = 1 / dl[j];
      PetscCall(VecRestoreArray(c, &cv));
      PetscCall(MatDiagonalScale(asd, NULL, c));
      PetscCall(VecDestroy(&c));
    }
    PetscCall(VecDestroy(&r));
    if (scal) PetscCall(InverseScaLAPACK(ass, rb->nlS, &rb->Zss));
    else PetscCall(InverseLAPACK(&ass, &rb->Zss)); /* in place: ass NULL where it succeeded */
    PetscCall(MatDestroy(&ass));
    if (rb->Zss) {
      PetscCall(MatGetColumnNorms(rb->Zss, NORM_1, cs));
      for (PetscInt j = 0; j < rb->NS; j++) *z1 = PetscMax(*z1, cs[j]);
      if (asd) {
        PetscCall(ZsdProduct(rb, asd));
        PetscCall(MatGetColumnNorms(rb->Zsd, NORM_1, cd));
        for (PetscInt j = 0; j < rb->ND; j++) *z1 = PetscMax(*z1, 1 / rb->dval[j] + cd[j]);
      }
    }
    PetscCall(MatDestroy(&asd));
    PetscCall(PetscFree2(cs, cd));
  }
  PetscCall(ISDestroy(&isS));
  PetscCall(ISDestroy(&isD));
  PetscCall(PetscFree3(grow, srho, dl));
  PetscFunctionReturn(0);
}

/* the kept inverse from its blocks: Z's rows S (|S| x N, columns in W's numbering) from Z_SS and
   Z_SD, the diagonal D_DD^-1, and the maps between W's local rows and Z's */
static PetscErrorCode ReferenceInverseAssemble(MBC_Newton *nt, Mat W, const ReferenceBlocks *rb)
{
  MPI_Comm     comm = PetscObjectComm((PetscObject)W);
  PetscInt     N, rs, re, lda;
  PetscScalar *z;
  PetscMPIInt  rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(MatGetSize(W, &N, NULL));
  PetscCall(MatGetOwnershipRange(W, &rs, &re));
  PetscCall(MatCreateDense(comm, rb->nlS, re - rs, rb->NS, N, NULL, &nt->Z));
  PetscCall(MatDenseGetLDA(nt->Z, &lda));
  PetscCall(MatDenseGetArrayWrite(nt->Z, &z));
  for (PetscInt b = 0; b < 2; b++) {
    const Mat          zb = b ? rb->Zsd : rb->Zss;
    const PetscInt    *g  = b ? rb->gD : rb->gS;
    const PetscScalar *v;
    PetscInt           n, ldv;
    if (!zb) continue;
    PetscCall(MatGetSize(zb, NULL, &n));
    PetscCall(MatDenseGetLDA(zb, &ldv));
    PetscCall(MatDenseGetArrayRead(zb, &v));
    for (PetscInt j = 0; j < n; j++) PetscCall(PetscArraycpy(z + (size_t)g[j] * lda, v + (size_t)j * ldv, rb->nlS));
    PetscCall(MatDenseRestoreArrayRead(zb, &v));
  }
  PetscCall(MatDenseRestoreArrayWrite(nt->Z, &z));
  PetscCall(MatAssemblyBegin(nt->Z, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(nt->Z, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateVecs(nt->Z, NULL, &nt->zx));
  PetscCall(PetscMalloc3(re - rs + 1, &nt->zrow, rb->nlS + 1, &nt->zsloc, re - rs + 1, &nt->zdinv));
  for (PetscInt s = 0; s < rb->nlS; s++) nt->zrow[rb->sloc[s]] = s, nt->zdinv[rb->sloc[s]] = 0, nt->zsloc[s] = rb->sloc[s];
  for (PetscInt j = 0; j < rb->nlD; j++) nt->zrow[rb->dloc[j]] = -1, nt->zdinv[rb->dloc[j]] = 1 / rb->dval[rb->dspD[rank] + j];
  PetscFunctionReturn(0);
}

/* Z = J_ref^-1 with the reference ref (one value a row, 1: separated; NULL: the current state's
   separated contacts), dense in W's row layout, from its blocks (ReferenceBlocks); NULL where J_ref
   is singular or too badly conditioned for its inverse to carry the step (cond_1 > 1e10). */
static PetscErrorCode NewtonLowRankSetUp(MBCMultiplier m, const PetscScalar ref[])
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  ReferenceBlocks     rb   = {0};
  PetscInt            N, nopen = 0;
  PetscReal           dmax = 0, n1 = 0, z1 = 0;
  PetscBool           scal = (PetscBool)strcmp(nt->densetype, MATDENSE);
  PetscMPIInt         size;

  PetscFunctionBegin;
  PetscCall(MBCNewtonLowRankDestroyReference(nt));
  nt->zbuilt  = PETSC_TRUE;
  nt->zrho    = nt->rho_used;
  nt->zdirect = 0;
  for (PetscInt i = 0; i < fp->nc; i++) nt->refopen[i] = (PetscBool)(ref ? PetscRealPart(ref[fp->off[i]]) > 0.5 : !nt->active[i]);
  PetscCallMPI(MPI_Comm_size(comm, &size));
  if (size > 1 && !scal) PetscFunctionReturn(0); /* no distributed LU to invert with */
  PetscCall(PetscLogEventBegin(MBC_NewtonInverse, m, 0, 0, 0));
  PetscCall(MatGetSize(fp->W, &N, NULL));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt dim = fp->off[i + 1] - fp->off[i];
    nopen += nt->refopen[i];
    for (PetscInt d = 0; d < dim; d++)
      if (!nt->frozen[fp->off[i] + d]) dmax = PetscMax(dmax, PetscAbsReal(nt->rho[2 * i + (d > 0)] * nt->diag[9 * i + (dim + 1) * d]));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nopen, 1, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPIU_REAL, MPIU_MAX, comm));
  nt->zsigma = nt->shift * PetscMax(dmax, 1.0);
  PetscCall(ReferenceBlocksBuild(m, scal, &rb, &n1, &z1));
  if (rb.Zss || !rb.NS) {
    const PetscBool bad = (PetscBool)!(n1 * z1 <= 1e10);
    PetscCall(PetscInfo(m, "Reference Newton matrix %" PetscInt_FMT " (%" PetscInt_FMT " contacts separated): inverted (its %" PetscInt_FMT " rows not diagonal), cond_1 %g%s\n", N, nopen, rb.NS, (double)(n1 * z1), bad ? ": too large, the direct solve instead" : ""));
    if (!bad) {
      PetscCall(ReferenceInverseAssemble(nt, fp->W, &rb));
      PetscCall(NewtonLowRankWZ(m, &rb));
    }
  } else PetscCall(PetscInfo(m, "Reference Newton matrix %" PetscInt_FMT ": singular, the direct solve instead\n", N));
  PetscCall(ReferenceBlocksDestroy(&rb));
  PetscCall(PetscLogEventEnd(MBC_NewtonInverse, m, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* res = b - J x, J at the current iterate (nt->A, B, active) with the shift of J_ref */
static PetscErrorCode NewtonLowRankResidual(MBCMultiplier m, Vec x, Vec b, Vec res)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  const PetscScalar  *xv, *bv, *yv;
  PetscScalar        *rv;

  PetscFunctionBegin;
  PetscCall(MBCNewtonWMult(nt, x, PETSC_FALSE, nt->wdr));
  PetscCall(VecGetArrayRead(x, &xv));
  PetscCall(VecGetArrayRead(b, &bv));
  PetscCall(VecGetArrayRead(nt->wdr, &yv));
  PetscCall(VecGetArray(res, &rv));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    for (PetscInt d = 0; d < dim; d++) {
      PetscReal v = PetscRealPart(xv[o + d]);
      if (nt->active[i]) {
        v *= nt->zsigma;
        for (PetscInt e = 0; e < dim; e++) v += nt->A[9 * i + dim * d + e] * PetscRealPart(xv[o + e]) + nt->B[9 * i + dim * d + e] * PetscRealPart(yv[o + e]);
      }
      rv[o + d] = bv[o + d] - v;
    }
  }
  PetscCall(VecRestoreArray(res, &rv));
  PetscCall(VecRestoreArrayRead(nt->wdr, &yv));
  PetscCall(VecRestoreArrayRead(b, &bv));
  PetscCall(VecRestoreArrayRead(x, &xv));
  PetscFunctionReturn(0);
}

/* the k rows C, the same on every rank */
#define LR_ROW 10 /* reals a row: dim, its position in its contact, alpha (3), beta (3), reference
                     open, the reference's rho (0: open or frozen, its W row is zero) */
typedef struct {
  PetscInt      k;
  PetscInt     *row;   /* global rows, in rank order: every row of the contacts with a row in C (U^T's
                          rows read the whole contact's x and W x) */
  PetscInt      kc, *c; /* the rows C, by their place in row[]: a slipping contact's normal row is the
                          sticking reference's, so a strong phase's M is two thirds the size */
  PetscReal    *pq;    /* LR_ROW a row */
  PetscScalar  *M;     /* M = I + U^T Z E_C (column-major) */
  Mat           Mm;    /* M as a MATSEQDENSE on that array */
  KSP           kM;    /* its LU: single precision's refined in double (PCMBCMIXEDLU) */
  Vec           tb, tx; /* k entries: a right side of M and its solution (M's layout where dist) */
  PetscBool     dist;  /* M factored over the ranks (ScaLAPACK), else on every rank */
  IS            is;    /* row[] */
  Vec           seq;   /* k entries */
  VecScatter    gather;
  Mat           Wc;    /* W's rows C (dense, k x N, on every rank): (W x)_C without a pass over W; NULL
                          where W has a dense copy (WColumnsDot) */
  Vec           all, wc; /* x on every rank; (W x)_C */
  VecScatter    toall;
} LowRank;

/* (W v)_C from W's dense copy: W is symmetric, so its rows C are its columns C, which each rank
   holds for its own rows (contiguous): k dot products and one sum over the ranks, without W's
   rows C gathered on every rank (a k x N copy a step) nor v */
static PetscErrorCode WColumnsDot(Mat Wd, const LowRank *lr, Vec v, Vec wc)
{
  const PetscScalar *a, *x;
  PetscScalar       *t;
  PetscInt           lda, nl;
  PetscBLASInt       n, one = 1;

  PetscFunctionBegin;
  PetscCall(MatDenseGetLDA(Wd, &lda));
  PetscCall(MatDenseGetArrayRead(Wd, &a));
  PetscCall(VecGetLocalSize(v, &nl));
  PetscCall(PetscBLASIntCast(nl, &n));
  PetscCall(VecGetArrayRead(v, &x));
  PetscCall(VecGetArrayWrite(wc, &t));
  for (PetscInt r = 0; r < lr->k; r++) t[r] = n ? BLASdot_(&n, a + (size_t)lr->row[r] * lda, &one, x, &one) : 0;
  PetscCall(SumOverRanks(PetscObjectComm((PetscObject)Wd), t, lr->k));
  PetscCall(VecRestoreArrayWrite(wc, &t));
  PetscCall(VecRestoreArrayRead(v, &x));
  PetscCall(MatDenseRestoreArrayRead(Wd, &a));
  PetscCall(PetscLogFlops(2.0 * lr->k * nl));
  PetscFunctionReturn(0);
}

/* t = U^T v on the rows C, from v and W v on the rows row[], both on every rank */
static PetscErrorCode LowRankApplyU(Mat Wprod, LowRank *lr, Vec v, PetscScalar t[])
{
  const PetscScalar *a;

  PetscFunctionBegin;
  if (!lr->Wc) PetscCall(WColumnsDot(Wprod, lr, v, lr->wc));
  else {
    PetscCall(VecScatterBegin(lr->toall, v, lr->all, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(lr->toall, v, lr->all, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(MatMult(lr->Wc, lr->all, lr->wc));
  }
  PetscCall(VecScatterBegin(lr->gather, v, lr->seq, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(lr->gather, v, lr->seq, INSERT_VALUES, SCATTER_FORWARD));
  for (PetscInt j = 0; j < lr->kc; j++) t[j] = 0;
  for (PetscInt pass = 0; pass < 2; pass++) {
    PetscCall(VecGetArrayRead(pass ? lr->wc : lr->seq, &a));
    for (PetscInt j = 0; j < lr->kc; j++) {
      const PetscInt   r     = lr->c[j];
      const PetscReal *q     = lr->pq + LR_ROW * r;
      const PetscInt   first = r - (PetscInt)q[1];
      for (PetscInt e = 0; e < (PetscInt)q[0]; e++) t[j] += q[2 + 3 * pass + e] * a[first + e];
    }
    PetscCall(VecRestoreArrayRead(pass ? lr->wc : lr->seq, &a));
  }
  PetscFunctionReturn(0);
}

/* x = J^-1 b = v - Z E_C M^-1 U^T v, v = Z b: one pass over Z, and its k columns C (this rank's
   rows of them: Z is stored by columns) for the correction */
static PetscErrorCode NewtonLowRankApply(MBCMultiplier m, LowRank *lr, Vec b, Vec x)
{
  MBC_Newton        *nt = (MBC_Newton *)m->data;
  PetscScalar       *t, *xv;
  const PetscScalar *z, *tv;
  PetscBLASInt       k;
  PetscInt           nl, lda, nS, rs;

  PetscFunctionBegin;
  { /* x = Z b: Z's rows S, the diagonal on D */
    const PetscScalar *bv, *sv;
    PetscScalar       *xv;
    PetscCall(MatMult(nt->Z, b, nt->zx));
    PetscCall(VecGetLocalSize(nt->zx, &nS));
    PetscCall(VecGetLocalSize(x, &nl));
    PetscCall(VecGetArrayRead(b, &bv));
    PetscCall(VecGetArrayRead(nt->zx, &sv));
    PetscCall(VecGetArray(x, &xv));
    for (PetscInt i = 0; i < nl; i++) xv[i] = nt->zdinv[i] * bv[i];
    for (PetscInt s = 0; s < nS; s++) xv[nt->zsloc[s]] = sv[s];
    PetscCall(VecRestoreArray(x, &xv));
    PetscCall(VecRestoreArrayRead(nt->zx, &sv));
    PetscCall(VecRestoreArrayRead(b, &bv));
  }
  PetscCall(PetscBLASIntCast(lr->kc, &k));
  if (k) {
    KSPConvergedReason reason;
    PetscCall(PetscMalloc1(lr->kc, &t));
    PetscCall(LowRankApplyU(nt->Wprod, lr, x, t));
    if (lr->dist) { /* t's share in, the solution gathered on every rank */
      const PetscInt *ranges;
      PetscMPIInt     size, *cnt, *dsp;
      PetscScalar    *bv;
      PetscInt        rs, re;
      PetscCall(VecGetOwnershipRange(lr->tb, &rs, &re));
      PetscCall(VecGetArrayWrite(lr->tb, &bv));
      PetscCall(PetscArraycpy(bv, t + rs, re - rs));
      PetscCall(VecRestoreArrayWrite(lr->tb, &bv));
      PetscCall(KSPSolve(lr->kM, lr->tb, lr->tx));
      PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)lr->tx), &size));
      PetscCall(VecGetOwnershipRanges(lr->tx, &ranges));
      PetscCall(PetscMalloc2(size, &cnt, size, &dsp));
      for (PetscMPIInt p = 0; p < size; p++) {
        PetscCall(PetscMPIIntCast(ranges[p + 1] - ranges[p], &cnt[p]));
        PetscCall(PetscMPIIntCast(ranges[p], &dsp[p]));
      }
      PetscCall(VecGetArrayRead(lr->tx, &tv));
      PetscCallMPI(MPI_Allgatherv(tv, (PetscMPIInt)(re - rs), MPIU_SCALAR, t, cnt, dsp, MPIU_SCALAR, PetscObjectComm((PetscObject)lr->tx)));
      PetscCall(VecRestoreArrayRead(lr->tx, &tv));
      PetscCall(PetscFree2(cnt, dsp));
    } else {
      PetscCall(VecPlaceArray(lr->tb, t));
      PetscCall(KSPSolve(lr->kM, lr->tb, lr->tx));
      PetscCall(VecResetArray(lr->tb));
      PetscCall(VecGetArrayRead(lr->tx, &tv));
      PetscCall(PetscArraycpy(t, tv, lr->kc));
      PetscCall(VecRestoreArrayRead(lr->tx, &tv));
    }
    PetscCall(KSPGetConvergedReason(lr->kM, &reason));
    PetscCheck(reason >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "The kept inverse's %d x %d correction: its LU failed in a solve (%s)", (int)k, (int)k, KSPConvergedReasons[reason]);
    PetscCall(MatDenseGetLDA(nt->Z, &lda));
    PetscCall(MatDenseGetArrayRead(nt->Z, &z));
    PetscCall(MatGetLocalSize(nt->Z, &nS, NULL));
    PetscCall(MatGetOwnershipRangeColumn(nt->Z, &rs, NULL));
    PetscCall(VecGetArray(x, &xv));
    for (PetscInt j = 0; j < lr->kc; j++) { /* Z's column of C's row j: on S, and its diagonal on D */
      const PetscInt     row = lr->row[lr->c[j]];
      const PetscScalar *zc  = z + row * lda;
      const PetscInt     l   = row - rs;
      for (PetscInt s = 0; s < nS; s++) xv[nt->zsloc[s]] -= zc[s] * t[j];
      if (l >= 0 && l < nl && nt->zrow[l] < 0) xv[l] -= nt->zdinv[l] * t[j];
    }
    PetscCall(VecRestoreArray(x, &xv));
    PetscCall(MatDenseRestoreArrayRead(nt->Z, &z));
    PetscCall(PetscFree(t));
  }
  { /* the separated rows' x = b exactly, as the direct solve's: their multipliers end at 0, not
       at rounding (a point with a force of 1e-15 is reported in contact) */
    MBCFrictionProblem *fp = m->fp;
    const PetscScalar  *bv;
    PetscScalar        *xv;
    PetscCall(VecGetArrayRead(b, &bv));
    PetscCall(VecGetArray(x, &xv));
    for (PetscInt i = 0; i < fp->nc; i++)
      if (!nt->active[i])
        for (PetscInt d = fp->off[i]; d < fp->off[i + 1]; d++) xv[d] = bv[d];
    PetscCall(VecRestoreArray(x, &xv));
    PetscCall(VecRestoreArrayRead(b, &bv));
  }
  PetscFunctionReturn(0);
}

#if defined(PETSC_HAVE_SCALAPACK)
/* *A: the k x k column-major array a, the same on every rank, as a MATSCALAPACK on comm (each rank
   takes its block-cyclic entries) */
static PetscErrorCode ReplicatedToScaLAPACK(MPI_Comm comm, PetscInt k, const PetscScalar a[], Mat *A)
{
  Mat_ScaLAPACK      *s;
  Mat_ScaLAPACK_Grid *g;

  PetscFunctionBegin;
  PetscCall(MatCreateScaLAPACK(comm, PETSC_DECIDE, PETSC_DECIDE, k, k, 0, 0, A)); /* its own row layout */
  s = (Mat_ScaLAPACK *)(*A)->data;
  g = s->grid;
  for (PetscBLASInt lj = 0; lj < s->locc; lj++) {
    const PetscInt gj = ((PetscInt)(lj / s->nb) * g->npcol + (g->mycol - s->csrc + g->npcol) % g->npcol) * s->nb + lj % s->nb;
    for (PetscBLASInt li = 0; li < s->locr; li++) {
      const PetscInt gi = ((PetscInt)(li / s->mb) * g->nprow + (g->myrow - s->rsrc + g->nprow) % g->nprow) * s->mb + li % s->mb;
      s->loc[li + (size_t)lj * s->lld] = a[(size_t)gj * k + gi];
    }
  }
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}
#else
static PetscErrorCode ReplicatedToScaLAPACK(MPI_Comm comm, PetscInt k, const PetscScalar a[], Mat *A)
{
  PetscFunctionBegin;
  SETERRQ(comm, PETSC_ERR_SUP, "Needs ScaLAPACK");
}
#endif

/* M = I + U^T Z E_C, factored on every rank: Z_CC gathered; (W Z)_CC from J_ref Z = I on the
   rows of contacts sticking in the reference, from (W Z)_O (NewtonLowRankWZ) on the others'
   (closed since). Also W's rows C (WRowsDense) for U^T, where W has no dense copy. */
static PetscErrorCode NewtonLowRankFactor(MBCMultiplier m, LowRank *lr, PetscBLASInt *info)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  PetscScalar        *z;
  const PetscInt      lda = lr->k;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_NewtonLowRankFactor, m, 0, 0, 0));
  PetscCall(ZRowsCols(nt, lr->is, &z));
  if (nt->Wprod == fp->W) PetscCall(WRowsDense(fp->W, lr->is, &lr->Wc));
  PetscCall(PetscMalloc1(lr->kc * lr->kc, &lr->M));
  for (PetscInt jc = 0; jc < lr->kc; jc++)
    for (PetscInt jr = 0; jr < lr->kc; jr++) {
      const PetscInt   c = lr->c[jc], r = lr->c[jr]; /* their places in row[] (Z's entries z) */
      const PetscReal *q     = lr->pq + LR_ROW * r;
      const PetscInt   first = r - (PetscInt)q[1];
      PetscScalar      v     = jr == jc ? 1 : 0;
      for (PetscInt e = 0; e < (PetscInt)q[0]; e++) {
        const PetscInt  p    = first + e; /* a row of the same contact */
        const PetscReal beta = q[5 + e];
        PetscScalar     wzpc = 0;
        v += q[2 + e] * z[c * lda + p];
        if (beta == 0) continue;
        if (lr->pq[LR_ROW * p + 8] > 0.5) {
          const PetscInt o = nt->oidx[lr->row[p]];
          PetscCheck(o >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Row %" PetscInt_FMT " separated in the reference is not among (W Z)_O's", lr->row[p]);
          wzpc = nt->WZ[(size_t)nt->wzcol[lr->row[c]] * nt->nO + o];
        } else if (lr->pq[LR_ROW * p + 9] > 0) wzpc = ((p == c ? 1 : 0) - nt->zsigma * z[c * lda + p]) / lr->pq[LR_ROW * p + 9]; /* rho_p (W Z)_p + sigma Z_p = e_p */
        v += beta * wzpc;
      }
      lr->M[jc * lr->kc + jr] = v;
    }
  PetscCall(PetscFree(z));
  { /* M's LU in single precision, refined in double: half the time of getrf where k reaches the
       thousands (the strong phase); the same answers (the PC's solves have double's backward
       error). Singular in double: the direct solve instead. */
    PC             pc;
    PetscErrorCode ierr;
    PetscMPIInt    size;
    PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)m), &size));
#if defined(PETSC_HAVE_SCALAPACK)
    lr->dist = (PetscBool)(size > 1 && lr->kc >= nt->lowrank_dist_min && strcmp(nt->densetype, MATDENSE));
#endif
    if (lr->dist) {
      PetscCall(ReplicatedToScaLAPACK(PetscObjectComm((PetscObject)m), lr->kc, lr->M, &lr->Mm));
      PetscCall(KSPCreate(PetscObjectComm((PetscObject)m), &lr->kM));
      PetscCall(MatCreateVecs(lr->Mm, &lr->tx, &lr->tb));
    } else {
      PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, lr->kc, lr->kc, lr->M, &lr->Mm));
      PetscCall(KSPCreate(PETSC_COMM_SELF, &lr->kM));
      PetscCall(MatCreateVecs(lr->Mm, &lr->tx, NULL));
      PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, lr->kc, NULL, &lr->tb));
    }
    PetscCall(KSPSetType(lr->kM, KSPPREONLY));
    PetscCall(KSPGetPC(lr->kM, &pc));
    PetscCall(PCSetType(pc, PCMBCMIXEDLU));
    PetscCall(KSPSetOperators(lr->kM, lr->Mm, lr->Mm));
    PetscCall(KSPSetErrorIfNotConverged(lr->kM, PETSC_FALSE));
    PetscCall(PetscLogEventDeactivatePush(MBC_MixedLUFactor)); /* that event counts the direct steps' LUs */
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = KSPSetUp(lr->kM);
    PetscCall(PetscPopErrorHandler());
    PetscCall(PetscLogEventDeactivatePop(MBC_MixedLUFactor));
    PetscCheck(!ierr || ierr == PETSC_ERR_MAT_LU_ZRPVT, PETSC_COMM_SELF, ierr, "The kept inverse's correction: its LU failed");
    PetscCall(PetscBLASIntCast(ierr ? 1 : 0, info));
  }
  PetscCall(PetscLogEventEnd(MBC_NewtonLowRankFactor, m, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* k[0]: the rows that differ from the reference (C), k[1]: the active rows, k[2]: the rows that
   would differ from a reference taken now (the tangential rows of the active contacts not
   sticking); over all ranks */
static PetscErrorCode NewtonLowRankCount(MBCMultiplier m, PetscInt k[3])
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;

  PetscFunctionBegin;
  k[0] = k[1] = k[2] = 0;
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    if (nt->active[i]) k[1] += dim;
    if (nt->active[i] && !nt->sticks[i]) k[2] += dim - 1; /* its normal row sticks */
    if (NewtonRowsDiffer(nt, i))
      for (PetscInt d = 0; d < dim; d++) {
        PetscReal q[LR_ROW];
        k[0] += NewtonRowDiff(nt, i, o, dim, d, nt->zsigma, q);
      }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, k, 3, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)m)));
  PetscFunctionReturn(0);
}

/* Z's cost in LUs of the active rows: getrf + getri, 2 N^3, against 2/3 n^3 */
static PetscReal NewtonInverseCost(PetscInt N, PetscInt n)
{
  return 3 * PetscPowReal((PetscReal)N / (PetscReal)n, 3);
}

/* A restart's state (MBCMultiplierSetRestartState), at the first step with the W it was given
   for: the direct steps taken, and Z with the run's reference where the run had built it */
static PetscErrorCode NewtonLowRankRestore(MBCMultiplier m)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  PetscBool           built;

  PetscFunctionBegin;
  if (!nt->refW) PetscFunctionReturn(0);
  if (nt->refW == fp->W) {
    const PetscScalar *a;
    PetscCall(VecGetArrayRead(nt->refpending, &a));
    built = (PetscBool)(fp->nc && PetscRealPart(a[0]) >= 0);
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &built, 1, MPIU_BOOL, MPI_LOR, PetscObjectComm((PetscObject)m)));
    if (built) PetscCall(NewtonLowRankSetUp(m, a));
    nt->zdirect = nt->zdirectpending;
    PetscCall(VecRestoreArrayRead(nt->refpending, &a));
  }
  PetscCall(VecDestroy(&nt->refpending));
  PetscCall(MatDestroy(&nt->refW));
  PetscFunctionReturn(0);
}

/* The step dr = J^-1 (-phi) on every row, where it pays and succeeds: *done */
PetscErrorCode MBCNewtonLowRankStep(MBCMultiplier m, PetscBool *done)
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  PetscMPIInt         size, *cnt, *dsp, kl;
  PetscInt            nloc = 0, kA[3], rs, *lrow, N;
  PetscReal          *lpq, sigma, b0 = 0, r0 = 0, r1;
  PetscInt            refined = 0;
  PetscBool           wdr_valid = PETSC_TRUE;
  LowRank             lr = {0};
  Vec                 b, res, dx;
  PetscBLASInt        info = 0;

  PetscFunctionBegin;
  *done = PETSC_FALSE;
  if (!nt->lowrank || fp->G || fp->Winv) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(MBC_NewtonLowRank, m, 0, 0, 0));
  PetscCall(NewtonLowRankRestore(m));
  PetscCall(MatGetSize(fp->W, &N, NULL));
  if (!nt->zbuilt) { /* build Z once the direct steps with this W have cost what it does: a whole
                        stage then pays it back many times, a W that serves a few steps (a static
                        load step) costs at most twice its direct steps */
    PetscCall(NewtonLowRankCount(m, kA));
    if (kA[1] && nt->zdirect >= NewtonInverseCost(N, kA[1])) PetscCall(NewtonLowRankSetUp(m, NULL));
    else {
      if (kA[1]) nt->zdirect++;
      PetscCall(PetscLogEventEnd(MBC_NewtonLowRank, m, 0, 0, 0));
      PetscFunctionReturn(0);
    }
  }
  if (!nt->Z || nt->zrho != nt->rho_used) {
    PetscCall(PetscLogEventEnd(MBC_NewtonLowRank, m, 0, 0, 0));
    PetscFunctionReturn(0);
  }
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(MatGetOwnershipRange(fp->W, &rs, NULL));
  PetscCall(NewtonLowRankCount(m, kA));
  if (kA[0] > nt->lowrank_max * kA[1] && kA[2] <= 0.5 * nt->lowrank_max * kA[1] && kA[1] && nt->zdirect >= NewtonInverseCost(N, kA[1])) {
    /* the state has drifted from the reference, and a new one would serve: by the same rule */
    PetscCall(PetscInfo(m, "Newton step: %" PetscInt_FMT " rows differ from the kept inverse's after %" PetscInt_FMT " direct steps: a new reference\n", kA[0], nt->zdirect));
    PetscCall(NewtonLowRankSetUp(m, NULL));
    PetscCall(NewtonLowRankCount(m, kA));
    if (!nt->Z) {
      PetscCall(PetscLogEventEnd(MBC_NewtonLowRank, m, 0, 0, 0));
      PetscFunctionReturn(0);
    }
  }
  if (!kA[1] || kA[0] > nt->lowrank_max * kA[1]) { /* an LU of the active rows is not much dearer */
    nt->zdirect++;
    PetscCall(PetscInfo(m, "Newton step: %" PetscInt_FMT " rows differ from the kept inverse's, of %" PetscInt_FMT " active: the direct solve\n", kA[0], kA[1]));
    PetscCall(PetscLogEventEnd(MBC_NewtonLowRank, m, 0, 0, 0));
    PetscFunctionReturn(0);
  }
  sigma = nt->zsigma;
  PetscCall(PetscMalloc2(fp->off[fp->nc] + 1, &lrow, LR_ROW * (fp->off[fp->nc] + 1), &lpq));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    if (!NewtonRowsDiffer(nt, i)) continue;
    for (PetscInt d = 0; d < dim; d++, nloc++) {
      PetscReal *q = lpq + LR_ROW * nloc;
      lrow[nloc]   = NewtonRowDiff(nt, i, o, dim, d, sigma, q) ? rs + o + d : -(rs + o + d) - 1; /* < 0: not in C */
      q[0]         = dim;
      q[1]         = d;
      q[8]         = nt->refopen[i];
    }
  }
  PetscCall(PetscMPIIntCast(nloc, &kl));
  PetscCall(MBCNewtonRowsAllGather(comm, nloc, lrow, &lr.k, &lr.row, &cnt, &dsp));
  PetscCall(PetscMalloc1(LR_ROW * (lr.k + 1), &lr.pq));
  for (PetscMPIInt p = 0; p < size; p++) cnt[p] *= LR_ROW, dsp[p] *= LR_ROW;
  PetscCallMPI(MPI_Allgatherv(lpq, LR_ROW * kl, MPIU_REAL, lr.pq, cnt, dsp, MPIU_REAL, comm));
  PetscCall(PetscFree2(cnt, dsp));
  PetscCall(PetscFree2(lrow, lpq));
  PetscCall(PetscMalloc1(lr.k + 1, &lr.c));
  for (PetscInt r = 0; r < lr.k; r++) {
    if (lr.row[r] >= 0) lr.c[lr.kc++] = r;
    else lr.row[r] = -lr.row[r] - 1;
  }
  PetscCall(MatCreateVecs(fp->W, &b, NULL));
  PetscCall(VecDuplicate(b, &res));
  PetscCall(VecDuplicate(b, &dx));
  if (lr.kc) {
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, lr.k, lr.row, PETSC_USE_POINTER, &lr.is));
    PetscCall(VecCreateSeq(PETSC_COMM_SELF, lr.k, &lr.seq));
    PetscCall(VecScatterCreate(b, lr.is, lr.seq, NULL, &lr.gather));
    if (nt->Wprod == fp->W) PetscCall(VecScatterCreateToAll(b, &lr.toall, &lr.all));
    PetscCall(VecDuplicate(lr.seq, &lr.wc));
    PetscCall(NewtonLowRankFactor(m, &lr, &info)); /* every rank factors the same M: the same info */
  }
  if (!info) {
    PetscCall(VecCopy(nt->phi, b));
    PetscCall(VecScale(b, -1.0));
    PetscCall(NewtonLowRankApply(m, &lr, b, nt->dr));
    PetscCall(VecNorm(b, NORM_2, &b0));
    PetscCall(NewtonLowRankResidual(m, nt->dr, b, res));
    PetscCall(VecNorm(res, NORM_2, &r0));
    for (PetscInt it = 0; it < 2 && r0 > 1e-12 * b0; it++) { /* refinement, as the direct solve's */
      PetscCall(NewtonLowRankApply(m, &lr, res, dx));
      PetscCall(VecAXPY(nt->dr, 1.0, dx));
      PetscCall(NewtonLowRankResidual(m, nt->dr, b, res));
      PetscCall(VecNorm(res, NORM_2, &r1));
      if (!(r1 < 0.5 * r0)) {
        PetscCall(VecAXPY(nt->dr, -1.0, dx));
        wdr_valid = PETSC_FALSE;
        break;
      }
      r0 = r1;
      refined++;
    }
    *done = (PetscBool)(r0 <= 1e-8 * b0);
    PetscInt closed = 0; /* rows separated in the reference, active now */
    for (PetscInt j = 0; j < lr.kc; j++) closed += lr.pq[LR_ROW * lr.c[j] + 8] > 0.5;
    PetscCall(PetscInfo(m, "Newton step by the kept inverse: %" PetscInt_FMT " rows differ of %" PetscInt_FMT " active (%" PetscInt_FMT " closed since), residual %g of the right side after %" PetscInt_FMT " refinements%s\n", lr.kc, kA[1], closed, (double)(b0 > 0 ? r0 / b0 : 0), refined, *done ? "" : ": the direct solve instead"));
  } else PetscCall(PetscInfo(m, "Newton step by the kept inverse: its %" PetscInt_FMT " x %" PetscInt_FMT " correction singular, the direct solve instead\n", lr.kc, lr.kc));
  if (*done) nt->lowranks++;
  nt->wdr_of_dr = (PetscBool)(*done && wdr_valid); /* the residual's W dr serves the line search */
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&res));
  PetscCall(VecDestroy(&dx));
  PetscCall(VecScatterDestroy(&lr.gather));
  PetscCall(VecDestroy(&lr.seq));
  PetscCall(VecScatterDestroy(&lr.toall));
  PetscCall(VecDestroy(&lr.all));
  PetscCall(VecDestroy(&lr.wc));
  PetscCall(MatDestroy(&lr.Wc));
  PetscCall(ISDestroy(&lr.is));
  PetscCall(KSPDestroy(&lr.kM));
  PetscCall(MatDestroy(&lr.Mm));
  PetscCall(VecDestroy(&lr.tb));
  PetscCall(VecDestroy(&lr.tx));
  PetscCall(PetscFree(lr.M));
  PetscCall(PetscFree(lr.row));
  PetscCall(PetscFree(lr.c));
  PetscCall(PetscFree(lr.pq));
  PetscCall(PetscLogEventEnd(MBC_NewtonLowRank, m, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* the reference of Z, one value a row (1: the contact separated in it; -1: no Z yet), and the
   direct steps since W or Z (when one pays), for a restart */
static PetscErrorCode MBCMultiplierGetRestartState_Newton(MBCMultiplier m, Vec s, PetscInt *count, PetscBool *has)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  PetscScalar        *a;

  PetscFunctionBegin;
  *has   = (PetscBool)(nt->zbuilt || nt->zdirect);
  *count = nt->zdirect;
  if (!*has) PetscFunctionReturn(0);
  PetscCall(VecGetArray(s, &a));
  for (PetscInt i = 0; i < fp->nc; i++)
    for (PetscInt d = fp->off[i]; d < fp->off[i + 1]; d++) a[d] = !nt->zbuilt ? -1 : nt->refopen[i] ? 1 : 0;
  PetscCall(VecRestoreArray(s, &a));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierSetRestartState_Newton(MBCMultiplier m, Vec s, PetscInt count)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  PetscCheck(m->fp && m->fp->W, PetscObjectComm((PetscObject)m), PETSC_ERR_ORDER, "MBCMultiplierSetProblem() first");
  PetscCall(VecDestroy(&nt->refpending));
  PetscCall(MatDestroy(&nt->refW));
  PetscCall(VecDuplicate(s, &nt->refpending));
  PetscCall(VecCopy(s, nt->refpending));
  PetscCall(PetscObjectReference((PetscObject)m->fp->W));
  nt->refW           = m->fp->W;
  nt->zdirectpending = count;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCNewtonLowRankCompose(MBCMultiplier m)
{
  PetscFunctionBegin;
  PetscCall(PetscObjectComposeFunction((PetscObject)m, "MBCMultiplierGetRestartState_C", MBCMultiplierGetRestartState_Newton));
  PetscCall(PetscObjectComposeFunction((PetscObject)m, "MBCMultiplierSetRestartState_C", MBCMultiplierSetRestartState_Newton));
  PetscFunctionReturn(0);
}
