/* Bodies onto ranks: METIS on the body graph (vertex weight: the body's work, BodyWork; edge
   weight: the contact faces of the couples between two bodies), so small bodies in contact share
   a rank and the rows of D stay local; a body above a rank's share of the work gets a range of
   ranks of its own. */
#include <mbc/private/solverimpl.h>
#include <metis.h>

/* A body's work: its factor's entries, ~N^(4/3) for a nested-dissection ordering of a 3D mesh of
   N DOFs (MUMPS on the dam's bodies, 25k-185k DOFs: nnz(L) = 15.6-20.0 N^(4/3)). Every body solve
   reads the factor once, and those solves (the matrix-free D's products, the multi-right-hand-side
   D, the dynamic steps) are most of a large run; DOFs alone would put the dam's 420k-DOF
   foundation level with three 145k-DOF monoliths, whose factors are together 0.7 of its one. */
static PetscReal BodyWork(MBCScene scene, PetscInt b)
{
  return PetscPowReal(3.0 * scene->bodies[b].num_vertices, 4.0 / 3.0);
}

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

/* METIS's partition kept only if it is about as balanced as the greedy one (largest work first,
   each onto the least loaded part, ties to the part it shares most contact faces with): on a
   handful of bodies of very different work METIS may miss its balance by far (the 200k dam on 2
   ranks: one 25k-DOF monolith alone, the foundation and three monoliths on the other rank). */
static PetscErrorCode BalanceSmallBodies(MBCScene scene, const PetscReal w[], PetscInt ns, const PetscInt small[], PetscInt nparts, PetscInt part[])
{
  const PetscInt N = scene->nbodies;
  PetscReal     *load, *cut, *key, lmetis = 0, lgreedy = 0;
  PetscInt      *order, *greedy;

  PetscFunctionBegin;
  PetscCall(PetscCalloc2(nparts, &load, nparts, &cut));
  PetscCall(PetscMalloc3(ns, &key, ns, &order, ns, &greedy));
  for (PetscInt i = 0; i < ns; i++) load[part[i]] += BodyWork(scene, small[i]);
  for (PetscInt q = 0; q < nparts; q++) lmetis = PetscMax(lmetis, load[q]);
  PetscCall(PetscArrayzero(load, nparts));
  for (PetscInt i = 0; i < ns; i++) key[i] = -BodyWork(scene, small[i]), order[i] = i;
  PetscCall(PetscSortRealWithArrayInt(ns, key, order));
  for (PetscInt j = 0; j < ns; j++) {
    const PetscInt i = order[j];
    PetscInt       best = 0;
    PetscCall(PetscArrayzero(cut, nparts)); /* the contact faces body i shares with each part so far */
    for (PetscInt jj = 0; jj < j; jj++) cut[greedy[order[jj]]] += w[small[i] * N + small[order[jj]]];
    for (PetscInt q = 1; q < nparts; q++)
      if (load[q] < load[best] || (load[q] == load[best] && cut[q] > cut[best])) best = q;
    greedy[i] = best;
    load[best] += BodyWork(scene, small[i]);
  }
  for (PetscInt q = 0; q < nparts; q++) lgreedy = PetscMax(lgreedy, load[q]);
  if (lmetis > 1.05 * lgreedy) {
    PetscCall(PetscInfo(NULL, "METIS's partition of %" PetscInt_FMT " bodies onto %" PetscInt_FMT " ranks has a largest work %g times the greedy one's: the greedy one taken\n", ns, nparts, (double)(lmetis / lgreedy)));
    PetscCall(PetscArraycpy(part, greedy, ns));
  }
  PetscCall(PetscFree2(load, cut));
  PetscCall(PetscFree3(key, order, greedy));
  PetscFunctionReturn(0);
}

/* METIS partition of the bodies listed in small[] (ns of them) into nparts parts. */
static PetscErrorCode PartitionSmallBodies(MBCScene scene, const PetscReal w[], PetscInt ns, const PetscInt small[], PetscInt nparts, PetscInt part[])
{
  const PetscInt N = scene->nbodies;
  idx_t         *xadj, *adjncy, *vwgt, *adjwgt, *p, nv = (idx_t)ns, ncon = 1, np = (idx_t)nparts, cut, opts[METIS_NOPTIONS];
  PetscInt       ne = 0;
  PetscReal      wsum = 0;
  int            err;

  PetscFunctionBegin;
  if (nparts == 1 || ns <= nparts) { /* trivial: all on one rank, or one body per rank */
    for (PetscInt i = 0; i < ns; i++) part[i] = nparts == 1 ? 0 : i;
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc5(ns + 1, &xadj, ns * ns + 1, &adjncy, ns, &vwgt, ns * ns + 1, &adjwgt, ns, &p));
  xadj[0] = 0;
  for (PetscInt i = 0; i < ns; i++) wsum += BodyWork(scene, small[i]);
  for (PetscInt i = 0; i < ns; i++) {
    vwgt[i] = (idx_t)PetscMax(1, PetscFloorReal(1e6 * BodyWork(scene, small[i]) / wsum + 0.5)); /* N^(4/3) overflows idx_t over many bodies */
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
  PetscCall(BalanceSmallBodies(scene, w, ns, small, nparts, part));
  PetscFunctionReturn(0);
}

/* The body of list[] (n > 0) with the most work per rank. */
static PetscInt MostWorkPerRank(MBCScene scene, const PetscMPIInt nranks[], PetscInt n, const PetscInt list[])
{
  PetscInt best = list[0];
  for (PetscInt i = 1; i < n; i++)
    if (BodyWork(scene, list[i]) / nranks[list[i]] > BodyWork(scene, best) / nranks[best]) best = list[i];
  return best;
}

/* extra more ranks, one at a time, to the body of list[] with the most work per rank. */
static void SpreadRanks(MBCScene scene, PetscMPIInt nranks[], PetscInt n, const PetscInt list[], PetscInt extra)
{
  for (; extra > 0 && n > 0; extra--) nranks[MostWorkPerRank(scene, nranks, n, list)]++;
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
  for (PetscInt b = 0; b < N; b++) total += BodyWork(scene, b);
  share = total / P;
  /* a body above a rank's share gets floor(work / share) ranks of its own; the others share the
     R = P - sum of those ranks left (R >= 1 when some are left: their work is > 0) */
  for (PetscInt b = 0; b < N; b++) {
    const PetscReal r = BodyWork(scene, b) / share;
    if (r > 1) {
      s->body_nranks[b] = (PetscMPIInt)PetscFloorReal(r);
      nbig += s->body_nranks[b];
      big[nb++] = b;
    } else small[ns++] = b;
  }
  { /* then one more rank at a time to the big body with the most work per rank, while that lowers
       the larger of its work per rank and the small bodies' (the 200k dam on 3 ranks: the
       foundation, 1.75 shares, on 2 ranks and the four monoliths on one: 1.23 of the mean, not 1.77) */
    PetscReal wsmall = 0;
    for (PetscInt i = 0; i < ns; i++) wsmall += BodyWork(scene, small[i]);
    while (nb && P - nbig > (ns ? 1 : 0)) {
      const PetscInt  best   = MostWorkPerRank(scene, s->body_nranks, nb, big);
      const PetscReal before = PetscMax(BodyWork(scene, best) / s->body_nranks[best], ns ? wsmall / (P - nbig) : 0);
      PetscInt        most;
      s->body_nranks[best]++;
      most = MostWorkPerRank(scene, s->body_nranks, nb, big);
      if (!(PetscMax(BodyWork(scene, most) / s->body_nranks[most], ns ? wsmall / (P - nbig - 1) : 0) < before)) {
        s->body_nranks[best]--;
        break;
      }
      nbig++;
    }
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
  /* the figures -mbc_view prints: contact faces between bodies on different ranks, the largest
     rank's work over the mean */
  s->decomp_cut = 0;
  for (PetscInt a = 0; a < N; a++)
    for (PetscInt b = a + 1; b < N; b++)
      if (s->body_first_rank[a] != s->body_first_rank[b] || s->body_nranks[a] > 1 || s->body_nranks[b] > 1) s->decomp_cut += w[a * N + b];
  {
    PetscReal *load, lmax = 0;
    PetscCall(PetscCalloc1(P, &load));
    for (PetscInt b = 0; b < N; b++)
      for (PetscMPIInt r = s->body_first_rank[b]; r < s->body_first_rank[b] + s->body_nranks[b]; r++) load[r] += BodyWork(scene, b) / s->body_nranks[b];
    for (PetscMPIInt r = 0; r < P; r++) lmax = PetscMax(lmax, load[r]);
    s->decomp_imbalance = lmax / share;
    PetscCall(PetscFree(load));
  }
  PetscCall(PetscFree4(small, big, part, w));
  PetscFunctionReturn(0);
}
