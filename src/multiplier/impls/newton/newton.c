/* MBCMULTIPLIERNEWTON: a globalised semismooth Newton method on the Alart-Curnier function.
   Per contact, with u = W r + q (+ G^T alpha) and augmentations rho_n, rho_t,
     xi_n = r_n - rho_n u_n,  phi_n = r_n - max(0, xi_n),
     xi_t = r_t - rho_t u_t,  phi_t = r_t - proj_{|x| <= mu max(0, xi_n)}(xi_t)
   (a frictionless 1-block has phi_n only). phi = 0 is Coulomb's law; its generalised Jacobian is
   dphi = A dr + B du with 3x3 blocks A, B in closed form (separated: A = I, B = 0; stick:
   A = 0, B = diag(rho); slip: the disk projection's derivative). A Newton step solves
   (A + B W) dr = -phi on the contacts not separated (the others get dr = -r), with a sparse LU
   (KSP, prefix -mbc_newton_, MUMPS by default); a non-monotone Armijo line search on
   1/2 |phi|^2 globalises it, and Gauss-Seidel sweeps (type pgs) give the warm start and the
   fallback when the line search fails. rho = 1 / (the diagonal of the contact's block of W),
   so phi is in units of r and each contact's augmentation matches its own flexibility.
   A direction without flexibility (W_dd = 0: the DOFs are prescribed on both sides) carries no
   multiplier: phi_d = r_d. With equilibrium constraints G r = e (bodies free in a static
   analysis), alpha joins the unknowns and the step solves the saddle point system
   [A + B W, B G^T; G, 0]. The merit that stops the iteration is FCLIB's. */
#include "newtonimpl.h"
#include <mbcontact.h>
#include <petscblaslapack.h>
#if defined(PETSC_HAVE_SCALAPACK)
  #include <petsc/private/petscscalapack.h>
#endif

PETSC_EXTERN void dsymv_(const char *, const PetscBLASInt *, const PetscScalar *, const PetscScalar *, const PetscBLASInt *, const PetscScalar *, const PetscBLASInt *, const PetscScalar *, PetscScalar *, const PetscBLASInt *);

/* Alart-Curnier residual of this rank's contacts at (r, u) into phi; with jac, also the Jacobian
   blocks and the active flags; stick: every contact in contact is taken as sticking (the
   predictor from r = 0). Returns psi = 1/2 |phi|^2 + 1/2 |G r - e|^2 over all ranks. */
static PetscErrorCode ACResidual(MBCMultiplier m, Vec r, Vec u, PetscBool jac, PetscBool stick, PetscReal *psi, PetscBool *slips)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  const PetscScalar  *rv, *uv;
  PetscScalar        *pv;
  PetscReal           s2 = 0, gn2 = 0;
  PetscBool           slip = PETSC_FALSE;
  const PetscBool     closed = (PetscBool)(stick && nt->closeall);

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(r, &rv));
  PetscCall(VecGetArrayRead(u, &uv));
  PetscCall(VecGetArray(nt->phi, &pv));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt  o = fp->off[i], dim = fp->off[i + 1] - o;
    const PetscReal rn = nt->rho[2 * i], rt = nt->rho[2 * i + 1], mu = dim == 3 ? fp->mu[i] : 0;
    PetscReal       R[3] = {0, 0, 0}, U[3] = {0, 0, 0}, P[3], A[9] = {0}, B[9] = {0}, xn;
    for (PetscInt d = 0; d < dim; d++) R[d] = PetscRealPart(rv[o + d]), U[d] = PetscRealPart(uv[o + d]);
    xn = R[0] - rn * U[0];
    if (jac) nt->sticks[i] = PETSC_FALSE, nt->nu[2 * i] = nt->nu[2 * i + 1] = 0;
    if (nt->frozen[o] || (xn <= 0 && !closed)) { /* separated (or no flexibility along the normal): r = 0 */
      for (PetscInt d = 0; d < dim; d++) P[d] = R[d], A[4 * d] = 1;
      if (jac) nt->active[i] = PETSC_FALSE;
    } else {
      P[0] = rn * U[0], B[0] = rn;
      if (jac && dim == 1) nt->sticks[i] = PETSC_TRUE;
      if (dim == 3) {
        const PetscReal g = mu * xn;
        PetscReal       xt[2], nrm;
        for (PetscInt d = 1; d < 3; d++) xt[d - 1] = nt->frozen[o + d] ? 0 : R[d] - rt * U[d];
        nrm = PetscSqrtReal(xt[0] * xt[0] + xt[1] * xt[1]);
        if ((nrm <= g || stick) && (g > 0 || (closed && mu > 0))) { /* stick */
          for (PetscInt d = 1; d < 3; d++) P[d] = rt * U[d], B[4 * d] = rt;
          if (jac) nt->sticks[i] = PETSC_TRUE;
        } else if (g == 0 || nrm == 0) { /* no friction force */
          for (PetscInt d = 1; d < 3; d++) P[d] = R[d], A[4 * d] = 1;
        } else { /* slip: r_t = g nu, nu = xi_t / |xi_t| */
          const PetscReal nu[2] = {xt[0] / nrm, xt[1] / nrm}, sc = g / nrm;
          slip = PETSC_TRUE;
          if (jac) nt->nu[2 * i] = nu[0], nt->nu[2 * i + 1] = nu[1];
          for (PetscInt a = 0; a < 2; a++) {
            P[1 + a] = R[1 + a] - g * nu[a];
            for (PetscInt b = 0; b < 2; b++) {
              const PetscReal proj = (a == b ? 1 : 0) - nu[a] * nu[b];
              A[3 * (1 + a) + 1 + b] = (a == b ? 1 : 0) - sc * proj;
              B[3 * (1 + a) + 1 + b] = sc * rt * proj;
            }
            A[3 * (1 + a)] = -mu * nu[a];
            B[3 * (1 + a)] = mu * rn * nu[a];
          }
        }
        for (PetscInt d = 1; d < 3; d++)
          if (nt->frozen[o + d]) { /* no multiplier along it */
            P[d] = R[d];
            for (PetscInt e = 0; e < 3; e++) A[3 * d + e] = B[3 * d + e] = 0;
            A[4 * d] = 1;
          }
      }
      if (jac) nt->active[i] = PETSC_TRUE;
    }
    for (PetscInt d = 0; d < dim; d++) {
      pv[o + d] = P[d];
      s2 += P[d] * P[d];
    }
    if (jac) /* stored dim x dim, row-major, in 9 slots */
      for (PetscInt d = 0; d < dim; d++)
        for (PetscInt e = 0; e < dim; e++) nt->A[9 * i + dim * d + e] = A[3 * d + e], nt->B[9 * i + dim * d + e] = B[3 * d + e];
  }
  PetscCall(VecRestoreArray(nt->phi, &pv));
  PetscCall(VecRestoreArrayRead(u, &uv));
  PetscCall(VecRestoreArrayRead(r, &rv));
  PetscCall(MBCFrictionEquilibriumResidual2(fp, r, &gn2));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &s2, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)m)));
  *psi = 0.5 * (s2 + gn2);
  if (slips) PetscCallMPI(MPI_Allreduce(&slip, slips, 1, MPIU_BOOL, MPI_LOR, PetscObjectComm((PetscObject)m)));
  PetscFunctionReturn(0);
}

/* Factors J (the operator of ksp, the sparse or the dense KSP). LAPACK's and ScaLAPACK's LU in
   PETSc 3.18 raise an error on a singular matrix (a zero pivot, ScaLAPACK's info > 0) instead of
   flagging a failed factor: it is returned as *failed, collectively, and the step falls back. */
static PetscErrorCode NewtonFactor(MBCMultiplier m, KSP ksp, PetscBool *failed)
{
  MBC_Newton    *nt    = (MBC_Newton *)m->data;
  PetscBool      dense = (PetscBool)(ksp == nt->kdense);
  PetscErrorCode ierr;
  PetscMPIInt    bad;

  PetscFunctionBegin;
  if (dense) PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KSPSetUp(ksp);
  if (dense) PetscCall(PetscPopErrorHandler());
  PetscCheck(!ierr || ierr == PETSC_ERR_MAT_LU_ZRPVT || ierr == PETSC_ERR_LIB, PETSC_COMM_SELF, ierr, "The Newton matrix's factorization failed");
  bad = ierr ? 1 : 0; /* LAPACK under PCREDUNDANT fails on every rank alike, yet all must know */
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, PetscObjectComm((PetscObject)m)));
  *failed = (PetscBool)bad;
  if (bad) {
    PetscCall(PetscInfo(m, "Newton matrix: a zero pivot in its dense LU\n"));
    PetscCall(KSPReset(ksp));
  }
  nt->klu = bad ? NULL : ksp;
  nt->factors++;
  PetscFunctionReturn(0);
}

/* x = J^-1 b by the kept factor, then (unless its PC refines, PCMBCMIXEDLU) up to two steps of
   iterative refinement against the factor's rounding: the static saddle-point systems (free
   bodies) are conditioned enough that a plain solve floored the merit near 1e-8. b and x hold
   each rank's active rows; ScaLAPACK's J has equal rows per rank, so there the solve runs in J's
   layout. */
static PetscErrorCode NewtonLUSolve(KSP klu, Vec b, Vec x, KSPConvergedReason *reason)
{
  Mat         J;
  Vec         bj = b, xj = x, res, dx;
  VecScatter  lay = NULL;
  PetscInt    nj, nb;
  PetscMPIInt differ;
  PetscReal   r0, r1;
  PetscBool   refined; /* the PC refines its solves itself */

  PetscFunctionBegin;
  PetscCall(KSPGetOperators(klu, &J, NULL));
  PetscCall(MatGetLocalSize(J, &nj, NULL));
  PetscCall(VecGetLocalSize(b, &nb));
  differ = nj != nb;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &differ, 1, MPI_INT, MPI_LOR, PetscObjectComm((PetscObject)klu)));
  if (differ) {
    IS       rows;
    PetscInt start;
    PetscCall(MatCreateVecs(J, &xj, &bj));
    PetscCall(VecGetOwnershipRange(b, &start, NULL));
    PetscCall(ISCreateStride(PetscObjectComm((PetscObject)klu), nb, start, 1, &rows)); /* the same global rows */
    PetscCall(VecScatterCreate(b, rows, bj, rows, &lay));
    PetscCall(ISDestroy(&rows));
    PetscCall(VecScatterBegin(lay, b, bj, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(lay, b, bj, INSERT_VALUES, SCATTER_FORWARD));
  }
  PetscCall(KSPSolve(klu, bj, xj));
  PetscCall(KSPGetConvergedReason(klu, reason));
  {
    PC pc;
    PetscCall(KSPGetPC(klu, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCMBCMIXEDLU, &refined));
  }
  if (*reason >= 0 && !refined) {
    PetscCall(VecDuplicate(bj, &res));
    PetscCall(VecDuplicate(bj, &dx));
    PetscCall(MatMult(J, xj, res));
    PetscCall(VecAYPX(res, -1.0, bj));
    for (PetscInt k = 0, shifted = 1; k < 2 && shifted; k++) {
      PetscCall(VecNorm(res, NORM_2, &r0));
      PetscCall(KSPSolve(klu, res, dx));
      PetscCall(VecAXPY(xj, 1.0, dx));
      PetscCall(MatMult(J, xj, res));
      PetscCall(VecAYPX(res, -1.0, bj));
      PetscCall(VecNorm(res, NORM_2, &r1));
      if (!(r1 < 0.5 * r0)) { /* no gain: undo and stop */
        PetscCall(VecAXPY(xj, -1.0, dx));
        shifted = 0;
      }
    }
    PetscCall(VecDestroy(&res));
    PetscCall(VecDestroy(&dx));
  }
  if (differ) {
    PetscCall(VecScatterBegin(lay, xj, x, INSERT_VALUES, SCATTER_REVERSE));
    PetscCall(VecScatterEnd(lay, xj, x, INSERT_VALUES, SCATTER_REVERSE));
    PetscCall(VecScatterDestroy(&lay));
    PetscCall(VecDestroy(&bj));
    PetscCall(VecDestroy(&xj));
  }
  PetscFunctionReturn(0);
}

/* A slipping contact's rows of the Newton step: its tangential row along the slip direction nu,
   less mu times its normal row, reads dr_nu - mu dr_n = c, c = mu phi_n - nu . phi_t, free of W
   (the normal row is rho_n du_n, the nu row -mu dr_n + dr_nu + mu rho_n du_n). So dr_nu = mu dr_n
   + c is eliminated: the contact keeps two unknowns y (dr_n, and dr_tau along tau, nu turned by
   90 degrees), dr = T y + (0, c nu), and two rows L (the normal row, tau . the tangential rows).
   The step is the same; its LU has two rows, not three, per slipping contact, where in an
   earthquake's strong phase 40-80 % of the active contacts slip. */
typedef struct {
  PetscInt  n;       /* the contact's rows (and unknowns) in the Newton matrix */
  PetscBool reduced; /* its slip row eliminated: n = 2, L and T hold */
  PetscReal L[6];    /* 2 x 3, row-major */
  PetscReal T[6];    /* 3 x 2, row-major */
} NewtonFrame;

static void NewtonContactFrame(const MBC_Newton *nt, const MBCFrictionProblem *fp, PetscBool eliminate, PetscInt i, NewtonFrame *f)
{
  const PetscInt   o = fp->off[i], dim = fp->off[i + 1] - o;
  const PetscReal *nu = &nt->nu[2 * i];

  f->n       = dim;
  f->reduced = (PetscBool)(eliminate && dim == 3 && nt->active[i] && (nu[0] != 0 || nu[1] != 0) && !nt->frozen[o] && !nt->frozen[o + 1] && !nt->frozen[o + 2]);
  if (f->reduced) {
    const PetscReal mu = fp->mu[i], tau[2] = {-nu[1], nu[0]};
    const PetscReal L[6] = {1, 0, 0, 0, tau[0], tau[1]}, T[6] = {1, 0, mu * nu[0], tau[0], mu * nu[1], tau[1]};
    f->n = 2;
    for (PetscInt k = 0; k < 6; k++) f->L[k] = L[k], f->T[k] = T[k];
  }
}

static inline PetscReal FrameL(const NewtonFrame *f, PetscInt d, PetscInt e)
{
  return f->reduced ? f->L[3 * d + e] : (PetscReal)(d == e);
}

static inline PetscReal FrameT(const NewtonFrame *f, PetscInt e, PetscInt d)
{
  return f->reduced ? f->T[2 * e + d] : (PetscReal)(e == d);
}

#if defined(PETSC_HAVE_SCALAPACK)
/* J (a MATSCALAPACK) from each rank's block of consecutive rows [rstart, rstart + nloc), dense in
   jl (ld x N, column-major, ld the largest nloc over the ranks): one pdgemr2d a rank's block from
   a padded row-block layout on the P x 1 grid into J's block-cyclic one. Setting the entries one
   by one went through PETSc's stash (a hash of every entry, then its messages). */
static PetscErrorCode DenseRowsToScaLAPACK(Mat J, PetscInt rstart, PetscInt nloc, PetscInt ld, PetscScalar *jl)
{
  Mat_ScaLAPACK *a = (Mat_ScaLAPACK *)J->data;
  MPI_Comm       comm = PetscObjectComm((PetscObject)J);
  PetscMPIInt    size;
  PetscInt      *all;
  PetscBLASInt   desc[9], M, mb, nb, lld, zero = 0, one = 1, info;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscMalloc1(2 * size, &all));
  {
    PetscInt mine[2] = {rstart, nloc};
    PetscCallMPI(MPI_Allgather(mine, 2, MPIU_INT, all, 2, MPIU_INT, comm));
  }
  PetscCall(PetscBLASIntCast(size * ld, &M));
  PetscCall(PetscBLASIntCast(ld, &mb));
  nb  = PetscMax(a->N, 1);
  lld = PetscMax(mb, 1);
  PetscCallBLAS("SCALAPACKdescinit", SCALAPACKdescinit_(desc, &M, &a->N, &mb, &nb, &zero, &zero, &a->grid->ictxcol, &lld, &info));
  PetscCheckScaLapackInfo("descinit", info);
  for (PetscMPIInt p = 0; p < size; p++) {
    PetscBLASInt m, ia, ib;
    if (!all[2 * p + 1]) continue;
    PetscCall(PetscBLASIntCast(all[2 * p + 1], &m));
    PetscCall(PetscBLASIntCast(p * ld + 1, &ia));
    PetscCall(PetscBLASIntCast(all[2 * p] + 1, &ib));
    PetscCallBLAS("SCALAPACKgemr2d", SCALAPACKgemr2d_(&m, &a->N, jl, &ia, &one, desc, a->loc, &ib, &one, a->desc, &a->grid->ictxcol));
  }
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}
#endif

/* A part of W's local rows in CSR (an AIJ W: on several ranks its diagonal block, columns from
   cstart, and its off-diagonal block, columns through cmap), for the Newton matrix's assembly. */
typedef struct {
  Mat                A;
  PetscInt           n, cstart;
  const PetscInt    *i, *j, *cmap;
  const PetscScalar *a;
  PetscBool          done;
} WCSR;

static PetscErrorCode WCSRGet(Mat W, WCSR w[2], PetscInt *n)
{
  PetscBool seq, mpi;

  PetscFunctionBegin;
  *n = 0;
  PetscCall(PetscObjectTypeCompare((PetscObject)W, MATSEQAIJ, &seq));
  PetscCall(PetscObjectTypeCompare((PetscObject)W, MATMPIAIJ, &mpi));
  if (seq) w[0].A = W, *n = 1;
  else if (mpi) {
    PetscCall(MatMPIAIJGetSeqAIJ(W, &w[0].A, &w[1].A, &w[1].cmap));
    PetscCall(MatGetOwnershipRangeColumn(W, &w[0].cstart, NULL));
    *n = 2;
  }
  for (PetscInt p = 0; p < *n; p++) {
    PetscCall(MatGetRowIJ(w[p].A, 0, PETSC_FALSE, PETSC_FALSE, &w[p].n, &w[p].i, &w[p].j, &w[p].done));
    PetscCheck(w[p].done, PETSC_COMM_SELF, PETSC_ERR_PLIB, "W's CSR arrays not available");
    PetscCall(MatSeqAIJGetArrayRead(w[p].A, &w[p].a));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode WCSRRestore(WCSR w[2], PetscInt n)
{
  PetscFunctionBegin;
  for (PetscInt p = 0; p < n; p++) {
    PetscCall(MatSeqAIJRestoreArrayRead(w[p].A, &w[p].a));
    PetscCall(MatRestoreRowIJ(w[p].A, 0, PETSC_FALSE, PETSC_FALSE, &w[p].n, &w[p].i, &w[p].j, &w[p].done));
  }
  PetscFunctionReturn(0);
}

/* W's local rows o .. o + dim - 1 (a contact's) have the same columns in every part */
static PetscBool WCSRRowsAlike(const WCSR w[2], PetscInt n, PetscInt o, PetscInt dim)
{
  for (PetscInt p = 0; p < n; p++) {
    const PetscInt *wi = w[p].i, *wj = w[p].j, c = wi[o + 1] - wi[o];
    for (PetscInt e = 1; e < dim; e++)
      if (wi[o + e + 1] - wi[o + e] != c || memcmp(wj + wi[o], wj + wi[o + e], (size_t)c * sizeof(PetscInt))) return PETSC_FALSE;
  }
  return PETSC_TRUE;
}

/* The Newton step at the current iterate (A, B, active from ACResidual): dr on every row,
   dalpha with equilibrium constraints. Rows of separated contacts: dr = -phi = -r. The active
   rows solve J dr_A = -phi_A - B_A (W dr_I)_A with J = A + B W_AA (+ shift), bordered by
   [B G_A^T; G_A 0] with constraints, each slipping contact in its frame (NewtonFrame). J's rows:
   each rank's active contacts' rows in rank order, then the rigid modes on the last rank. */
static PetscErrorCode NewtonStep(MBCMultiplier m, Vec r, PetscBool slips)
{
  MBC_Newton         *nt   = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp   = m->fp;
  MPI_Comm            comm = PetscObjectComm((PetscObject)m);
  PetscMPIInt         rank, size;
  PetscInt            nA = 0, NA, astart = 0, nR = 0, NR, rstart = 0, ng = 0, nglocal = 0, gstart = 0, *rows, nloc, Nloc;
  IS                  isA;
  Vec                 b, x;
  PetscBool           reuse = PETSC_FALSE, failed = PETSC_FALSE, eliminate;
  KSPConvergedReason  reason;
  NewtonFrame        *fr;
  PetscReal          *cnu; /* per contact: c of its eliminated row */

  PetscFunctionBegin;
  {
    PetscBool done;
    nt->wdr_of_dr = PETSC_FALSE;
    PetscCall(MBCNewtonLowRankStep(m, &done));
    if (done) PetscFunctionReturn(0);
  }
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  eliminate = (PetscBool)(nt->slip_eliminate && slips && !fp->Winv);
  PetscCall(PetscMalloc1(fp->off[fp->nc] + 1, &rows));
  PetscCall(PetscMalloc2(fp->nc + 1, &fr, fp->nc + 1, &cnu));
  {
    PetscInt           rs;
    const PetscScalar *pv;
    PetscCall(MatGetOwnershipRange(fp->W, &rs, NULL));
    PetscCall(VecGetArrayRead(nt->phi, &pv));
    for (PetscInt i = 0; i < fp->nc; i++) {
      const PetscInt o = fp->off[i];
      cnu[i]           = 0;
      if (!nt->active[i]) continue;
      for (PetscInt d = o; d < fp->off[i + 1]; d++) rows[nA++] = rs + d;
      NewtonContactFrame(nt, fp, eliminate, i, &fr[i]);
      nR += fr[i].n;
      if (fr[i].reduced) cnu[i] = fp->mu[i] * PetscRealPart(pv[o]) - nt->nu[2 * i] * PetscRealPart(pv[o + 1]) - nt->nu[2 * i + 1] * PetscRealPart(pv[o + 2]);
    }
    PetscCall(VecRestoreArrayRead(nt->phi, &pv));
  }
  PetscCall(ISCreateGeneral(comm, nA, rows, PETSC_OWN_POINTER, &isA));
  PetscCall(MPIU_Allreduce(&nA, &NA, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(MPIU_Allreduce(&nR, &NR, 1, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Exscan(&nA, &astart, 1, MPIU_INT, MPI_SUM, comm));
  PetscCallMPI(MPI_Exscan(&nR, &rstart, 1, MPIU_INT, MPI_SUM, comm));
  if (!rank) astart = rstart = 0;
  if (fp->G) {
    PetscCall(MatGetSize(fp->G, &ng, NULL));
    PetscCall(MatGetOwnershipRange(fp->G, &gstart, NULL));
    PetscCall(MatGetLocalSize(fp->G, &nglocal, NULL));
  }
  /* dr = -phi on the separated rows, 0 on the active ones but a slipping contact's eliminated
     part (0, c nu), then t = W dr */
  PetscCall(VecCopy(nt->phi, nt->dr));
  PetscCall(VecScale(nt->dr, -1.0));
  {
    PetscScalar *dv;
    PetscCall(VecGetArray(nt->dr, &dv));
    for (PetscInt i = 0; i < fp->nc; i++)
      if (nt->active[i]) {
        const PetscInt o = fp->off[i];
        for (PetscInt d = o; d < fp->off[i + 1]; d++) dv[d] = 0;
        if (fr[i].reduced) dv[o + 1] = cnu[i] * nt->nu[2 * i], dv[o + 2] = cnu[i] * nt->nu[2 * i + 1];
      }
    PetscCall(VecRestoreArray(nt->dr, &dv));
  }
  PetscCall(MBCNewtonWMult(nt, nt->dr, PETSC_FALSE, nt->wdr));
  nloc = nR + (rank == size - 1 ? ng : 0);
  Nloc = NR + ng;
  if (!Nloc) { /* every contact separated */
    PetscCall(ISDestroy(&isA));
    PetscCall(PetscFree2(fr, cnu));
    PetscFunctionReturn(0);
  }
  /* right side: L (-phi_A - B_A (W dr)_A); with constraints e - G (r + dr) */
  PetscCall(VecCreateMPI(comm, nloc, Nloc, &b));
  PetscCall(VecDuplicate(b, &x));
  {
    const PetscScalar *pv, *tv;
    PetscScalar       *bv;
    PetscCall(VecGetArrayRead(nt->phi, &pv));
    PetscCall(VecGetArrayRead(nt->wdr, &tv));
    PetscCall(VecGetArray(b, &bv));
    for (PetscInt i = 0, k = 0; i < fp->nc; i++) {
      const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
      PetscReal      bf[3];
      if (!nt->active[i]) continue;
      for (PetscInt d = 0; d < dim; d++) {
        bf[d] = -PetscRealPart(pv[o + d]);
        for (PetscInt e = 0; e < dim; e++) bf[d] -= nt->B[9 * i + dim * d + e] * PetscRealPart(tv[o + e]);
      }
      for (PetscInt d = 0; d < fr[i].n; d++, k++) {
        bv[k] = 0;
        for (PetscInt e = 0; e < dim; e++) bv[k] += FrameL(&fr[i], d, e) * bf[e];
      }
    }
    PetscCall(VecRestoreArray(b, &bv));
    PetscCall(VecRestoreArrayRead(nt->wdr, &tv));
    PetscCall(VecRestoreArrayRead(nt->phi, &pv));
  }
  if (fp->G) { /* e - G (r + dr), into the last rank's tail of b */
    Vec        g, t;
    VecScatter sc;
    IS         isg;
    PetscCall(VecDuplicate(fp->e, &g));
    PetscCall(VecDuplicate(r, &t));
    PetscCall(VecWAXPY(t, 1.0, r, nt->dr));
    PetscCall(MatMult(fp->G, t, g));
    PetscCall(VecAYPX(g, -1.0, fp->e));
    PetscCall(ISCreateStride(comm, nglocal, NR + gstart, 1, &isg));
    PetscCall(VecScatterCreate(g, NULL, b, isg, &sc));
    PetscCall(VecScatterBegin(sc, g, b, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, g, b, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterDestroy(&sc));
    PetscCall(ISDestroy(&isg));
    PetscCall(VecDestroy(&g));
    PetscCall(VecDestroy(&t));
  }
  if (fp->Winv) { /* W a shell: GMRES (newtonkrylov.c) */
    PetscCall(MBCNewtonKrylovSolve(m, isA, nA, b, x, &reason));
  } else {
    /* an all-stick system on the same rows is the kept one (J = B W_AA: B depends on rho only) */
    if (!slips && !fp->G && nt->isbuilt && !nt->keptslip) {
      PetscBool same;
      PetscCall(ISEqualUnsorted(isA, nt->isbuilt, &same));
      reuse = same;
    }
    if (!reuse) {
      Mat          J, GTs = NULL, Gs = NULL;
      PetscInt    *dnz, *onz, jstart, jend, nmark, *act, wstart, *tcol;
      PetscReal    dmax = 0, nnz = 0, *twt;
      PetscBool    dense = PETSC_FALSE;
      PetscScalar *vals, *jl = NULL; /* jl: this rank's rows of a ScaLAPACK J, dense (jld x Nloc) */
      PetscInt     jld = 0;
      WCSR         wcsr[2] = {{0}}; /* W's CSR parts on this rank: its diagonal and off-diagonal blocks */
      PetscInt     nwcsr   = 0;
      { /* per column of W, its active row (-1: not active), and per active row the (up to two)
           columns of J it contributes to with their weights (T's row): J's rows are read from W's
           own rows (copying W_AA out first, MatCreateSubMatrix, took 4 s of a 90-step dam
           earthquake) */
        IS              isall;
        const PetscInt *all;
        PetscInt        NW, *lcol, n2;
        PetscReal      *lwt;
        PetscMPIInt    *cnt, *dsp;
        PetscCall(MatGetSize(fp->W, &NW, NULL));
        PetscCall(PetscMalloc1(NW + 1, &act));
        for (PetscInt c = 0; c < NW; c++) act[c] = -1;
        PetscCall(ISAllGather(isA, &isall));
        PetscCall(ISGetIndices(isall, &all));
        for (PetscInt j = 0; j < NA; j++) act[all[j]] = j;
        PetscCall(ISRestoreIndices(isall, &all));
        PetscCall(ISDestroy(&isall));
        PetscCall(MatGetOwnershipRange(fp->W, &wstart, NULL));
        PetscCall(PetscMalloc2(2 * nA + 1, &lcol, 2 * nA + 1, &lwt));
        for (PetscInt i = 0, ka = 0, k = rstart; i < fp->nc; i++) {
          const PetscInt dim = fp->off[i + 1] - fp->off[i];
          if (!nt->active[i]) continue;
          for (PetscInt e = 0; e < dim; e++, ka++)
            for (PetscInt s = 0; s < 2; s++) {
              const PetscReal w = fr[i].reduced ? FrameT(&fr[i], e, s) : (s ? 0 : 1);
              lcol[2 * ka + s]  = w != 0 ? k + (fr[i].reduced ? s : e) : -1;
              lwt[2 * ka + s]   = w;
            }
          k += fr[i].n;
        }
        PetscCall(MBCNewtonRowsAllGather(comm, 2 * nA, lcol, &n2, &tcol, &cnt, &dsp));
        PetscCall(PetscMalloc1(n2 + 1, &twt));
        PetscCallMPI(MPI_Allgatherv(lwt, cnt[rank], MPIU_REAL, twt, cnt, dsp, MPIU_REAL, comm));
        PetscCall(PetscFree2(cnt, dsp));
        PetscCall(PetscFree2(lcol, lwt));
      }
      if (fp->G) {
        Mat GT;
        IS  isall, isgrows;
        PetscCall(MatTranspose(fp->G, MAT_INITIAL_MATRIX, &GT));
        PetscCall(ISCreateStride(comm, rank == size - 1 ? ng : 0, 0, 1, &isall));
        PetscCall(MatCreateSubMatrix(GT, isA, isall, MAT_INITIAL_MATRIX, &GTs));
        PetscCall(ISCreateStride(comm, nglocal, gstart, 1, &isgrows));
        PetscCall(MatCreateSubMatrix(fp->G, isgrows, isA, MAT_INITIAL_MATRIX, &Gs));
        PetscCall(ISDestroy(&isall));
        PetscCall(ISDestroy(&isgrows));
        PetscCall(MatDestroy(&GT));
      }
      jstart = rstart; /* J's rows and columns on this rank */
      jend   = rstart + nloc;
      if (!nt->work) PetscCall(PetscMalloc3(3 * (Nloc + 1), &nt->work, Nloc + 1, &nt->mark, Nloc + 1, &nt->cols));
      else {
        PetscCall(PetscFree3(nt->work, nt->mark, nt->cols));
        PetscCall(PetscMalloc3(3 * (Nloc + 1), &nt->work, Nloc + 1, &nt->mark, Nloc + 1, &nt->cols));
      }
      for (PetscInt k = 0; k <= Nloc; k++) nt->mark[k] = -1;
      for (PetscInt k = 0; k < 3 * (Nloc + 1); k++) nt->work[k] = 0;
      PetscCall(PetscMalloc3(nloc + 1, &dnz, nloc + 1, &onz, Nloc + 1, &vals));
      if (!GTs) PetscCall(WCSRGet(fp->W, wcsr, &nwcsr));
      /* two passes over the active contacts: the row patterns (preallocation), then the values */
      for (PetscInt pass = 0; pass < 2; pass++) {
        if (pass == 1) { /* dense storage and LAPACK's LU when J is mostly nonzero: a dam's
                            interface couples every contact with every other through its bodies
                            (99 % of the 198k dam's J), where MUMPS's sparse LU ran 2 x slower;
                            from about half full LAPACK wins (bench/newton_lu.py) */
          for (PetscInt k = 0; k < nloc; k++) nnz += (PetscReal)(dnz[k] + onz[k]);
          PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nnz, 1, MPIU_REAL, MPIU_SUM, comm));
          dense = (PetscBool)(nnz >= nt->dense_fill * (PetscReal)Nloc * (PetscReal)Nloc);
          PetscCall(PetscInfo(m, "Newton matrix %" PetscInt_FMT ": %.3g of its entries nonzero, %s, %" PetscInt_FMT " slip rows eliminated\n", Nloc, (double)(nnz / ((PetscReal)Nloc * Nloc)), !dense ? "sparse" : strcmp(nt->densetype, MATDENSE) ? "dense (ScaLAPACK LU)" : "dense (LAPACK LU)", NA + ng - Nloc));
          if (dense && strcmp(nt->densetype, MATDENSE)) { /* ScaLAPACK's own row layout (NewtonLUSolve) */
            PetscCall(MatCreateScaLAPACK(comm, PETSC_DECIDE, PETSC_DECIDE, Nloc, Nloc, 0, 0, &J));
#if defined(PETSC_HAVE_SCALAPACK)
            if (!Gs) { /* the rows dense here, then moved (DenseRowsToScaLAPACK); G's rows come from every rank */
              PetscCallMPI(MPI_Allreduce(&nloc, &jld, 1, MPIU_INT, MPI_MAX, comm));
              PetscCall(PetscCalloc1((size_t)jld * Nloc + 1, &jl));
            }
#endif
          } else if (dense) {
            PetscCall(MatCreateDense(comm, nloc, nloc, Nloc, Nloc, NULL, &J));
          } else {
            PetscCall(MatCreateAIJ(comm, nloc, nloc, Nloc, Nloc, 0, dnz, 0, onz, &J));
            PetscCall(MatSetOption(J, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
          }
        }
        for (PetscInt i = 0, k = 0, ka = 0; i < fp->nc; i++) {
          const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o, nd = fr[i].n;
          PetscReal      Br[9], Ar[9]; /* L B (nd x dim) and L A T (nd x nd) */
          if (!nt->active[i]) continue;
          for (PetscInt d = 0; d < nd && pass == 1; d++) {
            for (PetscInt e = 0; e < dim; e++) {
              Br[3 * d + e] = 0;
              for (PetscInt g = 0; g < dim; g++) Br[3 * d + e] += FrameL(&fr[i], d, g) * nt->B[9 * i + dim * g + e];
            }
            for (PetscInt e = 0; e < nd; e++) {
              Ar[3 * d + e] = 0;
              for (PetscInt g = 0; g < dim; g++)
                for (PetscInt h = 0; h < dim; h++) Ar[3 * d + e] += FrameL(&fr[i], d, g) * nt->A[9 * i + dim * g + h] * FrameT(&fr[i], h, e);
            }
          }
          nmark = 0;
          if (nwcsr && WCSRRowsAlike(wcsr, nwcsr, o, dim)) { /* one pass over the columns for all its rows */
            for (PetscInt part = 0; part < nwcsr; part++) {
              const WCSR     *w  = &wcsr[part];
              const PetscInt *cc = w->j + w->i[o];
              for (PetscInt j = 0; j < w->i[o + 1] - w->i[o]; j++) {
                const PetscInt ja = act[w->cmap ? w->cmap[cc[j]] : w->cstart + cc[j]];
                PetscReal      bw[3] = {0, 0, 0}; /* L B W's column on the contact's rows */
                if (ja < 0) continue;
                for (PetscInt d = 0; d < nd && pass == 1; d++)
                  for (PetscInt e = 0; e < dim; e++) bw[d] += Br[3 * d + e] * PetscRealPart(w->a[w->i[o + e] + j]);
                for (PetscInt s = 0; s < 2; s++) {
                  const PetscInt c = tcol[2 * ja + s];
                  if (c < 0) continue;
                  if (nt->mark[c] < 0) nt->mark[c] = nmark, nt->cols[nmark++] = c;
                  if (pass == 1)
                    for (PetscInt d = 0; d < nd; d++) nt->work[3 * nt->mark[c] + d] += twt[2 * ja + s] * bw[d];
                }
              }
            }
          } else {
            for (PetscInt e = 0; e < dim; e++) { /* the union of the contact's rows of W_AA and G_A^T */
              for (PetscInt part = 0; part < (GTs ? 2 : 1); part++) {
                Mat                src = part ? GTs : fp->W;
                const PetscInt     grow = part ? astart + ka + e : wstart + o + e;
                PetscInt           ncols;
                const PetscInt    *cc;
                const PetscScalar *vv;
                PetscCall(MatGetRow(src, grow, &ncols, &cc, &vv));
                for (PetscInt j = 0; j < ncols; j++) {
                  const PetscInt ja = part ? -1 : act[cc[j]];
                  if (!part && ja < 0) continue;
                  for (PetscInt s = 0; s < (part ? 1 : 2); s++) {
                    const PetscInt  c = part ? cc[j] + NR : tcol[2 * ja + s];
                    const PetscReal v = part ? PetscRealPart(vv[j]) : twt[2 * ja + s] * PetscRealPart(vv[j]);
                    if (c < 0) continue;
                    if (nt->mark[c] < 0) nt->mark[c] = nmark, nt->cols[nmark++] = c;
                    if (pass == 1)
                      for (PetscInt d = 0; d < nd; d++) nt->work[3 * nt->mark[c] + d] += Br[3 * d + e] * v;
                  }
                }
                PetscCall(MatRestoreRow(src, grow, &ncols, &cc, &vv));
              }
            }
          }
          for (PetscInt e = 0; e < nd; e++) { /* the contact's own columns (A and the shift) */
            const PetscInt c = rstart + k + e;
            if (nt->mark[c] < 0) nt->mark[c] = nmark, nt->cols[nmark++] = c;
          }
          for (PetscInt d = 0; d < nd; d++) {
            const PetscInt grow = rstart + k + d;
            if (pass == 0) {
              dnz[k + d] = onz[k + d] = 0;
              for (PetscInt j = 0; j < nmark; j++) {
                if (nt->cols[j] >= jstart && nt->cols[j] < jend) dnz[k + d]++;
                else onz[k + d]++;
              }
            } else {
              for (PetscInt e = 0; e < nd; e++) nt->work[3 * nt->mark[rstart + k + e] + d] += Ar[3 * d + e];
              dmax = PetscMax(dmax, PetscAbsReal(nt->work[3 * nt->mark[grow] + d]));
              if (jl)
                for (PetscInt j = 0; j < nmark; j++) jl[k + d + (size_t)jld * nt->cols[j]] = nt->work[3 * j + d];
              else {
                for (PetscInt j = 0; j < nmark; j++) vals[j] = nt->work[3 * j + d];
                PetscCall(MatSetValues(J, 1, &grow, nmark, nt->cols, vals, INSERT_VALUES));
              }
            }
          }
          for (PetscInt j = 0; j < nmark; j++) { /* clear the work rows */
            nt->mark[nt->cols[j]] = -1;
            for (PetscInt d = 0; d < 3; d++) nt->work[3 * j + d] = 0;
          }
          k += nd;
          ka += dim;
        }
        if (Gs) { /* equilibrium rows G_A T on the last rank's tail */
          for (PetscInt j = 0; j < nglocal; j++) {
            const PetscInt     grow = gstart + j, jrow = NR + gstart + j;
            PetscInt           ncols;
            const PetscInt    *cc;
            const PetscScalar *vv;
            if (pass == 0) continue;
            PetscCall(MatGetRow(Gs, grow, &ncols, &cc, &vv));
            nmark = 0;
            for (PetscInt l = 0; l < ncols; l++)
              for (PetscInt s = 0; s < 2; s++) {
                const PetscInt c = tcol[2 * cc[l] + s];
                if (c < 0) continue;
                if (nt->mark[c] < 0) nt->mark[c] = nmark, nt->cols[nmark++] = c;
                nt->work[3 * nt->mark[c]] += twt[2 * cc[l] + s] * PetscRealPart(vv[l]);
              }
            PetscCall(MatRestoreRow(Gs, grow, &ncols, &cc, &vv));
            if (nt->mark[jrow] < 0) nt->mark[jrow] = nmark, nt->cols[nmark++] = jrow;
            for (PetscInt l = 0; l < nmark; l++) {
              vals[l]                = nt->work[3 * l];
              nt->mark[nt->cols[l]] = -1;
              nt->work[3 * l]        = 0;
            }
            PetscCall(MatSetValues(J, 1, &jrow, nmark, nt->cols, vals, INSERT_VALUES));
          }
          if (pass == 0 && rank == size - 1)
            for (PetscInt j = 0; j < ng; j++) dnz[nR + j] = nloc, onz[nR + j] = Nloc - nloc;
        }
      }
      PetscCall(WCSRRestore(wcsr, nwcsr));
      if (!jl) {
        PetscCall(MatAssemblyBegin(J, MAT_FLUSH_ASSEMBLY));
        PetscCall(MatAssemblyEnd(J, MAT_FLUSH_ASSEMBLY));
      }
      /* a shift of the contact rows: stick rows of a rank-deficient W (rigid bodies, redundant
         constraints) are singular; it picks the least-force solution and costs the step only
         shift x cond of accuracy, which the next steps recover */
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPIU_REAL, MPIU_MAX, comm));
      if (jl) {
        for (PetscInt k = 0; k < nR; k++) jl[k + (size_t)jld * (rstart + k)] += nt->shift * dmax;
#if defined(PETSC_HAVE_SCALAPACK)
        PetscCall(DenseRowsToScaLAPACK(J, rstart, nloc, jld, jl));
#endif
        PetscCall(PetscFree(jl));
      } else
        for (PetscInt k = 0; k < nR; k++) PetscCall(MatSetValue(J, rstart + k, rstart + k, nt->shift * dmax, ADD_VALUES));
      PetscCall(MatAssemblyBegin(J, MAT_FINAL_ASSEMBLY));
      PetscCall(MatAssemblyEnd(J, MAT_FINAL_ASSEMBLY));
      PetscCall(PetscFree3(dnz, onz, vals));
      PetscCall(PetscFree(act));
      PetscCall(PetscFree(tcol));
      PetscCall(PetscFree(twt));
      PetscCall(MatDestroy(&GTs));
      PetscCall(MatDestroy(&Gs));
      PetscCall(KSPReset(nt->ksp)); /* the old factor, either kind */
      PetscCall(KSPReset(nt->kdense));
      PetscCall(KSPSetOperators(dense ? nt->kdense : nt->ksp, J, J));
      PetscCall(MatDestroy(&J));
      PetscCall(NewtonFactor(m, dense ? nt->kdense : nt->ksp, &failed));
      PetscCall(ISDestroy(&nt->isbuilt));
      if (!failed) {
        nt->isbuilt  = isA;
        nt->keptslip = (PetscBool)(slips || fp->G);
        isA          = NULL;
      }
    }
    if (failed) reason = KSP_DIVERGED_PC_FAILED;
    else PetscCall(NewtonLUSolve(nt->klu, b, x, &reason));
  }
  nt->stepfailed = (PetscBool)(reason < 0);
  if (reason < 0) { /* a failed factorization: steepest descent on 1/2|phi|^2 instead (dr = -phi) */
    PetscCall(PetscInfo(m, "Newton matrix: %s; falling back to dr = -phi\n", KSPConvergedReasons[reason]));
    PetscCall(VecCopy(nt->phi, nt->dr));
    PetscCall(VecScale(nt->dr, -1.0));
    if (fp->G) PetscCall(VecZeroEntries(nt->dalpha));
    PetscCall(ISDestroy(&nt->isbuilt));
  } else { /* dr_A = T y (+ c nu where the slip row is eliminated) */
    const PetscScalar *xv;
    PetscScalar       *dv;
    PetscCall(VecGetArrayRead(x, &xv));
    PetscCall(VecGetArray(nt->dr, &dv));
    for (PetscInt i = 0, k = 0; i < fp->nc; i++) {
      const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
      if (!nt->active[i]) continue;
      if (fr[i].reduced)
        for (PetscInt e = 0; e < 3; e++) dv[o + e] = fr[i].T[2 * e] * xv[k] + fr[i].T[2 * e + 1] * xv[k + 1] + (e ? cnu[i] * nt->nu[2 * i + e - 1] : 0);
      else
        for (PetscInt d = 0; d < dim; d++) dv[o + d] = xv[k + d];
      k += fr[i].n;
    }
    PetscCall(VecRestoreArray(nt->dr, &dv));
    PetscCall(VecRestoreArrayRead(x, &xv));
    if (fp->G) { /* dalpha from the tail of x */
      VecScatter sc;
      IS         isg;
      PetscCall(ISCreateStride(comm, nglocal, NR + gstart, 1, &isg));
      PetscCall(VecScatterCreate(x, isg, nt->dalpha, NULL, &sc));
      PetscCall(VecScatterBegin(sc, x, nt->dalpha, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterEnd(sc, x, nt->dalpha, INSERT_VALUES, SCATTER_FORWARD));
      PetscCall(VecScatterDestroy(&sc));
      PetscCall(ISDestroy(&isg));
    }
  }
  PetscCall(ISDestroy(&isA));
  PetscCall(PetscFree2(fr, cnu));
  PetscCall(VecDestroy(&b));
  PetscCall(VecDestroy(&x));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierSetFromOptions_Newton(MBCMultiplier m, PetscOptionItems *PetscOptionsObject)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  PetscOptionsHeadBegin(PetscOptionsObject, "Semismooth Newton, Alart-Curnier (-mbc_multiplier_type newton)");
  PetscCall(PetscOptionsReal("-newton_rho", "Augmentation rho = this / (the contact's diagonal of W); default 1, 0.5 with a matrix-free W", "MBCMultiplierSetFromOptions", nt->rho_scale, &nt->rho_scale, &nt->rho_set));
  PetscCall(PetscOptionsInt("-newton_pgs_warm", "Gauss-Seidel sweeps before the first Newton step", "MBCMultiplierSetFromOptions", nt->pgs_warm, &nt->pgs_warm, NULL));
  PetscCall(PetscOptionsInt("-newton_pgs_fallback", "Gauss-Seidel sweeps when the line search fails", "MBCMultiplierSetFromOptions", nt->pgs_fallback, &nt->pgs_fallback, NULL));
  PetscCall(PetscOptionsInt("-newton_ls_max", "Halvings of the step in the line search", "MBCMultiplierSetFromOptions", nt->ls_max, &nt->ls_max, NULL));
  PetscCall(PetscOptionsInt("-newton_nonmonotone", "Memory of the non-monotone line search (1: monotone Armijo)", "MBCMultiplierSetFromOptions", nt->nonmonotone, &nt->nonmonotone, NULL));
  PetscCall(PetscOptionsBool("-newton_predictor", "From r = 0, take the all-stick solution as the first iterate", "MBCMultiplierSetFromOptions", nt->predictor, &nt->predictor, NULL));
  PetscCall(PetscOptionsInt("-newton_watchdog", "Iterations without halving the best merit before the solve goes back to the best iterate and sweeps (without sweeps: other rho)", "MBCMultiplierSetFromOptions", nt->watchdog, &nt->watchdog, NULL));
  PetscCall(PetscOptionsReal("-newton_dense_fill", "Fraction of nonzero entries from which the Newton matrix is stored and factored dense (LAPACK); > 1: never", "MBCMultiplierSetFromOptions", nt->dense_fill, &nt->dense_fill, NULL));
  PetscCall(PetscOptionsReal("-newton_w_dense_fill", "Fraction of W's entries nonzero from which the solve's products with W go through a dense copy of it (BLAS); > 1: never", "MBCMultiplierSetFromOptions", nt->w_dense_fill, &nt->w_dense_fill, NULL));
  PetscCall(PetscOptionsBool("-newton_slip_eliminate", "Eliminate each slipping contact's row along its slip direction from the direct Newton step (an exact reduction: two rows, not three)", "MBCMultiplierSetFromOptions", nt->slip_eliminate, &nt->slip_eliminate, NULL));
  PetscCall(PetscOptionsBool("-newton_lowrank", "While W holds, take Newton steps through the kept inverse of a reference state's Newton matrix, corrected on the rows that differ", "MBCMultiplierSetFromOptions", nt->lowrank, &nt->lowrank, NULL));
  PetscCall(PetscOptionsReal("-newton_lowrank_max", "... unless the rows that differ exceed this fraction of the active ones", "MBCMultiplierSetFromOptions", nt->lowrank_max, &nt->lowrank_max, NULL));
  PetscCall(PetscOptionsInt("-newton_lowrank_dist_min", "On several ranks, the kept inverse's correction (k x k) factored over the ranks (ScaLAPACK) from this k on, else on every rank", "MBCMultiplierSetFromOptions", nt->lowrank_dist_min, &nt->lowrank_dist_min, NULL));
  PetscCall(PetscOptionsReal("-newton_shift", "Diagonal shift of the Newton matrix relative to its largest diagonal entry", "MBCMultiplierSetFromOptions", nt->shift, &nt->shift, NULL));
  PetscOptionsHeadEnd();
  PetscCheck(nt->rho_scale > 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_rho %g must be positive", (double)nt->rho_scale);
  PetscCheck(nt->pgs_warm >= 0 && nt->pgs_fallback >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_pgs_warm and -mbc_newton_pgs_fallback must be >= 0");
  PetscCheck(nt->ls_max >= 1 && nt->nonmonotone >= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_ls_max and -mbc_newton_nonmonotone must be at least 1");
  PetscCheck(nt->dense_fill >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_dense_fill %g must be >= 0", (double)nt->dense_fill);
  PetscCheck(nt->w_dense_fill >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_w_dense_fill %g must be >= 0", (double)nt->w_dense_fill);
  PetscCheck(nt->lowrank_max >= 0 && nt->lowrank_max <= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_lowrank_max %g must lie in [0, 1]", (double)nt->lowrank_max);
  PetscCheck(nt->lowrank_dist_min >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_lowrank_dist_min %" PetscInt_FMT " must be >= 0", nt->lowrank_dist_min);
  PetscCheck(nt->shift >= 0 && nt->shift < 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_newton_shift %g must lie in [0, 1)", (double)nt->shift);
  PetscCall(KSPSetFromOptions(nt->ksp));
  PetscCall(KSPSetFromOptions(nt->kdense));
  PetscCall(KSPSetFromOptions(nt->kmf));
  /* the Gauss-Seidel sweeps take the pgs type's options too (-mbc_pgs_omega, ...), never its
     active-set step */
  PetscCall((*nt->pgs->ops->setfromoptions)(nt->pgs, PetscOptionsObject));
  PetscCall(MBCMultiplierPGSSetActiveSet(nt->pgs, 0));
  PetscFunctionReturn(0);
}

/* The augmentations' scale: -mbc_newton_rho, else 1 on W's diagonal, and 1/2 on the lumped estimate
   of a matrix-free W's. That estimate is up to 19 times below W_dd at some points (the joints of
   the 100k dynamic dam, docs/performance.md), and a rho too large there flips their active sets
   with every small change of u: 1/2 took that dam's stalled step from 59 (41 with the watchdog's
   restarts) to 18 Newton steps, the two blocks' 5 steps from 8 to 6, and left the small dynamic
   dam's 75 steps at 235 -> 240. */
static PetscReal NewtonRhoScale(MBCMultiplier m)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;
  return nt->rho_set ? nt->rho_scale : (m->fp && m->fp->Winv ? 0.5 : 1.0);
}

/* rho = scale / (the contact's diagonal of W), normal and tangential; 0 where W has no flexibility. */
static void NewtonAugmentations(MBCMultiplier m, PetscReal scale)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;

  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    PetscReal      wt = 0;
    PetscInt       nt_ = 0;
    nt->rho[2 * i] = nt->frozen[o] ? 0 : scale / nt->diag[0 + 9 * i];
    for (PetscInt d = 1; d < dim; d++)
      if (!nt->frozen[o + d]) wt += nt->diag[9 * i + (dim + 1) * d], nt_++;
    nt->rho[2 * i + 1] = nt_ ? scale * nt_ / wt : 0;
  }
  nt->rho_used = scale;
}

/* *D = W dense in W's layouts, written from W's CSR arrays (MatConvert to MPIDense set it entry by
   entry through the stash: 3.0 s for the 198k dam's W, 0.95 GB) */
static PetscErrorCode WDenseCopy(Mat W, Mat *D)
{
  WCSR         w[2] = {{0}}; /* cstart 0, no cmap: one rank's SeqAIJ W */
  PetscInt     n, mloc, nloc, M, N, lda;
  PetscScalar *d;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(W, &mloc, &nloc));
  PetscCall(MatGetSize(W, &M, &N));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)W), mloc, nloc, M, N, NULL, D));
  PetscCall(MatDenseGetLDA(*D, &lda));
  PetscCall(MatDenseGetArrayWrite(*D, &d)); /* zeroed by its preallocation */
  PetscCall(WCSRGet(W, w, &n));
  PetscCheck(n, PETSC_COMM_SELF, PETSC_ERR_PLIB, "W's dense copy: W is not SeqAIJ or MPIAIJ");
  for (PetscInt p = 0; p < n; p++)
    for (PetscInt i = 0; i < mloc; i++)
      for (PetscInt e = w[p].i[i]; e < w[p].i[i + 1]; e++) d[(size_t)(w[p].cmap ? w[p].cmap[w[p].j[e]] : w[p].cstart + w[p].j[e]) * lda + i] = w[p].a[e];
  PetscCall(WCSRRestore(w, n));
  PetscCall(MatDenseRestoreArrayWrite(*D, &d));
  PetscCall(MatAssemblyBegin(*D, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*D, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}

/* nt->Wprod: W for the solve's products (a few a Newton iteration: the step's W dr, u = W r + q). An
   assembled W fuller than -mbc_newton_w_dense_fill is copied dense: dgemv streams 8 bytes an
   entry at the memory's speed, MatMult_SeqAIJ_Inode 12 bytes at a third of it (the 49k dam's W,
   68 % full: 3.4 ms against 14-21 ms a product). */
static PetscErrorCode NewtonProductOperator(MBCMultiplier m)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  PetscBool           aij, copy;
  MatInfo             info;
  PetscInt            n, mloc;
  PetscReal           fill, avail = 0, mb;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)fp->W, &aij, MATSEQAIJ, MATMPIAIJ, "")); /* the types whose CSR arrays WCSRGet reads */
  if (!aij || nt->w_dense_fill > 1) {
    PetscCall(PetscObjectReference((PetscObject)fp->W));
    nt->Wprod = fp->W;
    PetscFunctionReturn(0);
  }
  PetscCall(MatGetSize(fp->W, &n, NULL));
  PetscCall(MatGetLocalSize(fp->W, &mloc, NULL));
  PetscCall(MatGetInfo(fp->W, MAT_GLOBAL_SUM, &info));
  fill = n ? info.nz_used / ((PetscReal)n * n) : 0;
  copy = (PetscBool)(fill >= nt->w_dense_fill);
  if (copy) { /* an optimization that must not take the memory the solve's factors need next (the
                 Newton matrix, the kept inverse: of the copy's size again): at most a quarter of
                 what this rank may still take */
    PetscCall(MBCMemoryAvailable(PetscObjectComm((PetscObject)m), &avail));
    mb   = 8.0 * mloc * n / 1048576.0;
    copy = (PetscBool)(avail == 0 || mb <= 0.25 * avail);
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &copy, 1, MPIU_BOOL, MPI_LAND, PetscObjectComm((PetscObject)m)));
  }
  if (copy) PetscCall(WDenseCopy(fp->W, &nt->Wprod));
  else {
    PetscCall(PetscObjectReference((PetscObject)fp->W));
    nt->Wprod = fp->W;
  }
  PetscCall(PetscInfo(m, "W %" PetscInt_FMT " x %" PetscInt_FMT ", %.3g full: its products through %s\n", n, n, (double)fill, copy ? "a dense copy" : (fill >= nt->w_dense_fill ? "W (its dense copy would take more than a quarter of the memory this rank may still take)" : "W")));
  PetscFunctionReturn(0);
}

/* y = W x, or y += W x, through nt->Wprod. W is symmetric: its dense copy's diagonal block (on one
   rank the whole copy) by dsymv, which reads one triangle (N = 3 384: 1.7 against 3.8 ms by dgemv
   here), the columns beside it by dgemv from x gathered on every rank. */
PetscErrorCode MBCNewtonWMult(MBC_Newton *nt, Vec x, PetscBool add, Vec y)
{
  const PetscScalar *a, *xa, one = 1, beta = add ? 1 : 0;
  PetscScalar       *ya;
  PetscInt           lda, rstart, rend, N;
  PetscBLASInt       m, nl, nr, blda, inc = 1;
  PetscBool          dense;
  PetscMPIInt        size;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)nt->Wprod, &dense, MATSEQDENSE, MATMPIDENSE, ""));
  if (!dense) {
    if (add) PetscCall(MatMultAdd(nt->Wprod, x, y, y));
    else PetscCall(MatMult(nt->Wprod, x, y));
    PetscFunctionReturn(0);
  }
  PetscCall(MatGetOwnershipRange(nt->Wprod, &rstart, &rend));
  PetscCall(MatGetSize(nt->Wprod, &N, NULL));
  PetscCall(MatDenseGetLDA(nt->Wprod, &lda));
  PetscCall(PetscBLASIntCast(rend - rstart, &m));
  PetscCall(PetscBLASIntCast(rstart, &nl));
  PetscCall(PetscBLASIntCast(N - rend, &nr));
  PetscCall(PetscBLASIntCast(lda, &blda));
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)nt->Wprod), &size));
  if (size > 1 && !nt->wtoall) PetscCall(VecScatterCreateToAll(x, &nt->wtoall, &nt->wxall));
  if (nt->wtoall) {
    PetscCall(VecScatterBegin(nt->wtoall, x, nt->wxall, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(nt->wtoall, x, nt->wxall, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecGetArrayRead(nt->wxall, &xa));
  } else PetscCall(VecGetArrayRead(x, &xa));
  PetscCall(MatDenseGetArrayRead(nt->Wprod, &a));
  PetscCall(VecGetArray(y, &ya));
  if (m) {
    PetscCallBLAS("BLASsymv", dsymv_("U", &m, &one, a + (size_t)rstart * lda, &blda, xa + rstart, &inc, &beta, ya, &inc));
    if (nl) PetscCallBLAS("BLASgemv", BLASgemv_("N", &m, &nl, &one, a, &blda, xa, &inc, &one, ya, &inc));
    if (nr) PetscCallBLAS("BLASgemv", BLASgemv_("N", &m, &nr, &one, a + (size_t)rend * lda, &blda, xa + rend, &inc, &one, ya, &inc));
  }
  PetscCall(PetscLogFlops(2.0 * m * N));
  PetscCall(VecRestoreArray(y, &ya));
  PetscCall(MatDenseRestoreArrayRead(nt->Wprod, &a));
  if (nt->wtoall) PetscCall(VecRestoreArrayRead(nt->wxall, &xa));
  else PetscCall(VecRestoreArrayRead(x, &xa));
  PetscFunctionReturn(0);
}

/* u = W r + q (+ G^T alpha), W's products through nt->Wprod */
PetscErrorCode MBCNewtonVelocity(MBCMultiplier m, Vec r, Vec u)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;

  PetscFunctionBegin;
  PetscCall(VecCopy(fp->q, u));
  PetscCall(MBCNewtonWMult(nt, r, PETSC_TRUE, u));
  if (fp->G) PetscCall(MatMultTransposeAdd(fp->G, fp->alpha, u, u));
  PetscFunctionReturn(0);
}

/* Per W: the diagonal blocks, the augmentations, the directions without flexibility, W for the products. */
static PetscErrorCode MBCMultiplierSetUp_Newton(MBCMultiplier m)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  Mat                 Wd;
  PetscBool           mpi;
  PetscReal           dmax = 0;
  const PetscInt      nrows = fp->off[fp->nc];

  PetscFunctionBegin;
  PetscCall(PetscObjectBaseTypeCompare((PetscObject)fp->W, MATMPIAIJ, &mpi));
  if (fp->Winv) { /* W a shell: W_dd ~ 1 / Winv_dd (FETI's lumped estimate; 0 stays 0, no flexibility) */
    Vec                d;
    const PetscScalar *da;
    PetscCall(PetscCalloc1(9 * fp->nc + 1, &nt->diag));
    PetscCall(MatCreateVecs(fp->Winv, &d, NULL));
    PetscCall(MatGetDiagonal(fp->Winv, d));
    PetscCall(VecGetArrayRead(d, &da));
    for (PetscInt i = 0; i < fp->nc; i++)
      for (PetscInt k = 0, dim = fp->off[i + 1] - fp->off[i]; k < dim; k++) {
        const PetscReal w = PetscRealPart(da[fp->off[i] + k]);
        nt->diag[9 * i + (dim + 1) * k] = w > 0 ? 1.0 / w : 0;
      }
    PetscCall(VecRestoreArrayRead(d, &da));
    PetscCall(VecDestroy(&d));
  } else {
    if (mpi) PetscCall(MatMPIAIJGetSeqAIJ(fp->W, &Wd, NULL, NULL));
    else Wd = fp->W;
    PetscCall(MBCMultiplierDiagonalBlocks(fp, Wd, &nt->diag));
  }
  PetscCall(PetscMalloc5(2 * fp->nc + 1, &nt->rho, nrows + 1, &nt->frozen, 9 * fp->nc + 1, &nt->A, 9 * fp->nc + 1, &nt->B, fp->nc + 1, &nt->active));
  PetscCall(PetscCalloc3(fp->nc + 1, &nt->sticks, fp->nc + 1, &nt->refopen, 2 * fp->nc + 1, &nt->nu));
  for (PetscInt i = 0; i < fp->nc; i++)
    for (PetscInt d = 0, dim = fp->off[i + 1] - fp->off[i]; d < dim; d++) dmax = PetscMax(dmax, nt->diag[9 * i + (dim + 1) * d]);
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &dmax, 1, MPIU_REAL, MPIU_MAX, PetscObjectComm((PetscObject)m)));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    for (PetscInt d = 0; d < dim; d++) nt->frozen[o + d] = (PetscBool)!(nt->diag[9 * i + (dim + 1) * d] > 1e-12 * dmax);
  }
  NewtonAugmentations(m, NewtonRhoScale(m));
  PetscCall(NewtonProductOperator(m));
  PetscCall(MatCreateVecs(fp->W, &nt->phi, NULL));
  PetscCall(VecDuplicate(nt->phi, &nt->dr));
  PetscCall(VecDuplicate(nt->phi, &nt->wdr));
  PetscCall(VecDuplicate(nt->phi, &nt->rt));
  PetscCall(VecDuplicate(nt->phi, &nt->ut));
  if (fp->G) {
    PetscCall(VecDuplicate(fp->alpha, &nt->dalpha));
    PetscCall(VecDuplicate(fp->alpha, &nt->alphat));
  }
  PetscCall(MBCMultiplierSetProblem(nt->pgs, fp));
  PetscFunctionReturn(0);
}

/* Can Gauss-Seidel sweep? Not with equilibrium constraints, nor on W without rows (a shell). */
static PetscBool NewtonCanSweep(MBCMultiplier m)
{
  return (PetscBool)!(m->fp->G || m->fp->Winv);
}

/* Gauss-Seidel sweeps from r (where NewtonCanSweep); u = W r + q after. */
static PetscErrorCode NewtonSweeps(MBCMultiplier m, PetscInt n, Vec r, Vec u)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  if (!n || !NewtonCanSweep(m)) PetscFunctionReturn(0);
  PetscCall(MBCMultiplierSetTolerances(nt->pgs, m->rtol, n));
  PetscCall(MBCMultiplierSolve(nt->pgs, r, u));
  nt->pgssweeps += nt->pgs->its;
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierSolve_Newton(MBCMultiplier m, Vec r, Vec u)
{
  MBC_Newton         *nt = (MBC_Newton *)m->data;
  MBCFrictionProblem *fp = m->fp;
  PetscReal           psi, *hist;
  PetscReal           best;
  PetscBool           slips, ufresh = PETSC_TRUE; /* u = W r + q (+ G^T alpha) computed, not accumulated */
  PetscInt            fails = 0, stall = 0, restarts = 0;
  Vec                 rbest, abest = NULL;
  char                line[128] = "";

  PetscFunctionBegin;
  nt->lsfail = nt->pgssweeps = nt->factors = nt->kits = nt->lowranks = 0;
  if (nt->rho_used != NewtonRhoScale(m)) { /* a restart of the last solve changed them */
    NewtonAugmentations(m, NewtonRhoScale(m));
    PetscCall(ISDestroy(&nt->isbuilt));
  }
  PetscCall(PetscMalloc1(nt->nonmonotone, &hist));
  PetscCall(VecDuplicate(r, &rbest));
  if (fp->G) PetscCall(VecDuplicate(fp->alpha, &abest));
  PetscCall(NewtonSweeps(m, nt->pgs_warm, r, u));
  PetscCall(MBCNewtonVelocity(m, r, u));
  PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
  {
    PetscReal rn;
    PetscCall(VecNorm(r, NORM_INFINITY, &rn));
    if (rn == 0 && nt->predictor && fp->G) { /* from r = 0, the all-stick solution first: Newton's first
                                       classification by the free increment q alone would slip
                                       contacts along q_t, and the iteration may end in another of
                                       the solutions a frictional static problem can have */
      PetscCall(ACResidual(m, r, u, PETSC_TRUE, PETSC_TRUE, &psi, &slips));
      PetscCall(NewtonStep(m, r, PETSC_FALSE));
      if (nt->stepfailed) { /* the contacts the free increment closes cannot hold a free body (its
                               Newton matrix singular: a block stacked on another free block, whose
                               increment alone opens their joint): every contact closed instead */
        PetscCall(PetscInfo(m, "Newton predictor: its matrix singular; every contact taken as closed and sticking\n"));
        nt->closeall = PETSC_TRUE;
        PetscCall(ACResidual(m, r, u, PETSC_TRUE, PETSC_TRUE, &psi, &slips));
        PetscCall(NewtonStep(m, r, PETSC_FALSE));
        nt->closeall = PETSC_FALSE;
      }
      PetscCall(VecAXPY(r, 1.0, nt->dr));
      if (fp->G) PetscCall(VecAXPY(fp->alpha, 1.0, nt->dalpha));
      PetscCall(MBCNewtonVelocity(m, r, u));
      PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      if (PetscIsInfOrNanReal(m->merit)) { /* a failed predictor: start from 0 as without it */
        PetscCall(VecZeroEntries(r));
        if (fp->G) PetscCall(VecZeroEntries(fp->alpha));
        PetscCall(MBCNewtonVelocity(m, r, u));
        PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      }
      PetscCall(ISDestroy(&nt->isbuilt)); /* its factor is no Newton matrix */
    }
  }
  PetscCall(ACResidual(m, r, u, PETSC_TRUE, PETSC_FALSE, &psi, &slips));
  for (PetscInt k = 0; k < nt->nonmonotone; k++) hist[k] = psi;
  best = m->merit;
  PetscCall(VecCopy(r, rbest));
  if (abest) PetscCall(VecCopy(fp->alpha, abest));
  for (m->its = 0;; m->its++) {
    PetscReal ref = hist[0], t = 1, psit = psi;
    PetscInt  ls;
    if (!ufresh && m->merit < m->rtol) { /* converged on the accumulated u: confirmed on u afresh */
      PetscCall(MBCNewtonVelocity(m, r, u));
      PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      PetscCall(ACResidual(m, r, u, PETSC_TRUE, PETSC_FALSE, &psi, &slips));
      ufresh = PETSC_TRUE;
    }
    PetscCall(MBCMultiplierMonitorMerit(m, m->its, m->merit, line));
    if (PetscIsInfOrNanReal(m->merit)) m->reason = MBC_MULTIPLIER_DIVERGED_NANORINF;
    else if (m->merit < m->rtol) m->reason = MBC_MULTIPLIER_CONVERGED_RTOL;
    else if (m->its >= m->max_it) m->reason = MBC_MULTIPLIER_DIVERGED_ITS;
    else if (fails >= 5) m->reason = MBC_MULTIPLIER_DIVERGED_LINE_SEARCH;
    if (m->reason != MBC_MULTIPLIER_ITERATING) break;
    PetscCall(NewtonStep(m, r, slips));
    if (!nt->wdr_of_dr) PetscCall(MBCNewtonWMult(nt, nt->dr, PETSC_FALSE, nt->wdr)); /* wdr = W dr (+ G^T dalpha) */
    if (fp->G) PetscCall(MatMultTransposeAdd(fp->G, nt->dalpha, nt->wdr, nt->wdr));
    for (PetscInt k = 1; k < nt->nonmonotone; k++) ref = PetscMax(ref, hist[k]);
    for (ls = 0; ls < nt->ls_max; ls++, t *= 0.5) { /* Armijo on 1/2|phi|^2: its slope along a Newton step is -|phi|^2 */
      PetscCall(VecWAXPY(nt->rt, t, nt->dr, r));
      PetscCall(VecWAXPY(nt->ut, t, nt->wdr, u));
      if (fp->G) PetscCall(VecWAXPY(nt->alphat, t, nt->dalpha, fp->alpha));
      PetscCall(ACResidual(m, nt->rt, nt->ut, PETSC_FALSE, PETSC_FALSE, &psit, NULL));
      if (psit <= ref - nt->sigma * t * 2 * psi) break;
    }
    if (ls < nt->ls_max || !NewtonCanSweep(m)) { /* accepted (with constraints, or no sweeps to fall back on, the last, shortest step is taken anyway) */
      PetscCall(VecCopy(nt->rt, r));
      if (fp->G) PetscCall(VecCopy(nt->alphat, fp->alpha));
      if (ls == nt->ls_max) fails++, nt->lsfail++;
      else fails = 0;
      /* u + t W dr, not W r + q afresh: a product of W less an iteration (a third of a kept-inverse
         step's cost); the rounding it accumulates is removed where the merit says converged */
      PetscCall(VecCopy(nt->ut, u));
      ufresh = PETSC_FALSE;
    } else { /* Gauss-Seidel sweeps instead (u afresh after them) */
      nt->lsfail++;
      PetscCall(NewtonSweeps(m, nt->pgs_fallback, r, u));
      if (!nt->pgs_fallback) PetscCall(MBCNewtonVelocity(m, r, u));
      ufresh = PETSC_TRUE;
    }
    PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
    if (m->merit < 0.5 * best || (m->merit < best && stall < nt->watchdog)) { /* the best iterate, kept */
      if (m->merit < 0.5 * best) stall = 0;
      else stall++;
      best = m->merit;
      PetscCall(VecCopy(r, rbest));
      if (abest) PetscCall(VecCopy(fp->alpha, abest));
    } else stall++;
    if (stall >= nt->watchdog && m->merit >= m->rtol) { /* the watchdog: no halving of the best merit for a while
                                                           (the non-monotone search wandered, or Newton cycles
                                                           between active sets): back to the best iterate, and
                                                           Gauss-Seidel sweeps, more at each restart, to move it */
      PetscCall(VecCopy(rbest, r));
      if (abest) PetscCall(VecCopy(abest, fp->alpha));
      restarts++;
      if (!nt->pgs_fallback || !NewtonCanSweep(m)) { /* no sweeps to move it (W a shell, or constraints):
                                                      other augmentations, x 2, / 2, x 4, / 4, ... The
                                                      solution does not depend on rho, but the active
                                                      sets Newton visits do: the same start with the same
                                                      rho stalls again (dynamic dam 100k, matrix-free:
                                                      59 steps; from rho 1/2 the first restart at 1
                                                      ended it in 18, one at 1/4 in 26) */
        const PetscInt k = (restarts + 1) / 2;
        NewtonAugmentations(m, NewtonRhoScale(m) * (restarts % 2 ? PetscPowInt(2, k) : 1.0 / PetscPowInt(2, k)));
        PetscCall(ISDestroy(&nt->isbuilt)); /* its Newton matrix had the old rho */
        if (m->monitor) PetscCall(PetscPrintf(PetscObjectComm((PetscObject)m), "  newton watchdog: back to the best iterate (merit %g), rho %g / diag(W)\n", (double)best, (double)nt->rho_used));
      } else PetscCall(NewtonSweeps(m, restarts * nt->pgs_fallback, r, u));
      PetscCall(MBCNewtonVelocity(m, r, u));
      PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
      ufresh = PETSC_TRUE;
      stall = 0;
    }
    PetscCall(ACResidual(m, r, u, PETSC_TRUE, PETSC_FALSE, &psi, &slips));
    if (stall == 0 && restarts && m->merit == best) for (PetscInt k = 0; k < nt->nonmonotone; k++) hist[k] = psi;
    for (PetscInt k = nt->nonmonotone - 1; k > 0; k--) hist[k] = hist[k - 1];
    hist[0] = psi;
    if (m->monitor) PetscCall(PetscSNPrintf(line, sizeof(line), " (%s step %g)", ls < nt->ls_max ? "Newton" : (!NewtonCanSweep(m) ? "shortest" : "Gauss-Seidel after a failed"), (double)t));
  }
  if (!ufresh) { /* a solve stopped unconverged on the accumulated u */
    PetscCall(MBCNewtonVelocity(m, r, u));
    PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
  }
  if (m->reason > 0) { /* the iterate into the cones (Newton's iterates are not in them), kept if it
                          still meets the tolerance: with a rank-deficient W a projection can move u
                          by much more than it moves r */
    PetscScalar *rv;
    PetscReal    before = m->merit;
    PetscCall(VecCopy(r, rbest));
    PetscCall(VecGetArray(r, &rv));
    for (PetscInt i = 0; i < fp->nc; i++) {
      const PetscInt o = fp->off[i];
      if (fp->off[i + 1] - o == 1) rv[o] = PetscMax(0, PetscRealPart(rv[o]));
      else {
        PetscReal x[3] = {PetscRealPart(rv[o]), PetscRealPart(rv[o + 1]), PetscRealPart(rv[o + 2])}, p[3];
        MBCProjectCone(x, fp->mu[i], p);
        for (PetscInt d = 0; d < 3; d++) rv[o + d] = p[d];
      }
    }
    PetscCall(VecRestoreArray(r, &rv));
    PetscCall(MBCNewtonVelocity(m, r, u));
    PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
    if (!(m->merit < m->rtol)) {
      PetscCall(VecCopy(rbest, r));
      PetscCall(MBCNewtonVelocity(m, r, u));
      m->merit = before;
    }
  }
  if (m->reason < 0 && (best < m->merit || PetscIsInfOrNanReal(m->merit))) { /* not converged: return the best iterate (never a NaN one: NaN < x is false) */
    PetscCall(VecCopy(rbest, r));
    if (abest) PetscCall(VecCopy(abest, fp->alpha));
    PetscCall(MBCNewtonVelocity(m, r, u));
    PetscCall(MBCFrictionMerit(fp, r, u, &m->merit));
  }
  PetscCall(VecDestroy(&rbest));
  PetscCall(VecDestroy(&abest));
  PetscCall(PetscFree(hist));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierReset_Newton(MBCMultiplier m)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  PetscCall(MatDestroy(&nt->Wprod));
  PetscCall(VecScatterDestroy(&nt->wtoall));
  PetscCall(VecDestroy(&nt->wxall));
  PetscCall(PetscFree(nt->diag));
  PetscCall(PetscFree5(nt->rho, nt->frozen, nt->A, nt->B, nt->active));
  PetscCall(PetscFree3(nt->sticks, nt->refopen, nt->nu));
  PetscCall(MBCNewtonLowRankDestroyReference(nt));
  nt->zbuilt  = PETSC_FALSE;
  nt->zdirect = 0;
  PetscCall(PetscFree3(nt->work, nt->mark, nt->cols));
  PetscCall(VecDestroy(&nt->phi));
  PetscCall(VecDestroy(&nt->dr));
  PetscCall(VecDestroy(&nt->wdr));
  PetscCall(VecDestroy(&nt->rt));
  PetscCall(VecDestroy(&nt->ut));
  PetscCall(VecDestroy(&nt->dalpha));
  PetscCall(VecDestroy(&nt->alphat));
  PetscCall(ISDestroy(&nt->isbuilt));
  PetscCall(KSPReset(nt->ksp));
  PetscCall(KSPReset(nt->kdense));
  nt->klu = NULL;
  PetscCall(KSPReset(nt->kmf));
  PetscCall(MBCMultiplierReset(nt->pgs));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierDestroy_Newton(MBCMultiplier m)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  PetscCall(MBCMultiplierReset_Newton(m));
  PetscCall(VecDestroy(&nt->refpending));
  PetscCall(MatDestroy(&nt->refW));
  PetscCall(PetscObjectComposeFunction((PetscObject)m, "MBCMultiplierGetRestartState_C", NULL));
  PetscCall(PetscObjectComposeFunction((PetscObject)m, "MBCMultiplierSetRestartState_C", NULL));
  PetscCall(KSPDestroy(&nt->ksp));
  PetscCall(KSPDestroy(&nt->kdense));
  PetscCall(KSPDestroy(&nt->kmf));
  PetscCall(MBCMultiplierDestroy(&nt->pgs));
  PetscCall(PetscFree(m->data));
  PetscFunctionReturn(0);
}

static PetscErrorCode MBCMultiplierView_Newton(MBCMultiplier m, PetscViewer viewer)
{
  MBC_Newton *nt = (MBC_Newton *)m->data;

  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "Alart-Curnier, rho %g / diag(W), non-monotone Armijo (memory %" PetscInt_FMT ", %" PetscInt_FMT " halvings), shift %g; Gauss-Seidel: %" PetscInt_FMT " warm-start sweeps, %" PetscInt_FMT " on a failed line search\n", (double)NewtonRhoScale(m), nt->nonmonotone, nt->ls_max, (double)nt->shift, nt->pgs_warm, nt->pgs_fallback));
  PetscCall(PetscViewerASCIIPrintf(viewer, "last solve: %" PetscInt_FMT " factorizations, %" PetscInt_FMT " steps through the kept inverse, %" PetscInt_FMT " failed line searches, %" PetscInt_FMT " Gauss-Seidel sweeps, %" PetscInt_FMT " Krylov iterations (matrix-free W)\n", nt->factors, nt->lowranks, nt->lsfail, nt->pgssweeps, nt->kits));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(KSPView(nt->klu ? nt->klu : nt->ksp, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* A direct solve of the Newton matrix, options prefix <m's prefix><name>: PREONLY and an LU by the
   package solver (NULL: PCMBCMIXEDLU), under PCREDUNDANT when every rank factors the whole matrix */
static PetscErrorCode NewtonLUCreate(MBCMultiplier m, const char name[], PetscBool redundant, MatSolverType solver, KSP *ksp)
{
  const char *prefix;
  char        p[256];
  PC          pc;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)m, &prefix));
  PetscCall(PetscSNPrintf(p, sizeof(p), "%s%s", prefix ? prefix : "", name));
  PetscCall(KSPCreate(PetscObjectComm((PetscObject)m), ksp));
  PetscCall(KSPSetOptionsPrefix(*ksp, p));
  PetscCall(KSPSetType(*ksp, KSPPREONLY));
  PetscCall(KSPGetPC(*ksp, &pc));
  if (redundant) {
    KSP inner;
    PetscCall(PCSetType(pc, PCREDUNDANT));
    PetscCall(PCRedundantGetKSP(pc, &inner));
    PetscCall(KSPSetType(inner, KSPPREONLY));
    PetscCall(KSPGetPC(inner, &pc));
  }
  if (solver) {
    PetscCall(PCSetType(pc, PCLU));
    PetscCall(PCFactorSetMatSolverType(pc, solver));
  } else PetscCall(PCSetType(pc, PCMBCMIXEDLU));
  PetscCall(KSPSetErrorIfNotConverged(*ksp, PETSC_FALSE));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierCreate_Newton(MBCMultiplier m)
{
  MBC_Newton *nt;
  const char *prefix;
  char        p[256];
  PetscBool   mumps, scalapack;
  PetscMPIInt size;

  PetscFunctionBegin;
  PetscCall(PetscNew(&nt));
  nt->rho_scale    = 1.0;
  nt->pgs_warm     = 0;
  nt->pgs_fallback = 10;
  nt->sigma        = 1e-4;
  nt->ls_max       = 20;
  nt->nonmonotone  = 5;
  nt->watchdog     = 10;
  nt->predictor    = PETSC_TRUE;
  nt->shift        = 1e-12;
  nt->dense_fill   = 0.5;
  nt->w_dense_fill = 0.5; /* the dense copy's memory 8 N^2 against AIJ's 12 f N^2: at f = 0.5 its products were 4x faster (dgemv against MatMult_SeqAIJ_Inode, N = 3 384, one thread) */
  nt->slip_eliminate = PETSC_TRUE;
  nt->lowrank      = PETSC_TRUE;
  nt->lowrank_max  = 0.8; /* the 198k dam's strong phase: 0.6 fell back to LUs and new references (71 LUs, 3 inverses against 39, 1), 1.0 paid more in k x k corrections */
  nt->lowrank_dist_min = 1000; /* M's LU (k^3) then dominates the step, and every rank factoring it alone costs more than the direct step's LU over the ranks where k nears the active rows */
  m->data          = nt;
  if (m->max_it < 0) m->max_it = 100;
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)m, &prefix));
  PetscCall(PetscHasExternalPackage("mumps", &mumps));
  PetscCall(PetscHasExternalPackage("scalapack", &scalapack));
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)m), &size));
  /* the sparse LU: the Newton system is the contact problem's size, so on several ranks each
     factors all of it (PCREDUNDANT). MUMPS on distributed input skips its maximum-transversal
     permutation, and the zero block of the free bodies' equilibrium rows then gave infinite steps
     (a static dam on 2 ranks) */
  PetscCall(NewtonLUCreate(m, "newton_", size > 1, mumps ? MATSOLVERMUMPS : MATSOLVERPETSC, &nt->ksp));
  /* the dense LU: on several ranks ScaLAPACK's, 4 x faster at n = 3000 on 2 ranks than every rank
     factoring the whole matrix (PCREDUNDANT), and it holds the matrix once, not per rank */
  nt->densetype = size > 1 && scalapack ? MATSCALAPACK : MATDENSE;
  /* single precision's LU refined in double (src/pc/mixedlu.c; ScaLAPACK's psgetrf over the
     ranks): half the time of the double LU, double's accuracy */
  PetscCall(NewtonLUCreate(m, "newton_dense_", size > 1 && !scalapack, size > 1 && !scalapack ? MATSOLVERPETSC : NULL, &nt->kdense));
  { /* the steps with a matrix-free W: right-preconditioned GMRES, so its residual is J's own; 1e-4
       leaves the outer iteration linear convergence at that rate near the solution */
    PetscCall(PetscSNPrintf(p, sizeof(p), "%snewton_mf_", prefix ? prefix : ""));
    PetscCall(KSPCreate(PetscObjectComm((PetscObject)m), &nt->kmf));
    PetscCall(KSPSetOptionsPrefix(nt->kmf, p));
    PetscCall(KSPSetType(nt->kmf, KSPGMRES));
    PetscCall(KSPGMRESSetRestart(nt->kmf, 100));
    PetscCall(KSPSetPCSide(nt->kmf, PC_RIGHT));
    PetscCall(KSPSetTolerances(nt->kmf, 1e-4, 0.0, PETSC_DEFAULT, 500));
    PetscCall(KSPSetErrorIfNotConverged(nt->kmf, PETSC_FALSE));
  }
  PetscCall(MBCMultiplierCreate(PetscObjectComm((PetscObject)m), &nt->pgs));
  PetscCall(MBCMultiplierSetOptionsPrefix(nt->pgs, prefix));
  PetscCall(MBCMultiplierSetType(nt->pgs, MBCMULTIPLIERPGS));
  PetscCall(MBCMultiplierPGSSetActiveSet(nt->pgs, 0));
  m->ops->setfromoptions = MBCMultiplierSetFromOptions_Newton;
  m->ops->setup          = MBCMultiplierSetUp_Newton;
  m->ops->solve          = MBCMultiplierSolve_Newton;
  m->ops->reset          = MBCMultiplierReset_Newton;
  m->ops->destroy        = MBCMultiplierDestroy_Newton;
  m->ops->view           = MBCMultiplierView_Newton;
  PetscCall(MBCNewtonLowRankCompose(m));
  PetscFunctionReturn(0);
}
