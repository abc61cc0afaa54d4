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
#include <mbc/private/interfaceimpl.h>
#include <petscblaslapack.h>
#include <stdint.h>

PetscLogEvent MBC_FlexibilityAssemble;

/* The interface between the bodies of a scene with couples; it borrows the scene, the search
   (contact), the bodies and their ranks from the solver, and makes the multiplier solve from the
   options (prefix <prefix>mbc_, prefix the solver's or NULL). H and D come with MBCInterfaceSetUp. */
PetscErrorCode MBCInterfaceCreate(MPI_Comm comm, MBCScene scene, MBCContact contact, PetscInt nbodies, MBCBody bodies[], const PetscMPIInt body_first_rank[], const PetscMPIInt body_nranks[], const char prefix[], MBCInterface *iface)
{
  MBCInterface ifc;

  PetscFunctionBegin;
  PetscCall(PetscNew(&ifc));
  ifc->comm            = comm;
  ifc->scene           = scene;
  ifc->contact         = contact;
  ifc->nbodies         = nbodies;
  ifc->bodies          = bodies;
  ifc->body_first_rank = body_first_rank;
  ifc->body_nranks     = body_nranks;
  ifc->analysis        = scene->analysis;
  ifc->theta           = 1;
  ifc->dblock          = 256;
  ifc->jtol            = 1e-6; /* -mbc_joint_break_rtol */
  ifc->jfrac           = 1;    /* -mbc_joint_break_fraction */
  ifc->fclib_step      = -1;
  PetscCall(MBCMultiplierCreate(comm, &ifc->mult));
  PetscCall(MBCMultiplierSetOptionsPrefix(ifc->mult, prefix));
  PetscCall(MBCMultiplierAppendOptionsPrefix(ifc->mult, "mbc_"));
  PetscCall(MBCMultiplierSetFromOptions(ifc->mult));
  PetscCall(PetscCalloc6(nbodies, &ifc->H, nbodies, &ifc->Hu, nbodies, &ifc->lam, nbodies, &ifc->Hl, nbodies, &ifc->Xl, nbodies, &ifc->nbcols));
  PetscCall(PetscCalloc1(nbodies, &ifc->bcols));
  PetscCall(PetscCalloc1(nbodies, &ifc->released));
  PetscCall(PetscCalloc4(nbodies, &ifc->sinv, nbodies, &ifc->sinv_is, nbodies, &ifc->sinv_id, nbodies, &ifc->sinv_state));
  PetscCall(PetscMalloc1(nbodies, &ifc->schur_fits));
  for (PetscInt b = 0; b < nbodies; b++) ifc->schur_fits[b] = -1;
  *iface = ifc;
  PetscFunctionReturn(0);
}

/* Complementarity on theta lambda_n+1 + (1 - theta) lambda_n (see above): theta = gamma
   (dynamic) or 1 (static, whose free bodies' rigid modes also enter the problem). release: a
   dynamic step's lambda_n enters through the acceleration only (Newmark), and the points that
   leave the contact set go on as open points (interfacerelease.c). Before the first
   MBCInterfaceSetUp, and at each analysis stage (its acceleration from the forces that act: no
   released force). */
PetscErrorCode MBCInterfaceSetTimeStepping(MBCInterface ifc, MBCAnalysisType analysis, PetscReal theta, PetscBool release)
{
  PetscFunctionBegin;
  ifc->analysis = analysis;
  ifc->theta    = theta;
  ifc->carry    = (1 - theta) / theta;
  ifc->release  = (PetscBool)(release && analysis == MBC_ANALYSIS_DYNAMIC);
  PetscCall(MBCInterfaceReleasedClear(ifc));
  PetscFunctionReturn(0);
}

/* Columns of A^-1 H per multi-right-hand-side solve while D is built (-mbc_contact_block). */
PetscErrorCode MBCInterfaceSetBlockSize(MBCInterface ifc, PetscInt dblock)
{
  PetscFunctionBegin;
  ifc->dblock = dblock;
  PetscFunctionReturn(0);
}

/* How D_i is had (-mbc_d_route, MBCDRoute); auto's limits: the memory of a body's Schur route
   (-mbc_d_schur_max_mb), of the dense D with the Newton matrix (-mbc_d_dense_max_mb), and the
   solves to build D where the Schur route does not fit (-mbc_d_solves_max). */
PetscErrorCode MBCInterfaceSetDRoute(MBCInterface ifc, PetscInt route, PetscReal schur_max_mb, PetscReal dense_max_mb, PetscReal solves_max)
{
  PetscFunctionBegin;
  ifc->droute       = route;
  ifc->schur_max_mb = schur_max_mb;
  ifc->dense_max_mb = dense_max_mb;
  ifc->solves_max   = solves_max;
  PetscFunctionReturn(0);
}

/* Contact points' rows split evenly over the ranks (-mbc_contact_rows_even), in the order of the
   ranks that compute most of each row */
PetscErrorCode MBCInterfaceSetRowsEven(MBCInterface ifc, PetscBool even)
{
  PetscFunctionBegin;
  ifc->rows_even = even;
  PetscFunctionReturn(0);
}

/* Points per patch of the matrix-free Newton steps' coarse space (-mbc_d_coarse_points; 0: none)
   and the most memory its W Phi may take (-mbc_d_coarse_max_mb). */
PetscErrorCode MBCInterfaceSetCoarse(MBCInterface ifc, PetscInt points, PetscReal max_mb)
{
  PetscFunctionBegin;
  ifc->coarse_points = points;
  ifc->coarse_max_mb = max_mb;
  PetscFunctionReturn(0);
}

/* Write the multiplier problem of step `step` to FCLIB file `file` (none if file is empty). */
PetscErrorCode MBCInterfaceSetFclibWrite(MBCInterface ifc, const char file[], PetscInt step)
{
  PetscFunctionBegin;
  PetscCall(PetscStrncpy(ifc->fclib_file, file, sizeof(ifc->fclib_file)));
  ifc->fclib_step = step;
  PetscFunctionReturn(0);
}

/* Contact points and multipliers of the last build (0 before the first). */
PetscErrorCode MBCInterfaceGetSize(MBCInterface ifc, PetscInt *npoints, PetscInt *nmult)
{
  PetscFunctionBegin;
  if (npoints) *npoints = ifc->ncontact;
  if (nmult) *nmult = ifc->coff ? ifc->coff[ifc->ncontact] : 0;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCInterfaceGetMultiplier(MBCInterface ifc, MBCMultiplier *mult)
{
  PetscFunctionBegin;
  *mult = ifc->mult;
  PetscFunctionReturn(0);
}

/* lambda_n+1 of the last step (physical, rows of W); NULL before the first build. */
PetscErrorCode MBCInterfaceGetMultipliers(MBCInterface ifc, Vec *lambda)
{
  PetscFunctionBegin;
  *lambda = ifc->lamprev;
  PetscFunctionReturn(0);
}

/* lambda_n+1 into each body's column layout (MBCInterfaceBodyForce); collective. */
PetscErrorCode MBCInterfaceMultipliersToBodies(MBCInterface ifc)
{
  PetscFunctionBegin;
  if (ifc->csf) PetscCall(MBCInterfaceToBodies(ifc, ifc->lamprev));
  PetscFunctionReturn(0);
}

/* f = H_b lambda_b, the contact force on body b, with lambda_n+1 of the last step after
   MBCInterfaceMultipliersToBodies; f = 0 where no point touches body b. On the body's ranks. */
PetscErrorCode MBCInterfaceBodyForce(MBCInterface ifc, PetscInt b, Vec f)
{
  PetscFunctionBegin;
  if (ifc->H[b]) PetscCall(MatMult(ifc->H[b], ifc->lam[b], f));
  else PetscCall(VecZeroEntries(f));
  PetscFunctionReturn(0);
}

/* Does point j of cp keep the slave nodes of the constraint built as bn[0..nb) (weights bw)? The
   mortar weights of nodes along a shared edge of nearly matching meshes, or at a face's corner
   the master node's share just reaches, come and go as the bodies move (Hertz, dynamic; the joints
   of an earthquake at every other step); with hysteresis a node counts as come only from 2e-2 of
   the largest weight if it had less than 5e-3 at the build, and as gone below 5e-3 if it had 2e-2,
   so weights that hover near a threshold rebuild nothing. Without hysteresis: the sets of nodes
   from 1e-2 of the largest weight. */
static PetscBool SlaveNodesKept(const MBCCouple *cp, PetscInt j, PetscInt nb, const PetscInt bn[], const PetscReal bw[], PetscBool hysteresis)
{
  const PetscReal lo = hysteresis ? 5e-3 : 1e-2, hi = hysteresis ? 2e-2 : 1e-2;
  PetscReal       wmax = 0, bmax = 0;

  for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) wmax = PetscMax(wmax, PetscAbsReal(cp->sw[l]));
  for (PetscInt l = 0; l < nb; l++) bmax = PetscMax(bmax, PetscAbsReal(bw[l]));
  for (PetscInt pass = 0; pass < 2; pass++) { /* came: now >= hi, built < lo; gone: built >= hi, now < lo */
    const PetscInt   n1 = pass ? nb : cp->soff[j + 1] - cp->soff[j], n2 = pass ? cp->soff[j + 1] - cp->soff[j] : nb;
    const PetscInt  *a1 = pass ? bn : cp->snode + cp->soff[j], *a2 = pass ? cp->snode + cp->soff[j] : bn;
    const PetscReal *w1 = pass ? bw : cp->sw + cp->soff[j], *w2 = pass ? cp->sw + cp->soff[j] : bw;
    const PetscReal  m1 = pass ? bmax : wmax, m2 = pass ? wmax : bmax;
    for (PetscInt l = 0; l < n1; l++) {
      PetscReal w = 0;
      if (!(PetscAbsReal(w1[l]) >= hi * m1)) continue;
      for (PetscInt i = 0; i < n2; i++)
        if (a2[i] == a1[l]) w = PetscAbsReal(w2[i]);
      if (!(w >= lo * m2)) return PETSC_FALSE;
    }
  }
  return PETSC_TRUE;
}

/* The contact pairs of the current search: per point (couple, master node, slave face, hash of
   the slave nodes of its integrated constraint); *changed when they differ from those H and D
   were built for (SlaveNodesKept: a point whose slave nodes it keeps takes the built hash). The
   caller owns pairs (MBCInterfaceSetUp takes them). */
PetscErrorCode MBCInterfaceGetPairs(MBCInterface ifc, PetscInt *npairs, PetscInt **pairs_out, PetscBool *changed)
{
  MBCContact      c = ifc->contact;
  const PetscBool hysteresis = (PetscBool)(c->hysteresis > 0);
  PetscInt        n = 0, k = 0, *pairs;
  PetscBool       same;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].npoints;
  PetscCall(PetscMalloc1(MBC_PAIR_SIZE * n + 1, &pairs));
  for (PetscInt i = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const MBCCouple *cp = &c->couples[i];
      const PetscInt  *b  = ifc->pairs_built && n == ifc->npairs_built ? ifc->pairs_built + MBC_PAIR_SIZE * k : NULL;
      uint32_t         h  = 2166136261u; /* FNV-1a of the slave nodes the point's constraint involves */
      PetscReal        wmax = 0;
      for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) wmax = PetscMax(wmax, PetscAbsReal(cp->sw[l]));
      for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++)
        if (PetscAbsReal(cp->sw[l]) >= 1e-2 * wmax) h = (h ^ (uint32_t)cp->snode[l]) * 16777619u;
      pairs[MBC_PAIR_SIZE * k]     = i;
      pairs[MBC_PAIR_SIZE * k + 1] = cp->points[j].master;
      pairs[MBC_PAIR_SIZE * k + 2] = cp->points[j].face;
      pairs[MBC_PAIR_SIZE * k + 3] = (PetscInt)(h & 0x7fffffff);
      if (b && b[0] == i && b[1] == cp->points[j].master && b[2] == cp->points[j].face && b[3] != pairs[MBC_PAIR_SIZE * k + 3] && SlaveNodesKept(cp, j, ifc->bsoff[k + 1] - ifc->bsoff[k], ifc->bsnode + ifc->bsoff[k], ifc->bsw + ifc->bsoff[k], hysteresis)) pairs[MBC_PAIR_SIZE * k + 3] = b[3];
    }
  same = (PetscBool)(ifc->pairs_built && n == ifc->npairs_built);
  if (same) PetscCall(PetscArraycmp(pairs, ifc->pairs_built, MBC_PAIR_SIZE * n, &same));
  *npairs    = n;
  *pairs_out = pairs;
  *changed   = (PetscBool)!same;
  PetscFunctionReturn(0);
}

/* Contact points of all couples in one list: (couple, point). */
static PetscInt NumContacts(MBCContact c)
{
  PetscInt n = 0;
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].npoints;
  return n;
}

/* Does the constraint of point j of cp involve body b? */
PetscBool MBCInterfacePointTouches(const MBCCouple *cp, PetscInt j, PetscInt b)
{
  for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++)
    if (cp->master.nbody[cp->mnode[l]] == b) return PETSC_TRUE;
  for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++)
    if (cp->slave.nbody[cp->snode[l]] == b) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* The distinct bodies whose nodes carry point j of cp (its master node's, then its slave nodes':
   the bodies its row of W couples) in bodies[] (room for every body), their number returned. */
static PetscInt PointBodies(const MBCCouple *cp, PetscInt j, PetscInt bodies[])
{
  PetscInt n = 0;
  for (PetscInt side = 0; side < 2; side++) {
    const PetscInt  lo = side ? cp->soff[j] : cp->moff[j], hi = side ? cp->soff[j + 1] : cp->moff[j + 1];
    const PetscInt *node = side ? cp->snode : cp->mnode, *nbody = side ? cp->slave.nbody : cp->master.nbody;
    for (PetscInt l = lo; l < hi; l++) {
      PetscInt i = 0;
      while (i < n && bodies[i] != nbody[node[l]]) i++;
      if (i == n) bodies[n++] = nbody[node[l]];
    }
  }
  return n;
}

/* Rank order: each point on a rank of the body, among those its constraint couples, that the most
   points touch (ties: its master's): that body computes the largest D_b, so most of the point's
   row of W is computed on its rank. On the 198k dam's 2 ranks every base point lives with the
   foundation instead of its monolith: the foundation's D_b (7.5 M entries) no longer crosses
   ranks in W's assembly, and the run takes 21.6 -> 18.9 s (docs/performance.md 3f). A body's
   points split evenly over its ranks, in couple order; points stably sorted by rank; the same on
   every rank. With rows_even that order is then cut into equal shares: the multiplier solve's
   row-wise work (W's and Z's products, their GEMMs) is the rows' owners', and on the 49k dam's 2
   ranks every point lived with the monoliths (rank 1), rank 0 waiting. */
static PetscErrorCode InterfaceRankOrder(MBCInterface ifc, const PetscInt dims[])
{
  MBCContact  c  = ifc->contact;
  PetscInt    nc = ifc->ncontact, *owner, *count, *seen, *touch, *home, *bodies;
  PetscMPIInt P, rank;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(ifc->comm, &P));
  PetscCallMPI(MPI_Comm_rank(ifc->comm, &rank));
  PetscCall(PetscMalloc3(nc + 1, &owner, ifc->nbodies, &count, ifc->nbodies, &seen));
  PetscCall(PetscCalloc3(ifc->nbodies, &touch, nc + 1, &home, ifc->nbodies, &bodies));
  PetscCall(PetscArrayzero(count, ifc->nbodies));
  PetscCall(PetscArrayzero(seen, ifc->nbodies));
  for (PetscInt k = 0; k < nc; k++) {
    const PetscInt n = PointBodies(&c->couples[ifc->kcouple[k]], ifc->kpoint[k], bodies);
    for (PetscInt i = 0; i < n; i++) touch[bodies[i]]++;
  }
  for (PetscInt k = 0; k < nc; k++) {
    const MBCCouple *cp = &c->couples[ifc->kcouple[k]];
    const PetscInt   n  = PointBodies(cp, ifc->kpoint[k], bodies);
    home[k] = cp->master.nbody[cp->points[ifc->kpoint[k]].master];
    for (PetscInt i = 0; i < n; i++)
      if (touch[bodies[i]] > touch[home[k]]) home[k] = bodies[i];
    count[home[k]]++;
  }
  for (PetscInt k = 0; k < nc; k++) {
    const PetscInt b = home[k];
    owner[k] = ifc->body_first_rank[b] + (seen[b]++ * ifc->body_nranks[b]) / count[b];
  }
  if (ifc->rows_even && P > 1) { /* that order cut into equal shares (-mbc_contact_rows_even) */
    PetscInt q = 0, *even;
    PetscCall(PetscMalloc1(nc + 1, &even));
    for (PetscMPIInt r = 0; r < P; r++)
      for (PetscInt k = 0; k < nc; k++)
        if (owner[k] == r) even[k] = (PetscInt)(((PetscInt64)q++ * P) / nc);
    PetscCall(PetscArraycpy(owner, even, nc));
    PetscCall(PetscFree(even));
  }
  PetscCall(PetscMalloc4(nc + 1, &ifc->perm, nc + 1, &ifc->order, nc + 1, &ifc->coff, nc + 1, &ifc->poff));
  ifc->coff[0] = 0;
  for (PetscInt k = 0; k < nc; k++) ifc->coff[k + 1] = ifc->coff[k] + dims[k];
  {
    PetscInt p = 0;
    for (PetscMPIInt r = 0; r < P; r++) {
      if (r == rank) ifc->pfirst = p;
      for (PetscInt k = 0; k < nc; k++)
        if (owner[k] == r) ifc->order[p] = k, ifc->perm[k] = p++;
      if (r == rank) ifc->plast = p;
    }
  }
  ifc->poff[0] = 0;
  for (PetscInt p = 0; p < nc; p++) ifc->poff[p + 1] = ifc->poff[p] + dims[ifc->order[p]];
  if (P > 1) PetscCall(PetscInfo(NULL, "%" PetscInt_FMT " of %" PetscInt_FMT " contact points on this rank\n", ifc->plast - ifc->pfirst, nc));
  PetscCall(PetscFree3(owner, count, seen));
  PetscCall(PetscFree3(touch, home, bodies));
  PetscFunctionReturn(0);
}

/* bcols[b]: the W rows (rank order, ascending) of the multipliers of the points touching body b;
   first[k]: the first H column of point k in body b, or -1. On every rank, for every body. */
static PetscErrorCode BodyColumns(MBCInterface ifc, PetscInt b, PetscInt first[])
{
  MBCContact c = ifc->contact;
  PetscInt   n = 0;

  PetscFunctionBegin;
  PetscCall(PetscFree(ifc->bcols[b]));
  for (PetscInt k = 0; k < ifc->ncontact; k++) first[k] = MBCInterfacePointTouches(&c->couples[ifc->kcouple[k]], ifc->kpoint[k], b) ? 0 : -1;
  for (PetscInt p = 0; p < ifc->ncontact; p++) {
    const PetscInt k = ifc->order[p];
    if (first[k] < 0) continue;
    first[k] = n;
    n += ifc->coff[k + 1] - ifc->coff[k];
  }
  ifc->nbcols[b] = n;
  PetscCall(PetscMalloc1(n + 1, &ifc->bcols[b]));
  for (PetscInt p = 0; p < ifc->ncontact; p++) {
    const PetscInt k = ifc->order[p];
    if (first[k] < 0) continue;
    for (PetscInt a = 0; a < ifc->coff[k + 1] - ifc->coff[k]; a++) ifc->bcols[b][first[k] + a] = ifc->poff[p] + a;
  }
  PetscFunctionReturn(0);
}

/* H of one body: the point's frame times its master (+) and slave (-) node weights
   (MBCCoupleIntegrate) in the columns first[k] + (0, 1, 2); rows of constrained DOFs are
   zero (a prescribed DOF takes no contact force; the PGS treats a contact with no free DOF as
   inactive). */
static PetscErrorCode BodyContactMatrix(MBCInterface ifc, MBCBody body, const PetscInt first[], Mat *H)
{
  MBCContact  c = ifc->contact;
  PetscMPIInt brank;
  PetscInt    ndof, nloc, rstart, k = 0, *cnt, *onz;
  MPI_Comm    bcomm;
  Vec         bu;
  PetscInt    bindex;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetDisplacement(body, &bu));
  PetscCall(MBCBodyGetIndex(body, &bindex));
  PetscCall(VecGetSize(bu, &ndof));
  PetscCall(VecGetLocalSize(bu, &nloc));
  PetscCall(VecGetOwnershipRange(bu, &rstart, NULL));
  /* preallocation: per local row the entries inserted into it (an upper bound: a slave node's row
     takes the columns of every point whose integrated constraint reaches it, often more than the
     24 a row had; every row that overflowed copied the whole matrix, 12 % of the 20k dam's run) */
  PetscCall(PetscCalloc2(nloc + 1, &cnt, nloc + 1, &onz));
  for (PetscInt i = 0, kk = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    for (PetscInt j = 0; j < cp->npoints; j++, kk++) {
      const PetscInt dim = ifc->coff[kk + 1] - ifc->coff[kk];
      if (first[kk] < 0) continue;
      for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++) {
        const PetscInt node = cp->mnode[l], r = cp->master.nrow[node] - rstart;
        if (cp->master.nbody[node] != bindex || r < 0 || r >= nloc) continue;
        for (PetscInt d = 0; d < 3; d++) cnt[r + d] += dim;
      }
      for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) {
        const PetscInt node = cp->snode[l], r = cp->slave.nrow[node] - rstart;
        if (cp->slave.nbody[node] != bindex || r < 0 || r >= nloc) continue;
        for (PetscInt d = 0; d < 3; d++) cnt[r + d] += dim;
      }
    }
  }
  {
    PetscInt nlc = PETSC_DECIDE, N = ifc->nbcols[bindex];
    PetscCall(PetscSplitOwnership(bcomm, &nlc, &N));
    for (PetscInt r = 0; r < nloc; r++) onz[r] = PetscMin(cnt[r], N - nlc), cnt[r] = PetscMin(cnt[r], nlc);
    PetscCall(MatCreateAIJ(bcomm, nloc, nlc, ndof, N, 0, cnt, 0, onz, H));
  }
  PetscCall(PetscFree2(cnt, onz));
  PetscCall(MatSetOption(*H, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple  *cp = &c->couples[i];
    MBCSurface *m = &cp->master, *sl = &cp->slave;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const PetscReal *e[3] = {&ifc->frames[9 * k], &ifc->frames[9 * k + 3], &ifc->frames[9 * k + 6]};
      if (brank || first[k] < 0) continue; /* rank 0 of the body inserts; assembly sends rows to their owners */
      for (PetscInt a = 0; a < ifc->coff[k + 1] - ifc->coff[k]; a++) {
        const PetscInt col = first[k] + a;
        if (ifc->held[k] & (1 << a)) continue; /* held on both sides: no multiplier acts along it */
        for (PetscInt l = cp->moff[j]; l < cp->moff[j + 1]; l++) {
          const PetscInt node = cp->mnode[l];
          if (m->nbody[node] != bindex) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, m->nrow[node] + d, col, cp->mw[l] * e[a][d], ADD_VALUES));
        }
        for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) {
          const PetscInt node = cp->snode[l];
          if (sl->nbody[node] != bindex) continue;
          for (PetscInt d = 0; d < 3; d++) PetscCall(MatSetValue(*H, sl->nrow[node] + d, col, -cp->sw[l] * e[a][d], ADD_VALUES));
        }
      }
    }
  }
  PetscCall(MatAssemblyBegin(*H, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*H, MAT_FINAL_ASSEMBLY));
  {
    PetscInt        nbc;
    const PetscInt *bcrows;
    PetscCall(MBCBodyGetPrescribedRows(body, &nbc, &bcrows));
    PetscCall(MatZeroRows(*H, nbc, bcrows, 0.0, NULL, NULL));
  }
  PetscFunctionReturn(0);
}

/* Everything built with H: per body H, its vectors and column lists; the star forest; W, q,
   lambda; the gathered copies. */
static PetscErrorCode InterfaceReset(MBCInterface ifc)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscCall(MatDestroy(&ifc->H[b]));
    PetscCall(VecDestroy(&ifc->Hu[b]));
    PetscCall(VecDestroy(&ifc->lam[b]));
    PetscCall(VecDestroy(&ifc->Hl[b]));
    PetscCall(VecDestroy(&ifc->Xl[b]));
    PetscCall(PetscFree(ifc->bcols[b]));
    ifc->nbcols[b] = 0;
  }
  PetscCall(PetscSFDestroy(&ifc->csf));
  PetscCall(PetscFree(ifc->leaf));
  PetscCall(VecScatterDestroy(&ifc->gather));
  PetscCall(VecDestroy(&ifc->gathered));
  PetscCall(PetscFree2(ifc->rall, ifc->uall));
  PetscCall(PetscFree4(ifc->perm, ifc->order, ifc->coff, ifc->poff));
  PetscCall(PetscFree2(ifc->kcouple, ifc->kpoint));
  PetscCall(MBCFrictionProblemDestroy(&ifc->fp));
  PetscCall(PetscFree(ifc->goff));
  PetscCall(PetscFree(ifc->gQ));
  PetscCall(PetscFree(ifc->grange));
  PetscCall(PetscFree(ifc->gscale));
  ifc->ngrigid = 0;
  PetscCall(MBCMultiplierReset(ifc->mult));
  PetscCall(VecDestroy(&ifc->lambda));
  PetscCall(VecDestroy(&ifc->ucontact));
  PetscCall(VecDestroy(&ifc->lamprev));
  PetscCall(VecDestroy(&ifc->lamsave));
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
static PetscErrorCode InterfaceForest(MBCInterface ifc)
{
  PetscInt    nleaf = 0, *remote;
  PetscLayout layout;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscInt lo, hi;
    if (!ifc->lam[b]) continue;
    PetscCall(VecGetOwnershipRange(ifc->lam[b], &lo, &hi));
    nleaf += hi - lo;
  }
  PetscCall(PetscMalloc1(nleaf + 1, &remote));
  PetscCall(PetscMalloc1(nleaf + 1, &ifc->leaf));
  nleaf = 0;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscInt lo, hi;
    if (!ifc->lam[b]) continue;
    PetscCall(VecGetOwnershipRange(ifc->lam[b], &lo, &hi));
    for (PetscInt j = lo; j < hi; j++) remote[nleaf++] = ifc->bcols[b][j];
  }
  PetscCall(VecGetLayout(ifc->fp.q, &layout));
  PetscCall(PetscSFCreate(ifc->comm, &ifc->csf));
  PetscCall(PetscSFSetGraphLayout(ifc->csf, layout, nleaf, NULL, PETSC_OWN_POINTER, remote));
  PetscCall(PetscSFSetUp(ifc->csf));
  PetscCall(PetscFree(remote));
  PetscFunctionReturn(0);
}

/* v (rows of W) into lam[b], every body's on this rank (H's column layout). */
PetscErrorCode MBCInterfaceScatterToBodies(MBCInterface ifc, Vec v, Vec lam[])
{
  const PetscScalar *a;
  PetscInt           l = 0;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(v, &a));
  PetscCall(PetscSFBcastBegin(ifc->csf, MPIU_SCALAR, a, ifc->leaf, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(ifc->csf, MPIU_SCALAR, a, ifc->leaf, MPI_REPLACE));
  PetscCall(VecRestoreArrayRead(v, &a));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscScalar *la;
    PetscInt     n;
    if (!ifc->lam[b]) continue;
    PetscCall(VecGetLocalSize(lam[b], &n));
    PetscCall(VecGetArray(lam[b], &la));
    PetscCall(PetscArraycpy(la, ifc->leaf + l, n));
    PetscCall(VecRestoreArray(lam[b], &la));
    l += n;
  }
  PetscFunctionReturn(0);
}

/* v (rows of W) = the sum over bodies of hu[b] (H's column layout). */
PetscErrorCode MBCInterfaceGatherFromBodies(MBCInterface ifc, Vec hu[], Vec v)
{
  PetscScalar *a;
  PetscInt     l = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    const PetscScalar *ha;
    PetscInt           n;
    if (!ifc->Hu[b]) continue;
    PetscCall(VecGetLocalSize(hu[b], &n));
    PetscCall(VecGetArrayRead(hu[b], &ha));
    PetscCall(PetscArraycpy(ifc->leaf + l, ha, n));
    PetscCall(VecRestoreArrayRead(hu[b], &ha));
    l += n;
  }
  PetscCall(VecZeroEntries(v));
  PetscCall(VecGetArray(v, &a));
  PetscCall(PetscSFReduceBegin(ifc->csf, MPIU_SCALAR, ifc->leaf, a, MPIU_SUM));
  PetscCall(PetscSFReduceEnd(ifc->csf, MPIU_SCALAR, ifc->leaf, a, MPIU_SUM));
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

/* v (rows of W) into every body's lam[b] on this rank. */
PetscErrorCode MBCInterfaceToBodies(MBCInterface ifc, Vec v)
{
  PetscFunctionBegin;
  PetscCall(MBCInterfaceScatterToBodies(ifc, v, ifc->lam));
  PetscFunctionReturn(0);
}

/* v (rows of W) = the sum over bodies of Hu[b]. */
PetscErrorCode MBCInterfaceFromBodies(MBCInterface ifc, Vec v)
{
  PetscFunctionBegin;
  PetscCall(MBCInterfaceGatherFromBodies(ifc, ifc->Hu, v));
  PetscFunctionReturn(0);
}

/* The gap a step starts from at point k: the search's, on the current geometry. A dynamic step
   closes a penetration it starts from within the step, and the contact forces then do work
   z |g| on the bodies (docs/design.md, departure 2, needs g_n >= 0 for no gain). Such
   penetrations are the second-order difference between the gap a step predicted (g_n + H^T du
   with H of the last rebuild) and the one the search finds after it: ~1e-12 m on the bouncing
   blocks of bench/extremes_dynamic.py. (A first-order one, the gap measured to a warped slave
   quad's mean plane while H moved its corners, reached 1e-5 m per step and pumped in 2600 times
   the impact energy: MBCCoupleProjectOnFace.) -mbc_contact_keep_penetration starts a dynamic step
   from max(g, 0): the normal work z max(g, 0) is then never negative whatever the geometry does,
   and a penetration is only kept from growing (an initial one, accepted by
   -mbc_contact_penetration_tol, stays). */
PetscReal MBCInterfaceStartGap(MBCInterface ifc, PetscInt k)
{
  const PetscReal g = ifc->contact->couples[ifc->kcouple[k]].igap[ifc->kpoint[k]];

  return ifc->analysis == MBC_ANALYSIS_DYNAMIC && ifc->contact->keep_penetration ? PetscMax(g, 0) : g;
}

/* q = sum_i H_i^T du_i + (gap, 0, 0): this rank's rows. */
PetscErrorCode MBCInterfaceGapRate(MBCInterface ifc, Vec q)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    Vec du;
    if (!ifc->H[b]) continue;
    PetscCall(MBCBodyGetIncrement(ifc->bodies[b], &du));
    PetscCall(MatMultTranspose(ifc->H[b], du, ifc->Hu[b]));
  }
  PetscCall(MBCInterfaceFromBodies(ifc, q));
  PetscCall(VecGetOwnershipRange(q, &rstart, NULL));
  PetscCall(VecGetArray(q, &a));
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) { /* this rank's points */
    const PetscInt k = ifc->order[p];
    a[ifc->poff[p] - rstart] += MBCInterfaceStartGap(ifc, k);
  }
  PetscCall(VecRestoreArray(q, &a));
  PetscFunctionReturn(0);
}

/* v (rows of W) on every rank in couple order (out: coff layout). */
PetscErrorCode MBCInterfaceGather(MBCInterface ifc, Vec v, PetscReal out[])
{
  const PetscScalar *a;

  PetscFunctionBegin;
  PetscCall(VecScatterBegin(ifc->gather, v, ifc->gathered, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(ifc->gather, v, ifc->gathered, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecGetArrayRead(ifc->gathered, &a));
  for (PetscInt k = 0; k < ifc->ncontact; k++)
    for (PetscInt d = 0; d < ifc->coff[k + 1] - ifc->coff[k]; d++) out[ifc->coff[k] + d] = PetscRealPart(a[ifc->poff[ifc->perm[k]] + d]);
  PetscCall(VecRestoreArrayRead(ifc->gathered, &a));
  PetscFunctionReturn(0);
}

/* Couple-order values (coff layout, every rank) into this rank's rows of v. */
static PetscErrorCode InterfaceScatterLocal(MBCInterface ifc, const PetscReal in[], Vec v)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(v, &rstart, NULL));
  PetscCall(VecGetArray(v, &a));
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) {
    const PetscInt k = ifc->order[p];
    for (PetscInt d = 0; d < ifc->coff[k + 1] - ifc->coff[k]; d++) a[ifc->poff[p] + d - rstart] = in[ifc->coff[k] + d];
  }
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

/* The state a restart needs (solvercheckpoint.c), couple order, every rank: nc points, m
   multipliers; lambda_n+1 (physical, into lamprev[m], the caller's), the warm start r (scaled, m),
   the slip (3 nc) and the pairs H and D were built for (MBC_PAIR_SIZE nc). Collective. */
PetscErrorCode MBCInterfaceGetState(MBCInterface ifc, PetscInt *nc, PetscInt *m, PetscReal lamprev[], const PetscReal **r, const PetscReal **slip, const PetscInt **pairs)
{
  PetscFunctionBegin;
  *nc = ifc->lamprev ? ifc->ncontact : 0;
  *m  = *nc ? ifc->coff[*nc] : 0;
  if (lamprev && *nc) PetscCall(MBCInterfaceGather(ifc, ifc->lamprev, lamprev));
  if (r) *r = ifc->rall;
  if (slip) *slip = ifc->slip;
  if (pairs) *pairs = ifc->pairs_built;
  PetscFunctionReturn(0);
}

/* The multipliers, warm start and slip of MBCInterfaceGetState back, after MBCInterfaceSetUp
   with the same pairs. */
PetscErrorCode MBCInterfaceSetState(MBCInterface ifc, const PetscReal lamprev[], const PetscReal r[], const PetscReal slip[])
{
  PetscFunctionBegin;
  if (!ifc->ncontact || !ifc->lamprev) PetscFunctionReturn(0);
  PetscCall(InterfaceScatterLocal(ifc, lamprev, ifc->lamprev));
  PetscCall(InterfaceScatterLocal(ifc, r, ifc->lambda));
  PetscCall(PetscArraycpy(ifc->rall, r, ifc->coff[ifc->ncontact]));
  PetscCall(PetscArraycpy(ifc->slip, slip, 3 * ifc->ncontact));
  PetscCall(PetscArrayzero(ifc->stepslip, 3 * ifc->ncontact));
  PetscCall(PetscArrayzero(ifc->cutslip, 3 * ifc->ncontact));
  PetscFunctionReturn(0);
}

/* The multiplier solve's restart state (MBCMultiplierGetRestartState) in couple order, m values
   on every rank, then its count (m + 1 in all); *has false where the solve keeps none. Collective. */
PetscErrorCode MBCInterfaceGetSolveState(MBCInterface ifc, PetscReal state[], PetscBool *has)
{
  Vec      v;
  PetscInt count;

  PetscFunctionBegin;
  *has = PETSC_FALSE;
  if (!ifc->ncontact || !ifc->lambda) PetscFunctionReturn(0);
  PetscCall(VecDuplicate(ifc->lambda, &v));
  PetscCall(MBCMultiplierGetRestartState(ifc->mult, v, &count, has));
  if (*has) PetscCall(MBCInterfaceGather(ifc, v, state));
  state[ifc->coff[ifc->ncontact]] = (PetscReal)count;
  PetscCall(VecDestroy(&v));
  PetscFunctionReturn(0);
}

/* ... given back after MBCInterfaceSetUp with the same pairs */
PetscErrorCode MBCInterfaceSetSolveState(MBCInterface ifc, const PetscReal state[])
{
  Vec v;

  PetscFunctionBegin;
  if (!ifc->ncontact || !ifc->lambda) PetscFunctionReturn(0);
  PetscCall(VecDuplicate(ifc->lambda, &v));
  PetscCall(InterfaceScatterLocal(ifc, state, v));
  PetscCall(MBCMultiplierSetProblem(ifc->mult, &ifc->fp)); /* the state belongs to this W */
  PetscCall(MBCMultiplierSetRestartState(ifc->mult, v, (PetscInt)state[ifc->coff[ifc->ncontact]]));
  PetscCall(VecDestroy(&v));
  PetscFunctionReturn(0);
}

/* W's preallocation: a point's row couples to the multipliers of the bodies its constraint
   touches (the master body, the slave body). */
static PetscErrorCode InterfacePreallocation(MBCInterface ifc, PetscInt rstart, PetscInt rend, PetscInt dnz[], PetscInt onz[])
{
  MBCContact c = ifc->contact;

  PetscFunctionBegin;
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) {
    const PetscInt   k = ifc->order[p];
    const MBCCouple *cp = &c->couples[ifc->kcouple[k]];
    PetscInt         bs[2], nb = 0, d = 0, o = 0;
    for (PetscInt b = 0; b < ifc->nbodies && nb < 2; b++) /* at most two: a master node, a slave face */
      if (MBCInterfacePointTouches(cp, ifc->kpoint[k], b)) bs[nb++] = b;
    if (nb == 1) {
      for (PetscInt j = 0; j < ifc->nbcols[bs[0]]; j++) (ifc->bcols[bs[0]][j] >= rstart && ifc->bcols[bs[0]][j] < rend) ? d++ : o++;
    } else if (nb == 2) { /* the union of two ascending lists */
      const PetscInt *x = ifc->bcols[bs[0]], *y = ifc->bcols[bs[1]], nx = ifc->nbcols[bs[0]], ny = ifc->nbcols[bs[1]];
      PetscInt        ix = 0, iy = 0;
      while (ix < nx || iy < ny) {
        PetscInt v;
        if (iy >= ny || (ix < nx && x[ix] < y[iy])) v = x[ix++];
        else if (ix >= nx || y[iy] < x[ix]) v = y[iy++];
        else v = x[ix++], iy++;
        (v >= rstart && v < rend) ? d++ : o++;
      }
    }
    for (PetscInt a = 0; a < ifc->coff[k + 1] - ifc->coff[k]; a++) dnz[ifc->poff[p] + a - rstart] = d, onz[ifc->poff[p] + a - rstart] = o;
  }
  PetscFunctionReturn(0);
}

/* W(rows[i], cols[j]) += a[(i - lo) + j lda] for i in [lo, hi), j < w, the entries that are not
   zero, one MatSetValues per row instead of one MatSetValue per entry (a million calls per build at
   49k DOFs; no measurable time either way); the same additions in the same order. */
static PetscErrorCode AddDenseBlock(Mat W, const PetscInt rows[], PetscInt lo, PetscInt hi, const PetscInt cols[], PetscInt w, const PetscScalar a[], PetscInt lda)
{
  PetscInt    *c;
  PetscScalar *v;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(w + 1, &c, w + 1, &v));
  for (PetscInt i = lo; i < hi; i++) {
    PetscInt n = 0;
    for (PetscInt j = 0; j < w; j++)
      if (a[(i - lo) + j * lda] != 0.0) c[n] = cols[j], v[n++] = a[(i - lo) + j * lda];
    PetscCall(MatSetValues(W, 1, &rows[i], n, c, v, ADD_VALUES));
  }
  PetscCall(PetscFree2(c, v));
  PetscFunctionReturn(0);
}

/* r = 1 on the DOFs of body b's nodes on its contact surfaces (every couple, both sides) that
   K^+ does not hold, 0 elsewhere: C of the Schur route, fixed by the scene. */
static PetscErrorCode BodyContactDofs(MBCInterface ifc, PetscInt b, Vec r)
{
  MBCContact   c = ifc->contact;
  PetscScalar *ra;
  PetscInt     n, rs;

  PetscFunctionBegin;
  PetscCall(VecGetLocalSize(r, &n));
  PetscCall(VecGetOwnershipRange(r, &rs, NULL));
  PetscCall(VecGetArray(r, &ra));
  for (PetscInt i = 0; i < n; i++) ra[i] = 0;
  for (PetscInt k = 0; k < c->ncouples; k++)
    for (PetscInt side = 0; side < 2; side++) {
      const MBCSurface *sf = side ? &c->couples[k].slave : &c->couples[k].master;
      for (PetscInt v = 0; v < sf->nnodes; v++)
        if (sf->nbody[v] == b && sf->nrow[v] >= rs && sf->nrow[v] < rs + n) /* the surfaces are on every rank, the rows on their owner */
          for (PetscInt d = 0; d < 3; d++) ra[sf->nrow[v] - rs + d] = 1;
    }
  PetscCall(VecRestoreArray(r, &ra));
  PetscCall(MBCBodyZeroHeldRows(ifc->bodies[b], r, NULL));
  PetscFunctionReturn(0);
}

/* The rows of BodyContactDofs in the body's global numbering, ascending, all on the body's first
   rank (an empty IS on the others; a body on one rank: all of them); is NULL: only their number
   *nC, on every rank of the body. Collective on the body. */
static PetscErrorCode BodyContactIS(MBCInterface ifc, PetscInt b, IS *is, PetscInt *nC)
{
  MBCBody      body = ifc->bodies[b];
  Vec          r;
  PetscInt     n, nl = 0, rs, *idx, *all = NULL;
  PetscMPIInt  size, rank, cnt, *counts = NULL, *displs = NULL;
  PetscScalar *ra;
  MPI_Comm     bcomm;
  Vec          bu;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetDisplacement(body, &bu));
  PetscCallMPI(MPI_Comm_size(bcomm, &size));
  PetscCallMPI(MPI_Comm_rank(bcomm, &rank));
  PetscCall(VecDuplicate(bu, &r));
  PetscCall(VecGetLocalSize(r, &n));
  PetscCall(VecGetOwnershipRange(r, &rs, NULL));
  PetscCall(BodyContactDofs(ifc, b, r));
  PetscCall(VecGetArray(r, &ra));
  PetscCall(PetscMalloc1(n + 1, &idx));
  for (PetscInt i = 0; i < n; i++)
    if (ra[i] != 0.0) idx[nl++] = rs + i;
  PetscCall(VecRestoreArray(r, &ra));
  PetscCall(VecDestroy(&r));
  PetscCall(MPIU_Allreduce(&nl, nC, 1, MPIU_INT, MPI_SUM, bcomm));
  if (!is) {
    PetscCall(PetscFree(idx));
    PetscFunctionReturn(0);
  }
  if (size == 1) {
    PetscCall(ISCreateGeneral(PETSC_COMM_SELF, nl, idx, PETSC_OWN_POINTER, is));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMPIIntCast(nl, &cnt));
  if (!rank) PetscCall(PetscMalloc3(size, &counts, size, &displs, *nC + 1, &all));
  PetscCallMPI(MPI_Gather(&cnt, 1, MPI_INT, counts, 1, MPI_INT, 0, bcomm));
  for (PetscMPIInt p = 0; !rank && p < size; p++) displs[p] = p ? displs[p - 1] + counts[p - 1] : 0;
  PetscCallMPI(MPI_Gatherv(idx, cnt, MPIU_INT, all, counts, displs, MPIU_INT, 0, bcomm)); /* rank order: ascending */
  PetscCall(PetscFree(idx));
  PetscCall(ISCreateGeneral(PETSC_COMM_SELF, rank ? 0 : *nC, all, PETSC_COPY_VALUES, is));
  if (!rank) PetscCall(PetscFree3(counts, displs, all));
  PetscFunctionReturn(0);
}

/* Columns of the inverse's entries asked of MUMPS at once (BodyInverseEntries): their pattern
   takes 12 |C| bytes each. */
#define MBC_SINV_BLOCK 1024

/* -mbc_d_route auto: the Schur route for a body whose S^-1 (|C|^2 doubles) and the
   pattern of one block of the inverse's entries asked of MUMPS fit in -mbc_d_schur_max_mb. S^-1
   comes from the body's own factor (BodySchurInverse), so nothing else is allocated: until stop 27
   a second MUMPS factorization with C as its Schur set held S dense in its fronts, a workspace 9 to
   17 times S^-1 (1.75 GB at the 200k dam's foundation, 4 GB at the 400k one), which auto had to
   estimate by a symbolic analysis per body. Decided once per body: C is fixed by the scene. */
static PetscErrorCode BodyUsesSchur(MBCInterface ifc, PetscInt b, PetscBool *schur)
{
  MBCBody     body = ifc->bodies[b];
  PetscMPIInt brank;
  PetscBool   rigid;
  MPI_Comm    bcomm;
  const char *bname;

  PetscFunctionBegin;
  *schur = PETSC_FALSE;
  PetscCall(MBCBodyGetElement(body, NULL, &rigid));
  if (ifc->droute == MBC_D_ROUTE_MULTIRHS || ifc->droute == MBC_D_ROUTE_MATFREE || rigid) PetscFunctionReturn(0); /* a rigid body has no factor: its projection is cheap */
  if (ifc->droute == MBC_D_ROUTE_SCHUR) {
    *schur = PETSC_TRUE;
    PetscFunctionReturn(0);
  }
  if (ifc->schur_fits[b] < 0) {
    PetscInt  nC;
    PetscReal mb, pat;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetName(body, &bname));
    PetscCall(BodyContactIS(ifc, b, NULL, &nC));
    mb                 = 8.0 * nC * nC / 1048576.0;
    pat                = 12.0 * nC * PetscMin(nC, MBC_SINV_BLOCK) / 1048576.0;
    ifc->schur_fits[b] = mb + pat <= ifc->schur_max_mb;
    PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
    if (!brank) PetscCall(PetscInfo(NULL, "Body %s: the Schur route onto %" PetscInt_FMT " contact DOFs would take %g MB (S^-1 %g, the inverse's entries asked %g): %s -mbc_d_schur_max_mb %g\n", bname, nC, mb + pat, mb, pat, ifc->schur_fits[b] ? "within" : "beyond", (double)ifc->schur_max_mb));
  }
  *schur = (PetscBool)ifc->schur_fits[b];
  PetscFunctionReturn(0);
}

/* S (nC x nC, dense, on the body's first rank; 0 x 0 on its others) = (A^-1)_CC from A's MUMPS
   factor F on comm (the body's): the selected entries of the inverse (ICNTL(30)), blocks of
   MBC_SINV_BLOCK columns at a time; isC holds C (global rows, ascending) on the first rank. A sparse
   right-hand side names the entries, so MUMPS's solves skip what cannot reach C (the forward
   substitution from each column's leaf, the backward one only to C's rows): faster than the solves
   of the multi-right-hand-side route, and than the second factorization with C as Schur set it
   replaces (the 200k dam's monoliths 0.3 against 1.0 s each, its foundation's 3 672 contact DOFs
   16.3 against 21.6 s). On several ranks MUMPS takes the pattern and gives the entries on the first
   rank (centralised), and solves in parallel. *ok false when MUMPS fails (INFOG(1) then says why),
   the same on every rank; F's controls as they were. Collective on comm. */
static PetscErrorCode BodyInverseEntries(Mat F, MPI_Comm comm, IS isC, PetscInt n, PetscInt nC, Mat *S, PetscInt *infog1, PetscBool *ok)
{
  const PetscInt *ci;
  PetscInt        nl, *pos = NULL, *ia, *ja = NULL, icntl20, icntl21, icntl27;
  PetscScalar    *va = NULL, *sa;
  PetscMPIInt     size, rank;

  PetscFunctionBegin;
  *ok     = PETSC_TRUE;
  *infog1 = 0;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(ISGetLocalSize(isC, &nl));
  PetscCall(ISGetIndices(isC, &ci));
  PetscCall(MatMumpsGetIcntl(F, 20, &icntl20));
  PetscCall(MatMumpsGetIcntl(F, 21, &icntl21));
  PetscCall(MatMumpsGetIcntl(F, 27, &icntl27));
  PetscCall(MatMumpsSetIcntl(F, 27, 128)); /* right-hand sides per block of MUMPS's solve: 128 took the
                                              100k dam's foundation (2 352 contact DOFs) 6.2 -> 4.1 s */
  if (!rank) { /* the pattern: this rank holds all of it */
    PetscCall(PetscMalloc4(n, &pos, n + 1, &ia, (size_t)nC * PetscMin(nC, MBC_SINV_BLOCK) + 1, &ja, (size_t)nC * PetscMin(nC, MBC_SINV_BLOCK) + 1, &va));
    for (PetscInt i = 0; i < n; i++) pos[i] = -1;
    for (PetscInt k = 0; k < nl; k++) pos[ci[k]] = k;
  } else {
    PetscCall(PetscCalloc1(1, &ia));
  }
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, rank ? 0 : nC, rank ? 0 : nC, NULL, S));
  PetscCall(MatDenseGetArrayWrite(*S, &sa));
  for (PetscInt k0 = 0; k0 < nC && *ok; k0 += MBC_SINV_BLOCK) {
    const PetscInt     k1 = PetscMin(nC, k0 + MBC_SINV_BLOCK);
    const PetscScalar *v  = va;
    Mat                Bt, spRHS, Ad = NULL;
    PetscErrorCode     ierr;
    if (!rank) { /* Bt's row j (the inverse's column j, j in C's block) asks for the rows of C from
                    j on: A^-1 is symmetric, the upper triangle is mirrored (half the entries; the
                    198k dam's foundation 11.0 -> 9.3 s, the backward solves prune more) */
      ia[0] = 0;
      for (PetscInt i = 0, nz = 0; i < n; i++) {
        if (pos[i] >= k0 && pos[i] < k1)
          for (PetscInt k = pos[i]; k < nC; k++) ja[nz++] = ci[k];
        ia[i + 1] = nz;
      }
      PetscCall(PetscArrayzero(va, (size_t)nC * (k1 - k0)));
    }
    if (size == 1) PetscCall(MatCreateSeqAIJWithArrays(PETSC_COMM_SELF, n, n, ia, ja, va, &Bt)); /* the answer in va */
    else PetscCall(MatCreateMPIAIJWithArrays(comm, rank ? 0 : n, rank ? 0 : n, n, n, ia, ja, va, &Bt));
    PetscCall(MatCreateTranspose(Bt, &spRHS));
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL)); /* MUMPS's failure: the caller decides */
    ierr = MatMumpsGetInverse(F, spRHS);
    PetscCall(PetscPopErrorHandler());
    if (ierr) {
      PetscCall(MatMumpsGetInfog(F, 1, infog1));
      *ok = PETSC_FALSE;
    }
    if (size > 1 && !rank) { /* the answer in Bt's diagonal block: the first rank owns every row and column */
      PetscCall(MatMPIAIJGetSeqAIJ(Bt, &Ad, NULL, NULL));
      PetscCall(MatSeqAIJGetArrayRead(Ad, &v));
    }
    for (PetscInt i = 0; !rank && i < n && *ok; i++)
      if (pos[i] >= k0 && pos[i] < k1)
        for (PetscInt z = ia[i]; z < ia[i + 1]; z++) sa[pos[ja[z]] + (size_t)nC * pos[i]] = sa[pos[i] + (size_t)nC * pos[ja[z]]] = v[z];
    if (Ad) PetscCall(MatSeqAIJRestoreArrayRead(Ad, &v));
    PetscCall(MatDestroy(&spRHS));
    PetscCall(MatDestroy(&Bt));
  }
  PetscCall(MatDenseRestoreArrayWrite(*S, &sa));
  /* the factor serves the body's solves again */
  PetscCall(MatMumpsSetIcntl(F, 30, 0));
  PetscCall(MatMumpsSetIcntl(F, 20, icntl20));
  PetscCall(MatMumpsSetIcntl(F, 21, icntl21));
  PetscCall(MatMumpsSetIcntl(F, 27, icntl27));
  if (!rank) PetscCall(PetscFree4(pos, ia, ja, va));
  else PetscCall(PetscFree(ia));
  PetscCall(ISRestoreIndices(isC, &ci));
  if (!*ok) PetscCall(MatDestroy(S));
  PetscFunctionReturn(0);
}

/* D_b = H_b^T A_b^-1 H_b through the Schur complement (-mbc_d_route schur): C the DOFs of the body's
   nodes on its contact surfaces (every couple, both sides) that are not held (MBCBodyZeroHeldRows):
   a set fixed by the scene, which holds the rows of every H_b the search can make. S^-1 =
   (A^-1)_CC, with S = A_CC - A_CI A_II^-1 A_IC the Schur complement onto C, from the body's own
   factor (BodyInverseEntries; on the body's first rank), kept while the operator is the same
   object in the same state; then D_b = H_C^T S^-1 H_C for the pairs of each build: the same D as
   the multi-right-hand-side route, and a rebuild for new pairs costs two products with the sparse H_C, no solve.
   A restart computes S^-1 from the same operator and the same C, so it builds the same D.
   Collective on the body. */
static PetscErrorCode BodySchurInverse(MBCInterface ifc, PetscInt b, PetscBool *ok)
{
  MBCBody          body = ifc->bodies[b];
  Mat              Ainv, A, P, S, F;
  KSP              ksp;
  PC               pc;
  PetscInt         n, nC, infog1;
  PetscObjectState state;
  PetscObjectId    id;
  PetscLogDouble   t0, t1;
  PetscMPIInt      bsize, brank;
  MPI_Comm         bcomm;
  Vec              bu;
  const char      *bname;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MBCBodyGetDisplacement(body, &bu));
  PetscCall(MBCBodyGetName(body, &bname));
  *ok = PETSC_TRUE;
  PetscCallMPI(MPI_Comm_size(bcomm, &bsize));
  PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
  PetscCall(MBCBodyGetInverse(body, &Ainv));
  PetscCall(MBCInverseGetKSP(Ainv, &ksp));
  PetscCall(KSPGetOperators(ksp, &A, &P));
  PetscCall(PetscObjectStateGet((PetscObject)A, &state));
  PetscCall(PetscObjectGetId((PetscObject)A, &id));
  if (ifc->sinv[b] && ifc->sinv_id[b] == id && ifc->sinv_state[b] == state) {
    if (!brank) PetscCall(PetscInfo(NULL, "Body %s: D through the Schur complement, S^-1 reused\n", bname));
    PetscFunctionReturn(0);
  }
  PetscCall(MatDestroy(&ifc->sinv[b]));
  PetscCall(ISDestroy(&ifc->sinv_is[b]));
  PetscCall(BodyContactIS(ifc, b, &ifc->sinv_is[b], &nC)); /* the held rows depend on the operator (K^+) */
  PetscCall(VecGetSize(bu, &n));
  PetscCall(PetscTime(&t0));
  /* also where every DOF lies on a contact surface (S^-1 = A^-1: a coarse monolith with joints on
     both sides), which the Schur factorization had to take by LAPACK on A dense */
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCFactorGetMatrix(pc, &F));
  PetscCall(BodyInverseEntries(F, bcomm, ifc->sinv_is[b], n, nC, &S, &infog1, ok));
  if (!*ok) { /* MUMPS's workspace or the machine's memory ran out: the caller takes the solves */
    PetscCall(ISDestroy(&ifc->sinv_is[b]));
    PetscCheck(ifc->droute == MBC_D_ROUTE_AUTO, bcomm, PETSC_ERR_MEM, "Body '%s': the entries of its inverse on its %" PetscInt_FMT " contact DOFs failed (MUMPS INFOG(1) = %" PetscInt_FMT "); -mbc_d_route schur cannot be used for it", bname, nC, infog1);
    if (!brank) PetscCall(PetscInfo(NULL, "Body %s: the entries of its inverse failed (INFOG(1) = %" PetscInt_FMT "): its D by solves from now on\n", bname, infog1));
    ifc->schur_fits[b] = 0;
    PetscFunctionReturn(0);
  }
  ifc->sinv[b]       = S;
  ifc->sinv_id[b]    = id;
  ifc->sinv_state[b] = state;
  PetscCall(PetscTime(&t1));
  if (!brank) PetscCall(PetscInfo(NULL, "Body %s: D through the Schur complement onto %" PetscInt_FMT " contact DOFs of %" PetscInt_FMT " (S^-1, the inverse's entries from the body's factor, %d rank%s, in %g s)\n", bname, nC, n, (int)bsize, bsize > 1 ? "s" : "", t1 - t0));
  PetscFunctionReturn(0);
}

/* *D = H_C^T S H_C, column by column: y = S H_C(:,q) from the 3 to 12 columns of S that the
   multiplier's DOFs name, then D(:,q) = H_C^T y. With H_C dense, S H_C cost 2 |C|^2 m flops: 74
   GFlop and 2.7 s a build on the 198k dam's foundation (|C| 3 672, m 2 736); this way
   2 (|C| + m) nnz(H_C). */
static PetscErrorCode SchurProject(Mat S, Mat HC, Mat *D)
{
  Mat                HCt;
  Vec                y, d;
  const PetscScalar *sa;
  PetscScalar       *da, *ya;
  PetscInt           nC, m, lds, ldd;
  PetscLogDouble     nnz = 0;

  PetscFunctionBegin;
  PetscCall(MatGetSize(HC, &nC, &m));
  PetscCall(MatCreateSeqDense(PETSC_COMM_SELF, m, m, NULL, D));
  PetscCall(MatTranspose(HC, MAT_INITIAL_MATRIX, &HCt)); /* its row q: H_C's column q */
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, nC, &y));
  PetscCall(VecCreateSeqWithArray(PETSC_COMM_SELF, 1, m, NULL, &d));
  PetscCall(MatDenseGetLDA(S, &lds));
  PetscCall(MatDenseGetLDA(*D, &ldd));
  PetscCall(MatDenseGetArrayRead(S, &sa));
  PetscCall(MatDenseGetArrayWrite(*D, &da));
  for (PetscInt q = 0; q < m; q++) {
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscInt           nz;
    PetscCall(VecGetArrayWrite(y, &ya));
    PetscCall(PetscArrayzero(ya, nC));
    PetscCall(MatGetRow(HCt, q, &nz, &cols, &vals));
    nnz += nz;
    for (PetscInt k = 0; k < nz; k++) {
      const PetscScalar *sc = sa + (size_t)lds * cols[k];
      for (PetscInt i = 0; i < nC; i++) ya[i] += vals[k] * sc[i];
    }
    PetscCall(MatRestoreRow(HCt, q, &nz, &cols, &vals));
    PetscCall(VecRestoreArrayWrite(y, &ya));
    PetscCall(VecPlaceArray(d, da + (size_t)ldd * q));
    PetscCall(MatMult(HCt, y, d));
    PetscCall(VecResetArray(d));
  }
  PetscCall(PetscLogFlops(2.0 * nC * nnz)); /* MatMult logs its own */
  PetscCall(MatDenseRestoreArrayWrite(*D, &da));
  PetscCall(MatDenseRestoreArrayRead(S, &sa));
  PetscCall(VecDestroy(&d));
  PetscCall(VecDestroy(&y));
  PetscCall(MatDestroy(&HCt));
  PetscFunctionReturn(0);
}

/* *Dout: the dense nb x nb D_b = H_C^T S^-1 H_C (BodySchurInverse) on the body's first rank, 0 x 0
   on its others; NULL on every rank if the inverse's entries failed (auto then takes the solves).
   Collective on the body. */
static PetscErrorCode BodyDSchur(MBCInterface ifc, PetscInt b, Mat *Dout)
{
  Mat       HC, *sub;
  IS        cols;
  PetscBool ok;
  PetscInt  nrow;

  PetscFunctionBegin;
  *Dout = NULL;
  PetscCall(BodySchurInverse(ifc, b, &ok));
  if (!ok) PetscFunctionReturn(0);
  /* H's rows C, all its columns, on the first rank (H is distributed by the body's rows) */
  PetscCall(ISGetLocalSize(ifc->sinv_is[b], &nrow));
  PetscCall(ISCreateStride(PETSC_COMM_SELF, nrow ? ifc->nbcols[b] : 0, 0, 1, &cols));
  PetscCall(MatCreateSubMatrices(ifc->H[b], 1, &ifc->sinv_is[b], &cols, MAT_INITIAL_MATRIX, &sub));
  PetscCall(ISDestroy(&cols));
  HC = sub[0];
  PetscCall(SchurProject(ifc->sinv[b], HC, Dout));
  PetscCall(MatDestroySubMatrices(1, &sub));
  PetscFunctionReturn(0);
}

/* Whether D is matrix-free: -mbc_d_route matfree, or auto where the dense D would not fit in
   -mbc_d_dense_max_mb (W holds every body's dense D_b, sum nb^2 entries at 12 bytes as AIJ, and the
   Newton type factors its active part, up to m^2 doubles dense), or would cost more than
   -mbc_d_solves_max solves to build (the bodies the Schur route does not fit: a solve per column;
   a multiplier solve on the matrix-free D took 60 to 100 products per static iteration on the dams
   of 50k to 400k DOFs, each a solve per body). The pgs type and -mbc_fclib_write need W's entries,
   so auto keeps them whatever they cost. The same on every rank. Collective. */
static PetscErrorCode InterfaceUsesShell(MBCInterface ifc, PetscInt m, PetscBool *shell)
{
  PetscReal bytes = 8.0 * m * m, solves = 0;
  PetscBool newton;

  PetscFunctionBegin;
  *shell = (PetscBool)(ifc->droute == MBC_D_ROUTE_MATFREE);
  if (ifc->droute != MBC_D_ROUTE_AUTO) PetscFunctionReturn(0);
  PetscCall(PetscObjectTypeCompare((PetscObject)ifc->mult, MBCMULTIPLIERNEWTON, &newton));
  if (!((PetscObject)ifc->mult)->type_name) newton = PETSC_TRUE; /* the default type */
  for (PetscInt b = 0; b < ifc->nbodies; b++) bytes += 12.0 * ifc->nbcols[b] * ifc->nbcols[b];
  if (!(bytes > ifc->dense_max_mb * 1048576.0) || !newton || ifc->fclib_file[0]) {
    for (PetscInt b = 0; b < ifc->nbodies; b++) {
      PetscBool   schur = PETSC_TRUE;
      PetscMPIInt brank = 1;
      MPI_Comm    bcomm;
      if (!ifc->bodies[b] || !ifc->nbcols[b]) continue;
      PetscCall(BodyUsesSchur(ifc, b, &schur));
      PetscCall(MBCBodyGetComm(ifc->bodies[b], &bcomm));
      PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
      if (!schur && !brank) solves += ifc->nbcols[b];
    }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &solves, 1, MPIU_REAL, MPIU_SUM, ifc->comm));
    if (!(bytes > ifc->dense_max_mb * 1048576.0) && !(solves > ifc->solves_max)) PetscFunctionReturn(0);
  }
  *shell = (PetscBool)(newton && !ifc->fclib_file[0]);
  if (*shell && !(solves > 0)) PetscCall(PetscInfo(NULL, "D dense would take %g MB (-mbc_d_dense_max_mb %g): matrix-free\n", bytes / 1048576.0, (double)ifc->dense_max_mb));
  else PetscCall(PetscInfo(NULL, "D dense would take %g MB (-mbc_d_dense_max_mb %g) and %g solves to build (-mbc_d_solves_max %g): %s\n", bytes / 1048576.0, (double)ifc->dense_max_mb, solves, (double)ifc->solves_max, *shell ? "matrix-free" : "dense all the same (the pgs type or -mbc_fclib_write needs its entries)"));
  PetscFunctionReturn(0);
}

/* Columns hcols[0..n) (ascending) of body b's H, dense, with the rows K^+ holds zeroed (*Hd), and
   X = A_b^-1 Hd by one multi-right-hand-side solve with the body's factor. Collective on the body. */
PetscErrorCode MBCInterfaceBodySolveColumns(MBCInterface ifc, PetscInt b, PetscInt n, const PetscInt hcols[], Mat *Hd, Mat *X)
{
  MBCBody      body = ifc->bodies[b];
  Mat          Ainv;
  PetscScalar *h;
  PetscInt     lda, rlo, rhi;
  MPI_Comm     bcomm;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetComm(body, &bcomm));
  PetscCall(MatGetOwnershipRange(ifc->H[b], &rlo, &rhi));
  PetscCall(MatCreateDense(bcomm, rhi - rlo, PETSC_DECIDE, PETSC_DETERMINE, n, NULL, Hd));
  PetscCall(MatDenseGetArrayWrite(*Hd, &h));
  PetscCall(MatDenseGetLDA(*Hd, &lda));
  PetscCall(PetscArrayzero(h, lda * n));
  for (PetscInt row = rlo; row < rhi; row++) {
    PetscInt           ncols, at;
    const PetscInt    *cols;
    const PetscScalar *vals;
    PetscCall(MatGetRow(ifc->H[b], row, &ncols, &cols, &vals));
    for (PetscInt k = 0; k < ncols; k++) {
      if (cols[k] < hcols[0] || cols[k] > hcols[n - 1]) continue;
      PetscCall(PetscFindInt(cols[k], n, hcols, &at));
      if (at >= 0) h[(row - rlo) + at * lda] = vals[k];
    }
    PetscCall(MatRestoreRow(ifc->H[b], row, &ncols, &cols, &vals));
  }
  PetscCall(MatDenseRestoreArrayWrite(*Hd, &h));
  PetscCall(MBCBodyZeroHeldRows(body, NULL, *Hd));
  PetscCall(MBCBodyGetInverse(body, &Ainv));
  PetscCall(MatMatMult(Ainv, *Hd, MAT_INITIAL_MATRIX, PETSC_DEFAULT, X));
  PetscFunctionReturn(0);
}

/* D_i = H_i^T A_i^-1 H_i of the bodies on this rank, by blocks of -mbc_contact_block columns
   (memory: DOFs x block, not DOFs x multipliers), added into W (rows where they live); then
   W = D / dscale with dscale the mean diagonal: r = dscale lambda has the units of u, so the
   FCLIB merit weighs forces and displacements alike. */
static PetscErrorCode InterfaceBuildD(MBCInterface ifc, PetscInt m, PetscInt mloc)
{
  PetscInt *dnz, *onz, rstart;
  Vec       diag;

  PetscFunctionBegin;
  {
    PetscBool shell;
    PetscCall(InterfaceUsesShell(ifc, m, &shell));
    if (shell) {
      PetscCall(MBCInterfaceBuildDShell(ifc, m, mloc));
      PetscFunctionReturn(0);
    }
  }
  PetscCallMPI(MPI_Scan(&mloc, &rstart, 1, MPIU_INT, MPI_SUM, ifc->comm));
  rstart -= mloc;
  PetscCall(PetscMalloc2(mloc + 1, &dnz, mloc + 1, &onz));
  PetscCall(InterfacePreallocation(ifc, rstart, rstart + mloc, dnz, onz));
  PetscCall(MatCreateAIJ(ifc->comm, mloc, mloc, m, m, 0, dnz, 0, onz, &ifc->fp.W));
  PetscCall(MatSetOption(ifc->fp.W, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(PetscFree2(dnz, onz));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    MBCBody   body = ifc->bodies[b];
    PetscInt  nb = ifc->nbcols[b], clo, chi, *hcols;
    if (!body || !nb) continue;
    PetscCall(MatGetOwnershipRangeColumn(ifc->H[b], &clo, &chi));
    {
      PetscBool schur;
      PetscCall(BodyUsesSchur(ifc, b, &schur));
      if (schur) {
        Mat                D;
        const PetscScalar *a;
        PetscInt           lda;
        PetscCall(BodyDSchur(ifc, b, &D));
        if (D) { /* else the inverse's entries failed: the solves below */
          PetscInt nr;
          PetscCall(MatGetSize(D, &nr, NULL));
          PetscCall(MatDenseGetArrayRead(D, &a));
          PetscCall(MatDenseGetLDA(D, &lda));
          if (nr) PetscCall(AddDenseBlock(ifc->fp.W, ifc->bcols[b], 0, nb, ifc->bcols[b], nb, a, lda)); /* the body's first rank adds it all */
          PetscCall(MatDenseRestoreArrayRead(D, &a));
          PetscCall(MatDestroy(&D));
          continue;
        }
      }
    }
    PetscCall(PetscMalloc1(ifc->dblock, &hcols));
    for (PetscInt j0 = 0; j0 < nb; j0 += ifc->dblock) {
      const PetscInt     j1 = PetscMin(nb, j0 + ifc->dblock), w = j1 - j0;
      Mat                Hd, X, D;
      const PetscScalar *a;
      PetscInt           lda;
      for (PetscInt j = 0; j < w; j++) hcols[j] = j0 + j;
      PetscCall(MBCInterfaceBodySolveColumns(ifc, b, w, hcols, &Hd, &X));
      PetscCall(MatDestroy(&Hd));
      /* H^T X with H sparse (a dozen entries per column): 2 nnz(H) w flops, not 2 N m w */
      PetscCall(MatTransposeMatMult(ifc->H[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &D));
      PetscCall(MatDestroy(&X));
      PetscCall(MatDenseGetArrayRead(D, &a));
      PetscCall(MatDenseGetLDA(D, &lda));
      PetscCall(AddDenseBlock(ifc->fp.W, ifc->bcols[b], clo, chi, ifc->bcols[b] + j0, w, a, lda)); /* this rank's rows of D_i (H's column layout) */
      PetscCall(MatDenseRestoreArrayRead(D, &a));
      PetscCall(MatDestroy(&D));
    }
    PetscCall(PetscFree(hcols));
  }
  PetscCall(MatAssemblyBegin(ifc->fp.W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(ifc->fp.W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateVecs(ifc->fp.W, &diag, NULL));
  PetscCall(MatGetDiagonal(ifc->fp.W, diag));
  PetscCall(VecSum(diag, &ifc->dscale));
  PetscCall(VecDestroy(&diag));
  ifc->dscale /= m;
  PetscCall(PetscInfo(NULL, "D: dscale (the mean of D_dd) %g\n", (double)ifc->dscale));
  PetscCheck(ifc->dscale > 0, ifc->comm, PETSC_ERR_ARG_WRONG, "The contact flexibility matrix has no positive diagonal: every contact DOF is prescribed");
  PetscCall(MatScale(ifc->fp.W, 1.0 / ifc->dscale));
  PetscFunctionReturn(0);
}

/* D again for the bodies' new operators (the next analysis stage: Newmark's K~ instead of K, or
   back), H as built: the multipliers go on acting on the geometry they balance. After
   MBCInterfaceSetTimeStepping; the warm start becomes that of a step at rest (lambda_n+1 =
   lambda_n, r = dscale (1 + c) lambda_n). Collective. */
PetscErrorCode MBCInterfaceRebuildD(MBCInterface ifc)
{
  PetscFunctionBegin;
  if (!ifc->ncontact || !ifc->fp.W) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscCall(MatDestroy(&ifc->fp.W));
  PetscCall(MatDestroy(&ifc->fp.Winv));
  PetscCall(MatDestroy(&ifc->fp.WPhi));
  PetscCall(PetscFree2(ifc->fp.cocol, ifc->fp.cow));
  ifc->fp.nco = 0;
  PetscCall(MatDestroy(&ifc->fp.G));
  PetscCall(VecDestroy(&ifc->fp.e));
  PetscCall(VecDestroy(&ifc->fp.alpha));
  PetscCall(PetscFree(ifc->gQ));
  PetscCall(PetscFree(ifc->grange));
  PetscCall(PetscFree(ifc->gscale));
  PetscCall(MBCMultiplierReset(ifc->mult));
  PetscCall(InterfaceBuildD(ifc, ifc->coff[ifc->ncontact], ifc->poff[ifc->plast] - ifc->poff[ifc->pfirst]));
  PetscCall(MBCInterfaceRigidModes(ifc));
  PetscCall(VecAXPBY(ifc->lambda, ifc->dscale * (1 + ifc->carry), 0.0, ifc->lamprev));
  PetscCall(MBCInterfaceGather(ifc, ifc->lambda, ifc->rall));
  PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Builds H and D for the contact points of pairs (couple, master, face per point; takes pairs),
   and carries the last step's contact forces, the PGS warm start and the slip over to them. */
PetscErrorCode MBCInterfaceSetUp(MBCInterface ifc, PetscInt n, PetscInt pairs[])
{
  MBCContact c  = ifc->contact;
  PetscInt   nc = NumContacts(c), nold = ifc->npairs_built, *oldpairs = ifc->pairs_built, *oldoff = NULL, *dims, m, mloc;
  PetscReal *oldframes = ifc->frames, *oldlam = NULL, *oldr = NULL, *oldslip = ifc->slip, *oldstepslip = ifc->stepslip, *oldcutslip = ifc->cutslip;

  PetscFunctionBegin;
  PetscCheck(n == nc, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Contact pairs and points disagree");
  PetscCall(PetscLogEventBegin(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  if (nold && ifc->lamprev) { /* keep what the new points inherit, in couple order */
    const PetscInt mold = ifc->coff[nold];
    PetscCall(PetscMalloc3(nold + 1, &oldoff, mold + 1, &oldlam, mold + 1, &oldr));
    PetscCall(PetscArraycpy(oldoff, ifc->coff, nold + 1));
    PetscCall(MBCInterfaceGather(ifc, ifc->lamprev, oldlam));
    for (PetscInt i = 0; i < mold; i++) oldr[i] = ifc->rall[i] / ifc->dscale;
    PetscCall(MBCInterfaceRelease(ifc, n, pairs, oldlam)); /* with the old H */
  }
  ifc->frames = NULL;
  ifc->slip     = NULL;
  ifc->stepslip = NULL;
  ifc->cutslip  = NULL;
  PetscCall(InterfaceReset(ifc));
  ifc->pairs_built  = pairs;
  ifc->npairs_built = n;
  { /* the slave nodes and weights of each point's constraint, for SlaveNodesKept */
    PetscInt ns = 0;
    for (PetscInt i = 0; i < c->ncouples; i++) ns += c->couples[i].npoints ? c->couples[i].soff[c->couples[i].npoints] : 0;
    PetscCall(PetscFree3(ifc->bsoff, ifc->bsnode, ifc->bsw));
    PetscCall(PetscMalloc3(n + 1, &ifc->bsoff, ns + 1, &ifc->bsnode, ns + 1, &ifc->bsw));
    ifc->bsoff[0] = 0;
    for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
      for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
        const MBCCouple *cp = &c->couples[i];
        const PetscInt   o = ifc->bsoff[k], len = cp->soff[j + 1] - cp->soff[j];
        PetscCall(PetscArraycpy(ifc->bsnode + o, cp->snode + cp->soff[j], len));
        PetscCall(PetscArraycpy(ifc->bsw + o, cp->sw + cp->soff[j], len));
        ifc->bsoff[k + 1] = o + len;
      }
  }
  PetscCall(MBCContactSetPreferredFaces(c, n, pairs, MBC_PAIR_SIZE)); /* the next searches keep these faces where they tie */
  ifc->ncontact     = nc;
  PetscCall(PetscMalloc1(nc + 1, &dims));
  PetscCall(PetscMalloc2(nc + 1, &ifc->kcouple, nc + 1, &ifc->kpoint));
  PetscCall(PetscMalloc1(9 * nc + 1, &ifc->frames));
  PetscCall(PetscCalloc1(3 * nc + 1, &ifc->slip));
  PetscCall(PetscCalloc1(3 * nc + 1, &ifc->stepslip));
  PetscCall(PetscCalloc1(3 * nc + 1, &ifc->cutslip));
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const MBCContactPoint *p = &c->couples[i].points[j];
      ifc->kcouple[k] = i, ifc->kpoint[k] = j;
      dims[k] = c->couples[i].mu > 0 ? 3 : 1;
      for (PetscInt e = 0; e < 3; e++) {
        ifc->frames[9 * k + e]     = p->n[e];
        ifc->frames[9 * k + 3 + e] = p->t1[e];
        ifc->frames[9 * k + 6 + e] = p->t2[e];
      }
    }
  PetscCall(InterfaceRankOrder(ifc, dims));
  PetscCall(MBCInterfaceHeldDirections(ifc)); /* before H: the frames' held tangents */
  m = ifc->coff[nc];
  mloc = ifc->poff[ifc->plast] - ifc->poff[ifc->pfirst];
  { /* this rank's contacts of the multiplier problem */
    PetscInt *ldims;
    ifc->fp.nc = ifc->plast - ifc->pfirst;
    PetscCall(PetscMalloc1(ifc->fp.nc + 1, &ifc->fp.mu));
    PetscCall(PetscMalloc1(ifc->fp.nc + 1, &ldims));
    for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) {
      ifc->fp.mu[p - ifc->pfirst] = c->couples[ifc->kcouple[ifc->order[p]]].mu;
      ldims[p - ifc->pfirst]    = ifc->poff[p + 1] - ifc->poff[p];
    }
    PetscCall(MBCFrictionProblemSetBlocks(&ifc->fp, ldims));
    PetscCall(PetscFree(ldims));
  }
  PetscCall(PetscFree(dims));
  PetscCall(PetscMalloc2(m + 1, &ifc->rall, m + 1, &ifc->uall));
  PetscCall(PetscArrayzero(ifc->rall, m + 1));
  PetscCall(PetscArrayzero(ifc->uall, m + 1));
  if (nc) {
    PetscInt  *first;
    PetscReal *v[2];
    PetscCall(PetscMalloc1(nc + 1, &first));
    for (PetscInt b = 0; b < ifc->nbodies; b++) {
      PetscCall(BodyColumns(ifc, b, first));
      if (!ifc->bodies[b] || !ifc->nbcols[b]) continue;
      PetscCall(BodyContactMatrix(ifc, ifc->bodies[b], first, &ifc->H[b]));
      PetscCall(MatCreateVecs(ifc->H[b], &ifc->Hu[b], &ifc->Hl[b]));
      PetscCall(VecDuplicate(ifc->Hu[b], &ifc->lam[b]));
      PetscCall(VecDuplicate(ifc->Hl[b], &ifc->Xl[b]));
    }
    PetscCall(PetscFree(first));
    PetscCall(VecCreate(ifc->comm, &ifc->fp.q));
    PetscCall(VecSetSizes(ifc->fp.q, mloc, m));
    PetscCall(VecSetType(ifc->fp.q, VECSTANDARD));
    PetscCall(InterfaceForest(ifc)); /* before D: the matrix-free D's products go through it */
    PetscCall(InterfaceBuildD(ifc, m, mloc));
    PetscCall(MBCInterfaceRigidModes(ifc));
    PetscCall(VecDuplicate(ifc->fp.q, &ifc->lambda));
    PetscCall(VecDuplicate(ifc->fp.q, &ifc->ucontact));
    PetscCall(VecDuplicate(ifc->fp.q, &ifc->lamprev));
    PetscCall(VecScatterCreateToAll(ifc->lambda, &ifc->gather, &ifc->gathered));
    /* carry lambda_n and the warm start r (physical, then scaled) over to the new points */
    PetscCall(PetscMalloc2(m + 1, &v[0], m + 1, &v[1]));
    {
      const PetscReal *old[2] = {oldlam, oldr};
      PetscCall(CarryFields(2, oldoff ? nold : 0, oldpairs, oldframes, oldoff, old, nc, pairs, ifc->frames, ifc->coff, v));
    }
    for (PetscInt i = 0; i < m; i++) v[1][i] *= ifc->dscale;
    PetscCall(PetscArraycpy(ifc->rall, v[1], m));
    PetscCall(InterfaceScatterLocal(ifc, v[0], ifc->lamprev));
    PetscCall(InterfaceScatterLocal(ifc, v[1], ifc->lambda));
    PetscCall(PetscFree2(v[0], v[1]));
    if (oldslip && nold) { /* the slip so far and in this load step, (0, t1, t2) in each point's frame */
      PetscInt        *off3;
      const PetscReal *old[3]     = {oldslip, oldstepslip, oldcutslip};
      PetscReal       *carried[3] = {ifc->slip, ifc->stepslip, ifc->cutslip};
      PetscCall(PetscMalloc1(PetscMax(nold, nc) + 1, &off3));
      for (PetscInt i = 0; i <= PetscMax(nold, nc); i++) off3[i] = 3 * i;
      PetscCall(CarryFields(3, nold, oldpairs, oldframes, off3, old, nc, pairs, ifc->frames, off3, carried));
      for (PetscInt k = 0; k < nc; k++) ifc->slip[3 * k] = ifc->stepslip[3 * k] = ifc->cutslip[3 * k] = 0;
      PetscCall(PetscFree(off3));
    }
  }
  PetscCall(PetscFree3(oldoff, oldlam, oldr));
  PetscCall(PetscFree(oldslip));
  PetscCall(PetscFree(oldstepslip));
  PetscCall(PetscFree(oldcutslip));
  PetscCall(PetscFree(oldframes));
  PetscCall(PetscFree(oldpairs));
  PetscCall(PetscLogEventEnd(MBC_FlexibilityAssemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCInterfaceDestroy(MBCInterface *iface)
{
  MBCInterface ifc = *iface;

  PetscFunctionBegin;
  if (!ifc) PetscFunctionReturn(0);
  PetscCall(InterfaceReset(ifc));
  PetscCall(PetscFree6(ifc->H, ifc->Hu, ifc->lam, ifc->Hl, ifc->Xl, ifc->nbcols));
  PetscCall(PetscFree(ifc->bcols));
  PetscCall(MBCInterfaceReleasedClear(ifc));
  PetscCall(PetscFree(ifc->released));
  PetscCall(PetscFree(ifc->frames));
  PetscCall(PetscFree(ifc->held));
  PetscCall(PetscFree(ifc->slip));
  PetscCall(PetscFree(ifc->stepslip));
  PetscCall(PetscFree(ifc->cutslip));
  PetscCall(PetscFree(ifc->pairs_built));
  PetscCall(PetscFree3(ifc->bsoff, ifc->bsnode, ifc->bsw));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscCall(MatDestroy(&ifc->sinv[b]));
    PetscCall(ISDestroy(&ifc->sinv_is[b]));
  }
  PetscCall(PetscFree4(ifc->sinv, ifc->sinv_is, ifc->sinv_id, ifc->sinv_state));
  PetscCall(PetscFree(ifc->schur_fits));
  PetscCall(MBCMultiplierDestroy(&ifc->mult));
  PetscCall(MBCInterfaceJointDestroy(ifc));
  PetscCall(PetscFree(*iface));
  PetscFunctionReturn(0);
}
