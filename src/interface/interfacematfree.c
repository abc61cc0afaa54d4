/* The matrix-free flexibility matrix (-mbc_d_route matfree): W = D / dscale as a MatShell,
     D v = sum_b H_b^T A_b^-1 H_b v,
   one forward and back substitution with each body's factor per product, never stored: no m^2
   memory and no m solves per build, where the dense D_b of the other routes do not fit (the
   1M-DOF dam with its joints: 37 620 multipliers, W 11.7 GB assembled). With it goes a sparse
   approximation of W^-1 from FETI's lumped preconditioner Kl = sum_b W_b H~_b^T A_b H~_b W_b (H~: H
   with the rows K^+ holds zeroed, W_b the compliance scaling below), which gives the Newton type its
   augmentation (rho ~ 1 / W_dd), its directions without flexibility (Kl_dd = 0 exactly where
   D_dd = 0: both vanish with the column of H~) and the preconditioner of its Krylov steps. dscale,
   the mean of D_dd on the other routes, is estimated from a sample of D's diagonal (below): only the scaling of r = dscale lambda, which
   weighs forces against displacements in the FCLIB merit, can differ by the sample's error. */
#include <mbc/private/interfaceimpl.h>

PetscLogEvent MBC_FlexibilityMult;

#define MBC_D_SAMPLES 32

typedef struct {
  MBCInterface ifc;
  Vec         *lam, *Hl, *Xl, *Hu; /* per body, its own: the interface's hold the step's lambda */
} DShell;

static PetscErrorCode DShellMult(Mat W, Vec x, Vec y)
{
  DShell      *ctx;
  MBCInterface ifc;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(W, &ctx));
  ifc = ctx->ifc;
  PetscCall(PetscLogEventBegin(MBC_FlexibilityMult, 0, 0, 0, 0));
  PetscCall(MBCInterfaceScatterToBodies(ifc, x, ctx->lam));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    Mat Ainv;
    if (!ctx->lam[b]) continue;
    PetscCall(MatMult(ifc->H[b], ctx->lam[b], ctx->Hl[b]));
    PetscCall(MBCBodyGetInverse(ifc->bodies[b], &Ainv));
    PetscCall(MatMult(Ainv, ctx->Hl[b], ctx->Xl[b]));
    PetscCall(MatMultTranspose(ifc->H[b], ctx->Xl[b], ctx->Hu[b]));
  }
  PetscCall(MBCInterfaceGatherFromBodies(ifc, ctx->Hu, y));
  PetscCall(VecScale(y, 1.0 / ifc->dscale));
  PetscCall(PetscLogEventEnd(MBC_FlexibilityMult, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

static PetscErrorCode DShellDestroy(Mat W)
{
  DShell *ctx;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(W, &ctx));
  for (PetscInt b = 0; b < ctx->ifc->nbodies; b++) {
    PetscCall(VecDestroy(&ctx->lam[b]));
    PetscCall(VecDestroy(&ctx->Hl[b]));
    PetscCall(VecDestroy(&ctx->Xl[b]));
    PetscCall(VecDestroy(&ctx->Hu[b]));
  }
  PetscCall(PetscFree4(ctx->lam, ctx->Hl, ctx->Xl, ctx->Hu));
  PetscCall(PetscFree(ctx));
  PetscFunctionReturn(0);
}

/* K_b = H~_b^T A_b H~_b (nb x nb, H's column layout) of body b on its ranks. */
static PetscErrorCode BodyLumped(MBCInterface ifc, PetscInt b, Mat *Kb)
{
  MBCBody         body = ifc->bodies[b];
  Mat             Ainv, A, Ht;
  KSP             ksp;
  PetscInt        nheld;
  const PetscInt *held;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetInverse(body, &Ainv));
  PetscCall(MBCInverseGetKSP(Ainv, &ksp));
  PetscCall(KSPGetOperators(ksp, &A, NULL));
  PetscCall(MBCBodyGetHeldRows(body, &nheld, &held));
  PetscCall(MatDuplicate(ifc->H[b], MAT_COPY_VALUES, &Ht));
  PetscCall(MatZeroRows(Ht, nheld, held, 0.0, NULL, NULL));
  PetscCall(MatPtAP(A, Ht, MAT_INITIAL_MATRIX, PETSC_DEFAULT, Kb));
  PetscCall(MatDestroy(&Ht));
  PetscFunctionReturn(0);
}

/* Adds every body's K_b into Kl at the W rows of its columns (bcols). */
static PetscErrorCode LumpedAdd(MBCInterface ifc, Mat Kb[], Mat Kl)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscInt rlo, rhi, *gc;
    if (!Kb[b]) continue;
    PetscCall(MatGetOwnershipRange(Kb[b], &rlo, &rhi));
    PetscCall(PetscMalloc1(ifc->nbcols[b] + 1, &gc));
    for (PetscInt row = rlo; row < rhi; row++) {
      PetscInt           ncols;
      const PetscInt    *cols;
      const PetscScalar *vals;
      PetscCall(MatGetRow(Kb[b], row, &ncols, &cols, &vals));
      for (PetscInt k = 0; k < ncols; k++) gc[k] = ifc->bcols[b][cols[k]];
      PetscCall(MatSetValues(Kl, 1, &ifc->bcols[b][row], ncols, gc, vals, ADD_VALUES));
      PetscCall(MatRestoreRow(Kb[b], row, &ncols, &cols, &vals));
    }
    PetscCall(PetscFree(gc));
  }
  PetscFunctionReturn(0);
}

/* fp.W (the shell), fp.Winv and dscale for m multipliers, mloc on this rank. */
PetscErrorCode MBCInterfaceBuildDShell(MBCInterface ifc, PetscInt m, PetscInt mloc)
{
  DShell *ctx;
  Mat    *Kb, pre;

  PetscFunctionBegin;
  PetscCall(PetscNew(&ctx));
  ctx->ifc = ifc;
  PetscCall(PetscCalloc4(ifc->nbodies, &ctx->lam, ifc->nbodies, &ctx->Hl, ifc->nbodies, &ctx->Xl, ifc->nbodies, &ctx->Hu));
  PetscCall(PetscCalloc1(ifc->nbodies, &Kb));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    if (!ifc->bodies[b] || !ifc->nbcols[b]) continue;
    PetscCall(MatCreateVecs(ifc->H[b], &ctx->Hu[b], &ctx->Hl[b]));
    PetscCall(VecDuplicate(ctx->Hu[b], &ctx->lam[b]));
    PetscCall(VecDuplicate(ctx->Hl[b], &ctx->Xl[b]));
    PetscCall(BodyLumped(ifc, b, &Kb[b]));
  }
  { /* compliance (stiffness) scaling: a point between two bodies has W_dd = D1_dd + D2_dd, its
       bodies in series, and the sum K1 + K2 would take them in parallel; weighed by
       w_b = (1 / k_b) / sum_c (1 / k_c) (k_b the body's K_b diagonal at the point), the sum
       sum_b w_b^2 k_b is 1 / sum_c (1 / k_c), the series stiffness (FETI's rho-scaled lumped
       preconditioner) */
    Vec sum;
    PetscCall(VecCreate(ifc->comm, &sum));
    PetscCall(VecSetSizes(sum, mloc, m));
    PetscCall(VecSetType(sum, VECSTANDARD));
    for (PetscInt b = 0; b < ifc->nbodies; b++) {
      PetscScalar *a;
      PetscInt     n;
      if (!Kb[b]) continue;
      PetscCall(MatGetDiagonal(Kb[b], ctx->Hu[b]));
      PetscCall(VecGetLocalSize(ctx->Hu[b], &n));
      PetscCall(VecGetArray(ctx->Hu[b], &a));
      for (PetscInt i = 0; i < n; i++) a[i] = PetscRealPart(a[i]) > 0 ? 1.0 / a[i] : 0.0;
      PetscCall(VecRestoreArray(ctx->Hu[b], &a));
    }
    PetscCall(MBCInterfaceGatherFromBodies(ifc, ctx->Hu, sum));
    PetscCall(MBCInterfaceScatterToBodies(ifc, sum, ctx->lam));
    for (PetscInt b = 0; b < ifc->nbodies; b++) {
      PetscScalar       *w;
      const PetscScalar *t;
      PetscInt           n;
      if (!Kb[b]) continue;
      PetscCall(VecGetLocalSize(ctx->Hu[b], &n));
      PetscCall(VecGetArray(ctx->Hu[b], &w));
      PetscCall(VecGetArrayRead(ctx->lam[b], &t));
      for (PetscInt i = 0; i < n; i++) w[i] = PetscRealPart(t[i]) > 0 ? w[i] / t[i] : 0.0;
      PetscCall(VecRestoreArrayRead(ctx->lam[b], &t));
      PetscCall(VecRestoreArray(ctx->Hu[b], &w));
      PetscCall(MatDiagonalScale(Kb[b], ctx->Hu[b], ctx->Hu[b]));
    }
    PetscCall(VecDestroy(&sum));
  }
  /* Winv: its pattern from a first pass (a contact couples to the few sharing its nodes' stencils) */
  PetscCall(MatCreate(ifc->comm, &pre));
  PetscCall(MatSetSizes(pre, mloc, mloc, m, m));
  PetscCall(MatSetType(pre, MATPREALLOCATOR));
  PetscCall(MatSetUp(pre));
  PetscCall(LumpedAdd(ifc, Kb, pre));
  PetscCall(MatAssemblyBegin(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreate(ifc->comm, &ifc->fp.Winv));
  PetscCall(MatSetSizes(ifc->fp.Winv, mloc, mloc, m, m));
  PetscCall(MatSetType(ifc->fp.Winv, MATAIJ));
  PetscCall(MatPreallocatorPreallocate(pre, PETSC_TRUE, ifc->fp.Winv));
  PetscCall(MatDestroy(&pre));
  PetscCall(LumpedAdd(ifc, Kb, ifc->fp.Winv));
  PetscCall(MatAssemblyBegin(ifc->fp.Winv, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ifc->fp.Winv, MAT_FINAL_ASSEMBLY));
  for (PetscInt b = 0; b < ifc->nbodies; b++) PetscCall(MatDestroy(&Kb[b]));
  PetscCall(PetscFree(Kb));
  { /* directions without flexibility: Kl_dd and D_dd both scale with |H~ e_d|^2, which a frame's
       rounding leaves at ~1e-34 instead of 0 where the DOFs are prescribed (a roller under a
       tangent (1, 1e-17, 1e-17)); below 1e-12 of the largest (the dense route's test on D_dd),
       the direction's row and column go, as 1 / Kl_dd ~ 1e24 made dscale 1e22 (measured) */
    Vec                dg;
    const PetscScalar *d;
    PetscReal          dmax;
    PetscInt           n, nz = 0, rs, *rows;
    PetscCall(MatCreateVecs(ifc->fp.Winv, &dg, NULL));
    PetscCall(MatGetDiagonal(ifc->fp.Winv, dg));
    PetscCall(VecNorm(dg, NORM_INFINITY, &dmax));
    PetscCall(VecGetLocalSize(dg, &n));
    PetscCall(VecGetOwnershipRange(dg, &rs, NULL));
    PetscCall(PetscMalloc1(n + 1, &rows));
    PetscCall(VecGetArrayRead(dg, &d));
    for (PetscInt i = 0; i < n; i++)
      if (!(PetscRealPart(d[i]) > 1e-12 * dmax)) rows[nz++] = rs + i;
    PetscCall(VecRestoreArrayRead(dg, &d));
    PetscCall(MatZeroRowsColumns(ifc->fp.Winv, nz, rows, 0.0, NULL, NULL));
    PetscCall(PetscFree(rows));
    PetscCall(VecDestroy(&dg));
  }
  PetscCall(MatCreateShell(ifc->comm, mloc, mloc, m, m, ctx, &ifc->fp.W));
  PetscCall(MatShellSetOperation(ifc->fp.W, MATOP_MULT, (void (*)(void))DShellMult));
  PetscCall(MatShellSetOperation(ifc->fp.W, MATOP_DESTROY, (void (*)(void))DShellDestroy));
  PetscCall(MatSetOption(ifc->fp.W, MAT_SYMMETRIC, PETSC_TRUE));
  { /* 1 / Kl_dd underestimates D_dd, and not uniformly: by 4.6 times on average on the small
       static dam with the compliance scaling (17 without it, 5 to 66 over the points; measured:
       the free monoliths' K^+ adds their rigid-like flexibility, and a local stiffness's inverse
       is not the inverse's diagonal). The factor c, D_dd ~ c / Kl_dd, by the ratio estimator over MBC_D_SAMPLES diagonal entries of D
       (exact: per body one multi-right-hand-side solve with the sampled columns it has; points
       evenly spaced in couple order, so the same on any number of ranks); then dscale = the mean
       of c / Kl_dd and Winv = (dscale / c) Kl, so 1 / Winv_dd estimates W_dd and Winv_AA W_AA's
       inverse in scale, as the Newton type's augmentation and the balance of its preconditioner
       need. */
    const PetscInt     ns = PetscMin(ifc->ncontact, MBC_D_SAMPLES);
    PetscReal          sd = 0, sk = 0, sum = 0, c, samp[2 * MBC_D_SAMPLES];
    PetscInt           js[MBC_D_SAMPLES], rs, re;
    Vec                diag;
    const PetscScalar *d;
    PetscCall(MatCreateVecs(ifc->fp.Winv, &diag, NULL));
    PetscCall(MatGetDiagonal(ifc->fp.Winv, diag));
    PetscCall(VecGetOwnershipRange(diag, &rs, &re));
    PetscCall(VecGetArrayRead(diag, &d));
    PetscCall(PetscArrayzero(samp, 2 * ns));
    for (PetscInt k = 0; k < ns; k++) { /* samp: D_jj (its parts, body after body), then 1 / Kl_jj (its owner) */
      const PetscInt kc = (PetscInt)(((PetscInt64)k * ifc->ncontact) / ns), dim = ifc->coff[kc + 1] - ifc->coff[kc];
      js[k] = ifc->poff[ifc->perm[kc]] + k % dim; /* point kc in couple order (as on any number of ranks), a direction in turn */
      if (js[k] >= rs && js[k] < re && PetscRealPart(d[js[k] - rs]) > 0) samp[ns + k] = 1.0 / PetscRealPart(d[js[k] - rs]);
    }
    for (PetscInt i = 0; i < re - rs; i++)
      if (PetscRealPart(d[i]) > 0) sum += 1.0 / PetscRealPart(d[i]);
    PetscCall(VecRestoreArrayRead(diag, &d));
    PetscCall(VecDestroy(&diag));
    for (PetscInt b = 0; b < ifc->nbodies; b++) { /* D_jj = sum_b h_bj^T A_b^-1 h_bj: per body one solve with the sampled columns it has */
      PetscInt hc[MBC_D_SAMPLES], kk[MBC_D_SAMPLES], n = 0, nloc, lh, lx;
      Mat      Hd, X;
      const PetscScalar *h, *x;
      if (!ifc->bodies[b] || !ifc->nbcols[b]) continue;
      for (PetscInt k = 0; k < ns; k++) {
        PetscInt at;
        PetscCall(PetscFindInt(js[k], ifc->nbcols[b], ifc->bcols[b], &at));
        if (at >= 0) hc[n] = at, kk[n++] = k;
      }
      if (!n) continue;
      PetscCall(PetscSortIntWithArray(n, hc, kk)); /* the samples are in couple order, H's columns in rank order */
      PetscCall(MBCInterfaceBodySolveColumns(ifc, b, n, hc, &Hd, &X));
      PetscCall(MatGetLocalSize(Hd, &nloc, NULL));
      PetscCall(MatDenseGetLDA(Hd, &lh));
      PetscCall(MatDenseGetLDA(X, &lx));
      PetscCall(MatDenseGetArrayRead(Hd, &h));
      PetscCall(MatDenseGetArrayRead(X, &x));
      for (PetscInt i = 0; i < n; i++) /* this rank's part of the dot product h^T x */
        for (PetscInt r = 0; r < nloc; r++) samp[kk[i]] += PetscRealPart(h[r + i * lh] * x[r + i * lx]);
      PetscCall(MatDenseRestoreArrayRead(X, &x));
      PetscCall(MatDenseRestoreArrayRead(Hd, &h));
      PetscCall(MatDestroy(&Hd));
      PetscCall(MatDestroy(&X));
    }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, samp, 2 * ns, MPIU_REAL, MPIU_SUM, ifc->comm));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &sum, 1, MPIU_REAL, MPIU_SUM, ifc->comm));
    for (PetscInt k = 0; k < ns; k++)
      if (samp[ns + k] > 0) sd += samp[k], sk += samp[ns + k]; /* directions without flexibility left out */
    c           = sk > 0 && sd > 0 ? sd / sk : 1;
    ifc->dscale = c * sum / m;
    PetscCall(PetscInfo(NULL, "Matrix-free D: %" PetscInt_FMT " sampled columns, D_dd ~ %g / Kl_dd, dscale %g\n", ns, (double)c, (double)ifc->dscale));
    PetscCheck(ifc->dscale > 0, ifc->comm, PETSC_ERR_ARG_WRONG, "The contact flexibility matrix has no positive diagonal: every contact DOF is prescribed");
    PetscCall(MatScale(ifc->fp.Winv, ifc->dscale / c));
  }
  PetscCall(MBCInterfaceBuildCoarse(ifc, mloc));
  PetscFunctionReturn(0);
}
