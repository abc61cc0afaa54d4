/* Contact forces in the Newmark step (the paper's eqs. (2)-(9)): per body K~ dU = dF + H lambda,
   H mapping each contact point's frame (n, t1, t2) to the master node (+) and the slave face
   nodes (- weights). With dU_free = A^-1 dF and X = A^-1 H (one multi-right-hand-side solve per
   body with its factor), the multipliers solve u = D lambda + q in the Coulomb cone with
   D = sum_i H_i^T X_i, q = (gap, 0, 0) + sum_i H_i^T dU_free_i; then dU = dU_free + X lambda. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/pgsimpl.h>

/* Contact points of all couples in one list: (couple, point). */
static PetscInt NumContacts(MBCContact c)
{
  PetscInt n = 0;
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].npoints;
  return n;
}

/* H of one body: 3 columns per contact point; rows of constrained DOFs are zero (a prescribed
   DOF takes no contact force; the PGS treats a contact with no free DOF as inactive). */
static PetscErrorCode BodyContactMatrix(MBCSolver s, MBCBody body, PetscInt nc, Mat *H)
{
  MBCContact  c = s->contact;
  PetscMPIInt brank;
  PetscInt    ndof, nloc, k = 0;

  PetscFunctionBegin;
  PetscCall(VecGetSize(body->u, &ndof));
  PetscCall(VecGetLocalSize(body->u, &nloc));
  PetscCall(MatCreateAIJ(body->comm, nloc, PETSC_DECIDE, ndof, 3 * nc, 24, NULL, 24, NULL, H));
  PetscCall(MatSetOption(*H, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple  *cp = &c->couples[i];
    MBCSurface *m = &cp->master, *sl = &cp->slave;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscReal       *e[3] = {p->n, p->t1, p->t2};
      if (brank) continue; /* rank 0 of the body inserts; assembly sends rows to their owners */
      for (PetscInt a = 0; a < 3; a++) {
        const PetscInt col = 3 * k + a;
        if (m->nbody[p->master] == body->index)
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, m->nrow[p->master] + d, col, e[a][d], ADD_VALUES));
        for (PetscInt v = 0; v < p->nv; v++) {
          const PetscInt node = sl->fnode[MBC_MAX_FACE_NODES * p->face + v];
          if (sl->nbody[node] != body->index) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, sl->nrow[node] + d, col, -p->w[v] * e[a][d], ADD_VALUES));
        }
      }
    }
  }
  PetscCall(MatAssemblyBegin(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatZeroRows(*H, body->nbc, body->bc_rows, 0.0, NULL, NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverContactSetUp(MBCSolver s)
{
  MBCContact  c  = s->contact;
  PetscInt    nc = NumContacts(c);
  PetscScalar *Dl, *Dg;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscCall(MatDestroy(&s->H[b]));
    PetscCall(MatDestroy(&s->X[b]));
  }
  PetscCall(MBCFrictionProblemDestroy(&s->fp));
  s->fp.nc = nc;
  if (!nc) {
    PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscCalloc2(9 * nc * nc, &Dl, 9 * nc * nc, &Dg));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody     body = s->bodies[b];
    Mat         Hd, D;
    PetscMPIInt brank;
    if (!body) continue;
    PetscCall(BodyContactMatrix(s, body, nc, &s->H[b]));
    PetscCall(MatConvert(s->H[b], MATDENSE, MAT_INITIAL_MATRIX, &Hd));
    PetscCall(MatDuplicate(Hd, MAT_DO_NOT_COPY_VALUES, &s->X[b]));
    PetscCall(KSPMatSolve(body->ksp, Hd, s->X[b]));
    PetscCall(MatTransposeMatMult(Hd, s->X[b], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &D));
    { /* D_i (3nc x 3nc) to every rank of the body, then summed over bodies */
      Mat               *Dseq;
      IS                 all;
      const PetscScalar *a;
      PetscInt           lda;
      PetscCall(ISCreateStride(PETSC_COMM_SELF, 3 * nc, 0, 1, &all));
      PetscCall(MatCreateSubMatrices(D, 1, &all, &all, MAT_INITIAL_MATRIX, &Dseq));
      PetscCall(ISDestroy(&all));
      PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
      PetscCall(MatDenseGetLDA(Dseq[0], &lda));
      PetscCall(MatDenseGetArrayRead(Dseq[0], &a));
      if (!brank)
        for (PetscInt i = 0; i < 3 * nc; i++)
          for (PetscInt j = 0; j < 3 * nc; j++) Dl[i * 3 * nc + j] += a[i + j * lda]; /* row-major */
      PetscCall(MatDenseRestoreArrayRead(Dseq[0], &a));
      PetscCall(MatDestroySubMatrices(1, &Dseq));
    }
    PetscCall(MatDestroy(&D));
    PetscCall(MatDestroy(&Hd));
  }
  PetscCallMPI(MPI_Allreduce(Dl, Dg, (PetscMPIInt)(9 * nc * nc), MPIU_SCALAR, MPIU_SUM, s->comm)); /* sum over bodies */
  { /* W = D / dbar as SeqAIJ, dbar the mean diagonal: r = dbar lambda has the units of u, so the
       FCLIB merit weighs forces and displacements alike; the same on every rank (the PGS runs
       redundantly, deterministically) */
    PetscInt *nnz;
    s->dscale = 0;
    for (PetscInt i = 0; i < 3 * nc; i++) s->dscale += PetscRealPart(Dg[i * 3 * nc + i]) / (3 * nc);
    PetscCheck(s->dscale > 0, s->comm, PETSC_ERR_ARG_WRONG, "The contact flexibility matrix has no positive diagonal: every contact DOF is prescribed");
    for (PetscInt i = 0; i < 9 * nc * nc; i++) Dg[i] /= s->dscale;
    PetscCall(PetscCalloc1(3 * nc, &nnz));
    for (PetscInt i = 0; i < 3 * nc; i++)
      for (PetscInt j = 0; j < 3 * nc; j++) nnz[i] += Dg[i * 3 * nc + j] != 0.0;
    PetscCall(MatCreateSeqAIJ(PETSC_COMM_SELF, 3 * nc, 3 * nc, 0, nnz, &s->fp.W));
    for (PetscInt i = 0; i < 3 * nc; i++)
      for (PetscInt j = 0; j < 3 * nc; j++)
        if (Dg[i * 3 * nc + j] != 0.0) PetscCall(MatSetValue(s->fp.W, i, j, Dg[i * 3 * nc + j], INSERT_VALUES));
    PetscCall(MatAssemblyBegin(s->fp.W, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(s->fp.W, MAT_FINAL_ASSEMBLY));
    PetscCall(PetscFree(nnz));
  }
  PetscCall(PetscFree2(Dl, Dg));
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, 3 * nc, &s->fp.q));
  PetscCall(PetscMalloc1(nc, &s->fp.mu));
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++) s->fp.mu[k++] = c->couples[i].mu;
  PetscCall(VecDestroy(&s->lambda));
  PetscCall(VecDestroy(&s->ucontact));
  PetscCall(VecDuplicate(s->fp.q, &s->lambda));
  PetscCall(VecDuplicate(s->fp.q, &s->ucontact));
  PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Given every body's free increment in body->du, solves for the multipliers and adds X lambda. */
PetscErrorCode MBCSolverContactSolve(MBCSolver s)
{
  MBCContact   c  = s->contact;
  PetscInt     nc = s->fp.nc;
  PetscScalar *ql, *qg, *q;

  PetscFunctionBegin;
  if (!nc) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(3 * nc, &ql, 3 * nc, &qg));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody            body = s->bodies[b];
    Vec                Hu;
    PetscMPIInt        brank;
    VecScatter         sc;
    Vec                Hus;
    const PetscScalar *a;
    if (!body) continue;
    PetscCall(MatCreateVecs(s->H[b], &Hu, NULL));
    PetscCall(MatMultTranspose(s->H[b], body->du, Hu));
    PetscCall(VecScatterCreateToAll(Hu, &sc, &Hus));
    PetscCall(VecScatterBegin(sc, Hu, Hus, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, Hu, Hus, INSERT_VALUES, SCATTER_FORWARD));
    PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
    PetscCall(VecGetArrayRead(Hus, &a));
    if (!brank)
      for (PetscInt i = 0; i < 3 * nc; i++) ql[i] += a[i];
    PetscCall(VecRestoreArrayRead(Hus, &a));
    PetscCall(VecScatterDestroy(&sc));
    PetscCall(VecDestroy(&Hus));
    PetscCall(VecDestroy(&Hu));
  }
  PetscCallMPI(MPI_Allreduce(ql, qg, (PetscMPIInt)(3 * nc), MPIU_SCALAR, MPIU_SUM, s->comm)); /* sum over bodies */
  PetscCall(VecGetArray(s->fp.q, &q));
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      q[3 * k]     = c->couples[i].points[j].gap + qg[3 * k];
      q[3 * k + 1] = qg[3 * k + 1];
      q[3 * k + 2] = qg[3 * k + 2];
    }
  PetscCall(VecRestoreArray(s->fp.q, &q));
  PetscCall(PetscFree2(ql, qg));
  PetscCall(MBCPGSSolve(&s->pgs, &s->fp, s->lambda, s->ucontact)); /* warm start: lambda of the last step */
  PetscCheck(s->pgs.reason > 0, s->comm, PETSC_ERR_NOT_CONVERGED, "Contact multipliers at step %" PetscInt_FMT " (t = %g): projected Gauss-Seidel %s after %" PetscInt_FMT " sweeps, FCLIB error %g > -mbc_pgs_rtol %g", s->step, (double)s->time, MBCPGSReasonName(s->pgs.reason), s->pgs.its, (double)s->pgs.error, (double)s->pgs.rtol);
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    Vec     lam;
    if (!body) continue;
    PetscCall(MatCreateVecs(s->X[b], &lam, NULL));
    { /* physical lambda = r / dscale (replicated) into the owned part of X's column layout */
      const PetscScalar *l;
      PetscScalar       *la;
      PetscInt           lo, hi;
      PetscCall(VecGetOwnershipRange(lam, &lo, &hi));
      PetscCall(VecGetArrayRead(s->lambda, &l));
      PetscCall(VecGetArray(lam, &la));
      for (PetscInt i = lo; i < hi; i++) la[i - lo] = l[i] / s->dscale;
      PetscCall(VecRestoreArray(lam, &la));
      PetscCall(VecRestoreArrayRead(s->lambda, &l));
    }
    PetscCall(MatMultAdd(s->X[b], lam, body->du, body->du));
    PetscCall(VecDestroy(&lam));
  }
  PetscFunctionReturn(0);
}
