/* Contact forces in the Newmark step (the paper's eqs. (2)-(9)): per body K~ dU = dF + H lambda,
   H mapping each contact point's frame (n, t1, t2) to the master node (+) and the slave face
   nodes (- weights). With dU_free = A^-1 dF, the multipliers solve u = D lambda + q in the
   Coulomb cone with D = sum_i H_i^T A_i^-1 H_i, q = (gap, 0, 0) + sum_i H_i^T dU_free_i; then
   dU = dU_free + A^-1 H lambda (one more solve per body). A frictionless couple's points carry
   the normal multiplier only.

   Distributed: the search (and the per-point bookkeeping, in couple order) is replicated; the
   multiplier problem is not. A point's rows of W = D / dscale, q and lambda live on a rank of
   the body holding its master node (rank order); H_i has columns only for the multipliers of
   the points touching body i, and D_i = H_i^T A_i^-1 H_i, built by blocks of columns on the
   body's ranks, is added into W where its rows live. A star forest maps body columns to rows.

   Complementarity is imposed on the step's mean contact force z = theta lambda_n+1 +
   (1 - theta) lambda_n, theta = gamma (dynamic: the weights of Newmark's velocity update, so
   z dt is the contact impulse of the step) or 1 (static), not on lambda_n+1. With r = z / theta
   the problem keeps D: q' = q - c D lambda_n, c = (1 - theta) / theta, lambda_n+1 = r - c lambda_n.
   For the trapezoidal rule the contact work of a step is then z . (g_n+1 - g_n) = -z . g_n <= 0:
   a contact that opens gives back no energy. Imposed on lambda_n+1 itself it would be
   (lambda_n . g_n+1 - lambda_n+1 . g_n) / 2, an energy gain whenever a loaded contact opens (a
   bouncing block gains energy at every bounce). */
#include <mbc/private/solverimpl.h>
#include <mbc/private/multiplierimpl.h>
#include <petscblaslapack.h>

PetscLogEvent MBC_FlexibilityAssemble;

/* Contact points of all couples in one list: (couple, point). */
static PetscInt NumContacts(MBCContact c)
{
  PetscInt n = 0;
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].npoints;
  return n;
}

/* Body of the master node of point j of couple cp: the point's rows live there. */
static PetscInt PointBody(const MBCCouple *cp, PetscInt j)
{
  return cp->master.nbody[cp->points[j].master];
}

/* Does the constraint of point j of cp involve body b? */
PetscBool MBCSolverPointTouches(const MBCCouple *cp, PetscInt j, PetscInt b)
{
  for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++)
    if (cp->master.nbody[cp->mnode[l]] == b) return PETSC_TRUE;
  for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++)
    if (cp->slave.nbody[cp->snode[l]] == b) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Rank order: each point on a rank of its master body (a body's points split evenly over its
   ranks, in couple order), points stably sorted by rank; the same on every rank. */
static PetscErrorCode SolverContactRankOrder(MBCSolver s, const PetscInt dims[])
{
  MBCContact  c  = s->contact;
  PetscInt    nc = s->ncontact, *owner, *count, *seen;
  PetscMPIInt P, rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(s->comm, &P));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscMalloc3(nc + 1, &owner, s->nbodies, &count, s->nbodies, &seen));
  PetscCall(PetscArrayzero(count, s->nbodies));
  PetscCall(PetscArrayzero(seen, s->nbodies));
  for (PetscInt k = 0; k < nc; k++) count[PointBody(&c->couples[s->kcouple[k]], s->kpoint[k])]++;
  for (PetscInt k = 0; k < nc; k++) {
    const PetscInt b = PointBody(&c->couples[s->kcouple[k]], s->kpoint[k]);
    owner[k] = s->body_first_rank[b] + (seen[b]++ * s->body_nranks[b]) / count[b];
  }
  PetscCall(PetscMalloc4(nc + 1, &s->perm, nc + 1, &s->order, nc + 1, &s->coff, nc + 1, &s->poff));
  s->coff[0] = 0;
  for (PetscInt k = 0; k < nc; k++) s->coff[k + 1] = s->coff[k] + dims[k];
  {
    PetscInt p = 0;
    for (PetscMPIInt r = 0; r < P; r++) {
      if (r == rank) s->pfirst = p;
      for (PetscInt k = 0; k < nc; k++)
        if (owner[k] == r) s->order[p] = k, s->perm[k] = p++;
      if (r == rank) s->plast = p;
    }
  }
  s->poff[0] = 0;
  for (PetscInt p = 0; p < nc; p++) s->poff[p + 1] = s->poff[p] + dims[s->order[p]];
  PetscCall(PetscFree3(owner, count, seen));
  PetscFunctionReturn(0);
}

/* bcols[b]: the W rows (rank order, ascending) of the multipliers of the points touching body b;
   first[k]: the first H column of point k in body b, or -1. On every rank, for every body. */
static PetscErrorCode BodyColumns(MBCSolver s, PetscInt b, PetscInt first[])
{
  MBCContact c = s->contact;
  PetscInt   n = 0;

  PetscFunctionBegin;
  PetscCall(PetscFree(s->bcols[b]));
  for (PetscInt k = 0; k < s->ncontact; k++) first[k] = MBCSolverPointTouches(&c->couples[s->kcouple[k]], s->kpoint[k], b) ? 0 : -1;
  for (PetscInt p = 0; p < s->ncontact; p++) {
    const PetscInt k = s->order[p];
    if (first[k] < 0) continue;
    first[k] = n;
    n += s->coff[k + 1] - s->coff[k];
  }
  s->nbcols[b] = n;
  PetscCall(PetscMalloc1(n + 1, &s->bcols[b]));
  for (PetscInt p = 0; p < s->ncontact; p++) {
    const PetscInt k = s->order[p];
    if (first[k] < 0) continue;
    for (PetscInt a = 0; a < s->coff[k + 1] - s->coff[k]; a++) s->bcols[b][first[k] + a] = s->poff[p] + a;
  }
  PetscFunctionReturn(0);
}

/* H of one body: the point's frame times its master (+) and slave (-) node weights
   (MBCCoupleIntegrate) in the columns first[k] + (0, 1, 2); rows of constrained DOFs are
   zero (a prescribed DOF takes no contact force; the PGS treats a contact with no free DOF as
   inactive). */
static PetscErrorCode BodyContactMatrix(MBCSolver s, MBCBody body, const PetscInt first[], Mat *H)
{
  MBCContact  c = s->contact;
  PetscMPIInt brank;
  PetscInt    ndof, nloc, k = 0;

  PetscFunctionBegin;
  PetscCall(VecGetSize(body->u, &ndof));
  PetscCall(VecGetLocalSize(body->u, &nloc));
  PetscCall(MatCreateAIJ(body->comm, nloc, PETSC_DECIDE, ndof, s->nbcols[body->index], 24, NULL, 24, NULL, H));
  PetscCall(MatSetOption(*H, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple  *cp = &c->couples[i];
    MBCSurface *m = &cp->master, *sl = &cp->slave;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscReal       *e[3] = {p->n, p->t1, p->t2};
      if (brank || first[k] < 0) continue; /* rank 0 of the body inserts; assembly sends rows to their owners */
      for (PetscInt a = 0; a < s->coff[k + 1] - s->coff[k]; a++) {
        const PetscInt col = first[k] + a;
        for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++) {
          const PetscInt node = cp->mnode[l];
          if (m->nbody[node] != body->index) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, m->nrow[node] + d, col, cp->mw[l] * e[a][d], ADD_VALUES));
        }
        for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) {
          const PetscInt node = cp->snode[l];
          if (sl->nbody[node] != body->index) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, sl->nrow[node] + d, col, -cp->sw[l] * e[a][d], ADD_VALUES));
        }
      }
    }
  }
  PetscCall(MatAssemblyBegin(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatZeroRows(*H, body->nbc, body->bc_rows, 0.0, NULL, NULL));
  PetscFunctionReturn(0);
}

/* Everything built with H: per body H, its vectors and column lists; the star forest; W, q,
   lambda; the gathered copies. */
static PetscErrorCode SolverContactReset(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscCall(MatDestroy(&s->H[b]));
    PetscCall(VecDestroy(&s->Hu[b]));
    PetscCall(VecDestroy(&s->lam[b]));
    PetscCall(VecDestroy(&s->Hl[b]));
    PetscCall(VecDestroy(&s->Xl[b]));
    PetscCall(PetscFree(s->bcols[b]));
    s->nbcols[b] = 0;
  }
  PetscCall(PetscSFDestroy(&s->csf));
  PetscCall(PetscFree(s->leaf));
  PetscCall(VecScatterDestroy(&s->gather));
  PetscCall(VecDestroy(&s->gathered));
  PetscCall(PetscFree2(s->rall, s->uall));
  PetscCall(PetscFree4(s->perm, s->order, s->coff, s->poff));
  PetscCall(PetscFree2(s->kcouple, s->kpoint));
  PetscCall(MBCFrictionProblemDestroy(&s->fp));
  PetscCall(PetscFree(s->goff));
  PetscCall(PetscFree(s->gQ));
  PetscCall(PetscFree(s->grange));
  PetscCall(PetscFree(s->gscale));
  s->ngrigid = 0;
  PetscCall(MBCMultiplierReset(s->mult));
  PetscCall(VecDestroy(&s->lambda));
  PetscCall(VecDestroy(&s->ucontact));
  PetscCall(VecDestroy(&s->lamprev));
  PetscCall(VecDestroy(&s->lamsave));
  PetscFunctionReturn(0);
}

/* Carries nf per-point 3-vector fields (components in each point's frame n, t1, t2; 1 component
   if frictionless) from the points of the last build to the new ones, matched by (couple, master
   node), through global coordinates. Points without a match get 0. */
static PetscErrorCode CarryFields(PetscInt nf, PetscInt nold, const PetscInt oldpairs[], const PetscReal oldframes[], const PetscInt oldoff[], const PetscReal *oldv[], PetscInt nnew, const PetscInt newpairs[], const PetscReal newframes[], const PetscInt newoff[], PetscReal *newv[])
{
  PetscInt *key, *perm;

  PetscFunctionBegin;
  for (PetscInt f = 0; f < nf; f++)
    for (PetscInt k = 0; k < newoff[nnew]; k++) newv[f][k] = 0;
  if (!nold) PetscFunctionReturn(0);
  PetscCall(PetscMalloc2(nold, &key, nold, &perm));
  for (PetscInt lo = 0, hi; lo < nold; lo = hi) { /* points are grouped by couple */
    for (hi = lo; hi < nold && oldpairs[MBC_PAIR_SIZE * hi] == oldpairs[MBC_PAIR_SIZE * lo]; hi++) {
      key[hi]  = oldpairs[MBC_PAIR_SIZE * hi + 1];
      perm[hi] = hi;
    }
    PetscCall(PetscSortIntWithArray(hi - lo, key + lo, perm + lo));
    for (PetscInt k = 0; k < nnew; k++) {
      PetscInt j, dim = newoff[k + 1] - newoff[k];
      if (newpairs[MBC_PAIR_SIZE * k] != oldpairs[MBC_PAIR_SIZE * lo]) continue;
      PetscCall(PetscFindInt(newpairs[MBC_PAIR_SIZE * k + 1], hi - lo, key + lo, &j));
      if (j < 0) continue;
      j = perm[lo + j];
      for (PetscInt fi = 0; fi < nf; fi++) {
        PetscReal f[3] = {0, 0, 0};
        for (PetscInt d = 0; d < oldoff[j + 1] - oldoff[j]; d++)
          for (PetscInt e = 0; e < 3; e++) f[e] += oldv[fi][oldoff[j] + d] * oldframes[9 * j + 3 * d + e];
        for (PetscInt d = 0; d < dim; d++) newv[fi][newoff[k] + d] = f[0] * newframes[9 * k + 3 * d] + f[1] * newframes[9 * k + 3 * d + 1] + f[2] * newframes[9 * k + 3 * d + 2];
      }
    }
  }
  PetscCall(PetscFree2(key, perm));
  PetscFunctionReturn(0);
}

/* The star forest between the bodies' H columns on this rank (leaves, body after body, in each
   body's column layout) and the rows of W (roots, this rank's in rank order). */
static PetscErrorCode SolverContactForest(MBCSolver s)
{
  PetscInt    nleaf = 0, *remote;
  PetscLayout layout;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscInt lo, hi;
    if (!s->lam[b]) continue;
    PetscCall(VecGetOwnershipRange(s->lam[b], &lo, &hi));
    nleaf += hi - lo;
  }
  PetscCall(PetscMalloc1(nleaf + 1, &remote));
  PetscCall(PetscMalloc1(nleaf + 1, &s->leaf));
  nleaf = 0;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscInt lo, hi;
    if (!s->lam[b]) continue;
    PetscCall(VecGetOwnershipRange(s->lam[b], &lo, &hi));
    for (PetscInt j = lo; j < hi; j++) remote[nleaf++] = s->bcols[b][j];
  }
  PetscCall(VecGetLayout(s->fp.q, &layout));
  PetscCall(PetscSFCreate(s->comm, &s->csf));
  PetscCall(PetscSFSetGraphLayout(s->csf, layout, nleaf, NULL, PETSC_OWN_POINTER, remote));
  PetscCall(PetscSFSetUp(s->csf));
  PetscCall(PetscFree(remote));
  PetscFunctionReturn(0);
}

/* v (rows of W) into every body's lam[b] on this rank. */
PetscErrorCode MBCSolverContactToBodies(MBCSolver s, Vec v)
{
  const PetscScalar *a;
  PetscInt           l = 0;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(v, &a));
  PetscCall(PetscSFBcastBegin(s->csf, MPIU_SCALAR, a, s->leaf, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(s->csf, MPIU_SCALAR, a, s->leaf, MPI_REPLACE));
  PetscCall(VecRestoreArrayRead(v, &a));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscScalar *la;
    PetscInt     n;
    if (!s->lam[b]) continue;
    PetscCall(VecGetLocalSize(s->lam[b], &n));
    PetscCall(VecGetArray(s->lam[b], &la));
    PetscCall(PetscArraycpy(la, s->leaf + l, n));
    PetscCall(VecRestoreArray(s->lam[b], &la));
    l += n;
  }
  PetscFunctionReturn(0);
}

/* v (rows of W) = the sum over bodies of Hu[b]. */
static PetscErrorCode SolverContactFromBodies(MBCSolver s, Vec v)
{
  PetscScalar *a;
  PetscInt     l = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    const PetscScalar *ha;
    PetscInt           n;
    if (!s->Hu[b]) continue;
    PetscCall(VecGetLocalSize(s->Hu[b], &n));
    PetscCall(VecGetArrayRead(s->Hu[b], &ha));
    PetscCall(PetscArraycpy(s->leaf + l, ha, n));
    PetscCall(VecRestoreArrayRead(s->Hu[b], &ha));
    l += n;
  }
  PetscCall(VecZeroEntries(v));
  PetscCall(VecGetArray(v, &a));
  PetscCall(PetscSFReduceBegin(s->csf, MPIU_SCALAR, s->leaf, a, MPIU_SUM));
  PetscCall(PetscSFReduceEnd(s->csf, MPIU_SCALAR, s->leaf, a, MPIU_SUM));
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

/* Combined rigid motions of several free bodies that deform no contact (the whole stack free to
   slide or turn together: G^T v = 0) leave alpha undetermined along v and make the equilibrium
   rows dependent. With the eigenvectors of G G^T: Q, those of its range, replace G by Q^T G and
   alpha by Q beta; the null vectors N are kept, to check that the load balances along them
   (N^T e = 0), else no static equilibrium exists. */
static PetscErrorCode SolverContactRigidReduce(MBCSolver s)
{
  PetscMPIInt  size, rank;
  PetscInt     ng = s->ngrigid, nr = 0, M;
  PetscScalar *A, work[1024];
  PetscReal   *ev, emax = 0;
  PetscBool   *ev_keep;
  PetscBLASInt n, lwork = 1024, info;
  Mat          GGt, Gr;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscFree(s->gQ));
  PetscCall(PetscCalloc1(ng * ng, &A));
  PetscCall(PetscCalloc1(ng, &ev));
  PetscCall(MatMatTransposeMult(s->fp.G, s->fp.G, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &GGt));
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
  PetscCallMPI(MPI_Bcast(A, (PetscMPIInt)(ng * ng), MPIU_SCALAR, size - 1, s->comm));
  PetscCall(PetscBLASIntCast(ng, &n));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &n, A, &n, ev, work, &lwork, &info)); /* the same on every rank */
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK syev failed (%d) on the rigid-mode equilibrium", (int)info);
  for (PetscInt i = 0; i < ng; i++) emax = PetscMax(emax, ev[i]);
  PetscCall(PetscMalloc1(ng, &ev_keep));
  for (PetscInt i = 0; i < ng; i++) {
    ev_keep[i] = (PetscBool)(ev[i] > 1e-10 * emax);
    if (ev_keep[i]) nr++;
  }
  s->gQ = A, s->grank = nr; /* eigenvectors: the k-th is gQ[k * ng + i] */
  PetscCall(PetscFree(ev));
  PetscCall(PetscFree(s->grange));
  if (nr == ng) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(nr, &s->grange));
  for (PetscInt k = 0, c = 0; k < ng; k++)
    if (ev_keep[k]) s->grange[c++] = k;
  PetscCall(MatGetSize(s->fp.G, NULL, &M));
  PetscCall(MatCreateAIJ(s->comm, rank == size - 1 ? nr : 0, PETSC_DECIDE, nr, M, 0, NULL, 0, NULL, &Gr));
  {
    PetscInt mloc;
    PetscCall(MatGetLocalSize(s->fp.G, NULL, &mloc));
    PetscCall(MatDestroy(&Gr));
    PetscCall(MatCreateAIJ(s->comm, rank == size - 1 ? nr : 0, mloc, nr, M, 0, NULL, 0, NULL, &Gr));
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
        PetscCall(MatGetRow(s->fp.G, i, &nc, &cc, &vv));
        for (PetscInt j = 0; j < nc; j++) {
          if (!mark[cc[j]]) mark[cc[j]] = 1, cols[nmark++] = cc[j];
          acc[cc[j]] += q * vv[j];
        }
        PetscCall(MatRestoreRow(s->fp.G, i, &nc, &cc, &vv));
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
  PetscCall(MatDestroy(&s->fp.G));
  PetscCall(PetscFree(ev_keep));
  s->fp.G = Gr;
  PetscFunctionReturn(0);
}

/* Static analysis with bodies their supports leave free (FETI's natural coarse space): the
   equilibrium of body i, R_i^T (f_i + H_i lambda) = 0, is G lambda = e with G's rows
   (H_i^T R_ij)^T, one per free mode, in the multiplier layout (W's); the free motion
   u_i = K_i^+ (f_i + H_i lambda) + R_i alpha_i adds G^T alpha to the contact velocity. G, e,
   alpha have all their rows on the last rank (the Newton type's layout), scaled as W is: the
   problem's G is G / dscale, its alpha dscale alpha. */
static PetscErrorCode SolverContactRigidModes(MBCSolver s)
{
  PetscMPIInt size, rank;
  PetscInt    ng = 0, mloc, *nr;
  Vec         row;

  PetscFunctionBegin;
  PetscCall(PetscFree(s->goff));
  s->ngrigid = 0;
  if (s->analysis != MBC_ANALYSIS_STATIC) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc1(s->nbodies + 1, &s->goff));
  PetscCall(PetscCalloc1(s->nbodies + 1, &nr));
  for (PetscInt b = 0; b < s->nbodies; b++) { /* a body's count, once (from its first rank) */
    PetscMPIInt brank = 1;
    if (s->bodies[b]) PetscCallMPI(MPI_Comm_rank(s->bodies[b]->comm, &brank));
    if (!brank) nr[b] = s->bodies[b]->nrigid;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, nr, s->nbodies, MPIU_INT, MPI_SUM, s->comm));
  for (PetscInt b = 0; b < s->nbodies; b++) s->goff[b + 1] = s->goff[b] + nr[b];
  ng = s->ngrigid = s->goff[s->nbodies];
  PetscCall(PetscFree(nr));
  if (!ng) PetscFunctionReturn(0);
  PetscCall(MatGetLocalSize(s->fp.W, &mloc, NULL));
  PetscCall(MatCreateAIJ(s->comm, rank == size - 1 ? ng : 0, mloc, ng, PETSC_DETERMINE, 0, NULL, 0, NULL, &s->fp.G));
  PetscCall(MatSetOption(s->fp.G, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(VecDuplicate(s->fp.q, &row));
  for (PetscInt b = 0; b < s->nbodies; b++)
    for (PetscInt j = 0; j < s->goff[b + 1] - s->goff[b]; j++) {
      const PetscScalar *a;
      PetscInt           rstart, n, g = s->goff[b] + j;
      for (PetscInt o = 0; o < s->nbodies; o++) { /* H_b^T R_bj, the other bodies 0 */
        if (!s->Hu[o]) continue;
        if (o == b) PetscCall(MatMultTranspose(s->H[o], s->bodies[o]->rigid[j], s->Hu[o]));
        else PetscCall(VecZeroEntries(s->Hu[o]));
      }
      PetscCall(SolverContactFromBodies(s, row));
      PetscCall(VecGetOwnershipRange(row, &rstart, NULL));
      PetscCall(VecGetLocalSize(row, &n));
      PetscCall(VecGetArrayRead(row, &a));
      for (PetscInt i = 0; i < n; i++)
        if (a[i] != 0.0) PetscCall(MatSetValue(s->fp.G, g, rstart + i, a[i] / s->dscale, INSERT_VALUES));
      PetscCall(VecRestoreArrayRead(row, &a));
    }
  PetscCall(VecDestroy(&row));
  PetscCall(MatAssemblyBegin(s->fp.G, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(s->fp.G, MAT_FINAL_ASSEMBLY));
  PetscCall(SolverContactRigidReduce(s));
  { /* rows of G scaled to the unit entries of W: R's unit modes over N DOFs and 1 / dscale gave
       rows ~1e7 against W ~ 1, a saddle-point system the factorization could solve only to
       ~1e-8 (the static dam). e and alpha follow: G' = S G, e' = S e, alpha = S alpha'. */
    Vec       sc;
    PetscInt  n, rstart;
    PetscCall(MatCreateVecs(s->fp.G, NULL, &sc));
    PetscCall(VecGetLocalSize(sc, &n));
    PetscCall(VecGetOwnershipRange(sc, &rstart, NULL));
    PetscCall(PetscFree(s->gscale));
    PetscCall(PetscCalloc1(s->grank + 1, &s->gscale));
    for (PetscInt i = 0; i < n; i++) {
      PetscInt           nc;
      const PetscInt    *cc;
      const PetscScalar *vv;
      PetscReal          mx = 0;
      PetscCall(MatGetRow(s->fp.G, rstart + i, &nc, &cc, &vv));
      for (PetscInt j = 0; j < nc; j++) mx = PetscMax(mx, PetscAbsScalar(vv[j]));
      PetscCall(MatRestoreRow(s->fp.G, rstart + i, &nc, &cc, &vv));
      s->gscale[rstart + i] = mx > 0 ? 1 / mx : 1;
      PetscCall(VecSetValue(sc, rstart + i, s->gscale[rstart + i], INSERT_VALUES));
    }
    PetscCall(VecAssemblyBegin(sc));
    PetscCall(VecAssemblyEnd(sc));
    PetscCall(MatDiagonalScale(s->fp.G, sc, NULL));
    PetscCall(VecDestroy(&sc));
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, s->gscale, s->grank, MPIU_REAL, MPIU_SUM, s->comm));
  }
  PetscCall(MatCreateVecs(s->fp.G, NULL, &s->fp.e));
  PetscCall(VecDuplicate(s->fp.e, &s->fp.alpha));
  PetscCall(VecZeroEntries(s->fp.alpha));
  PetscFunctionReturn(0);
}

/* After a static solve with free bodies: du_i += R_i alpha_i, alpha = Q beta / dscale (beta the
   problem's alpha; Q = I when no combined motion was removed). */
PetscErrorCode MBCSolverContactRigidMotion(MBCSolver s)
{
  const PetscInt ng = s->ngrigid;
  PetscReal     *alpha;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(ng + 1, &alpha));
  {
    const PetscScalar *a;
    PetscInt           n;
    PetscCall(VecGetLocalSize(s->fp.alpha, &n)); /* all rows on the last rank */
    PetscCall(VecGetArrayRead(s->fp.alpha, &a));
    for (PetscInt c = 0; c < n; c++)
      for (PetscInt i = 0; i < ng; i++) alpha[i] += (s->grange ? s->gQ[s->grange[c] * ng + i] : (PetscScalar)(i == c)) * s->gscale[c] * PetscRealPart(a[c]) / s->dscale;
    PetscCall(VecRestoreArrayRead(s->fp.alpha, &a));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, alpha, ng, MPIU_REAL, MPIU_SUM, s->comm));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    if (!s->bodies[b]) continue;
    for (PetscInt j = 0; j < s->bodies[b]->nrigid; j++) PetscCall(VecAXPY(s->bodies[b]->du, alpha[s->goff[b] + j], s->bodies[b]->rigid[j]));
  }
  PetscCall(PetscFree(alpha));
  PetscFunctionReturn(0);
}

/* e = (-R_ij^T (F_i - K_i u_i)) from the bodies (each held on its ranks), Q^T e on the last rank.
   Along a combined rigid motion v that no contact resists the load must balance, v^T e = 0 (to
   1e-8 of the load R^T F): else no static equilibrium exists, an input error named here. */
PetscErrorCode MBCSolverContactRigidRHS(MBCSolver s)
{
  const PetscInt ng = s->ngrigid;
  PetscReal     *e, fscale = 0;
  PetscMPIInt    size, rank;

  PetscFunctionBegin;
  if (!s->fp.G) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc1(2 * ng + 1, &e));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscMPIInt brank;
    if (!s->bodies[b]) continue;
    PetscCallMPI(MPI_Comm_rank(s->bodies[b]->comm, &brank));
    if (!brank)
      for (PetscInt j = 0; j < s->bodies[b]->nrigid; j++) e[s->goff[b] + j] = s->bodies[b]->erigid[j], e[ng + s->goff[b] + j] = s->bodies[b]->frigid[j];
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, e, 2 * ng, MPIU_REAL, MPIU_SUM, s->comm));
  for (PetscInt i = 0; i < ng; i++) fscale = PetscMax(fscale, PetscAbsReal(e[ng + i]));
  if (s->grange) {
    PetscInt c = 0;
    for (PetscInt k = 0; k < ng; k++) {
      PetscReal ve = 0;
      for (PetscInt i = 0; i < ng; i++) ve += PetscRealPart(s->gQ[k * ng + i]) * e[i];
      if (c < s->grank && s->grange[c] == k) {
        e[ng + c++] = ve;
        continue;
      }
      if (PetscAbsReal(ve) > 1e-8 * fscale) { /* a mechanism under load: name its bodies */
        char     names[512] = "";
        size_t   len;
        for (PetscInt b = 0; b < s->nbodies; b++) {
          PetscReal share = 0;
          for (PetscInt i = s->goff[b]; i < s->goff[b + 1]; i++) share += PetscSqr(PetscRealPart(s->gQ[k * ng + i]));
          if (share > 1e-6) {
            PetscCall(PetscStrlen(names, &len));
            PetscCall(PetscSNPrintf(names + len, sizeof(names) - len, "%s'%s'", len ? ", " : "", s->scene->bodies[b].name));
          }
        }
        SETERRQ(s->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: bod%s %s can move as one rigid body that no support and no contact resists, and the load along that motion does not balance (%g, %.3g of the largest load on a rigid mode %g); prescribe a displacement that holds it, or run a dynamic analysis", s->step, (double)s->time, strchr(names, ',') ? "ies" : "y", names, (double)ve, (double)(PetscAbsReal(ve) / fscale), (double)fscale);
      }
    }
  } else
    for (PetscInt i = 0; i < ng; i++) e[ng + i] = e[i];
  if (rank == size - 1) {
    PetscScalar *a;
    PetscInt     n;
    PetscCall(VecGetLocalSize(s->fp.e, &n));
    PetscCall(VecGetArray(s->fp.e, &a));
    for (PetscInt i = 0; i < n; i++) a[i] = s->gscale[i] * e[ng + i];
    PetscCall(VecRestoreArray(s->fp.e, &a));
  }
  PetscCall(PetscFree(e));
  PetscFunctionReturn(0);
}

/* q = sum_i H_i^T du_i + (gap, 0, 0): this rank's rows. */
PetscErrorCode MBCSolverContactGapRate(MBCSolver s, Vec q)
{
  MBCContact   c = s->contact;
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->H[b]) PetscCall(MatMultTranspose(s->H[b], s->bodies[b]->du, s->Hu[b]));
  PetscCall(SolverContactFromBodies(s, q));
  PetscCall(VecGetOwnershipRange(q, &rstart, NULL));
  PetscCall(VecGetArray(q, &a));
  for (PetscInt p = s->pfirst; p < s->plast; p++) { /* this rank's points */
    const PetscInt k = s->order[p];
    a[s->poff[p] - rstart] += c->couples[s->kcouple[k]].igap[s->kpoint[k]];
  }
  PetscCall(VecRestoreArray(q, &a));
  PetscFunctionReturn(0);
}

/* v (rows of W) on every rank in couple order (out: coff layout). */
PetscErrorCode MBCSolverContactGather(MBCSolver s, Vec v, PetscReal out[])
{
  const PetscScalar *a;

  PetscFunctionBegin;
  PetscCall(VecScatterBegin(s->gather, v, s->gathered, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(s->gather, v, s->gathered, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(s->gathered, &a));
  for (PetscInt k = 0; k < s->ncontact; k++)
    for (PetscInt d = 0; d < s->coff[k + 1] - s->coff[k]; d++) out[s->coff[k] + d] = PetscRealPart(a[s->poff[s->perm[k]] + d]);
  PetscCall(VecRestoreArrayRead(s->gathered, &a));
  PetscFunctionReturn(0);
}

/* Couple-order values (coff layout, every rank) into this rank's rows of v. */
static PetscErrorCode SolverContactScatterLocal(MBCSolver s, const PetscReal in[], Vec v)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(v, &rstart, NULL));
  PetscCall(VecGetArray(v, &a));
  for (PetscInt p = s->pfirst; p < s->plast; p++) {
    const PetscInt k = s->order[p];
    for (PetscInt d = 0; d < s->coff[k + 1] - s->coff[k]; d++) a[s->poff[p] + d - rstart] = in[s->coff[k] + d];
  }
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

/* The acceleration a_n holds M^-1 H_old lambda_n; the next step assumes M^-1 H_new lambda_n' with
   the carried lambda_n' (points that left the contact carry nothing). a += M^-1 (H_new lambda_n' -
   H_old lambda_n) keeps M a_n = F_n - K u_n + H lambda_n true (u and v, hence the energy, do not
   change), so the step stays the trapezoidal rule on the mean contact force. */
static PetscErrorCode SolverContactAccelerationUpdate(MBCSolver s)
{
  PetscFunctionBegin;
  if (s->csf) PetscCall(MBCSolverContactToBodies(s, s->lamprev));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody   body = s->bodies[b];
    PetscReal norm;
    if (!body) continue;
    PetscCall(VecScale(body->fcontact, -1.0));
    if (s->H[b]) PetscCall(MatMultAdd(s->H[b], s->lam[b], body->fcontact, body->fcontact));
    PetscCall(VecNorm(body->fcontact, NORM_INFINITY, &norm));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &norm, 1, MPIU_REAL, MPIU_MAX, body->comm));
    if (norm == 0) continue;
    if (!body->kspM) PetscCall(MBCBodyFactor(body, 0.0, 1.0, &body->kspM, &body->Mc, "mass"));
    PetscCall(VecCopy(body->fcontact, body->rhs));
    PetscCall(MBCBodyConstrainedSolve(body, body->kspM, 0.0, 1.0, NULL, body->rhs, body->work));
    PetscCall(VecAXPY(body->a, 1.0, body->work));
  }
  PetscFunctionReturn(0);
}

/* W's preallocation: a point's row couples to the multipliers of the bodies its constraint
   touches (the master body, the slave body). */
static PetscErrorCode SolverContactPreallocation(MBCSolver s, PetscInt rstart, PetscInt rend, PetscInt dnz[], PetscInt onz[])
{
  MBCContact c = s->contact;

  PetscFunctionBegin;
  for (PetscInt p = s->pfirst; p < s->plast; p++) {
    const PetscInt   k = s->order[p];
    const MBCCouple *cp = &c->couples[s->kcouple[k]];
    PetscInt         bs[2], nb = 0, d = 0, o = 0;
    for (PetscInt b = 0; b < s->nbodies && nb < 2; b++) /* at most two: a master node, a slave face */
      if (MBCSolverPointTouches(cp, s->kpoint[k], b)) bs[nb++] = b;
    if (nb == 1) {
      for (PetscInt j = 0; j < s->nbcols[bs[0]]; j++) (s->bcols[bs[0]][j] >= rstart && s->bcols[bs[0]][j] < rend) ? d++ : o++;
    } else if (nb == 2) { /* the union of two ascending lists */
      const PetscInt *x = s->bcols[bs[0]], *y = s->bcols[bs[1]], nx = s->nbcols[bs[0]], ny = s->nbcols[bs[1]];
      PetscInt        ix = 0, iy = 0;
      while (ix < nx || iy < ny) {
        PetscInt v;
        if (iy >= ny || (ix < nx && x[ix] < y[iy])) v = x[ix++];
        else if (ix >= nx || y[iy] < x[ix]) v = y[iy++];
        else v = x[ix++], iy++;
        (v >= rstart && v < rend) ? d++ : o++;
      }
    }
    for (PetscInt a = 0; a < s->coff[k + 1] - s->coff[k]; a++) dnz[s->poff[p] + a - rstart] = d, onz[s->poff[p] + a - rstart] = o;
  }
  PetscFunctionReturn(0);
}

/* D_i = H_i^T A_i^-1 H_i of the bodies on this rank, by blocks of -mbc_contact_block columns
   (memory: DOFs x block, not DOFs x multipliers), added into W (rows where they live); then
   W = D / dscale with dscale the mean diagonal: r = dscale lambda has the units of u, so the
   FCLIB merit weighs forces and displacements alike. */
static PetscErrorCode SolverContactBuildD(MBCSolver s, PetscInt m, PetscInt mloc)
{
  PetscInt *dnz, *onz, rstart;
  Vec       diag;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Scan(&mloc, &rstart, 1, MPIU_INT, MPI_SUM, s->comm));
  rstart -= mloc;
  PetscCall(PetscMalloc2(mloc + 1, &dnz, mloc + 1, &onz));
  PetscCall(SolverContactPreallocation(s, rstart, rstart + mloc, dnz, onz));
  PetscCall(MatCreateAIJ(s->comm, mloc, mloc, m, m, 0, dnz, 0, onz, &s->fp.W));
  PetscCall(MatSetOption(s->fp.W, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(PetscFree2(dnz, onz));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody   body = s->bodies[b];
    PetscInt  nb = s->nbcols[b], rlo, rhi, clo, chi;
    if (!body || !nb) continue;
    PetscCall(MatGetOwnershipRange(s->H[b], &rlo, &rhi));
    PetscCall(MatGetOwnershipRangeColumn(s->H[b], &clo, &chi));
    for (PetscInt j0 = 0; j0 < nb; j0 += s->dblock) {
      const PetscInt     j1 = PetscMin(nb, j0 + s->dblock), w = j1 - j0;
      Mat                Hd, X, D;
      PetscScalar       *h;
      const PetscScalar *a;
      PetscInt           lda;
      PetscCall(MatCreateDense(body->comm, rhi - rlo, PETSC_DECIDE, PETSC_DETERMINE, w, NULL, &Hd));
      PetscCall(MatDenseGetArrayWrite(Hd, &h));
      PetscCall(MatDenseGetLDA(Hd, &lda));
      PetscCall(PetscArrayzero(h, lda * w));
      for (PetscInt row = rlo; row < rhi; row++) { /* columns j0..j1 of H, dense */
        PetscInt           ncols;
        const PetscInt    *cols;
        const PetscScalar *vals;
        PetscCall(MatGetRow(s->H[b], row, &ncols, &cols, &vals));
        for (PetscInt k = 0; k < ncols; k++)
          if (cols[k] >= j0 && cols[k] < j1) h[(row - rlo) + (cols[k] - j0) * lda] = vals[k];
        PetscCall(MatRestoreRow(s->H[b], row, &ncols, &cols, &vals));
      }
      PetscCall(MatDenseRestoreArrayWrite(Hd, &h));
      PetscCall(MatDuplicate(Hd, MAT_DO_NOT_COPY_VALUES, &X));
      PetscCall(MBCBodyZeroHeldRows(body, NULL, Hd));
      PetscCall(KSPMatSolve(body->ksp, Hd, X));
      PetscCall(MatDestroy(&Hd));
      /* H^T X with H sparse (a dozen entries per column): 2 nnz(H) w flops, not 2 N m w */
      PetscCall(MatTransposeMatMult(s->H[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &D));
      PetscCall(MatDestroy(&X));
      PetscCall(MatDenseGetArrayRead(D, &a));
      PetscCall(MatDenseGetLDA(D, &lda));
      for (PetscInt i = clo; i < chi; i++) /* this rank's rows of D_i (H's column layout) */
        for (PetscInt j = 0; j < w; j++)
          if (a[(i - clo) + j * lda] != 0.0) PetscCall(MatSetValue(s->fp.W, s->bcols[b][i], s->bcols[b][j0 + j], a[(i - clo) + j * lda], ADD_VALUES));
      PetscCall(MatDenseRestoreArrayRead(D, &a));
      PetscCall(MatDestroy(&D));
    }
  }
  PetscCall(MatAssemblyBegin(s->fp.W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(s->fp.W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateVecs(s->fp.W, &diag, NULL));
  PetscCall(MatGetDiagonal(s->fp.W, diag));
  PetscCall(VecSum(diag, &s->dscale));
  PetscCall(VecDestroy(&diag));
  s->dscale /= m;
  PetscCheck(s->dscale > 0, s->comm, PETSC_ERR_ARG_WRONG, "The contact flexibility matrix has no positive diagonal: every contact DOF is prescribed");
  PetscCall(MatScale(s->fp.W, 1.0 / s->dscale));
  PetscFunctionReturn(0);
}

/* Builds H and D for the contact points of pairs (couple, master, face per point), and carries
   the last step's contact forces, the PGS warm start and the slip over to them. */
PetscErrorCode MBCSolverContactSetUp(MBCSolver s, PetscInt n, PetscInt pairs[])
{
  MBCContact c  = s->contact;
  PetscInt   nc = NumContacts(c), nold = s->npairs_built, *oldpairs = s->pairs_built, *oldoff = NULL, *dims, m, mloc;
  PetscReal *oldframes = s->frames, *oldlam = NULL, *oldr = NULL, *oldslip = s->slip, *oldstepslip = s->stepslip;

  PetscFunctionBegin;
  PetscCheck(n == nc, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Contact pairs and points disagree");
  PetscCall(PetscLogEventBegin(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  if (nold && s->lamprev) { /* keep what the new points inherit, in couple order */
    const PetscInt mold = s->coff[nold];
    PetscCall(PetscMalloc3(nold + 1, &oldoff, mold + 1, &oldlam, mold + 1, &oldr));
    PetscCall(PetscArraycpy(oldoff, s->coff, nold + 1));
    PetscCall(MBCSolverContactGather(s, s->lamprev, oldlam));
    for (PetscInt i = 0; i < mold; i++) oldr[i] = s->rall[i] / s->dscale;
  }
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) { /* the contact force H lambda_n inside the acceleration */
    if (s->csf) PetscCall(MBCSolverContactToBodies(s, s->lamprev));
    for (PetscInt b = 0; b < s->nbodies; b++) {
      MBCBody body = s->bodies[b];
      if (!body) continue;
      if (!body->fcontact) PetscCall(VecDuplicate(body->u, &body->fcontact));
      if (s->H[b]) PetscCall(MatMult(s->H[b], s->lam[b], body->fcontact));
      else PetscCall(VecZeroEntries(body->fcontact));
    }
  }
  s->frames = NULL;
  s->slip     = NULL;
  s->stepslip = NULL;
  PetscCall(SolverContactReset(s));
  s->pairs_built  = pairs;
  s->npairs_built = n;
  s->ncontact     = nc;
  PetscCall(PetscMalloc1(nc + 1, &dims));
  PetscCall(PetscMalloc2(nc + 1, &s->kcouple, nc + 1, &s->kpoint));
  PetscCall(PetscMalloc1(9 * nc + 1, &s->frames));
  PetscCall(PetscCalloc1(3 * nc + 1, &s->slip));
  PetscCall(PetscCalloc1(3 * nc + 1, &s->stepslip));
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const MBCContactPoint *p = &c->couples[i].points[j];
      s->kcouple[k] = i, s->kpoint[k] = j;
      dims[k] = c->couples[i].mu > 0 ? 3 : 1;
      for (PetscInt e = 0; e < 3; e++) {
        s->frames[9 * k + e]     = p->n[e];
        s->frames[9 * k + 3 + e] = p->t1[e];
        s->frames[9 * k + 6 + e] = p->t2[e];
      }
    }
  PetscCall(SolverContactRankOrder(s, dims));
  m = s->coff[nc];
  mloc = s->poff[s->plast] - s->poff[s->pfirst];
  { /* this rank's contacts of the multiplier problem */
    PetscInt *ldims;
    s->fp.nc = s->plast - s->pfirst;
    PetscCall(PetscMalloc1(s->fp.nc + 1, &s->fp.mu));
    PetscCall(PetscMalloc1(s->fp.nc + 1, &ldims));
    for (PetscInt p = s->pfirst; p < s->plast; p++) {
      s->fp.mu[p - s->pfirst] = c->couples[s->kcouple[s->order[p]]].mu;
      ldims[p - s->pfirst]    = s->poff[p + 1] - s->poff[p];
    }
    PetscCall(MBCFrictionProblemSetBlocks(&s->fp, ldims));
    PetscCall(PetscFree(ldims));
  }
  PetscCall(PetscFree(dims));
  PetscCall(PetscMalloc2(m + 1, &s->rall, m + 1, &s->uall));
  PetscCall(PetscArrayzero(s->rall, m + 1));
  PetscCall(PetscArrayzero(s->uall, m + 1));
  if (nc) {
    PetscInt  *first;
    PetscReal *v[2];
    PetscCall(PetscMalloc1(nc + 1, &first));
    for (PetscInt b = 0; b < s->nbodies; b++) {
      PetscCall(BodyColumns(s, b, first));
      if (!s->bodies[b] || !s->nbcols[b]) continue;
      PetscCall(BodyContactMatrix(s, s->bodies[b], first, &s->H[b]));
      PetscCall(MatCreateVecs(s->H[b], &s->Hu[b], &s->Hl[b]));
      PetscCall(VecDuplicate(s->Hu[b], &s->lam[b]));
      PetscCall(VecDuplicate(s->Hl[b], &s->Xl[b]));
    }
    PetscCall(PetscFree(first));
    PetscCall(SolverContactBuildD(s, m, mloc));
    PetscCall(MatCreateVecs(s->fp.W, &s->fp.q, NULL));
    PetscCall(SolverContactForest(s));
    PetscCall(SolverContactRigidModes(s));
    PetscCall(VecDuplicate(s->fp.q, &s->lambda));
    PetscCall(VecDuplicate(s->fp.q, &s->ucontact));
    PetscCall(VecDuplicate(s->fp.q, &s->lamprev));
    PetscCall(VecScatterCreateToAll(s->lambda, &s->gather, &s->gathered));
    /* carry lambda_n and the warm start r (physical, then scaled) over to the new points */
    PetscCall(PetscMalloc2(m + 1, &v[0], m + 1, &v[1]));
    {
      const PetscReal *old[2] = {oldlam, oldr};
      PetscCall(CarryFields(2, oldoff ? nold : 0, oldpairs, oldframes, oldoff, old, nc, pairs, s->frames, s->coff, v));
    }
    for (PetscInt i = 0; i < m; i++) v[1][i] *= s->dscale;
    PetscCall(PetscArraycpy(s->rall, v[1], m));
    PetscCall(SolverContactScatterLocal(s, v[0], s->lamprev));
    PetscCall(SolverContactScatterLocal(s, v[1], s->lambda));
    PetscCall(PetscFree2(v[0], v[1]));
    if (oldslip && nold) { /* the slip so far and in this load step, (0, t1, t2) in each point's frame */
      PetscInt        *off3;
      const PetscReal *old[2] = {oldslip, oldstepslip};
      PetscReal       *carried[2] = {s->slip, s->stepslip};
      PetscCall(PetscMalloc1(PetscMax(nold, nc) + 1, &off3));
      for (PetscInt i = 0; i <= PetscMax(nold, nc); i++) off3[i] = 3 * i;
      PetscCall(CarryFields(2, nold, oldpairs, oldframes, off3, old, nc, pairs, s->frames, off3, carried));
      for (PetscInt k = 0; k < nc; k++) s->slip[3 * k] = s->stepslip[3 * k] = 0;
      PetscCall(PetscFree(off3));
    }
  }
  PetscCall(PetscFree3(oldoff, oldlam, oldr));
  PetscCall(PetscFree(oldslip));
  PetscCall(PetscFree(oldstepslip));
  PetscCall(PetscFree(oldframes));
  PetscCall(PetscFree(oldpairs));
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) PetscCall(SolverContactAccelerationUpdate(s)); /* also when no point is left */
  PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverContactDestroy(MBCSolver s)
{
  PetscFunctionBegin;
  if (!s->H) PetscFunctionReturn(0);
  PetscCall(SolverContactReset(s));
  PetscCall(PetscFree6(s->H, s->Hu, s->lam, s->Hl, s->Xl, s->nbcols));
  PetscCall(PetscFree(s->bcols));
  PetscCall(PetscFree(s->frames));
  PetscCall(PetscFree(s->slip));
  PetscCall(PetscFree(s->stepslip));
  PetscCall(PetscFree(s->pairs_built));
  PetscFunctionReturn(0);
}
