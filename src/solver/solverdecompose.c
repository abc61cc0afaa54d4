/* Bodies onto ranks: METIS on the body graph (vertex weight: DOFs; edge weight: the contact
   faces of the couples between two bodies), so small bodies in contact share a rank and the
   rows of D stay local; a body larger than a rank's share gets a range of ranks of its own. */
#include <mbc/private/solverimpl.h>
#include <metis.h>

/* Edge weights w[a * N + b] (symmetric): per couple, the slave faces on body a times the share
   of the master faces lying on body b (which master body a slave face meets is known only after
   the search). */
static PetscErrorCode BodyGraphWeights(MBCScene scene, PetscReal w[])
{
  const PetscInt N = scene->nbodies;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(w, N * N));
  for (PetscInt i = 0; i < scene->ncouples; i++) {
    const MBCCoupleDesc *c = &scene->couples[i];
    PetscReal            msum = 0;
    for (PetscInt b = 0; b < N; b++) msum += c->master_faces[b];
    if (msum == 0) continue;
    for (PetscInt a = 0; a < N; a++)
      for (PetscInt b = 0; b < N; b++) {
        const PetscReal e = c->slave_faces[a] * c->master_faces[b] / msum;
        if (a == b) continue;
        w[a * N + b] += e;
        w[b * N + a] += e;
      }
  }
  PetscFunctionReturn(0);
}

/* METIS partition of the bodies listed in small[] (ns of them) into nparts parts. */
static PetscErrorCode PartitionSmallBodies(MBCScene scene, const PetscReal w[], PetscInt ns, const PetscInt small[], PetscInt nparts, PetscInt part[])
{
  const PetscInt N = scene->nbodies;
  idx_t         *xadj, *adjncy, *vwgt, *adjwgt, *p, nv = (idx_t)ns, ncon = 1, np = (idx_t)nparts, cut, opts[METIS_NOPTIONS];
  PetscInt       ne = 0;
  int            err;

  PetscFunctionBegin;
  if (nparts == 1 || ns <= nparts) { /* trivial: all on one rank, or one body per rank */
    for (PetscInt i = 0; i < ns; i++) part[i] = nparts == 1 ? 0 : i;
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc5(ns + 1, &xadj, ns * ns + 1, &adjncy, ns, &vwgt, ns * ns + 1, &adjwgt, ns, &p));
  xadj[0] = 0;
  for (PetscInt i = 0; i < ns; i++) {
    vwgt[i] = (idx_t)(3 * scene->bodies[small[i]].num_vertices);
    for (PetscInt j = 0; j < ns; j++) {
      const PetscReal e = w[small[i] * N + small[j]];
      if (i == j || e <= 0) continue;
      adjncy[ne] = (idx_t)j;
      adjwgt[ne] = (idx_t)PetscMax(1, PetscCeilReal(e));
      ne++;
    }
    xadj[i + 1] = (idx_t)ne;
  }
  METIS_SetDefaultOptions(opts);
  opts[METIS_OPTION_NUMBERING] = 0;
  opts[METIS_OPTION_SEED]      = 1; /* the same partition on every rank */
  /* recursive bisection balances better than k-way on a handful of parts (METIS manual) */
  if (nparts <= 8) err = METIS_PartGraphRecursive(&nv, &ncon, xadj, adjncy, vwgt, NULL, adjwgt, &np, NULL, NULL, opts, &cut, p);
  else err = METIS_PartGraphKway(&nv, &ncon, xadj, adjncy, vwgt, NULL, adjwgt, &np, NULL, NULL, opts, &cut, p);
  PetscCheck(err == METIS_OK, PETSC_COMM_SELF, PETSC_ERR_LIB, "METIS failed (%d) partitioning %" PetscInt_FMT " bodies onto %" PetscInt_FMT " ranks", err, ns, nparts);
  for (PetscInt i = 0; i < ns; i++) part[i] = (PetscInt)p[i];
  PetscCall(PetscFree5(xadj, adjncy, vwgt, adjwgt, p));
  PetscFunctionReturn(0);
}

/* extra more ranks, one at a time, to the body of list[] with the most DOFs per rank. */
static void SpreadRanks(MBCScene scene, PetscMPIInt nranks[], PetscInt n, const PetscInt list[], PetscInt extra)
{
  for (; extra > 0 && n > 0; extra--) {
    PetscInt best = list[0];
    for (PetscInt i = 1; i < n; i++)
      if (3.0 * scene->bodies[list[i]].num_vertices / nranks[list[i]] > 3.0 * scene->bodies[best].num_vertices / nranks[best]) best = list[i];
    nranks[best]++;
  }
}

/* Every rank computes the same decomposition from the scene alone. */
PetscErrorCode MBCSolverDecompose(MBCSolver s)
{
  MBCScene    scene = s->scene;
  PetscInt    N     = scene->nbodies, ns = 0, nb = 0, nbig = 0, *small, *big, *part;
  PetscMPIInt P, first = 0;
  PetscReal   total = 0, share, *w;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(s->comm, &P));
  PetscCall(PetscCalloc2(N, &s->body_first_rank, N, &s->body_nranks));
  PetscCall(PetscMalloc4(N, &small, N, &big, N, &part, N * N, &w));
  for (PetscInt b = 0; b < N; b++) total += 3.0 * scene->bodies[b].num_vertices;
  share = total / P;
  /* a body above a rank's share gets floor(DOFs / share) ranks of its own; the others share the
     R = P - sum of those ranks left (R >= 1 when some are left: their DOFs are > 0) */
  for (PetscInt b = 0; b < N; b++) {
    const PetscReal r = 3.0 * scene->bodies[b].num_vertices / share;
    if (r > 1) {
      s->body_nranks[b] = (PetscMPIInt)PetscFloorReal(r);
      nbig += s->body_nranks[b];
      big[nb++] = b;
    } else small[ns++] = b;
  }
  PetscCall(BodyGraphWeights(scene, w));
  /* all bodies big: the ranks the floors leave go to the most loaded (two bodies of 972 and 960
     DOFs on 4 ranks: 2 + 1 and a rank idle, then 2 + 2) */
  if (!ns) SpreadRanks(scene, s->body_nranks, nb, big, P - nbig);
  /* ranks in order: the big bodies, then the small ones */
  for (PetscInt i = 0; i < nb; i++) {
    s->body_first_rank[big[i]] = first;
    first += s->body_nranks[big[i]];
  }
  if (ns) {
    const PetscInt R = P - nbig;
    PetscCall(PartitionSmallBodies(scene, w, ns, small, R, part));
    for (PetscInt i = 0; i < ns; i++) s->body_nranks[small[i]] = 1;
    if (ns < R) { /* fewer bodies than ranks: one each, the ranks left to those with most DOFs per rank */
      SpreadRanks(scene, s->body_nranks, ns, small, R - ns);
      for (PetscInt i = 0; i < ns; i++) {
        s->body_first_rank[small[i]] = first;
        first += s->body_nranks[small[i]];
      }
    } else
      for (PetscInt i = 0; i < ns; i++) s->body_first_rank[small[i]] = first + (PetscMPIInt)part[i];
  }
  /* the figures -mbc_view prints: contact faces between bodies on different ranks, load balance */
  s->decomp_cut = 0;
  for (PetscInt a = 0; a < N; a++)
    for (PetscInt b = a + 1; b < N; b++)
      if (s->body_first_rank[a] != s->body_first_rank[b] || s->body_nranks[a] > 1 || s->body_nranks[b] > 1) s->decomp_cut += w[a * N + b];
  {
    PetscReal *load, lmax = 0;
    PetscCall(PetscCalloc1(P, &load));
    for (PetscInt b = 0; b < N; b++)
      for (PetscMPIInt r = s->body_first_rank[b]; r < s->body_first_rank[b] + s->body_nranks[b]; r++) load[r] += 3.0 * scene->bodies[b].num_vertices / s->body_nranks[b];
    for (PetscMPIInt r = 0; r < P; r++) lmax = PetscMax(lmax, load[r]);
    s->decomp_imbalance = lmax / share;
    PetscCall(PetscFree(load));
  }
  PetscCall(PetscFree4(small, big, part, w));
  PetscFunctionReturn(0);
}
