/* Small sliding (a couple's `sliding: small`, or -mbc_contact_sliding small): the pairs, the constraints' weights and the frames
   of a search are kept, and a later update only gathers the nodes' coordinates and moves each
   point's gaps by the motion since that search, along its normal: the gap the constraint's
   weights give, n . (sum mw dx_m - sum sw dx_s) (H's normal column, so the gap is the one the
   multiplier problem predicted), the node-to-face gap with the face weights alike. What Abaqus
   calls small sliding and what dam analyses of joints use: the joints open and slide by
   millimetres under elements of metres, and the search and the integration cost more than the
   bodies' solves at every step. A point that slid more than -mbc_contact_slide_limit of its
   slave face's shortest edge is outside what the kept pairing describes: reported once per couple
   and reference, or searched again (-mbc_contact_slide_repair). Every real update of a
   small-sliding run is a global search, so a restart's replay of the last global search restores
   the reference. */
#include <mbc/private/contactimpl.h>

PetscErrorCode MBCCoupleSlidingDestroy(MBCCouple *cp)
{
  PetscFunctionBegin;
  PetscCall(PetscFree5(cp->xref_m, cp->xref_s, cp->gref, cp->igref, cp->slide_max));
  cp->nref_m = cp->nref_s = cp->nref_p = 0;
  PetscFunctionReturn(0);
}

/* The next update searches (a new stage, another step size, new pairs built). */
PetscErrorCode MBCContactSlidingReset(MBCContact c)
{
  PetscFunctionBegin;
  if (c) c->frozen = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* After a search: its coordinates and gaps become the reference. */
PetscErrorCode MBCContactSlidingFreeze(MBCContact c)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple  *cp = &c->couples[i];
    MBCSurface *sl = &cp->slave;
    if (!cp->small_sliding) continue;
    PetscCall(MBCCoupleSlidingDestroy(cp));
    cp->nref_m = cp->master.nnodes, cp->nref_s = sl->nnodes, cp->nref_p = cp->npoints;
    PetscCall(PetscMalloc5(3 * cp->nref_m + 1, &cp->xref_m, 3 * cp->nref_s + 1, &cp->xref_s, cp->nref_p + 1, &cp->gref, cp->nref_p + 1, &cp->igref, cp->nref_p + 1, &cp->slide_max));
    PetscCall(PetscArraycpy(cp->xref_m, cp->master.x, 3 * cp->nref_m));
    PetscCall(PetscArraycpy(cp->xref_s, sl->x, 3 * cp->nref_s));
    for (PetscInt k = 0; k < cp->npoints; k++) {
      const MBCContactPoint *p    = &cp->points[k];
      const PetscInt        *fv   = &sl->fnode[MBC_MAX_FACE_NODES * p->face];
      PetscReal              edge = PETSC_MAX_REAL;
      for (PetscInt j = 0; j < sl->fnv[p->face]; j++) {
        const PetscReal *a = &sl->x0[3 * fv[j]], *b = &sl->x0[3 * fv[(j + 1) % sl->fnv[p->face]]];
        edge = PetscMin(edge, PetscSqrtReal(PetscSqr(a[0] - b[0]) + PetscSqr(a[1] - b[1]) + PetscSqr(a[2] - b[2])));
      }
      cp->gref[k]      = p->gap;
      cp->igref[k]     = cp->igap[k];
      cp->slide_max[k] = c->slide_limit * edge;
    }
  }
  c->frozen = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* The gaps at the gathered coordinates (every rank holds the same); *repair: a point slid beyond
   its limit and -mbc_contact_slide_repair asks for a search (the same answer on every rank). */
PetscErrorCode MBCContactSlidingUpdate(MBCContact c, PetscBool *repair)
{
  PetscFunctionBegin;
  *repair = PETSC_FALSE;
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple       *cp = &c->couples[i];
    const MBCSurface *m = &cp->master, *sl = &cp->slave;
    PetscInt         nbeyond = 0, worst = -1;
    PetscReal        most = 0;
    if (!cp->small_sliding) continue;
    PetscCheck(m->nnodes == cp->nref_m && sl->nnodes == cp->nref_s && cp->npoints == cp->nref_p, c->comm, PETSC_ERR_PLIB, "Couple k = %" PetscInt_FMT ": its surfaces changed under small sliding", cp->k);
    for (PetscInt k = 0; k < cp->npoints; k++) {
      MBCContactPoint *p = &cp->points[k];
      PetscReal        d[3] = {0, 0, 0}, dn[3], dg, slide;
      for (PetscInt l = cp->moff[k]; l < cp->moff[k + 1]; l++)
        for (PetscInt e = 0; e < 3; e++) d[e] += cp->mw[l] * (m->x[3 * cp->mnode[l] + e] - cp->xref_m[3 * cp->mnode[l] + e]);
      for (PetscInt l = cp->soff[k]; l < cp->soff[k + 1]; l++)
        for (PetscInt e = 0; e < 3; e++) d[e] -= cp->sw[l] * (sl->x[3 * cp->snode[l] + e] - cp->xref_s[3 * cp->snode[l] + e]);
      dg          = MBCDot(d, p->n);
      cp->igap[k] = cp->igref[k] + dg;
      for (PetscInt e = 0; e < 3; e++) dn[e] = m->x[3 * p->master + e] - cp->xref_m[3 * p->master + e];
      for (PetscInt j = 0; j < p->nv; j++) {
        const PetscInt v = sl->fnode[MBC_MAX_FACE_NODES * p->face + j];
        for (PetscInt e = 0; e < 3; e++) dn[e] -= p->w[j] * (sl->x[3 * v + e] - cp->xref_s[3 * v + e]);
      }
      p->gap = cp->gref[k] + MBCDot(dn, p->n);
      slide  = PetscSqrtReal(PetscMax(0, MBCDot(d, d) - dg * dg));
      if (slide > cp->slide_max[k]) {
        nbeyond++;
        if (slide / cp->slide_max[k] > most) most = slide / cp->slide_max[k], worst = k;
      }
    }
    if (!nbeyond) continue;
    if (c->slide_repair) *repair = PETSC_TRUE;
    else { /* reported once per couple and reference */
      const PetscReal *x = &m->x[3 * cp->points[worst].master];
      PetscCall(PetscPrintf(c->comm, "mbcontact: warning: small sliding, couple k = %" PetscInt_FMT ": %" PetscInt_FMT " of its %" PetscInt_FMT " contact points slid more than -mbc_contact_slide_limit %g of their slave face's shortest edge since their pairs were fixed (the most %.3g edges, at the master node now at (%g, %g, %g)): their gaps are extrapolated beyond the faces they were paired with; search again there with -mbc_contact_slide_repair, or give the couple `sliding: finite`\n", cp->k, nbeyond, cp->npoints, (double)c->slide_limit, (double)(most * c->slide_limit), (double)x[0], (double)x[1], (double)x[2]));
      for (PetscInt k = 0; k < cp->npoints; k++) cp->slide_max[k] = PETSC_MAX_REAL;
    }
  }
  PetscFunctionReturn(0);
}

/* Every couple sliding small and frozen: the surfaces' coordinates x = x0 + u straight from the
   rows each rank owns (a node's body and first row are its surface's), one Allgatherv of (node,
   u) over the ranks, instead of the faces' records gathered, sorted and made into surfaces again
   (their order and set-up do not change while the pairs are kept). The same x, bit for bit.
   *done false: a node without an owner's value (a body without displacements), the records then. */
PetscErrorCode MBCContactSlidingGather(MBCContact c, PetscInt nbodies, MBCBody bodies[], PetscBool *done)
{
  PetscInt            n = 0, nmine = 0, idx = 0, *rs, *re;
  PetscReal          *mine, *all, **x, **x0;
  const PetscScalar **u;
  PetscMPIInt         size, count, *counts, *displs;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_RankWait, 0, 0, 0, 0));
  PetscCallMPI(MPI_Barrier(c->comm));
  PetscCall(PetscLogEventEnd(MBC_RankWait, 0, 0, 0, 0));
  PetscCall(PetscLogEventBegin(MBC_ContactGather, 0, 0, 0, 0));
  for (PetscInt i = 0; i < c->ncouples; i++) n += c->couples[i].master.nnodes + c->couples[i].slave.nnodes;
  PetscCall(PetscMalloc5(4 * n + 1, &mine, nbodies, &u, nbodies, &rs, nbodies, &re, 2 * n + 1, &x));
  x0 = x + n;
  for (PetscInt b = 0; b < nbodies; b++) {
    Vec ub = NULL;
    u[b]   = NULL;
    PetscCall(MBCBodyGetDisplacement(bodies[b], &ub));
    if (!ub) continue;
    PetscCall(VecGetOwnershipRange(ub, &rs[b], &re[b]));
    PetscCall(VecGetArrayRead(ub, &u[b]));
  }
  for (PetscInt i = 0; i < c->ncouples; i++)
    for (PetscInt side = 0; side < 2; side++) {
      MBCSurface *s = side ? &c->couples[i].slave : &c->couples[i].master;
      for (PetscInt v = 0; v < s->nnodes; v++, idx++) {
        const PetscInt b = s->nbody[v], r = s->nrow[v];
        x[idx] = &s->x[3 * v], x0[idx] = &s->x0[3 * v];
        if (b < 0 || b >= nbodies || !u[b] || r < rs[b] || r >= re[b]) continue;
        mine[4 * nmine] = idx;
        for (PetscInt d = 0; d < 3; d++) mine[4 * nmine + 1 + d] = PetscRealPart(u[b][r - rs[b] + d]);
        nmine++;
      }
    }
  for (PetscInt b = 0; b < nbodies; b++) {
    Vec ub;
    if (!u[b]) continue;
    PetscCall(MBCBodyGetDisplacement(bodies[b], &ub));
    PetscCall(VecRestoreArrayRead(ub, &u[b]));
  }
  PetscCallMPI(MPI_Comm_size(c->comm, &size));
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCall(PetscMPIIntCast(4 * nmine, &count));
  PetscCallMPI(MPI_Allgather(&count, 1, MPI_INT, counts, 1, MPI_INT, c->comm));
  displs[0] = 0;
  for (PetscMPIInt r = 0; r < size; r++) displs[r + 1] = displs[r] + counts[r];
  *done = (PetscBool)(displs[size] == 4 * n); /* the same on every rank */
  if (*done) {
    PetscCall(PetscMalloc1(4 * n + 1, &all));
    PetscCallMPI(MPI_Allgatherv(mine, count, MPIU_REAL, all, counts, displs, MPIU_REAL, c->comm));
    for (PetscInt k = 0; k < n; k++) {
      const PetscInt j = (PetscInt)all[4 * k];
      for (PetscInt d = 0; d < 3; d++) x[j][d] = x0[j][d] + all[4 * k + 1 + d];
    }
    PetscCall(PetscFree(all));
  }
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree5(mine, u, rs, re, x));
  PetscCall(PetscLogEventEnd(MBC_ContactGather, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
