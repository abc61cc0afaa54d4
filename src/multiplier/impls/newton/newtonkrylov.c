/* The Newton step of the newton type when W is a shell (the matrix-free D, -mbc_d_route matfree):
   W_AA has no entries to factor, so the system
     [A + B W_AA, B G_A^T; G_A, 0] [dr_A; dalpha] = b
   is solved by right-preconditioned GMRES (prefix -mbc_newton_mf_), one product with W (a solve
   per body) per iteration. The preconditioner takes W_AA^-1 ~ K = (Winv)_AA, FETI's lumped
   approximation (sparse), so J = A + B W_AA ~ (A K + B) K^-1 and
     P_J^-1 = K (A K + B)^-1,
   a sparse LU of A K + B (the type's KSP, MUMPS); for sticking contacts (A = 0) it is the lumped
   preconditioner K B^-1. Rows without flexibility (A = I, B = 0, K's row and column 0) get 1 on
   K's diagonal, so P_J^-1 is the identity there as J is. With equilibrium constraints the
   preconditioner is the constraint one,
     P^-1 [x; y] = [P_J^-1 x - Z s; s],  s = S^-1 (G_A P_J^-1 x - y),  Z = P_J^-1 B G_A^T,  S = G_A Z,
   with S (rigid modes x rigid modes) dense on every rank: the step then meets G dr = e - G r to
   GMRES's tolerance. */
#include "newtonimpl.h"
#include <petscblaslapack.h>

typedef struct {
  MBCMultiplier m;
  IS            isA;
  PetscInt      nA, ng;
  PetscMPIInt   last;     /* the rank holding the rigid modes' rows (G's row layout) */
  Mat           K;        /* (Winv)_AA, 1 on the rows without flexibility */
  Vec           vfull, wfull; /* W's layout */
  Vec           xA, yA, tA; /* nA on this rank */
  Vec           galpha;   /* G's row layout */
  Vec          *Z;        /* ng columns P_J^-1 B G_A^T */
  PetscScalar  *S;        /* ng x ng, LU-factored (getrf) */
  PetscBLASInt *piv;
  PetscInt      nco, nloc; /* the coarse space (fp->nco columns; 0: none), J's local rows */
  PetscInt      ncs;      /* E's size: nco, or nco + ng with the rigid modes */
  PetscInt     *acol;     /* per active local row: its column of Phi (-1: none) */
  PetscReal    *aw;       /*   and its value */
  PetscScalar  *JG;       /* nA x ng: J's rigid-mode columns on the active rows, B (G^T e_t)_A */
  PetscScalar  *GPhi;     /* ng x nco on the last rank: J's rigid-mode rows on Phi_A, G_A Phi_A */
  PetscScalar  *wc;       /* W's local rows: W Phi c */
  PetscScalar  *E;        /* ncs x ncs: the coarse matrix, LU-factored (getrf), on every rank */
  PetscBLASInt *cpiv;
  PetscScalar  *c;        /* ncs */
  Vec           xw;       /* J's layout: work */
} NewtonKrylov;

/* Rows [0, nA) of the J-layout array a into/from the W-layout vector v (active rows only). */
static PetscErrorCode ActiveToFull(NewtonKrylov *nk, const PetscScalar *a, Vec v)
{
  const PetscInt *rows;
  PetscInt        rs;
  PetscScalar    *va;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(v));
  PetscCall(VecGetOwnershipRange(v, &rs, NULL));
  PetscCall(ISGetIndices(nk->isA, &rows));
  PetscCall(VecGetArray(v, &va));
  for (PetscInt k = 0; k < nk->nA; k++) va[rows[k] - rs] = a[k];
  PetscCall(VecRestoreArray(v, &va));
  PetscCall(ISRestoreIndices(nk->isA, &rows));
  PetscFunctionReturn(0);
}

static PetscErrorCode FullToActive(NewtonKrylov *nk, Vec v, PetscScalar *a)
{
  const PetscInt    *rows;
  PetscInt           rs;
  const PetscScalar *va;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(v, &rs, NULL));
  PetscCall(ISGetIndices(nk->isA, &rows));
  PetscCall(VecGetArrayRead(v, &va));
  for (PetscInt k = 0; k < nk->nA; k++) a[k] = va[rows[k] - rs];
  PetscCall(VecRestoreArrayRead(v, &va));
  PetscCall(ISRestoreIndices(nk->isA, &rows));
  PetscFunctionReturn(0);
}

/* The ng entries of G's row layout (on the last rank) to every rank. */
static PetscErrorCode RigidToAll(NewtonKrylov *nk, Vec g, PetscScalar out[])
{
  PetscMPIInt rank;
  MPI_Comm    comm = PetscObjectComm((PetscObject)nk->m);

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == nk->last) {
    const PetscScalar *ga;
    PetscCall(VecGetArrayRead(g, &ga));
    PetscCall(PetscArraycpy(out, ga, nk->ng));
    PetscCall(VecRestoreArrayRead(g, &ga));
  }
  PetscCallMPI(MPI_Bcast(out, (PetscMPIInt)nk->ng, MPIU_SCALAR, nk->last, comm));
  PetscFunctionReturn(0);
}

/* y = J x: per active contact A x + B (W x + G^T alpha), then the rows G_A x. */
static PetscErrorCode NewtonKrylovMult(Mat J, Vec x, Vec y)
{
  NewtonKrylov       *nk;
  MBC_Newton         *nt;
  MBCFrictionProblem *fp;
  const PetscScalar  *xa, *wa;
  PetscScalar        *ya;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(J, &nk));
  nt = (MBC_Newton *)nk->m->data;
  fp = nk->m->fp;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(ActiveToFull(nk, xa, nk->vfull));
  PetscCall(MatMult(fp->W, nk->vfull, nk->wfull));
  if (fp->G) {
    PetscScalar *ga;
    PetscInt     n;
    PetscCall(VecGetLocalSize(nk->galpha, &n));
    PetscCall(VecGetArray(nk->galpha, &ga));
    PetscCall(PetscArraycpy(ga, xa + nk->nA, n));
    PetscCall(VecRestoreArray(nk->galpha, &ga));
    PetscCall(MatMultTransposeAdd(fp->G, nk->galpha, nk->wfull, nk->wfull));
  }
  PetscCall(VecGetArrayRead(nk->wfull, &wa));
  PetscCall(VecGetArray(y, &ya));
  for (PetscInt i = 0, k = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    if (!nt->active[i]) continue;
    for (PetscInt d = 0; d < dim; d++) {
      PetscScalar v = 0;
      for (PetscInt e = 0; e < dim; e++) v += nt->A[9 * i + dim * d + e] * xa[k + e] + nt->B[9 * i + dim * d + e] * wa[o + e];
      ya[k + d] = v;
    }
    k += dim;
  }
  PetscCall(VecRestoreArrayRead(nk->wfull, &wa));
  if (fp->G) { /* G_A x into the tail */
    const PetscScalar *ga;
    PetscInt           n;
    PetscCall(MatMult(fp->G, nk->vfull, nk->galpha));
    PetscCall(VecGetLocalSize(nk->galpha, &n));
    PetscCall(VecGetArrayRead(nk->galpha, &ga));
    PetscCall(PetscArraycpy(ya + nk->nA, ga, n));
    PetscCall(VecRestoreArrayRead(nk->galpha, &ga));
  }
  PetscCall(VecRestoreArray(y, &ya));
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscFunctionReturn(0);
}

/* yA = P_J^-1 xA = K (A K + B)^-1 xA */
static PetscErrorCode ApplyPJ(NewtonKrylov *nk, Vec xA, Vec yA)
{
  MBC_Newton *nt = (MBC_Newton *)nk->m->data;

  PetscFunctionBegin;
  PetscCall(KSPSolve(nt->ksp, xA, nk->tA));
  PetscCall(MatMult(nk->K, nk->tA, yA));
  PetscFunctionReturn(0);
}

/* y = P^-1 x, the lumped (and rigid-mode constraint) preconditioner */
static PetscErrorCode NewtonKrylovPCApplyFine(NewtonKrylov *nk, Vec x, Vec y)
{
  const PetscScalar *xa;
  PetscScalar       *ya, *s = NULL;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(VecPlaceArray(nk->xA, xa));
  PetscCall(ApplyPJ(nk, nk->xA, nk->yA));
  PetscCall(VecResetArray(nk->xA));
  if (nk->ng) { /* s = S^-1 (G_A z - y) */
    const PetscScalar *za;
    PetscBLASInt       n, one = 1, info;
    PetscCall(PetscMalloc1(nk->ng, &s));
    PetscCall(VecGetArrayRead(nk->yA, &za));
    PetscCall(ActiveToFull(nk, za, nk->vfull));
    PetscCall(VecRestoreArrayRead(nk->yA, &za));
    PetscCall(MatMult(nk->m->fp->G, nk->vfull, nk->galpha));
    {
      PetscInt n0;
      PetscScalar *ga;
      PetscCall(VecGetLocalSize(nk->galpha, &n0));
      PetscCall(VecGetArray(nk->galpha, &ga));
      for (PetscInt j = 0; j < n0; j++) ga[j] -= xa[nk->nA + j];
      PetscCall(VecRestoreArray(nk->galpha, &ga));
    }
    PetscCall(RigidToAll(nk, nk->galpha, s));
    PetscCall(PetscBLASIntCast(nk->ng, &n));
    PetscCallBLAS("LAPACKgetrs", LAPACKgetrs_("N", &n, &one, nk->S, &n, nk->piv, s, &n, &info));
    for (PetscInt j = 0; j < nk->ng; j++) PetscCall(VecAXPY(nk->yA, -s[j], nk->Z[j]));
  }
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscCall(VecGetArray(y, &ya));
  {
    const PetscScalar *za;
    PetscInt           n;
    PetscCall(VecGetArrayRead(nk->yA, &za));
    PetscCall(PetscArraycpy(ya, za, nk->nA));
    PetscCall(VecRestoreArrayRead(nk->yA, &za));
    PetscCall(VecGetLocalSize(y, &n));
    for (PetscInt j = nk->nA; j < n; j++) ya[j] = s[j - nk->nA]; /* the tail: the last rank's, all ng */
  }
  PetscCall(VecRestoreArray(y, &ya));
  PetscCall(PetscFree(s));
  PetscFunctionReturn(0);
}

/* K = (Winv)_AA with 1 on the rows without flexibility; then A K + B, factored by the type's KSP. */
static PetscErrorCode NewtonKrylovSetUpPJ(NewtonKrylov *nk)
{
  MBCMultiplier       m  = nk->m;
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  Mat                 Ab, Bb, M;
  PetscInt            rs;

  PetscFunctionBegin;
  PetscCall(MatCreateSubMatrix(fp->Winv, nk->isA, nk->isA, MAT_INITIAL_MATRIX, &nk->K));
  PetscCall(MatGetOwnershipRange(nk->K, &rs, NULL));
  PetscCall(MatSetOption(nk->K, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(MatCreateAIJ(comm, nk->nA, nk->nA, PETSC_DETERMINE, PETSC_DETERMINE, 3, NULL, 0, NULL, &Ab));
  PetscCall(MatCreateAIJ(comm, nk->nA, nk->nA, PETSC_DETERMINE, PETSC_DETERMINE, 3, NULL, 0, NULL, &Bb));
  for (PetscInt i = 0, k = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    PetscInt       idx[3];
    if (!nt->active[i]) continue;
    for (PetscInt d = 0; d < dim; d++) idx[d] = rs + k + d;
    PetscCall(MatSetValues(Ab, dim, idx, dim, idx, nt->A + 9 * i, INSERT_VALUES));
    PetscCall(MatSetValues(Bb, dim, idx, dim, idx, nt->B + 9 * i, INSERT_VALUES));
    for (PetscInt d = 0; d < dim; d++)
      if (nt->frozen[o + d]) PetscCall(MatSetValue(nk->K, idx[d], idx[d], 1.0, INSERT_VALUES));
    k += dim;
  }
  PetscCall(MatAssemblyBegin(nk->K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(nk->K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(Ab, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Ab, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(Bb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Bb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatMatMult(Ab, nk->K, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &M));
  PetscCall(MatAXPY(M, 1.0, Bb, DIFFERENT_NONZERO_PATTERN));
  PetscCall(MatDestroy(&Ab));
  PetscCall(MatDestroy(&Bb));
  PetscCall(KSPReset(nt->ksp));
  PetscCall(KSPSetOperators(nt->ksp, M, M));
  PetscCall(MatDestroy(&M));
  PetscCall(KSPSetUp(nt->ksp));
  nt->factors++;
  PetscCall(ISDestroy(&nt->isbuilt)); /* no direct factor of J is kept */
  PetscFunctionReturn(0);
}

/* za (nA) = B (G^T e_j)_A: the active rows of J's column for rigid mode j. */
static PetscErrorCode RigidColumn(NewtonKrylov *nk, PetscInt j, PetscScalar za[])
{
  MBC_Newton         *nt = (MBC_Newton *)nk->m->data;
  MBCFrictionProblem *fp = nk->m->fp;
  PetscInt            gs, ge;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(nk->galpha));
  PetscCall(VecGetOwnershipRange(nk->galpha, &gs, &ge));
  if (j >= gs && j < ge) PetscCall(VecSetValue(nk->galpha, j, 1.0, INSERT_VALUES));
  PetscCall(VecAssemblyBegin(nk->galpha));
  PetscCall(VecAssemblyEnd(nk->galpha));
  PetscCall(MatMultTranspose(fp->G, nk->galpha, nk->wfull)); /* G^T e_j */
  PetscCall(FullToActive(nk, nk->wfull, za));
  for (PetscInt i = 0, k = 0; i < fp->nc; i++) { /* B (G^T e_j)_A, in place */
    const PetscInt dim = fp->off[i + 1] - fp->off[i];
    PetscScalar    t[3];
    if (!nt->active[i]) continue;
    for (PetscInt d = 0; d < dim; d++) {
      t[d] = 0;
      for (PetscInt e = 0; e < dim; e++) t[d] += nt->B[9 * i + dim * d + e] * za[k + e];
    }
    for (PetscInt d = 0; d < dim; d++) za[k + d] = t[d];
    k += dim;
  }
  PetscFunctionReturn(0);
}

/* Z = P_J^-1 B G_A^T and S = G_A Z, LU-factored (a small shift if it is singular). */
static PetscErrorCode NewtonKrylovSetUpRigid(NewtonKrylov *nk)
{
  MBCMultiplier       m  = nk->m;
  MBCFrictionProblem *fp = m->fp;
  const PetscInt      ng = nk->ng;
  PetscBLASInt        n, info;
  PetscReal           smax = 0;

  PetscFunctionBegin;
  PetscCall(VecDuplicateVecs(nk->xA, ng, &nk->Z));
  PetscCall(PetscMalloc2(ng * ng, &nk->S, ng, &nk->piv));
  for (PetscInt j = 0; j < ng; j++) {
    PetscScalar *za, *col;
    PetscCall(VecGetArray(nk->xA, &za));
    PetscCall(RigidColumn(nk, j, za));
    PetscCall(VecRestoreArray(nk->xA, &za));
    PetscCall(ApplyPJ(nk, nk->xA, nk->Z[j]));
    PetscCall(VecGetArray(nk->Z[j], &za));
    PetscCall(ActiveToFull(nk, za, nk->vfull));
    PetscCall(VecRestoreArray(nk->Z[j], &za));
    PetscCall(MatMult(fp->G, nk->vfull, nk->galpha));
    col = nk->S + j * ng;
    PetscCall(RigidToAll(nk, nk->galpha, col));
    for (PetscInt i = 0; i < ng; i++) smax = PetscMax(smax, PetscAbsScalar(col[i]));
  }
  PetscCall(PetscBLASIntCast(ng, &n));
  {
    PetscScalar *S0;
    PetscCall(PetscMalloc1(ng * ng, &S0));
    PetscCall(PetscArraycpy(S0, nk->S, ng * ng));
    PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&n, &n, nk->S, &n, nk->piv, &info));
    if (info > 0) { /* a mode the active contacts do not resist: S singular; shifted, the
                       preconditioner stays defined and GMRES finds what the system allows */
      PetscCall(PetscInfo(m, "Rigid-mode Schur complement singular (getrf %d): shifted\n", (int)info));
      PetscCall(PetscArraycpy(nk->S, S0, ng * ng));
      for (PetscInt i = 0; i < ng; i++) nk->S[i + i * ng] += 1e-12 * (smax > 0 ? smax : 1);
      PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&n, &n, nk->S, &n, nk->piv, &info));
    }
    PetscCall(PetscFree(S0));
  }
  PetscFunctionReturn(0);
}

/* xa -= J [Phi_A c; a] with [c; a] = nk->c: J Phi_A c = A Phi_A c + B (W Phi c)_A from the stored
   W Phi (one dense product, no solve), the rigid modes' columns and rows from JG and GPhi. */
static PetscErrorCode CoarseResidual(NewtonKrylov *nk, PetscScalar xa[])
{
  MBC_Newton         *nt = (MBC_Newton *)nk->m->data;
  MBCFrictionProblem *fp = nk->m->fp;
  const PetscInt      nco = nk->nco, ngc = nk->ncs - nk->nco;
  const PetscScalar  *wphi;
  PetscInt            ldw, mloc;
  PetscBLASInt        bm, bn, bld, one = 1;
  PetscScalar         zero = 0, pone = 1;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(fp->WPhi, &mloc, NULL));
  PetscCall(MatDenseGetArrayRead(fp->WPhi, &wphi));
  PetscCall(MatDenseGetLDA(fp->WPhi, &ldw));
  PetscCall(PetscBLASIntCast(mloc, &bm));
  PetscCall(PetscBLASIntCast(nco, &bn));
  PetscCall(PetscBLASIntCast(PetscMax(ldw, 1), &bld));
  if (bm) PetscCallBLAS("BLASgemv", BLASgemv_("N", &bm, &bn, &pone, wphi, &bld, nk->c, &one, &zero, nk->wc, &one));
  PetscCall(MatDenseRestoreArrayRead(fp->WPhi, &wphi));
  for (PetscInt i = 0, k = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    if (!nt->active[i]) continue;
    for (PetscInt d = 0; d < dim; d++) {
      PetscScalar v = 0;
      for (PetscInt e = 0; e < dim; e++) {
        v += nt->B[9 * i + dim * d + e] * nk->wc[o + e];
        if (nk->acol[k + e] >= 0) v += nt->A[9 * i + dim * d + e] * nk->aw[k + e] * nk->c[nk->acol[k + e]];
      }
      for (PetscInt t = 0; t < ngc; t++) v += nk->JG[(k + d) + (size_t)nk->nA * t] * nk->c[nco + t];
      xa[k + d] -= v;
    }
    k += dim;
  }
  for (PetscInt t = 0; ngc && t < nk->nloc - nk->nA; t++) /* the rigid modes' rows (the last rank) */
    for (PetscInt j = 0; j < nco; j++) xa[nk->nA + t] -= nk->GPhi[t + (size_t)nk->ng * j] * nk->c[j];
  PetscFunctionReturn(0);
}

/* With the coarse space: [c; a] = E^-1 [Phi_A^T x_r; x_g] (x_r the contacts' rows, x_g the rigid
   modes'), then y = P^-1 (x - J [Phi_A c; a]) + [Phi_A c; a]; without, P^-1 x. A fixed linear map
   either way, as right-preconditioned GMRES needs. */
static PetscErrorCode NewtonKrylovPCApply(PC pc, Vec x, Vec y)
{
  NewtonKrylov *nk;
  PetscScalar  *xa, *ya;
  PetscBLASInt  n, one = 1, info;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &nk));
  if (!nk->nco) {
    PetscCall(NewtonKrylovPCApplyFine(nk, x, y));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscArrayzero(nk->c, nk->ncs));
  PetscCall(VecCopy(x, nk->xw));
  PetscCall(VecGetArray(nk->xw, &xa));
  for (PetscInt k = 0; k < nk->nA; k++)
    if (nk->acol[k] >= 0) nk->c[nk->acol[k]] += nk->aw[k] * xa[k];
  for (PetscInt t = 0; nk->ncs > nk->nco && t < nk->nloc - nk->nA; t++) nk->c[nk->nco + t] = xa[nk->nA + t]; /* the rigid modes' rows: the last rank's */
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nk->c, (PetscMPIInt)nk->ncs, MPIU_SCALAR, MPIU_SUM, PetscObjectComm((PetscObject)nk->m)));
  PetscCall(PetscBLASIntCast(nk->ncs, &n));
  PetscCallBLAS("LAPACKgetrs", LAPACKgetrs_("N", &n, &one, nk->E, &n, nk->cpiv, nk->c, &n, &info));
  PetscCall(CoarseResidual(nk, xa));
  PetscCall(VecRestoreArray(nk->xw, &xa));
  PetscCall(NewtonKrylovPCApplyFine(nk, nk->xw, y));
  PetscCall(VecGetArray(y, &ya));
  for (PetscInt k = 0; k < nk->nA; k++)
    if (nk->acol[k] >= 0) ya[k] += nk->aw[k] * nk->c[nk->acol[k]];
  for (PetscInt t = 0; nk->ncs > nk->nco && t < nk->nloc - nk->nA; t++) ya[nk->nA + t] += nk->c[nk->nco + t];
  PetscCall(VecRestoreArray(y, &ya));
  PetscFunctionReturn(0);
}

/* E = R^T J R with R = [Phi_A, 0; 0, I] (the coarse space and the rigid modes), LU-factored on every
   rank (withrigid false: R = Phi_A). J R is formed a contact's rows at a time from W Phi and
   summed into E, never stored (it would be as large as W Phi: 0.7 GB for the 1M dam). */
static PetscErrorCode CoarseMatrix(NewtonKrylov *nk, PetscBool withrigid, PetscBLASInt *info)
{
  MBC_Newton         *nt  = (MBC_Newton *)nk->m->data;
  MBCFrictionProblem *fp  = nk->m->fp;
  const PetscInt      ncs = nk->nco + (withrigid ? nk->ng : 0), nco = nk->nco;
  const PetscScalar  *wphi;
  PetscScalar        *row;
  PetscReal          *wsum;
  PetscInt            ldw;
  PetscBLASInt        n;
  PetscMPIInt         rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(PetscObjectComm((PetscObject)nk->m), &rank));
  nk->ncs = ncs;
  PetscCall(PetscArrayzero(nk->E, (size_t)ncs * ncs));
  PetscCall(PetscCalloc1(nco + 1, &wsum));
  PetscCall(PetscMalloc1(ncs + 1, &row));
  PetscCall(MatDenseGetArrayRead(fp->WPhi, &wphi));
  PetscCall(MatDenseGetLDA(fp->WPhi, &ldw));
  for (PetscInt i = 0, k = 0; i < fp->nc; i++) { /* row k + d of J R: A Phi_A + B (W Phi), then the rigid columns */
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    if (!nt->active[i]) continue;
    for (PetscInt d = 0; d < dim; d++) {
      const PetscInt l = nk->acol[k + d];
      if (l < 0) continue;
      PetscCall(PetscArrayzero(row, ncs));
      for (PetscInt e = 0; e < dim; e++) {
        const PetscReal b = nt->B[9 * i + dim * d + e], a = nt->A[9 * i + dim * d + e];
        if (b != 0)
          for (PetscInt j = 0; j < nco; j++) row[j] += b * wphi[(o + e) + (size_t)ldw * j];
        if (a != 0 && nk->acol[k + e] >= 0) row[nk->acol[k + e]] += a * nk->aw[k + e];
      }
      for (PetscInt t = nco; t < ncs; t++) row[t] = nk->JG[(k + d) + (size_t)nk->nA * (t - nco)];
      wsum[l] += nk->aw[k + d] * nk->aw[k + d];
      for (PetscInt j = 0; j < ncs; j++) nk->E[l + (size_t)ncs * j] += nk->aw[k + d] * row[j];
    }
    k += dim;
  }
  PetscCall(MatDenseRestoreArrayRead(fp->WPhi, &wphi));
  PetscCall(PetscFree(row));
  if (withrigid && rank == nk->last)
    for (PetscInt t = 0; t < nk->ng; t++)
      for (PetscInt j = 0; j < nco; j++) nk->E[(nco + t) + (size_t)ncs * j] += nk->GPhi[t + (size_t)nk->ng * j];
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nk->E, (PetscMPIInt)(ncs * ncs), MPIU_SCALAR, MPIU_SUM, PetscObjectComm((PetscObject)nk->m)));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, wsum, (PetscMPIInt)nco, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)nk->m)));
  for (PetscInt l = 0; l < nco; l++)
    if (wsum[l] == 0) { /* a column with no active row: its c stays 0 */
      for (PetscInt j = 0; j < ncs; j++) nk->E[l + (size_t)ncs * j] = nk->E[j + (size_t)ncs * l] = 0;
      nk->E[l + (size_t)ncs * l] = 1;
    }
  PetscCall(PetscFree(wsum));
  PetscCall(PetscBLASIntCast(ncs, &n));
  PetscCallBLAS("LAPACKgetrf", LAPACKgetrf_(&n, &n, nk->E, &n, nk->cpiv, info));
  if (!*info) { /* numerically singular too (fewer patches than the free bodies' rigid modes leave
                   E's zero block rank-deficient, and rounding hides the zero pivot: the correction
                   then ruined the Krylov steps, 100 iterations without convergence) */
    PetscReal umax = 0, umin = PETSC_MAX_REAL;
    for (PetscInt i = 0; i < ncs; i++) {
      const PetscReal u = PetscAbsScalar(nk->E[i + (size_t)ncs * i]);
      umax = PetscMax(umax, u), umin = PetscMin(umin, u);
    }
    if (!(umin > 1e-12 * umax)) *info = -1;
  }
  PetscFunctionReturn(0);
}

/* The coarse space for this Newton step: J's rigid-mode rows and columns on it, and E
   (CoarseMatrix). J Phi_A comes from the interface's W Phi, no product: Phi's columns include the
   inactive rows there, so where a patch has separated points it is an approximation, which only
   weakens the correction. */
static PetscErrorCode NewtonKrylovSetUpCoarse(NewtonKrylov *nk)
{
  MBCMultiplier       m   = nk->m;
  MBCFrictionProblem *fp  = m->fp;
  const PetscInt      nco = fp->nco, ntot = fp->nco + nk->ng;
  const PetscInt     *rows;
  PetscInt            rs, mloc;
  PetscBLASInt        info;

  PetscFunctionBegin;
  nk->nco = nco;
  PetscCall(MatGetLocalSize(fp->WPhi, &mloc, NULL));
  PetscCall(PetscMalloc5(nk->nA + 1, &nk->acol, nk->nA + 1, &nk->aw, (size_t)ntot * ntot, &nk->E, ntot, &nk->cpiv, mloc + 1, &nk->wc));
  PetscCall(PetscMalloc3(ntot, &nk->c, (size_t)nk->nA * nk->ng + 1, &nk->JG, (size_t)nk->ng * nco + 1, &nk->GPhi));
  PetscCall(VecGetOwnershipRange(nk->vfull, &rs, NULL));
  PetscCall(ISGetIndices(nk->isA, &rows));
  for (PetscInt k = 0; k < nk->nA; k++) nk->acol[k] = fp->cocol[rows[k] - rs], nk->aw[k] = fp->cow[rows[k] - rs];
  PetscCall(ISRestoreIndices(nk->isA, &rows));
  if (nk->ng) {
    PetscScalar *a;
    PetscCall(PetscArrayzero(nk->GPhi, (size_t)nk->ng * nco));
    for (PetscInt j = 0; j < nco; j++) { /* the rigid modes' rows: G_A Phi_A (G's rows on the last rank) */
      const PetscScalar *ga;
      PetscInt           ng;
      PetscCall(VecGetArray(nk->xA, &a));
      for (PetscInt k = 0; k < nk->nA; k++) a[k] = nk->acol[k] == j ? nk->aw[k] : 0.0;
      PetscCall(ActiveToFull(nk, a, nk->vfull));
      PetscCall(VecRestoreArray(nk->xA, &a));
      PetscCall(MatMult(fp->G, nk->vfull, nk->galpha));
      PetscCall(VecGetLocalSize(nk->galpha, &ng));
      PetscCall(VecGetArrayRead(nk->galpha, &ga));
      for (PetscInt t = 0; t < ng; t++) nk->GPhi[t + (size_t)nk->ng * j] = ga[t];
      PetscCall(VecRestoreArrayRead(nk->galpha, &ga));
    }
    for (PetscInt t = 0; t < nk->ng; t++) { /* the rigid modes' columns: B (G^T e_t)_A */
      PetscCall(VecGetArray(nk->xA, &a));
      PetscCall(RigidColumn(nk, t, a));
      PetscCall(PetscArraycpy(nk->JG + (size_t)nk->nA * t, a, nk->nA));
      PetscCall(VecRestoreArray(nk->xA, &a));
    }
  }
  PetscCall(CoarseMatrix(nk, (PetscBool)(nk->ng > 0), &info));
  if (info) { /* singular (too few patches to balance the free bodies' modes): no correction this
                 step; without the rigid modes in E, the correction fought the fine constraint
                 preconditioner (the small static dam: 27 Krylov iterations became 32 to 41) */
    PetscCall(PetscInfo(m, "Coarse matrix singular (getrf %d, -1: a pivot below 1e-12 of the largest): no coarse correction\n", (int)info));
    nk->nco = 0;
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCNewtonKrylovSolve(MBCMultiplier m, IS isA, PetscInt nA, Vec b, Vec x, KSPConvergedReason *reason)
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  NewtonKrylov        nk;
  PetscMPIInt         size;
  PetscInt            nloc, N, its;
  Mat                 J;
  PC                  pc;

  PetscFunctionBegin;
  {
    PetscInt NA;
    PetscCall(MPIU_Allreduce(&nA, &NA, 1, MPIU_INT, MPI_SUM, comm));
    if (!NA) { /* only the rigid modes' rows, with nothing to move them: no step (as the direct solve's singular factor) */
      *reason = KSP_DIVERGED_PC_FAILED;
      PetscFunctionReturn(0);
    }
  }
  PetscCall(PetscMemzero(&nk, sizeof(nk)));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  nk.m    = m;
  nk.isA  = isA;
  nk.nA   = nA;
  nk.last = size - 1;
  if (fp->G) PetscCall(MatGetSize(fp->G, &nk.ng, NULL));
  PetscCall(VecGetLocalSize(b, &nloc));
  PetscCall(VecGetSize(b, &N));
  PetscCall(MatCreateVecs(fp->W, &nk.vfull, &nk.wfull));
  PetscCall(VecCreateMPI(comm, nA, PETSC_DETERMINE, &nk.xA));
  PetscCall(VecDuplicate(nk.xA, &nk.yA));
  PetscCall(VecDuplicate(nk.xA, &nk.tA));
  if (fp->G) PetscCall(VecDuplicate(fp->alpha, &nk.galpha));
  PetscCall(NewtonKrylovSetUpPJ(&nk));
  if (nk.ng) PetscCall(NewtonKrylovSetUpRigid(&nk));
  nk.nloc = nloc;
  if (fp->nco) {
    PetscCall(VecDuplicate(b, &nk.xw));
    PetscCall(NewtonKrylovSetUpCoarse(&nk));
  }
  PetscCall(MatCreateShell(comm, nloc, nloc, N, N, &nk, &J));
  PetscCall(MatShellSetOperation(J, MATOP_MULT, (void (*)(void))NewtonKrylovMult));
  PetscCall(KSPSetOperators(nt->kmf, J, J));
  PetscCall(KSPGetPC(nt->kmf, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, &nk));
  PetscCall(PCShellSetApply(pc, NewtonKrylovPCApply));
  { /* the forcing term: -mbc_newton_mf_ksp_rtol far from the solution, then tight enough that the
       step lands a hundred times below the merit's tolerance (eta ~ 0.01 rtol / merit), as the
       direct step does: at 1e-4 throughout, the answer met the tolerance but not the dense route's
       accuracy (a patch test's pressure 1.6e-6 off, slipping points 8.5e-11 inside the cone) */
    PetscReal rtol, abstol, dtol, eta;
    PetscInt  maxit;
    PetscCall(KSPGetTolerances(nt->kmf, &rtol, &abstol, &dtol, &maxit));
    eta = PetscMax(PetscMin(rtol, 1e-4 * m->rtol / PetscMax(m->merit, PETSC_SMALL)), 1e-12);
    PetscCall(KSPSetTolerances(nt->kmf, eta, abstol, dtol, maxit));
    PetscCall(VecZeroEntries(x));
    PetscCall(KSPSolve(nt->kmf, b, x));
    PetscCall(KSPGetConvergedReason(nt->kmf, reason));
    if (*reason < 0 && nk.nco) { /* the coarse correction is an approximation (patches with separated
                                    points, a nearly singular E): never worse than without it */
      PetscInt its0;
      PetscCall(KSPGetIterationNumber(nt->kmf, &its0));
      nt->kits += its0;
      PetscCall(PetscInfo(m, "Krylov Newton step with the coarse space: %" PetscInt_FMT " iterations, %s; again without it\n", its0, KSPConvergedReasons[*reason]));
      nk.nco = 0;
      PetscCall(VecZeroEntries(x));
      PetscCall(KSPSolve(nt->kmf, b, x));
    }
    PetscCall(KSPSetTolerances(nt->kmf, rtol, abstol, dtol, maxit));
  }
  PetscCall(KSPGetConvergedReason(nt->kmf, reason));
  PetscCall(KSPGetIterationNumber(nt->kmf, &its));
  if (*reason < 0 && *reason != KSP_DIVERGED_NANORINF) { /* an unfinished solve (iterations, or the
                                 Krylov basis losing rank: stiffness contrasts of 1e6) is still a step if
                                 it reduced J's residual; the line search judges it */
    PetscReal rn, bn;
    PetscCall(KSPGetResidualNorm(nt->kmf, &rn));
    PetscCall(VecNorm(b, NORM_2, &bn));
    if (rn < 0.5 * bn) *reason = KSP_CONVERGED_ITS;
  }
  nt->kits += its;
  PetscCall(PetscInfo(m, "Krylov Newton step: %" PetscInt_FMT " iterations, %s\n", its, KSPConvergedReasons[*reason]));
  PetscCall(KSPReset(nt->kmf));
  PetscCall(MatDestroy(&J));
  PetscCall(MatDestroy(&nk.K));
  PetscCall(VecDestroy(&nk.vfull));
  PetscCall(VecDestroy(&nk.wfull));
  PetscCall(VecDestroy(&nk.xA));
  PetscCall(VecDestroy(&nk.yA));
  PetscCall(VecDestroy(&nk.tA));
  PetscCall(VecDestroy(&nk.galpha));
  if (nk.ng) PetscCall(VecDestroyVecs(nk.ng, &nk.Z));
  PetscCall(PetscFree2(nk.S, nk.piv));
  PetscCall(PetscFree5(nk.acol, nk.aw, nk.E, nk.cpiv, nk.wc));
  PetscCall(PetscFree3(nk.c, nk.JG, nk.GPhi));
  PetscCall(VecDestroy(&nk.xw));
  PetscFunctionReturn(0);
}
