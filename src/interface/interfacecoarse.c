/* The coarse space of the matrix-free Newton steps (-mbc_d_coarse_points): FETI's lumped
   preconditioner is local, so the Krylov iterations it leaves grow with the smooth, long-range
   modes of the interface flexibility (the contact pressure over a whole joint). Phi holds, per
   patch of about -mbc_d_coarse_points neighbouring points of a couple (recursive coordinate
   bisection of their positions) and per direction (normal, tangents), the normalised indicator of
   that direction over the patch: one nonzero per row of W. W Phi is computed here, once per W, by
   multi-right-hand-side solves per body with the patches touching it (a block of solves costs
   a fraction of as many single ones); the Newton steps then correct their preconditioner on
   span(Phi) with no product (newtonkrylov.c). */
#include <mbc/private/interfaceimpl.h>

PetscLogEvent MBC_FlexibilityCoarse;

/* idx[0..n) split into parts of at most cap points by halving along the widest extent of their
   positions x (3 per point); part[idx[i]] = the part. The same on every rank (the same input). */
static PetscErrorCode Bisect(const PetscReal x[], PetscInt idx[], PetscInt n, PetscInt cap, PetscReal key[], PetscInt part[], PetscInt *npart)
{
  PetscReal lo[3] = {PETSC_MAX_REAL, PETSC_MAX_REAL, PETSC_MAX_REAL}, hi[3] = {PETSC_MIN_REAL, PETSC_MIN_REAL, PETSC_MIN_REAL};
  PetscInt  axis = 0;

  PetscFunctionBegin;
  if (n <= cap) {
    for (PetscInt i = 0; i < n; i++) part[idx[i]] = *npart;
    (*npart)++;
    PetscFunctionReturn(0);
  }
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt d = 0; d < 3; d++) lo[d] = PetscMin(lo[d], x[3 * idx[i] + d]), hi[d] = PetscMax(hi[d], x[3 * idx[i] + d]);
  for (PetscInt d = 1; d < 3; d++)
    if (hi[d] - lo[d] > hi[axis] - lo[axis]) axis = d;
  for (PetscInt i = 0; i < n; i++) key[i] = x[3 * idx[i] + axis];
  PetscCall(PetscSortRealWithArrayInt(n, key, idx));
  PetscCall(Bisect(x, idx, n / 2, cap, key, part, npart));
  PetscCall(Bisect(x, idx + n / 2, n - n / 2, cap, key, part, npart));
  PetscFunctionReturn(0);
}

/* fp.nco, fp.cocol, fp.cow (Phi) and fp.WPhi = W Phi for the W just built (a shell). */
PetscErrorCode MBCInterfaceBuildCoarse(MBCInterface ifc, PetscInt mloc)
{
  MBCContact  c  = ifc->contact;
  const PetscInt np = ifc->ncontact, N = ifc->nbodies;
  /* blocks of 64 columns: faster than 256 (9.5 against 11.1 s at 200k DOFs) and a quarter of the memory */
  PetscInt   *patch, *pfirst, nco = 0, rs, cap, blk = PetscMax(PetscMin(ifc->dblock, 64), 1);
  PetscReal  *x, *key;
  Vec         phi, w, *lam, *Hl, *Hu;

  PetscFunctionBegin;
  PetscCall(PetscFree2(ifc->fp.cocol, ifc->fp.cow));
  PetscCall(MatDestroy(&ifc->fp.WPhi));
  ifc->fp.nco = 0;
  if (ifc->coarse_points <= 0 || !np) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(MBC_FlexibilityCoarse, 0, 0, 0, 0));
  { /* W Phi within -mbc_d_coarse_max_mb: larger patches where the multipliers are many (the 1M dam
       with its joints: 37 620 multipliers, 16 points a patch would give 2 352 columns, 0.7 GB; its
       static run peaked at 15.7 GB without it). Bisection leaves patches of cap/2 to cap points,
       so at most ~6 np / cap columns. */
    const PetscInt m = ifc->coff[np], maxcols = (PetscInt)PetscMax(1.0, ifc->coarse_max_mb * 1048576.0 / (8.0 * m));
    cap = PetscMax(ifc->coarse_points, (6 * np + maxcols - 1) / maxcols);
  }
  /* patches: per couple, its points (couple order k: couples one after the other) bisected */
  PetscCall(PetscMalloc4(np, &patch, np + 1, &pfirst, 3 * np, &x, np, &key));
  for (PetscInt k0 = 0; k0 < np;) {
    PetscInt k1 = k0, *idx;
    while (k1 < np && ifc->kcouple[k1] == ifc->kcouple[k0]) k1++;
    for (PetscInt k = k0; k < k1; k++) {
      const MBCContactPoint *p = &c->couples[ifc->kcouple[k]].points[ifc->kpoint[k]];
      for (PetscInt d = 0; d < 3; d++) x[3 * k + d] = p->p[d];
    }
    PetscCall(PetscMalloc1(k1 - k0, &idx));
    for (PetscInt k = k0; k < k1; k++) idx[k - k0] = k;
    PetscCall(Bisect(x, idx, k1 - k0, cap, key, patch, &nco));
    PetscCall(PetscFree(idx));
    k0 = k1;
  }
  { /* columns: patch q has one per direction of its points (3, or 1 frictionless) from pfirst[q] */
    PetscInt ncol = 0, *dimq;
    PetscCall(PetscCalloc1(nco + 1, &dimq));
    for (PetscInt k = 0; k < np; k++) dimq[patch[k]] = ifc->coff[k + 1] - ifc->coff[k];
    for (PetscInt q = 0; q < nco; q++) pfirst[q] = ncol, ncol += dimq[q];
    pfirst[nco] = ncol;
    PetscCall(PetscFree(dimq));
  }
  ifc->fp.nco = pfirst[nco];
  /* Phi: per local row its column and weight 1 / sqrt(points of its patch) */
  PetscCall(PetscMalloc2(mloc + 1, &ifc->fp.cocol, mloc + 1, &ifc->fp.cow));
  {
    PetscInt *count;
    PetscCall(PetscCalloc1(nco + 1, &count));
    for (PetscInt k = 0; k < np; k++) count[patch[k]]++;
    PetscCallMPI(MPI_Scan(&mloc, &rs, 1, MPIU_INT, MPI_SUM, ifc->comm));
    rs -= mloc;
    for (PetscInt i = 0; i < mloc; i++) ifc->fp.cocol[i] = -1, ifc->fp.cow[i] = 0;
    for (PetscInt k = 0; k < np; k++) {
      const PetscInt row = ifc->poff[ifc->perm[k]], dim = ifc->coff[k + 1] - ifc->coff[k];
      if (row < rs || row >= rs + mloc) continue;
      for (PetscInt d = 0; d < dim; d++) ifc->fp.cocol[row - rs + d] = pfirst[patch[k]] + d, ifc->fp.cow[row - rs + d] = 1.0 / PetscSqrtReal((PetscReal)count[patch[k]]);
    }
    PetscCall(PetscFree(count));
  }
  PetscCall(MatCreateDense(ifc->comm, mloc, PETSC_DECIDE, PETSC_DETERMINE, ifc->fp.nco, NULL, &ifc->fp.WPhi));
  /* W Phi by blocks of columns: per body, the block's columns that touch it (a patch touches the
     bodies of its points' master nodes and slave faces), H_b Phi, one multi-RHS solve, H_b^T X */
  PetscCall(VecCreateMPI(ifc->comm, mloc, PETSC_DETERMINE, &phi));
  PetscCall(VecDuplicate(phi, &w));
  PetscCall(PetscCalloc3(N, &lam, N, &Hl, N, &Hu));
  for (PetscInt b = 0; b < N; b++) {
    if (!ifc->bodies[b] || !ifc->nbcols[b]) continue;
    PetscCall(MatCreateVecs(ifc->H[b], &Hu[b], &Hl[b]));
    PetscCall(VecDuplicate(Hu[b], &lam[b]));
  }
  for (PetscInt j0 = 0; j0 < ifc->fp.nco; j0 += blk) {
    const PetscInt j1 = PetscMin(ifc->fp.nco, j0 + blk);
    Mat           *R, *Y;
    PetscInt      *nbj, *pos;
    PetscBool     *bt;
    PetscCall(PetscCalloc5(N, &R, N, &Y, N, &nbj, N * (j1 - j0), &pos, N * (j1 - j0), &bt));
    /* which bodies the block's columns touch (every rank: the couples are replicated) */
    for (PetscInt k = 0; k < np; k++) {
      const MBCCouple       *cp = &c->couples[ifc->kcouple[k]];
      const MBCContactPoint *p  = &cp->points[ifc->kpoint[k]];
      const PetscInt         bm = cp->master.nbody[p->master], bs = cp->slave.fbody[p->face], dim = ifc->coff[k + 1] - ifc->coff[k];
      for (PetscInt d = 0; d < dim; d++) {
        const PetscInt j = pfirst[patch[k]] + d;
        if (j < j0 || j >= j1) continue;
        bt[bm * (j1 - j0) + j - j0] = bt[bs * (j1 - j0) + j - j0] = PETSC_TRUE;
      }
    }
    for (PetscInt b = 0; b < N; b++) {
      PetscInt rlo, rhi;
      MPI_Comm bcomm;
      for (PetscInt j = j0; j < j1; j++)
        if (bt[b * (j1 - j0) + j - j0]) pos[b * (j1 - j0) + j - j0] = nbj[b]++;
      if (!Hl[b] || !nbj[b]) continue;
      PetscCall(VecGetOwnershipRange(Hl[b], &rlo, &rhi));
      PetscCall(MBCBodyGetComm(ifc->bodies[b], &bcomm));
      PetscCall(MatCreateDense(bcomm, rhi - rlo, PETSC_DECIDE, PETSC_DETERMINE, nbj[b], NULL, &R[b]));
    }
    for (PetscInt j = j0; j < j1; j++) { /* R_b's columns: H_b Phi_j */
      PetscScalar *pa;
      PetscCall(VecGetArrayWrite(phi, &pa));
      for (PetscInt i = 0; i < mloc; i++) pa[i] = ifc->fp.cocol[i] == j ? ifc->fp.cow[i] : 0.0;
      PetscCall(VecRestoreArrayWrite(phi, &pa));
      PetscCall(MBCInterfaceScatterToBodies(ifc, phi, lam));
      for (PetscInt b = 0; b < N; b++) {
        PetscScalar *ra;
        PetscInt     lda;
        if (!R[b] || !bt[b * (j1 - j0) + j - j0]) continue;
        PetscCall(MatDenseGetArray(R[b], &ra));
        PetscCall(MatDenseGetLDA(R[b], &lda));
        PetscCall(VecPlaceArray(Hl[b], ra + lda * pos[b * (j1 - j0) + j - j0]));
        PetscCall(MatMult(ifc->H[b], lam[b], Hl[b]));
        PetscCall(VecResetArray(Hl[b]));
        PetscCall(MatDenseRestoreArray(R[b], &ra));
      }
    }
    for (PetscInt b = 0; b < N; b++) { /* Y_b = H_b^T A_b^-1 R_b */
      Mat Ainv, X;
      if (!R[b]) continue;
      PetscCall(MBCBodyGetInverse(ifc->bodies[b], &Ainv));
      PetscCall(MatMatMult(Ainv, R[b], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &X));
      PetscCall(MatTransposeMatMult(ifc->H[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Y[b]));
      PetscCall(MatDestroy(&X));
    }
    for (PetscInt j = j0; j < j1; j++) { /* column j of W Phi: the bodies' parts gathered */
      const PetscScalar *wa;
      PetscScalar       *out;
      PetscInt           ldw;
      for (PetscInt b = 0; b < N; b++) {
        if (!Hu[b]) continue;
        if (Y[b] && bt[b * (j1 - j0) + j - j0]) {
          const PetscScalar *ya;
          PetscInt           lda, n;
          PetscScalar       *ha;
          PetscCall(MatDenseGetArrayRead(Y[b], &ya));
          PetscCall(MatDenseGetLDA(Y[b], &lda));
          PetscCall(VecGetLocalSize(Hu[b], &n));
          PetscCall(VecGetArrayWrite(Hu[b], &ha));
          PetscCall(PetscArraycpy(ha, ya + lda * pos[b * (j1 - j0) + j - j0], n));
          PetscCall(VecRestoreArrayWrite(Hu[b], &ha));
          PetscCall(MatDenseRestoreArrayRead(Y[b], &ya));
        } else PetscCall(VecZeroEntries(Hu[b]));
      }
      PetscCall(MBCInterfaceGatherFromBodies(ifc, Hu, w));
      PetscCall(VecGetArrayRead(w, &wa));
      PetscCall(MatDenseGetArray(ifc->fp.WPhi, &out));
      PetscCall(MatDenseGetLDA(ifc->fp.WPhi, &ldw));
      for (PetscInt i = 0; i < mloc; i++) out[i + ldw * j] = wa[i] / ifc->dscale;
      PetscCall(MatDenseRestoreArray(ifc->fp.WPhi, &out));
      PetscCall(VecRestoreArrayRead(w, &wa));
    }
    for (PetscInt b = 0; b < N; b++) {
      PetscCall(MatDestroy(&R[b]));
      PetscCall(MatDestroy(&Y[b]));
    }
    PetscCall(PetscFree5(R, Y, nbj, pos, bt));
  }
  for (PetscInt b = 0; b < N; b++) {
    PetscCall(VecDestroy(&lam[b]));
    PetscCall(VecDestroy(&Hl[b]));
    PetscCall(VecDestroy(&Hu[b]));
  }
  PetscCall(PetscFree3(lam, Hl, Hu));
  PetscCall(VecDestroy(&phi));
  PetscCall(VecDestroy(&w));
  PetscCall(PetscInfo(NULL, "Matrix-free D: coarse space of %" PetscInt_FMT " columns (%" PetscInt_FMT " patches of <= %" PetscInt_FMT " points)\n", ifc->fp.nco, nco, cap));
  PetscCall(PetscFree4(patch, pfirst, x, key));
  PetscCall(PetscLogEventEnd(MBC_FlexibilityCoarse, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
