/* Integrated constraints (an improvement over the paper's node-to-surface collocation): the gap
   of a contact point is a weighted average over its master node's share of the surface,
     g_k = int psi_k (x_m - x_s(pi(x))) . n dA / int psi_k dA,
   with pi(x) the projection of a master face point along the interpolated nodal normal onto
   the slave faces (the same projection, inside test and area coordinates as the local search,
   at Gauss points instead of nodes) and psi_k the dual basis of the master shape functions
   (int psi_k N_j = delta_kj int N_j; Wohlmuth's dual mortar). Then
   * the master side of the constraint is its node alone, as in the paper: D keeps the
     structure and conditioning of collocation (the standard basis N_k would couple neighbouring
     points so strongly that Gauss-Seidel crawls);
   * the slave side averages: sum_s (int psi_k w_s dA / int psi_k dA) x_s;
   * displacement fields linear across the interface (rigid motions, uniform strain) satisfy
     every constraint exactly, in all three directions;
   * a uniform pressure p loads the master nodes with p int N_k dA and the slave nodes with
     p int w_s dA (sum_k psi_k = 1): consistent nodal forces on both sides, so the contact
     patch test on non-matching meshes is passed up to the quadrature of the slave weights'
     kinks, where collocation loads the slave side with point forces and misses it by ~10 %.
   A point whose share is mostly uncovered (the edge of the contact zone) keeps the collocation
   at its node. */
#include <mbc/private/contactimpl.h>

typedef struct {
  PetscInt64 key; /* point * nnodes + node */
  PetscReal  w;
} Entry;

static int CompareEntry(const void *a, const void *b)
{
  const Entry *x = (const Entry *)a, *y = (const Entry *)b;
  return x->key < y->key ? -1 : (x->key > y->key);
}

typedef struct {
  Entry  *e;
  size_t  n, cap;
} EntryList;

static PetscErrorCode EntryAdd(EntryList *l, PetscInt64 key, PetscReal w)
{
  PetscFunctionBegin;
  if (l->n == l->cap) {
    Entry *e;
    l->cap = PetscMax(2 * l->cap, 1024);
    PetscCall(PetscMalloc1(l->cap, &e));
    if (l->n) PetscCall(PetscArraycpy(e, l->e, l->n));
    PetscCall(PetscFree(l->e));
    l->e = e;
  }
  l->e[l->n].key = key;
  l->e[l->n].w   = w;
  l->n++;
  PetscFunctionReturn(0);
}

/* Sorted and merged entries into CSR rows (one per point) scaled by 1 / area. */
static PetscErrorCode EntryCSR(EntryList *l, PetscInt npoints, PetscInt nnodes, const PetscReal area[], PetscInt **off, PetscInt **node, PetscReal **w)
{
  size_t n = 0;

  PetscFunctionBegin;
  if (l->n) qsort(l->e, l->n, sizeof(Entry), CompareEntry); /* qsort(NULL, 0) is undefined (UBSan) */
  for (size_t i = 0; i < l->n; i++) { /* merge duplicates in place */
    if (n && l->e[n - 1].key == l->e[i].key) l->e[n - 1].w += l->e[i].w;
    else l->e[n++] = l->e[i];
  }
  PetscCall(PetscCalloc1(npoints + 1, off));
  PetscCall(PetscMalloc1(n + 1, node));
  PetscCall(PetscMalloc1(n + 1, w));
  for (size_t i = 0; i < n; i++) {
    const PetscInt k = (PetscInt)(l->e[i].key / nnodes);
    (*off)[k + 1]++;
    (*node)[i] = (PetscInt)(l->e[i].key % nnodes);
    (*w)[i]    = l->e[i].w / area[k];
  }
  for (PetscInt k = 0; k < npoints; k++) (*off)[k + 1] += (*off)[k];
  PetscFunctionReturn(0);
}

/* Shape functions and area element at reference point (u, v) of [0,1]^2 on master face f:
   bilinear map for a quad4, the collapsed (Duffy) map for a tri3. */
static void FacePoint(MBCSurface *m, PetscInt f, PetscReal u, PetscReal v, PetscReal N[], PetscReal x[], PetscReal nrm[], PetscReal *dA)
{
  const PetscInt *fv = &m->fnode[MBC_MAX_FACE_NODES * f];
  PetscReal       dx[2][3] = {{0, 0, 0}, {0, 0, 0}}, c[3];

  if (m->fnv[f] == 4) {
    const PetscReal dNu[4] = {-(1 - v), 1 - v, v, -v}, dNv[4] = {-(1 - u), -u, u, 1 - u};
    N[0] = (1 - u) * (1 - v), N[1] = u * (1 - v), N[2] = u * v, N[3] = (1 - u) * v;
    for (PetscInt i = 0; i < 4; i++)
      for (PetscInt d = 0; d < 3; d++) {
        dx[0][d] += dNu[i] * m->x[3 * fv[i] + d];
        dx[1][d] += dNv[i] * m->x[3 * fv[i] + d];
      }
    MBCCross(dx[0], dx[1], c);
    *dA = PetscSqrtReal(MBCDot(c, c));
  } else {
    const PetscReal a = u, b = v * (1 - u); /* Duffy: triangle (0,0) (1,0) (0,1) */
    N[0] = 1 - a - b, N[1] = a, N[2] = b, N[3] = 0;
    for (PetscInt d = 0; d < 3; d++) {
      dx[0][d] = m->x[3 * fv[1] + d] - m->x[3 * fv[0] + d];
      dx[1][d] = m->x[3 * fv[2] + d] - m->x[3 * fv[0] + d];
    }
    MBCCross(dx[0], dx[1], c);
    *dA = PetscSqrtReal(MBCDot(c, c)) * (1 - u);
  }
  for (PetscInt d = 0; d < 3; d++) x[d] = nrm[d] = 0;
  for (PetscInt i = 0; i < m->fnv[f]; i++)
    for (PetscInt d = 0; d < 3; d++) {
      x[d] += N[i] * m->x[3 * fv[i] + d];
      nrm[d] += N[i] * m->nnormal[3 * fv[i] + d];
    }
  MBCNormalize(nrm);
}

/* Dual basis of master face f: psi_i = sum_j C_ij N_j with C = D M^-1, M_ij = int N_i N_j,
   D = diag(int N_i), so that int psi_i N_j = delta_ij int N_j: the master side of a constraint is
   its node alone, and sum_i psi_i = 1. C row-major, MBC_MAX_FACE_NODES wide. */
static PetscErrorCode DualBasis(MBCSurface *m, PetscInt f, PetscInt nq, const PetscReal xq[], const PetscReal wq[], PetscReal C[])
{
  const PetscInt nv = m->fnv[f];
  PetscReal      M[16] = {0}, D[4] = {0}, Mi[16] = {0};

  PetscFunctionBegin;
  for (PetscInt a = 0; a < nq; a++)
    for (PetscInt b = 0; b < nq; b++) {
      PetscReal N[4], x[3], nrm[3], dA;
      FacePoint(m, f, xq[a], xq[b], N, x, nrm, &dA);
      dA *= wq[a] * wq[b];
      for (PetscInt i = 0; i < nv; i++) {
        D[i] += N[i] * dA;
        for (PetscInt j = 0; j < nv; j++) M[4 * i + j] += N[i] * N[j] * dA;
      }
    }
  for (PetscInt i = 0; i < nv; i++) Mi[4 * i + i] = 1;
  for (PetscInt col = 0; col < nv; col++) { /* Gauss-Jordan: M is SPD, no pivoting needed */
    const PetscReal piv = M[4 * col + col];
    PetscCheck(piv > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Master contact face %" PetscInt_FMT " has no area", f);
    for (PetscInt j = 0; j < nv; j++) {
      M[4 * col + j] /= piv;
      Mi[4 * col + j] /= piv;
    }
    for (PetscInt i = 0; i < nv; i++) {
      const PetscReal fac = M[4 * i + col];
      if (i == col || fac == 0) continue;
      for (PetscInt j = 0; j < nv; j++) {
        M[4 * i + j] -= fac * M[4 * col + j];
        Mi[4 * i + j] -= fac * Mi[4 * col + j];
      }
    }
  }
  for (PetscInt i = 0; i < MBC_MAX_FACE_NODES * MBC_MAX_FACE_NODES; i++) C[i] = 0;
  for (PetscInt i = 0; i < nv; i++)
    for (PetscInt j = 0; j < nv; j++) C[MBC_MAX_FACE_NODES * i + j] = D[i] * Mi[4 * i + j];
  PetscFunctionReturn(0);
}

PetscErrorCode MBCCoupleIntegrateReset(MBCCouple *c)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(c->moff));
  PetscCall(PetscFree(c->mnode));
  PetscCall(PetscFree(c->mw));
  PetscCall(PetscFree(c->soff));
  PetscCall(PetscFree(c->snode));
  PetscCall(PetscFree(c->sw));
  PetscCall(PetscFree(c->igap));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCCoupleIntegrate(MBCCouple *c, PetscBool integrate, PetscInt nq)
{
  MBCSurface *m = &c->master, *s = &c->slave;
  PetscInt   *pointOf, *pairOf, nface = 0, *faces = NULL, maxfaces = 0;
  PetscReal  *area, *covered, *nsum, *xq, *wq, *gsum, C[MBC_MAX_FACE_NODES * MBC_MAX_FACE_NODES];
  EntryList   ml = {NULL, 0, 0}, sl = {NULL, 0, 0};

  PetscFunctionBegin;
  PetscCall(MBCCoupleIntegrateReset(c));
  PetscCall(PetscMalloc2(m->nnodes, &pointOf, m->nnodes, &pairOf));
  PetscCall(PetscCalloc4(c->npoints + 1, &area, c->npoints + 1, &covered, c->npoints + 1, &gsum, c->npoints + 1, &nsum));
  PetscCall(PetscMalloc2(nq, &xq, nq, &wq));
  PetscCall(PetscDTGaussQuadrature(nq, 0.0, 1.0, xq, wq));
  for (PetscInt v = 0; v < m->nnodes; v++) pointOf[v] = pairOf[v] = -1;
  for (PetscInt k = 0; k < c->npoints; k++) pointOf[c->points[k].master] = k;
  for (PetscInt i = 0; i < c->npairs; i++) pairOf[c->pairs[i].master] = i;
  for (PetscInt f = 0; f < m->nfaces; f++) {
    const PetscInt *fv = &m->fnode[MBC_MAX_FACE_NODES * f];
    PetscBool       any = PETSC_FALSE;
    for (PetscInt i = 0; i < m->fnv[f]; i++) any = (PetscBool)(any || pointOf[fv[i]] >= 0);
    if (!any) continue;
    /* candidate slave faces: those around the candidate slave nodes of the face's master nodes */
    nface = 0;
    if (integrate)
      for (PetscInt i = 0; i < m->fnv[f]; i++) {
        const PetscInt pr = pairOf[fv[i]];
        if (pr < 0) continue;
        for (PetscInt j = 0; j < c->pairs[pr].ncand; j++) {
          const PetscInt node = c->pairs[pr].cand[j];
          for (PetscInt k = s->n2foff[node]; k < s->n2foff[node + 1]; k++) {
            PetscInt at = 0;
            while (at < nface && faces[at] != s->n2f[k]) at++;
            if (at < nface) continue;
            if (nface == maxfaces) {
              PetscInt *grow;
              maxfaces = PetscMax(2 * maxfaces, 64);
              PetscCall(PetscMalloc1(maxfaces, &grow));
              if (nface) PetscCall(PetscArraycpy(grow, faces, nface));
              PetscCall(PetscFree(faces));
              faces = grow;
            }
            faces[nface++] = s->n2f[k];
          }
        }
      }
    PetscCall(DualBasis(m, f, nq, xq, wq, C));
    for (PetscInt a = 0; a < nq; a++)
      for (PetscInt b = 0; b < nq; b++) {
        PetscReal       N[4], psi[4], x[3], nrm[3], dA, q, bestq = -PETSC_MAX_REAL;
        MBCContactPoint cp, best;
        PetscBool       found = PETSC_FALSE;
        PetscCall(PetscMemzero(&best, sizeof(best)));
        FacePoint(m, f, xq[a], xq[b], N, x, nrm, &dA);
        dA *= wq[a] * wq[b];
        for (PetscInt i = 0; i < m->fnv[f]; i++)
          if (pointOf[fv[i]] >= 0) area[pointOf[fv[i]]] += N[i] * dA;
        for (PetscInt j = 0; j < nface; j++)
          if (MBCCoupleProjectOnFace(c, x, nrm, faces[j], &cp, &q) && (q > bestq + 1e-9 || (q >= bestq - 1e-9 && cp.face < best.face))) {
            best  = cp;
            bestq = q;
            found = PETSC_TRUE;
          }
        if (!found) continue;
        for (PetscInt i = 0; i < m->fnv[f]; i++) {
          psi[i] = 0;
          for (PetscInt j = 0; j < m->fnv[f]; j++) psi[i] += C[MBC_MAX_FACE_NODES * i + j] * N[j];
        }
        for (PetscInt i = 0; i < m->fnv[f]; i++) {
          const PetscInt k = pointOf[fv[i]];
          if (k < 0) continue;
          nsum[k] += N[i] * dA;
          covered[k] += psi[i] * dA;
          gsum[k] += psi[i] * dA * best.gap;
          for (PetscInt j = 0; j < best.nv; j++)
            if (best.w[j] != 0) PetscCall(EntryAdd(&sl, (PetscInt64)k * s->nnodes + s->fnode[MBC_MAX_FACE_NODES * best.face + j], psi[i] * best.w[j] * dA));
        }
      }
  }
  /* a point whose share is mostly uncovered (the dual weights lose their meaning there) keeps
     the collocation at its node: its integrated entries are dropped */
  for (size_t e = 0; e < sl.n; e++) {
    const PetscInt k = (PetscInt)(sl.e[e].key / s->nnodes);
    if (!(covered[k] >= 0.25 * area[k] && area[k] > 0)) sl.e[e].w = 0;
  }
  for (PetscInt k = 0; k < c->npoints; k++) { /* master side: the node alone (dual basis) */
    MBCContactPoint *p = &c->points[k];
    const PetscBool  integrated = (PetscBool)(covered[k] >= 0.25 * area[k] && area[k] > 0);
    p->area                     = nsum[k] > 0 ? nsum[k] : area[k];
    PetscCall(EntryAdd(&ml, (PetscInt64)k * m->nnodes + p->master, integrated ? covered[k] : area[k]));
    if (integrated) continue;
    covered[k] = area[k];
    for (PetscInt j = 0; j < p->nv; j++) PetscCall(EntryAdd(&sl, (PetscInt64)k * s->nnodes + s->fnode[MBC_MAX_FACE_NODES * p->face + j], p->w[j] * area[k]));
    gsum[k] = p->gap * area[k];
  }
  for (PetscInt k = 0; k < c->npoints; k++) PetscCheck(covered[k] > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Contact point %" PetscInt_FMT " of couple %" PetscInt_FMT " has no area", k, c->k);
  PetscCall(EntryCSR(&ml, c->npoints, m->nnodes, covered, &c->moff, &c->mnode, &c->mw));
  PetscCall(EntryCSR(&sl, c->npoints, s->nnodes, covered, &c->soff, &c->snode, &c->sw));
  PetscCall(PetscMalloc1(c->npoints + 1, &c->igap));
  for (PetscInt k = 0; k < c->npoints; k++) c->igap[k] = gsum[k] / covered[k];
  PetscCall(PetscFree(ml.e));
  PetscCall(PetscFree(sl.e));
  PetscCall(PetscFree(faces));
  PetscCall(PetscFree2(xq, wq));
  PetscCall(PetscFree4(area, covered, gsum, nsum));
  PetscCall(PetscFree2(pointOf, pairOf));
  PetscFunctionReturn(0);
}
