/* Free bodies in a static analysis (FETI's natural coarse space): the rows G = R^T H of their
   equilibrium in the multiplier problem, its right side e, and the rigid motion alpha the solve
   gives back to the bodies. */
#include <mbc/private/interfaceimpl.h>
#include <petscblaslapack.h>

/* Combined rigid motions of several free bodies that deform no contact (the whole stack free to
   slide or turn together: G^T v = 0) leave alpha undetermined along v and make the equilibrium
   rows dependent. With the eigenvectors of G G^T: Q, those of its range, replace G by Q^T G and
   alpha by Q beta; the null vectors N are kept, to check that the load balances along them
   (N^T e = 0), else no static equilibrium exists. */
static PetscErrorCode InterfaceRigidReduce(MBCInterface ifc)
{
  PetscMPIInt  size, rank;
  PetscInt     ng = ifc->ngrigid, nr = 0, M;
  PetscScalar *A, work[1024];
  PetscReal   *ev, emax = 0;
  PetscBool   *ev_keep;
  PetscBLASInt n, lwork = 1024, info;
  Mat          GGt, Gr;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(ifc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(ifc->comm, &rank));
  PetscCall(PetscFree(ifc->gQ));
  PetscCall(PetscCalloc1(ng * ng, &A));
  PetscCall(PetscCalloc1(ng, &ev));
  PetscCall(MatMatTransposeMult(ifc->fp.G, ifc->fp.G, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &GGt));
  if (rank == size - 1)
    for (PetscInt i = 0; i < ng; i++) {
      PetscInt           nc;
      const PetscInt    *cols;
      const PetscScalar *vals;
      PetscCall(MatGetRow(GGt, i, &nc, &cols, &vals));
      for (PetscInt j = 0; j < nc; j++) A[i * ng + cols[j]] = vals[j];
      PetscCall(MatRestoreRow(GGt, i, &nc, &cols, &vals));
    }
  PetscCall(MatDestroy(&GGt));
  PetscCallMPI(MPI_Bcast(A, (PetscMPIInt)(ng * ng), MPIU_SCALAR, size - 1, ifc->comm));
  PetscCall(PetscBLASIntCast(ng, &n));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &n, A, &n, ev, work, &lwork, &info)); /* the same on every rank */
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK syev failed (%d) on the rigid-mode equilibrium", (int)info);
  for (PetscInt i = 0; i < ng; i++) emax = PetscMax(emax, ev[i]);
  PetscCall(PetscMalloc1(ng, &ev_keep));
  for (PetscInt i = 0; i < ng; i++) {
    ev_keep[i] = (PetscBool)(ev[i] > 1e-10 * emax);
    if (ev_keep[i]) nr++;
  }
  ifc->gQ = A, ifc->grank = nr; /* eigenvectors: the k-th is gQ[k * ng + i] */
  PetscCall(PetscFree(ev));
  PetscCall(PetscFree(ifc->grange));
  if (nr == ng) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(nr, &ifc->grange));
  for (PetscInt k = 0, c = 0; k < ng; k++)
    if (ev_keep[k]) ifc->grange[c++] = k;
  PetscCall(MatGetSize(ifc->fp.G, NULL, &M));
  PetscCall(MatCreateAIJ(ifc->comm, rank == size - 1 ? nr : 0, PETSC_DECIDE, nr, M, 0, NULL, 0, NULL, &Gr));
  {
    PetscInt mloc;
    PetscCall(MatGetLocalSize(ifc->fp.G, NULL, &mloc));
    PetscCall(MatDestroy(&Gr));
    PetscCall(MatCreateAIJ(ifc->comm, rank == size - 1 ? nr : 0, mloc, nr, M, 0, NULL, 0, NULL, &Gr));
  }
  PetscCall(MatSetOption(Gr, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  if (rank == size - 1) {
    PetscScalar *acc;
    PetscInt    *mark, *cols, nmark;
    PetscCall(PetscCalloc3(M + 1, &acc, M + 1, &mark, M + 1, &cols));
    for (PetscInt k = 0, row = 0; k < ng; k++) {
      if (!ev_keep[k]) continue;
      nmark = 0;
      for (PetscInt i = 0; i < ng; i++) {
        PetscInt           nc;
        const PetscInt    *cc;
        const PetscScalar *vv;
        const PetscScalar  q = A[k * ng + i];
        if (q == 0.0) continue;
        PetscCall(MatGetRow(ifc->fp.G, i, &nc, &cc, &vv));
        for (PetscInt j = 0; j < nc; j++) {
          if (!mark[cc[j]]) mark[cc[j]] = 1, cols[nmark++] = cc[j];
          acc[cc[j]] += q * vv[j];
        }
        PetscCall(MatRestoreRow(ifc->fp.G, i, &nc, &cc, &vv));
      }
      for (PetscInt j = 0; j < nmark; j++) {
        PetscCall(MatSetValue(Gr, row, cols[j], acc[cols[j]], INSERT_VALUES));
        acc[cols[j]] = 0, mark[cols[j]] = 0;
      }
      row++;
    }
    PetscCall(PetscFree3(acc, mark, cols));
  }
  PetscCall(MatAssemblyBegin(Gr, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Gr, MAT_FINAL_ASSEMBLY));
  PetscCall(MatDestroy(&ifc->fp.G));
  PetscCall(PetscFree(ev_keep));
  ifc->fp.G = Gr;
  PetscFunctionReturn(0);
}

/* The least resistance, relative to |H|^T 1 max|R_j|, for which a contact holds a free mode:
   normals tilted by less than ~1e-3 rad are the deformation's, not a support's. */
#define MBC_RIGID_RESIST 1e-3

/* Static analysis with bodies their supports leave free (FETI's natural coarse space): the
   equilibrium of body i, R_i^T (f_i + H_i lambda) = 0, is G lambda = e with G's rows
   (H_i^T R_ij)^T, one per free mode, in the multiplier layout (W's); the free motion
   u_i = K_i^+ (f_i + H_i lambda) + R_i alpha_i adds G^T alpha to the contact velocity. G, e,
   alpha have all their rows on the last rank (the Newton type's layout), scaled as W is: the
   problem's G is G / dscale, its alpha dscale alpha. */
PetscErrorCode MBCInterfaceRigidModes(MBCInterface ifc)
{
  PetscMPIInt size, rank;
  PetscInt    ng = 0, mloc, *nr;
  Vec         row, rowabs;

  PetscFunctionBegin;
  PetscCall(PetscFree(ifc->goff));
  ifc->ngrigid = 0;
  if (ifc->analysis != MBC_ANALYSIS_STATIC) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(ifc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(ifc->comm, &rank));
  PetscCall(PetscCalloc1(ifc->nbodies + 1, &ifc->goff));
  PetscCall(PetscCalloc1(ifc->nbodies + 1, &nr));
  for (PetscInt b = 0; b < ifc->nbodies; b++) { /* a body's count, once (from its first rank) */
    PetscMPIInt brank = 1;
    MPI_Comm    bcomm;
    if (ifc->bodies[b]) {
      PetscCall(MBCBodyGetComm(ifc->bodies[b], &bcomm));
      PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
    }
    if (!brank) PetscCall(MBCBodyGetRigidModes(ifc->bodies[b], &nr[b], NULL));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nr, ifc->nbodies, MPIU_INT, MPI_SUM, ifc->comm));
  for (PetscInt b = 0; b < ifc->nbodies; b++) ifc->goff[b + 1] = ifc->goff[b] + nr[b];
  ng = ifc->ngrigid = ifc->goff[ifc->nbodies];
  PetscCall(PetscFree(nr));
  if (!ng) PetscFunctionReturn(0);
  PetscCall(MatGetLocalSize(ifc->fp.W, &mloc, NULL));
  PetscCall(MatCreateAIJ(ifc->comm, rank == size - 1 ? ng : 0, mloc, ng, PETSC_DETERMINE, 0, NULL, 0, NULL, &ifc->fp.G));
  PetscCall(MatSetOption(ifc->fp.G, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(VecDuplicate(ifc->fp.q, &row));
  PetscCall(VecDuplicate(ifc->fp.q, &rowabs));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscReal *hsum = NULL; /* |H_b|^T 1: per column of H_b, the sum of its magnitudes */
    const Vec *modes = NULL;
    PetscInt   nmodes;
    if (ifc->bodies[b]) PetscCall(MBCBodyGetRigidModes(ifc->bodies[b], &nmodes, &modes));
    if (ifc->goff[b + 1] > ifc->goff[b] && ifc->H[b]) {
      PetscCall(PetscMalloc1(ifc->nbcols[b] + 1, &hsum));
      PetscCall(MatGetColumnNorms(ifc->H[b], NORM_1, hsum));
    }
    for (PetscInt j = 0; j < ifc->goff[b + 1] - ifc->goff[b]; j++) {
      const PetscScalar *a, *aa;
      PetscInt           rstart, n, g = ifc->goff[b] + j;
      for (PetscInt o = 0; o < ifc->nbodies; o++) { /* H_b^T R_bj, the other bodies 0 */
        if (!ifc->Hu[o]) continue;
        if (o == b) PetscCall(MatMultTranspose(ifc->H[o], modes[j], ifc->Hu[o]));
        else PetscCall(VecZeroEntries(ifc->Hu[o]));
      }
      PetscCall(MBCInterfaceFromBodies(ifc, row));
      if (hsum) { /* |H_b|^T 1 max|R_bj|: the scale of each entry's rounding (the modes' entries
                     are known to a few eps of their largest: syev mixes the six modes) */
        PetscReal    rmax;
        PetscScalar *hu;
        PetscInt     cstart, cend;
        PetscCall(VecNorm(modes[j], NORM_INFINITY, &rmax));
        PetscCall(VecGetOwnershipRange(ifc->Hu[b], &cstart, &cend));
        PetscCall(VecGetArray(ifc->Hu[b], &hu));
        for (PetscInt i = cstart; i < cend; i++) hu[i - cstart] = rmax * hsum[i];
        PetscCall(VecRestoreArray(ifc->Hu[b], &hu));
      }
      PetscCall(MBCInterfaceFromBodies(ifc, rowabs));
      PetscCall(VecGetOwnershipRange(row, &rstart, NULL));
      PetscCall(VecGetLocalSize(row, &n));
      PetscCall(VecGetArrayRead(row, &a));
      PetscCall(VecGetArrayRead(rowabs, &aa));
      /* An entry below 1e-10 of the sum of its terms' magnitudes is rounding, not resistance: a
         flat frictionless face against the rotation about its normal gives ~1e-17 (the mode's
         few-eps share of the other rotations, measured). Kept, such a row made G lambda = e a saddle point
         of rank rounding and the rotation ~1e28 (a block held in z only, docs/stability.md).
         A mode that no point resists by more than MBC_RIGID_RESIST of that scale is free: the
         tilt of normals that the surfaces' own deformation makes (4e-5 after a load step that
         first pairs 4 of 16 points) is no support, and as one it set the block's free
         translation to residual / tilt (it slid 35 model sizes: docs/stability.md). */
      {
        PetscReal most = 0;
        for (PetscInt i = 0; i < n; i++)
          if (PetscRealPart(aa[i]) > 0) most = PetscMax(most, PetscAbsScalar(a[i]) / PetscRealPart(aa[i]));
        PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &most, 1, MPIU_REAL, MPIU_MAX, ifc->comm));
        for (PetscInt i = 0; i < n && most >= MBC_RIGID_RESIST; i++)
          if (PetscAbsScalar(a[i]) > 1e-10 * PetscRealPart(aa[i])) PetscCall(MatSetValue(ifc->fp.G, g, rstart + i, a[i] / ifc->dscale, INSERT_VALUES));
      }
      PetscCall(VecRestoreArrayRead(rowabs, &aa));
      PetscCall(VecRestoreArrayRead(row, &a));
    }
    PetscCall(PetscFree(hsum));
  }
  PetscCall(VecDestroy(&rowabs));
  PetscCall(VecDestroy(&row));
  PetscCall(MatAssemblyBegin(ifc->fp.G, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ifc->fp.G, MAT_FINAL_ASSEMBLY));
  PetscCall(InterfaceRigidReduce(ifc));
  { /* rows of G scaled to the unit entries of W: R's unit modes over N DOFs and 1 / dscale gave
       rows ~1e7 against W ~ 1, a saddle-point system the factorization could solve only to
       ~1e-8 (the static dam). e and alpha follow: G' = S G, e' = S e, alpha = S alpha'. */
    Vec       sc;
    PetscInt  n, rstart;
    PetscCall(MatCreateVecs(ifc->fp.G, NULL, &sc));
    PetscCall(VecGetLocalSize(sc, &n));
    PetscCall(VecGetOwnershipRange(sc, &rstart, NULL));
    PetscCall(PetscFree(ifc->gscale));
    PetscCall(PetscCalloc1(ifc->grank + 1, &ifc->gscale));
    for (PetscInt i = 0; i < n; i++) {
      PetscInt           nc;
      const PetscInt    *cc;
      const PetscScalar *vv;
      PetscReal          mx = 0;
      PetscCall(MatGetRow(ifc->fp.G, rstart + i, &nc, &cc, &vv));
      for (PetscInt j = 0; j < nc; j++) mx = PetscMax(mx, PetscAbsScalar(vv[j]));
      PetscCall(MatRestoreRow(ifc->fp.G, rstart + i, &nc, &cc, &vv));
      ifc->gscale[rstart + i] = mx > 0 ? 1 / mx : 1;
      PetscCall(VecSetValue(sc, rstart + i, ifc->gscale[rstart + i], INSERT_VALUES));
    }
    PetscCall(VecAssemblyBegin(sc));
    PetscCall(VecAssemblyEnd(sc));
    PetscCall(MatDiagonalScale(ifc->fp.G, sc, NULL));
    PetscCall(VecDestroy(&sc));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, ifc->gscale, ifc->grank, MPIU_REAL, MPIU_SUM, ifc->comm));
  }
  PetscCall(MatCreateVecs(ifc->fp.G, NULL, &ifc->fp.e));
  PetscCall(VecDuplicate(ifc->fp.e, &ifc->fp.alpha));
  PetscCall(VecZeroEntries(ifc->fp.alpha));
  PetscFunctionReturn(0);
}

/* After a static solve with free bodies: du_i += R_i alpha_i, alpha = Q beta / dscale (beta the
   problem's alpha; Q = I when no combined motion was removed). */
PetscErrorCode MBCInterfaceRigidMotion(MBCInterface ifc)
{
  const PetscInt ng = ifc->ngrigid;
  PetscReal     *alpha;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(ng + 1, &alpha));
  {
    const PetscScalar *a;
    PetscInt           n;
    PetscCall(VecGetLocalSize(ifc->fp.alpha, &n)); /* all rows on the last rank */
    PetscCall(VecGetArrayRead(ifc->fp.alpha, &a));
    for (PetscInt c = 0; c < n; c++)
      for (PetscInt i = 0; i < ng; i++) alpha[i] += (ifc->grange ? ifc->gQ[ifc->grange[c] * ng + i] : (PetscScalar)(i == c)) * ifc->gscale[c] * PetscRealPart(a[c]) / ifc->dscale;
    PetscCall(VecRestoreArrayRead(ifc->fp.alpha, &a));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, alpha, ng, MPIU_REAL, MPIU_SUM, ifc->comm));
  for (PetscInt b = 0; b < ifc->nbodies; b++)
    if (ifc->bodies[b]) PetscCall(MBCBodyAddRigidIncrement(ifc->bodies[b], &alpha[ifc->goff[b]]));
  PetscCall(PetscFree(alpha));
  PetscFunctionReturn(0);
}

/* e = (-R_ij^T (F_i - K_i u_i)) from the bodies (each held on its ranks), Q^T e on the last rank.
   Along a combined rigid motion v that no contact resists the load must balance, v^T e = 0 (to
   1e-8 of the load R^T F, or to the rounding of K u where no load acts on it: a prescribed
   displacement that moves a body rigidly): else no static equilibrium exists, an input error
   named here. */
PetscErrorCode MBCInterfaceRigidRHS(MBCInterface ifc, PetscInt step, PetscReal time)
{
  const PetscInt ng = ifc->ngrigid;
  PetscReal     *e, fscale = 0, eround = 0;
  PetscMPIInt    size, rank;

  PetscFunctionBegin;
  if (!ifc->fp.G) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(ifc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(ifc->comm, &rank));
  PetscCall(PetscCalloc1(2 * ng + 1, &e));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscMPIInt      brank;
    MPI_Comm         bcomm;
    PetscInt         nr;
    const PetscReal *eb, *fb;
    PetscReal        ebround;
    if (!ifc->bodies[b]) continue;
    PetscCall(MBCBodyGetComm(ifc->bodies[b], &bcomm));
    PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
    PetscCall(MBCBodyGetRigidModes(ifc->bodies[b], &nr, NULL));
    PetscCall(MBCBodyGetRigidEquilibrium(ifc->bodies[b], &eb, &fb, &ebround, NULL));
    if (!brank)
      for (PetscInt j = 0; j < nr; j++) e[ifc->goff[b] + j] = eb[j], e[ng + ifc->goff[b] + j] = fb[j];
    eround = PetscMax(eround, ebround);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, e, 2 * ng, MPIU_REAL, MPIU_SUM, ifc->comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &eround, 1, MPIU_REAL, MPIU_MAX, ifc->comm));
  for (PetscInt i = 0; i < ng; i++) fscale = PetscMax(fscale, PetscAbsReal(e[ng + i]));
  if (ifc->grange) {
    PetscInt c = 0;
    for (PetscInt k = 0; k < ng; k++) {
      PetscReal ve = 0;
      for (PetscInt i = 0; i < ng; i++) ve += PetscRealPart(ifc->gQ[k * ng + i]) * e[i];
      if (c < ifc->grank && ifc->grange[c] == k) {
        e[ng + c++] = ve;
        continue;
      }
      if (PetscAbsReal(ve) > PetscMax(1e-8 * fscale, eround)) { /* a mechanism under load: name its bodies */
        char     names[512] = "";
        size_t   len;
        for (PetscInt b = 0; b < ifc->nbodies; b++) {
          PetscReal share = 0;
          for (PetscInt i = ifc->goff[b]; i < ifc->goff[b + 1]; i++) share += PetscSqr(PetscRealPart(ifc->gQ[k * ng + i]));
          if (share > 1e-6) {
            PetscCall(PetscStrlen(names, &len));
            PetscCall(PetscSNPrintf(names + len, sizeof(names) - len, "%s'%s'", len ? ", " : "", ifc->scene->bodies[b].name));
          }
        }
        SETERRQ(ifc->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: bod%s %s can move as one rigid body that no support and no contact resists, and the load along that motion does not balance (%g against a largest load on a rigid mode of %g); prescribe a displacement that holds it, or run a dynamic analysis", step, (double)time, strchr(names, ',') ? "ies" : "y", names, (double)ve, (double)fscale);
      }
    }
  } else
    for (PetscInt i = 0; i < ng; i++) e[ng + i] = e[i];
  if (rank == size - 1) {
    PetscScalar *a;
    PetscInt     n;
    PetscCall(VecGetLocalSize(ifc->fp.e, &n));
    PetscCall(VecGetArray(ifc->fp.e, &a));
    for (PetscInt i = 0; i < n; i++) a[i] = ifc->gscale[i] * e[ng + i];
    PetscCall(VecRestoreArray(ifc->fp.e, &a));
  }
  PetscCall(PetscFree(e));
  PetscFunctionReturn(0);
}
