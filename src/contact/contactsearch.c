/* The contact search of the paper on gathered surfaces: averaged nodal normals, a cell grid
   with a 1D key for the global search, projection along the nodal normal with an inside/outside
   test and area coordinates for the local search. No nonlinear projection is solved. */
#include <mbc/private/contactimpl.h>

PetscErrorCode MBCSurfaceReset(MBCSurface *s)
{
  PetscFunctionBegin;
  PetscCall(PetscFree4(s->nbody, s->nrow, s->x0, s->x));
  PetscCall(PetscFree(s->nnormal));
  PetscCall(PetscFree(s->fcnormal));
  PetscCall(PetscFree3(s->fnv, s->fnode, s->fbody));
  PetscCall(PetscFree2(s->fnormal, s->fcenter));
  PetscCall(PetscFree2(s->n2foff, s->n2f));
  PetscCall(PetscFree(s->ffree));
  PetscCall(PetscFree2(s->fqnode, s->fqslot));
  PetscCall(PetscMemzero(s, sizeof(*s)));
  PetscFunctionReturn(0);
}

/* Face normals (Newell), centres, node -> face map, free-boundary edges, averaged nodal normals
   (mean of the unit normals of the faces around the node) and the faces' corner normals (the same
   mean over the faces within the feature angle of the face), from the current coordinates. */
PetscErrorCode MBCSurfaceSetUp(MBCSurface *s)
{
  PetscInt *count;

  PetscFunctionBegin;
  PetscCall(PetscFree2(s->fnormal, s->fcenter));
  PetscCall(PetscFree(s->nnormal));
  PetscCall(PetscFree(s->fcnormal));
  PetscCall(PetscFree2(s->n2foff, s->n2f));
  PetscCall(PetscFree(s->ffree));
  PetscCall(PetscCalloc2(3 * s->nfaces, &s->fnormal, 3 * s->nfaces, &s->fcenter));
  PetscCall(PetscCalloc1(3 * s->nnodes, &s->nnormal));
  for (PetscInt f = 0; f < s->nfaces; f++) {
    const PetscInt  nv = s->fnv[f], *v = &s->fnode[MBC_MAX_FACE_NODES * f];
    PetscReal      *n = &s->fnormal[3 * f], *c = &s->fcenter[3 * f];
    for (PetscInt i = 0; i < nv; i++) {
      const PetscReal *a = &s->x[3 * v[i]], *b = &s->x[3 * v[(i + 1) % nv]];
      n[0] += (a[1] - b[1]) * (a[2] + b[2]);
      n[1] += (a[2] - b[2]) * (a[0] + b[0]);
      n[2] += (a[0] - b[0]) * (a[1] + b[1]);
      for (PetscInt d = 0; d < 3; d++) c[d] += a[d] / nv;
    }
    PetscCheck(MBCNormalize(n) > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Contact face %" PetscInt_FMT " of body %" PetscInt_FMT " has zero area", f, s->fbody[f]);
  }
  PetscCall(PetscCalloc2(s->nnodes + 1, &s->n2foff, MBC_MAX_FACE_NODES * s->nfaces, &s->n2f));
  for (PetscInt f = 0; f < s->nfaces; f++)
    for (PetscInt i = 0; i < s->fnv[f]; i++) s->n2foff[s->fnode[MBC_MAX_FACE_NODES * f + i] + 1]++;
  for (PetscInt v = 0; v < s->nnodes; v++) s->n2foff[v + 1] += s->n2foff[v];
  PetscCall(PetscCalloc1(s->nnodes, &count));
  for (PetscInt f = 0; f < s->nfaces; f++) {
    for (PetscInt i = 0; i < s->fnv[f]; i++) {
      const PetscInt v = s->fnode[MBC_MAX_FACE_NODES * f + i];
      s->n2f[s->n2foff[v] + count[v]++] = f;
      for (PetscInt d = 0; d < 3; d++) s->nnormal[3 * v + d] += s->fnormal[3 * f + d];
    }
  }
  PetscCall(PetscFree(count));
  for (PetscInt v = 0; v < s->nnodes; v++) MBCNormalize(&s->nnormal[3 * v]);
  /* corner normals: a faceted curved surface's normal, continuous across the faces' shared edges
     (the contact normal at a point is their interpolation), a feature edge kept sharp */
  PetscCall(PetscCalloc1(3 * MBC_MAX_FACE_NODES * s->nfaces + 1, &s->fcnormal));
  for (PetscInt f = 0; f < s->nfaces; f++)
    for (PetscInt i = 0; i < s->fnv[f]; i++) {
      const PetscInt v = s->fnode[MBC_MAX_FACE_NODES * f + i];
      PetscReal     *cn = &s->fcnormal[3 * (MBC_MAX_FACE_NODES * f + i)];
      for (PetscInt k = s->n2foff[v]; k < s->n2foff[v + 1]; k++) {
        const PetscReal *ng = &s->fnormal[3 * s->n2f[k]];
        if (s->n2f[k] != f && !(MBCDot(ng, &s->fnormal[3 * f]) > MBC_FEATURE_COS)) continue;
        for (PetscInt d = 0; d < 3; d++) cn[d] += ng[d];
      }
      MBCNormalize(cn);
    }
  PetscCall(PetscMalloc1(MBC_MAX_FACE_NODES * s->nfaces + 1, &s->ffree));
  for (PetscInt f = 0; f < s->nfaces; f++) { /* edge (a, b) is free when no other face around a has b */
    const PetscInt nv = s->fnv[f], *fv = &s->fnode[MBC_MAX_FACE_NODES * f];
    for (PetscInt i = 0; i < MBC_MAX_FACE_NODES; i++) {
      PetscBool shared = PETSC_FALSE;
      if (i < nv)
        for (PetscInt k = s->n2foff[fv[i]]; k < s->n2foff[fv[i] + 1] && !shared; k++) {
          const PetscInt g = s->n2f[k];
          if (g == f) continue;
          for (PetscInt j = 0; j < s->fnv[g]; j++) shared = (PetscBool)(shared || s->fnode[MBC_MAX_FACE_NODES * g + j] == fv[(i + 1) % nv]);
        }
      s->ffree[MBC_MAX_FACE_NODES * f + i] = (PetscBool)(i < nv && !shared);
    }
  }
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt64 key;
  PetscInt   node;
} KeyNode;

static int CompareKeyNode(const void *a, const void *b)
{
  const KeyNode *x = (const KeyNode *)a, *y = (const KeyNode *)b;
  if (x->key != y->key) return x->key < y->key ? -1 : 1;
  return x->node < y->node ? -1 : (x->node > y->node);
}

/* first index in sorted keys with key >= k */
static PetscInt LowerBound(const KeyNode *a, PetscInt n, PetscInt64 k)
{
  PetscInt lo = 0, hi = n;
  while (lo < hi) {
    PetscInt mid = (lo + hi) / 2;
    if (a[mid].key < k) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/* Global search: box of the couple enlarged by the margin, cubic cells of edge h (the cell factor
   times the larger of the mean face edge and the longest slave face edge) numbered x
   first, then y, then z; every master node takes the nearest slave nodes within h from its own
   and the 26 neighbouring cells. Sorting the slave nodes by key costs N log N; the rest is linear. */
PetscErrorCode MBCCoupleGlobalSearch(MBCCouple *c, PetscReal cell_factor, PetscReal margin)
{
  MBCSurface *m = &c->master, *s = &c->slave;
  PetscReal   hi[3], edges = 0, longest = 0;
  PetscInt    nedges = 0;
  PetscInt64  ncell[3];
  KeyNode    *sk;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_GlobalSearch, 0, 0, 0, 0));
  for (PetscInt side = 0; side < 2; side++) { /* mean edge length of the couple's faces */
    MBCSurface *t = side ? s : m;
    for (PetscInt f = 0; f < t->nfaces; f++)
      for (PetscInt i = 0; i < t->fnv[f]; i++) {
        PetscReal e[3];
        MBCSub(&t->x[3 * t->fnode[MBC_MAX_FACE_NODES * f + i]], &t->x[3 * t->fnode[MBC_MAX_FACE_NODES * f + (i + 1) % t->fnv[f]]], e);
        edges += PetscSqrtReal(MBCDot(e, e));
        nedges++;
        if (side) longest = PetscMax(longest, PetscSqrtReal(MBCDot(e, e)));
      }
  }
  /* every point of a slave face lies within its longest edge of one of its vertices: with
     cells at least that big, a master node over a large slave face always finds a partner */
  c->h      = cell_factor * PetscMax(edges / PetscMax(nedges, 1), longest);
  c->margin = margin > 0 ? margin : c->h;
  for (PetscInt d = 0; d < 3; d++) {
    c->lo[d] = PETSC_MAX_REAL;
    hi[d]    = PETSC_MIN_REAL;
  }
  for (PetscInt side = 0; side < 2; side++) {
    MBCSurface *t = side ? s : m;
    for (PetscInt v = 0; v < t->nnodes; v++)
      for (PetscInt d = 0; d < 3; d++) {
        c->lo[d] = PetscMin(c->lo[d], t->x[3 * v + d]);
        hi[d]    = PetscMax(hi[d], t->x[3 * v + d]);
      }
  }
  for (PetscInt d = 0; d < 3; d++) {
    c->lo[d] -= c->margin;
    hi[d] += c->margin;
    /* the cell keys are int64: a margin or box far beyond the cell size would overflow them */
    PetscCheck(c->h > 0 && (hi[d] - c->lo[d]) / c->h < 1e6, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Contact couple k = %" PetscInt_FMT ": the search box is %g long in %c, %g search cells of %g (lower -mbc_contact_margin %g)", c->k, (double)(hi[d] - c->lo[d]), "xyz"[d], (double)((hi[d] - c->lo[d]) / c->h), (double)c->h, (double)c->margin);
    ncell[d] = (PetscInt64)PetscCeilReal((hi[d] - c->lo[d]) / c->h) + 1;
  }
#define CELL(x, d) ((PetscInt64)PetscFloorReal(((x) - c->lo[d]) / c->h))
#define KEY(i, j, l) ((i) + ncell[0] * ((j) + ncell[1] * (l)))
  PetscCall(PetscMalloc1(s->nnodes, &sk));
  for (PetscInt v = 0; v < s->nnodes; v++) {
    const PetscReal *x = &s->x[3 * v];
    sk[v].key  = KEY(CELL(x[0], 0), CELL(x[1], 1), CELL(x[2], 2));
    sk[v].node = v;
  }
  qsort(sk, (size_t)s->nnodes, sizeof(KeyNode), CompareKeyNode);
  PetscCall(PetscFree(c->pairs));
  PetscCall(PetscMalloc1(m->nnodes, &c->pairs));
  c->npairs = 0;
  for (PetscInt v = 0; v < m->nnodes; v++) {
    const PetscReal *x = &m->x[3 * v];
    const PetscInt64 ci = CELL(x[0], 0), cj = CELL(x[1], 1), cl = CELL(x[2], 2);
    MBCTestPair     *p = &c->pairs[c->npairs];
    PetscReal        dist[MBC_SEARCH_CANDIDATES];

    p->master = v;
    p->ncand  = 0;
    for (PetscInt64 dl = -1; dl <= 1; dl++)
      for (PetscInt64 dj = -1; dj <= 1; dj++) {
        /* cells (ci-1..ci+1, cj+dj, cl+dl) are consecutive keys */
        const PetscInt64 k0 = KEY(ci - 1, cj + dj, cl + dl);
        if (cj + dj < 0 || cl + dl < 0) continue;
        for (PetscInt i = LowerBound(sk, s->nnodes, k0); i < s->nnodes && sk[i].key <= k0 + 2; i++) {
          PetscReal e[3], d;
          PetscInt  at;
          MBCSub(&s->x[3 * sk[i].node], x, e);
          d = PetscSqrtReal(MBCDot(e, e));
          if (d > c->h) continue;
          /* insert into the sorted candidate list (distance, then canonical index) */
          for (at = p->ncand; at > 0 && (dist[at - 1] > d || (dist[at - 1] == d && p->cand[at - 1] > sk[i].node)); at--) { }
          if (at >= MBC_SEARCH_CANDIDATES) continue;
          for (PetscInt j = PetscMin(p->ncand, MBC_SEARCH_CANDIDATES - 1); j > at; j--) {
            dist[j]    = dist[j - 1];
            p->cand[j] = p->cand[j - 1];
          }
          dist[at]    = d;
          p->cand[at] = sk[i].node;
          p->ncand    = PetscMin(p->ncand + 1, MBC_SEARCH_CANDIDATES);
        }
      }
    if (p->ncand) {
      p->distance = dist[0];
      c->npairs++;
    }
  }
#undef KEY
#undef CELL
  PetscCall(PetscFree(sk));
  PetscCall(PetscLogEventEnd(MBC_GlobalSearch, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Projects the point xm along the unit direction nm (a master node's averaged normal, or its
   interpolation) onto slave face f; returns PETSC_TRUE and the contact point (slave weights,
   projection, gap, normal) when the face opposes nm and the projection falls inside it: within
   2e-6 of an edge across an edge shared with another face (that face takes the point), within
   c->extension of the edge's length beyond an edge on the slave surface's free boundary. Beyond
   a free edge the weights are those of the point clamped onto the face's boundary (the gap along
   n_f is the same on a planar face), so a master node above the edge of a slave surface of the
   same footprint does not drop out of contact when the two bodies' edges move apart by rounding
   or an unbalanced iterate. quality: the smallest weight inside, the most negative edge distance
   over the edge length outside, so the face that holds the point wins. With force the inside test
   is skipped (the caller knows the point lies on f: a segment of the mortar integration). */
PetscBool MBCCoupleProjectOnFace(MBCCouple *c, const PetscReal xm[], const PetscReal nm[], PetscInt f, PetscBool force, MBCContactPoint *cp, PetscReal *quality)
{
  return MBCCoupleProjectOnFacePlane(c, xm, nm, f, NULL, force, cp, quality);
}

/* The same with the slave face's plane P given (NULL: computed here if needed). */
PetscBool MBCCoupleProjectOnFacePlane(MBCCouple *c, const PetscReal xm[], const PetscReal nm[], PetscInt f, const MBCFacePlane *P, PetscBool force, MBCContactPoint *cp, PetscReal *quality)
{
  MBCSurface      *s = &c->slave;
  const PetscReal *nf = &s->fnormal[3 * f], *cf = &s->fcenter[3 * f];
  const PetscInt   nv = s->fnv[f], *fv = &s->fnode[MBC_MAX_FACE_NODES * f];
  const PetscReal  cosang = MBCDot(nm, nf);
  PetscReal        e[3], t, p[3], sub[MBC_MAX_FACE_NODES], area = 0, wmin = PETSC_MAX_REAL, out = 0;

  if (!(cosang < 0)) return PETSC_FALSE; /* the face must face the node */
  MBCSub(cf, xm, e);
  t = MBCDot(e, nf) / cosang;
  for (PetscInt d = 0; d < 3; d++) p[d] = xm[d] + t * nm[d];
  /* inside/outside: the sub-triangles (p, x_i, x_i+1) all turn like the face; sub_i = |e_i| d_i / 2
     with d_i the signed distance of p to edge i */
  for (PetscInt i = 0; i < nv; i++) {
    const PetscReal *a = &s->x[3 * fv[i]], *b = &s->x[3 * fv[(i + 1) % nv]];
    const PetscReal  tol = s->ffree && s->ffree[MBC_MAX_FACE_NODES * f + i] ? PetscMax(c->extension, 2e-6) : 2e-6;
    PetscReal        ab[3];
    sub[i] = MBCArea(p, a, b, nf);
    MBCSub(b, a, ab);
    if (!force && sub[i] < -0.5 * tol * MBCDot(ab, ab)) return PETSC_FALSE;
    out = PetscMin(out, 2 * sub[i] / MBCDot(ab, ab));
  }
  cp->nv = nv;
  if (nv == 3) { /* area coordinates (clamped onto the face outside it) */
    for (PetscInt i = 0; i < 3; i++) area += PetscMax(sub[i], 0);
    if (!(area > 0)) return PETSC_FALSE;
    for (PetscInt i = 0; i < 3; i++) cp->w[i] = PetscMax(sub[(i + 1) % 3], 0) / area;
    cp->w[3] = 0;
  } else { /* the face's bilinear shape functions at p (inverse of the bilinear map in the face's
              plane by Newton; clamped onto the face outside it): the trace of the
              slave element, so the slave nodes get consistent loads on any convex quad */
    MBCFacePlane Pf;
    PetscReal    y[2], u, v;
    if (!P) {
      MBCSurfaceFacePlane(s, f, &Pf);
      P = &Pf;
    }
    MBCFacePlaneCoords(P, p, y);
    u = v = 0.5;
    if (!MBCBilinearInverse(P->B, y, &u, &v)) return PETSC_FALSE;
    u        = PetscMin(PetscMax(u, 0), 1);
    v        = PetscMin(PetscMax(v, 0), 1);
    cp->w[0] = (1 - u) * (1 - v), cp->w[1] = u * (1 - v), cp->w[2] = u * v, cp->w[3] = (1 - u) * v;
  }
  for (PetscInt i = 0; i < nv; i++) wmin = PetscMin(wmin, cp->w[i]);
  cp->face = f;
  /* the contact normal: the face's corner normals interpolated with the weights, so it does not
     depend on which of the faces sharing an edge or vertex takes the point (on a faceted curved
     surface the face normal would tilt the normal of a point on a shared vertex by half the kink,
     always towards the face the tie rule picks: a tangential force on a frictionless interface) */
  for (PetscInt d = 0; d < 3; d++) {
    cp->p[d] = p[d];
    cp->n[d] = 0;
    for (PetscInt i = 0; i < nv; i++) cp->n[d] += cp->w[i] * s->fcnormal[3 * (MBC_MAX_FACE_NODES * f + i) + d];
  }
  if (!(MBCNormalize(cp->n) > 0) || !(MBCDot(cp->n, nm) < 0))
    for (PetscInt d = 0; d < 3; d++) cp->n[d] = nf[d];
  /* the gap to the point of the slave element the weights give, sum_i w_i x_i, not to p on the
     face's mean plane: H carries the slave side as those weights, so a warped (saddle) quad's
     corners, up to the warp off that plane, must move the gap as they move H^T du. Measured to
     the plane, the gap a dynamic step predicted and the one the next step found differed by the
     warp (a bouncing block: from 1e-16 to 1e-5 m per step, growing with the motion; the gain
     stayed with H rebuilt every step), and the step closing that difference pumped energy in
     (2600 times the impact energy within 0.48 s). On a planar face and on triangles the two are the same.
     Along the contact normal n, the direction H carries: then H^T du is the gap's change exactly. */
  for (PetscInt d = 0; d < 3; d++) {
    e[d] = xm[d];
    for (PetscInt i = 0; i < nv; i++) e[d] -= cp->w[i] * s->x[3 * fv[i] + d];
  }
  cp->gap  = MBCDot(e, cp->n);
  *quality = out < 0 ? out : wmin;
  return PETSC_TRUE;
}

/* The plane of face f: see MBCFacePlane. */
void MBCSurfaceFacePlane(const MBCSurface *s, PetscInt f, MBCFacePlane *P)
{
  const PetscInt *fv = &s->fnode[MBC_MAX_FACE_NODES * f];
  const PetscInt  nv = s->fnv[f];
  PetscReal       a;

  for (PetscInt d = 0; d < 3; d++) {
    P->c[d] = s->fcenter[3 * f + d];
    P->n[d] = s->fnormal[3 * f + d];
  }
  MBCSub(&s->x[3 * fv[1]], &s->x[3 * fv[0]], P->e1);
  a = MBCDot(P->e1, P->n);
  for (PetscInt d = 0; d < 3; d++) P->e1[d] -= a * P->n[d];
  MBCNormalize(P->e1);
  MBCCross(P->n, P->e1, P->e2);
  for (PetscInt i = 0; i < nv; i++) MBCFacePlaneCoords(P, &s->x[3 * fv[i]], P->Y[i]);
  for (PetscInt d = 0; d < 2 && nv == 4; d++) {
    P->B[0][d] = P->Y[0][d];
    P->B[1][d] = P->Y[1][d] - P->Y[0][d];
    P->B[2][d] = P->Y[3][d] - P->Y[0][d];
    P->B[3][d] = P->Y[0][d] - P->Y[1][d] + P->Y[2][d] - P->Y[3][d];
  }
}

/* (u, v) of y under a quad's bilinear map B0 + B1 u + B2 v + B3 u v (MBCFacePlane's B): Newton from
   (*u, *v), exact in one step on parallelograms (B3 = 0). Its error after a step is about
   |B3| / |J| (|du| + |dv|)^2, below 1e-16 once the step is below 1e-9 on a convex quad
   (|B3| <= |J|): that step is the last one. Start from the centre: from elsewhere in a strongly
   distorted quad it can find the map's other root (tests/c/test_bilinear.c). */
PetscBool MBCBilinearInverse(const PetscReal B[][2], const PetscReal y[], PetscReal *u, PetscReal *v)
{
  for (PetscInt it = 0; it < 30; it++) {
    const PetscReal U = *u, V = *v;
    const PetscReal r0 = B[0][0] + B[1][0] * U + B[2][0] * V + B[3][0] * U * V - y[0], r1 = B[0][1] + B[1][1] * U + B[2][1] * V + B[3][1] * U * V - y[1];
    const PetscReal J00 = B[1][0] + B[3][0] * V, J01 = B[2][0] + B[3][0] * U, J10 = B[1][1] + B[3][1] * V, J11 = B[2][1] + B[3][1] * U;
    const PetscReal det = J00 * J11 - J01 * J10;
    PetscReal       du, dv, idet;
    if (!(PetscAbsReal(det) > 0)) return PETSC_FALSE;
    idet = 1 / det;
    du   = (J11 * r0 - J01 * r1) * idet;
    dv   = (J00 * r1 - J10 * r0) * idet;
    *u -= du;
    *v -= dv;
    if (PetscAbsReal(du) + PetscAbsReal(dv) < 1e-9) return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

/* Pairing with hysteresis (-mbc_contact_hysteresis): does master node v (at xm, normal nm), whose
   best face is `face`, keep the face of the pairs H was built for, c->prefer[v]
   (MBCContactSetPreferredFaces)? Yes while that face still takes the projection: by the inside
   test, or clamped onto it with the projection at most c->hysteresis of an edge's length beyond
   its boundary, and the two faces lie on one smooth surface (normals within the feature angle,
   MBC_FEATURE_COS). A node on the common edge of two faces (the dams' base nodes over the
   foundation's edges, Hertz's faceted cylinders) otherwise changes its face with motions of 1e-7
   of an edge, and H and D were rebuilt at nearly every step of an earthquake for that alone. The
   kept pairing puts the point on the kept face's edge: its normal is interpolated from the corner
   normals there, which both faces share on a smooth surface, and an integrated constraint's
   weights do not depend on the face (they are integrated over the master node's share), so H
   and the gap differ from the best face's by the motion beyond the edge times the surface's
   curvature. cp: the kept point. */
PetscBool MBCCoupleKeepsFace(MBCCouple *c, const PetscReal xm[], const PetscReal nm[], PetscInt v, PetscInt face, MBCContactPoint *cp)
{
  PetscInt  f;
  PetscReal q;

  if (!(c->hysteresis > 0) || !c->prefer || v >= c->nprefer) return PETSC_FALSE;
  f = c->prefer[v];
  if (f < 0 || f == face || f >= c->slave.nfaces) return PETSC_FALSE;
  if (!(MBCDot(&c->slave.fnormal[3 * f], &c->slave.fnormal[3 * face]) > MBC_FEATURE_COS)) return PETSC_FALSE;
  if (MBCCoupleProjectOnFace(c, xm, nm, f, PETSC_FALSE, cp, &q)) return PETSC_TRUE;
  return (PetscBool)(MBCCoupleProjectOnFace(c, xm, nm, f, PETSC_TRUE, cp, &q) && q >= -c->hysteresis);
}

/* Tangents: t1 = e x n with e the axis least aligned with n, t2 = n x t1. */
static void Frame(MBCContactPoint *cp)
{
  PetscReal e[3] = {0, 0, 0};
  PetscInt  a    = 0;
  for (PetscInt d = 1; d < 3; d++)
    if (PetscAbsReal(cp->n[d]) < PetscAbsReal(cp->n[a])) a = d;
  e[a] = 1;
  MBCCross(e, cp->n, cp->t1);
  MBCNormalize(cp->t1);
  MBCCross(cp->n, cp->t1, cp->t2);
}

/* Local search: for every test pair, the faces around the partner slave node (then around the
   next candidates while none accepts); the accepting face with the largest smallest weight wins,
   so a point on a shared edge or vertex is assigned once. */
PetscErrorCode MBCCoupleLocalSearch(MBCCouple *c)
{
  MBCSurface *s = &c->slave;
  PetscInt   *mark, *queue;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_LocalSearch, 0, 0, 0, 0));
  PetscCall(PetscMalloc2(s->nfaces + 1, &mark, s->nfaces + 1, &queue));
  for (PetscInt f = 0; f < s->nfaces; f++) mark[f] = -1;
  PetscCall(PetscFree(c->points));
  PetscCall(PetscMalloc1(c->npairs, &c->points));
  c->npoints = 0;
  c->ntests  = 0;
  for (PetscInt i = 0; i < c->npairs; i++) {
    const MBCTestPair *pair = &c->pairs[i];
    const PetscReal   *xm = &c->master.x[3 * pair->master], *nm = &c->master.nnormal[3 * pair->master];
    MBCContactPoint    best, cp;
    PetscReal          bestq = -PETSC_MAX_REAL, q;
    PetscBool          found = PETSC_FALSE;
    PetscInt           nq = 0;

#define TRY(g) \
  do { \
    c->ntests++; \
    /* weights within 1e-9 tie (a point on a shared edge): the first face in canonical order \
       wins, so rounding does not move the point between faces from one step to the next */ \
    if (MBCCoupleProjectOnFace(c, xm, nm, (g), PETSC_FALSE, &cp, &q) && (q > bestq + 1e-9 || (q >= bestq - 1e-9 && cp.face < best.face))) { \
      best  = cp; \
      bestq = q; \
      found = PETSC_TRUE; \
    } \
  } while (0)
    for (PetscInt j = 0; j < pair->ncand && !found; j++) {
      const PetscInt node = pair->cand[j];
      for (PetscInt k = s->n2foff[node]; k < s->n2foff[node + 1]; k++) {
        if (mark[s->n2f[k]] == i) continue;
        mark[s->n2f[k]] = i;
        queue[nq++]     = s->n2f[k];
        TRY(s->n2f[k]);
      }
    }
    /* none accepts (the nearest slave nodes are not vertices of the face under the node: a curved
       or fine slave surface): walk from those faces over their vertex neighbours within 2h of the
       node until one accepts, then try the faces around that one (ties) */
    for (PetscInt at = 0; at < nq && !found; at++) {
      const PetscInt g = queue[at];
      for (PetscInt l = 0; l < s->fnv[g] && !found; l++) {
        const PetscInt v = s->fnode[MBC_MAX_FACE_NODES * g + l];
        for (PetscInt k = s->n2foff[v]; k < s->n2foff[v + 1]; k++) {
          const PetscInt h = s->n2f[k];
          PetscReal      e[3];
          if (mark[h] == i) continue;
          mark[h] = i;
          MBCSub(&s->fcenter[3 * h], xm, e);
          if (MBCDot(e, e) > 4 * c->h * c->h) continue;
          queue[nq++] = h;
          TRY(h);
        }
      }
      if (found)
        for (PetscInt l = 0; l < best.nv; l++) {
          const PetscInt v = s->fnode[MBC_MAX_FACE_NODES * best.face + l];
          for (PetscInt k = s->n2foff[v]; k < s->n2foff[v + 1]; k++)
            if (mark[s->n2f[k]] != i) {
              mark[s->n2f[k]] = i;
              TRY(s->n2f[k]);
            }
        }
    }
#undef TRY
    if (found && MBCCoupleKeepsFace(c, xm, nm, pair->master, best.face, &cp)) best = cp;
    if (!found || best.gap < -c->h || MBCCoupleExcludes(c, pair->master)) continue;
    best.master = pair->master;
    Frame(&best);
    c->points[c->npoints++] = best;
  }
  PetscCall(PetscFree2(mark, queue));
  PetscCall(PetscLogEventEnd(MBC_LocalSearch, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* -mbc_contact_check_search: every master node against every slave face, with the local search's
   acceptance and tie rules; *missed is the first master node whose brute-force pair (a face at
   |gap| <= 0.7 h, so that one of its vertices lies within h of the node and the search could see
   it) the search missed or paired with a worse face, -1 if none; *face its brute-force face. */
PetscErrorCode MBCCoupleCheckSearch(MBCCouple *c, PetscInt *missed, PetscInt *face, PetscReal *gap)
{
  MBCSurface *m = &c->master, *s = &c->slave;
  PetscInt   *pointOf;

  PetscFunctionBegin;
  *missed = -1;
  PetscCall(PetscMalloc1(m->nnodes, &pointOf));
  for (PetscInt v = 0; v < m->nnodes; v++) pointOf[v] = -1;
  for (PetscInt k = 0; k < c->npoints; k++) pointOf[c->points[k].master] = k;
  for (PetscInt v = 0; v < m->nnodes && *missed < 0; v++) {
    MBCContactPoint best, cp;
    PetscReal       bestq = -PETSC_MAX_REAL, q, qs = -PETSC_MAX_REAL;
    PetscBool       found = PETSC_FALSE;
    best.face = -1;
    for (PetscInt f = 0; f < s->nfaces; f++)
      if (MBCCoupleProjectOnFace(c, &m->x[3 * v], &m->nnormal[3 * v], f, PETSC_FALSE, &cp, &q) && PetscAbsReal(cp.gap) <= 0.7 * c->h && (q > bestq + 1e-9 || (q >= bestq - 1e-9 && cp.face < best.face))) {
        best  = cp;
        bestq = q;
        found = PETSC_TRUE;
      }
    if (!found || MBCCoupleExcludes(c, v)) continue;
    if (pointOf[v] >= 0) (void)MBCCoupleProjectOnFace(c, &m->x[3 * v], &m->nnormal[3 * v], c->points[pointOf[v]].face, PETSC_FALSE, &cp, &qs);
    if (pointOf[v] >= 0 && c->points[pointOf[v]].face != best.face && MBCCoupleKeepsFace(c, &m->x[3 * v], &m->nnormal[3 * v], v, best.face, &cp) && cp.face == c->points[pointOf[v]].face) continue; /* its kept face */
    if (pointOf[v] < 0 || (c->points[pointOf[v]].face != best.face && qs < bestq - 1e-9)) {
      *missed = v;
      *face   = best.face;
      *gap    = best.gap;
    }
  }
  PetscCall(PetscFree(pointOf));
  PetscFunctionReturn(0);
}
