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
  PetscInt64 key; /* point * nnodes + node; -1: an empty slot */
  PetscReal  w;
} Entry;

/* The weights summed per key as they come (open addressing). A point gets a handful of distinct
   nodes but many contributions: one per piece it covers, each piece's quadrature points summed
   before (Integrate). Kept as a list of every contribution and merged at the end they took 4 M
   entries, about 250 MB, on the 198k dam, held while a dynamic step's re-search runs beside the
   factors. Each key's sum takes its terms in the order they come, so the bits do not depend on
   the table's size. */
typedef struct {
  Entry *e;
  size_t n, cap; /* keys held, slots (a power of 2) */
} EntryList;

static size_t EntrySlot(const EntryList *l, PetscInt64 key)
{
  size_t i = (size_t)(((uint64_t)key * 0x9E3779B97F4A7C15ULL) >> 20) & (l->cap - 1);
  while (l->e[i].key >= 0 && l->e[i].key != key) i = (i + 1) & (l->cap - 1);
  return i;
}

static PetscErrorCode EntryAdd(EntryList *l, PetscInt64 key, PetscReal w)
{
  size_t i;

  PetscFunctionBegin;
  if (2 * (l->n + 1) > l->cap) { /* at most half full */
    EntryList grown = {NULL, 0, PetscMax(2 * l->cap, 1024)};
    PetscCall(PetscMalloc1(grown.cap, &grown.e));
    for (size_t j = 0; j < grown.cap; j++) grown.e[j].key = -1;
    for (size_t j = 0; j < l->cap; j++)
      if (l->e[j].key >= 0) grown.e[EntrySlot(&grown, l->e[j].key)] = l->e[j];
    grown.n = l->n;
    PetscCall(PetscFree(l->e));
    *l = grown;
  }
  i = EntrySlot(l, key);
  if (l->e[i].key < 0) l->e[i].key = key, l->e[i].w = w, l->n++;
  else l->e[i].w += w;
  PetscFunctionReturn(0);
}

/* The sums into CSR rows (one per point, its nodes ascending) scaled by 1 / area: a counting sort
   by point, then each point's few nodes sorted. */
static PetscErrorCode EntryCSR(EntryList *l, PetscInt npoints, PetscInt nnodes, const PetscReal area[], PetscInt **off, PetscInt **node, PetscReal **w)
{
  PetscInt *fill;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(npoints + 1, off));
  PetscCall(PetscMalloc1(npoints + 1, &fill));
  PetscCall(PetscMalloc1(l->n + 1, node));
  PetscCall(PetscMalloc1(l->n + 1, w));
  for (size_t i = 0; i < l->cap; i++)
    if (l->e[i].key >= 0) (*off)[l->e[i].key / nnodes + 1]++;
  for (PetscInt k = 0; k < npoints; k++) (*off)[k + 1] += (*off)[k];
  PetscCall(PetscArraycpy(fill, *off, npoints + 1));
  for (size_t i = 0; i < l->cap; i++)
    if (l->e[i].key >= 0) {
      const PetscInt k = (PetscInt)(l->e[i].key / nnodes), z = fill[k]++;
      (*node)[z] = (PetscInt)(l->e[i].key % nnodes);
      (*w)[z]    = l->e[i].w / area[k];
    }
  for (PetscInt k = 0; k < npoints; k++) /* a handful per point: insertion sort */
    for (PetscInt j = (*off)[k] + 1; j < (*off)[k + 1]; j++) {
      const PetscInt  a = (*node)[j];
      const PetscReal b = (*w)[j];
      PetscInt        i = j;
      for (; i > (*off)[k] && (*node)[i - 1] > a; i--) (*node)[i] = (*node)[i - 1], (*w)[i] = (*w)[i - 1];
      (*node)[i] = a, (*w)[i] = b;
    }
  PetscCall(PetscFree(fill));
  PetscFunctionReturn(0);
}

/* Shape functions and area element at reference point (u, v) of [0,1]^2 on master face f:
   bilinear map for a quad4, the collapsed (Duffy) map for a tri3; c: the tangents' cross product. */
static void FacePoint(MBCSurface *m, PetscInt f, PetscReal u, PetscReal v, PetscReal N[], PetscReal x[], PetscReal nrm[], PetscReal *dA, PetscReal c[3])
{
  const PetscInt *fv = &m->fnode[MBC_MAX_FACE_NODES * f];
  PetscReal       dx[2][3] = {{0, 0, 0}, {0, 0, 0}};

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

/* Area of master face f on the coordinates X (m->x0: the reference geometry; a quad by 2 x 2
   Gauss points, exact for a bilinear face's area element to second order). */
static PetscReal FaceArea(const MBCSurface *m, PetscInt f, const PetscReal X[])
{
  const PetscInt *fv = &m->fnode[MBC_MAX_FACE_NODES * f];
  PetscReal       dx[2][3], c[3], a = 0;

  if (m->fnv[f] == 4) {
    const PetscReal g[2] = {0.5 - 0.5 / PetscSqrtReal(3.0), 0.5 + 0.5 / PetscSqrtReal(3.0)};
    for (PetscInt qa = 0; qa < 2; qa++)
      for (PetscInt qb = 0; qb < 2; qb++) {
        const PetscReal u = g[qa], v = g[qb], dNu[4] = {-(1 - v), 1 - v, v, -v}, dNv[4] = {-(1 - u), -u, u, 1 - u};
        for (PetscInt d = 0; d < 3; d++) dx[0][d] = dx[1][d] = 0;
        for (PetscInt i = 0; i < 4; i++)
          for (PetscInt d = 0; d < 3; d++) {
            dx[0][d] += dNu[i] * X[3 * fv[i] + d];
            dx[1][d] += dNv[i] * X[3 * fv[i] + d];
          }
        MBCCross(dx[0], dx[1], c);
        a += 0.25 * PetscSqrtReal(MBCDot(c, c));
      }
    return a;
  }
  for (PetscInt d = 0; d < 3; d++) {
    dx[0][d] = X[3 * fv[1] + d] - X[3 * fv[0] + d];
    dx[1][d] = X[3 * fv[2] + d] - X[3 * fv[0] + d];
  }
  MBCCross(dx[0], dx[1], c);
  return 0.5 * PetscSqrtReal(MBCDot(c, c));
}

/* Dual basis of master face f: psi_i = sum_j C_ij N_j with C = D M^-1, M_ij = int N_i N_j,
   D = diag(int N_i), so that int psi_i N_j = delta_ij int N_j: the master side of a constraint is
   its node alone, and sum_i psi_i = 1. C row-major, MBC_MAX_FACE_NODES wide. */
static PetscErrorCode DualBasis(MBCSurface *m, PetscInt f, PetscInt nq, const PetscReal xq[], const PetscReal wq[], PetscReal C[], PetscReal Dout[])
{
  const PetscInt nv = m->fnv[f];
  PetscReal      M[16] = {0}, D[4] = {0}, Mi[16] = {0};

  PetscFunctionBegin;
  for (PetscInt a = 0; a < nq; a++)
    for (PetscInt b = 0; b < nq; b++) {
      PetscReal N[4], x[3], nrm[3], dA, cr[3];
      FacePoint(m, f, xq[a], xq[b], N, x, nrm, &dA, cr);
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
  for (PetscInt i = 0; i < MBC_MAX_FACE_NODES; i++) Dout[i] = i < nv ? D[i] : 0;
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

/* twice the signed area of the polygon y[0..n) */
static PetscReal PolyArea2(const PetscReal y[][2], PetscInt n)
{
  PetscReal a = 0;
  for (PetscInt i = 0; i < n; i++) a += y[i][0] * y[(i + 1) % n][1] - y[(i + 1) % n][0] * y[i][1];
  return a;
}

#define MBC_MAX_CLIP 16
/* Sutherland-Hodgman: the counter-clockwise polygon y (n vertices) clipped by the convex
   counter-clockwise polygon z (nz vertices), in place. */
static void Clip(PetscReal y[][2], PetscInt *n, const PetscReal z[][2], PetscInt nz)
{
  for (PetscInt e = 0; e < nz && *n > 0; e++) {
    const PetscReal *a = z[e], *b = z[(e + 1) % nz];
    PetscReal        in[MBC_MAX_CLIP][2], s[MBC_MAX_CLIP];
    PetscInt         m = 0;
    for (PetscInt i = 0; i < *n; i++) {
      in[i][0] = y[i][0];
      in[i][1] = y[i][1];
      s[i]     = (b[0] - a[0]) * (y[i][1] - a[1]) - (b[1] - a[1]) * (y[i][0] - a[0]); /* > 0: left of a -> b, inside */
    }
    for (PetscInt i = 0; i < *n; i++) {
      const PetscInt j = (i + 1) % *n;
      if (s[i] >= 0 && m < MBC_MAX_CLIP) {
        y[m][0] = in[i][0];
        y[m][1] = in[i][1];
        m++;
      }
      if (((s[i] >= 0) != (s[j] >= 0)) && m < MBC_MAX_CLIP) {
        const PetscReal t = s[i] / (s[i] - s[j]);
        y[m][0]           = in[i][0] + t * (in[j][0] - in[i][0]);
        y[m][1]           = in[i][1] + t * (in[j][1] - in[i][1]);
        m++;
      }
    }
    *n = m;
  }
}

/* The master face point whose projection on the face plane is y: its shape functions N, position x
   (on the face itself, warped quads too), interpolated unit normal and the ratio of its area
   element to the projected one. Barycentric for a tri3, Newton on the bilinear map for a quad4. */
static void MasterAt(MBCSurface *m, PetscInt f, const MBCFacePlane *P, const PetscReal y[], PetscReal N[], PetscReal x[], PetscReal nrm[], PetscReal *ratio)
{
  PetscReal u = 0.5, v = 0.5, c[3], dA;

  if (m->fnv[f] == 3) {
    const PetscReal(*Y)[2] = P->Y;
    const PetscReal a11 = Y[1][0] - Y[0][0], a12 = Y[2][0] - Y[0][0], a21 = Y[1][1] - Y[0][1], a22 = Y[2][1] - Y[0][1], det = a11 * a22 - a12 * a21;
    const PetscReal r0 = y[0] - Y[0][0], r1 = y[1] - Y[0][1], a = (a22 * r0 - a12 * r1) / det, b = (a11 * r1 - a21 * r0) / det;
    u = a;
    v = a < 1 ? b / (1 - a) : 0; /* FacePoint's collapsed coordinates */
  } else (void)MBCBilinearInverse(P->B, y, &u, &v); /* a convex quad: converges */
  FacePoint(m, f, u, v, N, x, nrm, &dA, c);
  /* area element of the face over that of its projection on the plane */
  *ratio = PetscSqrtReal(MBCDot(c, c)) / PetscAbsReal(MBCDot(c, P->n));
}

static PetscErrorCode FaceListAdd(PetscInt **faces, PetscInt *n, PetscInt *cap, PetscInt g)
{
  PetscFunctionBegin;
  if (*n == *cap) {
    PetscInt *grow;
    *cap = PetscMax(2 * (*cap), 64);
    PetscCall(PetscMalloc1(*cap, &grow));
    if (*n) PetscCall(PetscArraycpy(grow, *faces, *n));
    PetscCall(PetscFree(*faces));
    *faces = grow;
  }
  (*faces)[(*n)++] = g;
  PetscFunctionReturn(0);
}

/* The gap along n from the slave surface's point sum_j W_j x_s[node_j] (a tri6's quadratic point)
   to the master point xm: the gap H^T du moves exactly. */
static PetscReal SlavePointGap(const MBCSurface *s, PetscInt nw, const PetscInt node[], const PetscReal W[], const PetscReal xm[3], const PetscReal n[3])
{
  PetscReal dx[3];

  for (PetscInt d = 0; d < 3; d++) {
    dx[d] = xm[d];
    for (PetscInt j = 0; j < nw; j++) dx[d] -= W[j] * s->x[3 * node[j] + d];
  }
  return MBCDot(dx, n);
}

/* Segment-based (mortar) integration: every master face with a contact point at one of its nodes is
   cut, in its plane, by the orthogonal projections of the slave faces that face it; each piece (a
   convex polygon, master face ∩ slave face) is split into triangles and integrated with a collapsed
   nq x nq Gauss rule, the slave weights taken on that slave face. The integrand is smooth on each
   piece: psi_i times a slave weight, degree 4 in the plane on triangles and flat parallelograms,
   which the collapsed rule integrates exactly from nq = 3 on (degree 2 nq - 2; the Gauss grid over
   the whole master face it replaces missed the weights' kinks by 3.6 % in the pressure of a 2 x 2
   master on a 3 x 3 slave).
   The slave faces of a master face are found by a flood from the faces around its nodes' search
   candidates over the faces that share a vertex with a cut one, so none is missed however fine the
   slave mesh (brute: every slave face, for -mbc_contact_check_search). */
static PetscErrorCode Integrate(MBCCouple *c, PetscBool integrate, PetscInt nq, PetscBool brute, PetscReal area[], PetscReal covered[], PetscReal gsum[], PetscReal nsum[], EntryList *sl, EntryList *mq, PetscReal qmin[])
{
  MBCSurface *m = &c->master, *s = &c->slave;
  PetscInt   *pointOf, *pairOf, *mark, nface = 0, *faces = NULL, maxfaces = 0;
  PetscReal  *xq, *wq, C[MBC_MAX_FACE_NODES * MBC_MAX_FACE_NODES], Dm[MBC_MAX_FACE_NODES];

  PetscFunctionBegin;
  PetscCall(PetscMalloc3(m->nnodes, &pointOf, m->nnodes, &pairOf, s->nfaces + 1, &mark));
  PetscCall(PetscMalloc2(nq, &xq, nq, &wq));
  PetscCall(PetscDTGaussQuadrature(nq, 0.0, 1.0, xq, wq));
  for (PetscInt v = 0; v < m->nnodes; v++) pointOf[v] = pairOf[v] = -1;
  for (PetscInt g = 0; g < s->nfaces; g++) mark[g] = -1;
  for (PetscInt k = 0; k < c->npoints; k++) pointOf[c->points[k].master] = k;
  for (PetscInt i = 0; i < c->npairs; i++) pairOf[c->pairs[i].master] = i;
  for (PetscInt f = 0; f < m->nfaces; f++) {
    const PetscInt *fv = &m->fnode[MBC_MAX_FACE_NODES * f];
    const PetscInt  nv = m->fnv[f];
    const PetscBool quad = (PetscBool)(m->fqnode && m->fqnode[6 * f] >= 0);
    PetscBool       any  = PETSC_FALSE;
    MBCFacePlane    P;
    PetscReal       amaster, rf, mw[MBC_MAX_FACE_NODES][MBC_MAX_WEIGHT_NODES] = {{0}};
    PetscInt        mn[MBC_MAX_WEIGHT_NODES], nmw = 0;

    for (PetscInt i = 0; i < nv; i++) any = (PetscBool)(any || pointOf[fv[i]] >= 0);
    if (!any) continue;
    PetscCall(DualBasis(m, f, nq, xq, wq, C, Dm));
    /* the output's area is the reference one (forces per undeformed area, as the stresses); the
       gap and the projection stay on the current geometry. Per deformed area the plane-strain
       surface's sideways shrinkage put p_max 1 % above Hertz. */
    rf = FaceArea(m, f, m->x0) / FaceArea(m, f, m->x);
    for (PetscInt i = 0; i < nv; i++)
      if (pointOf[fv[i]] >= 0) area[pointOf[fv[i]]] += Dm[i];
    if (!integrate) continue;
    MBCSurfaceFacePlane(m, f, &P);
    amaster = PetscAbsReal(PolyArea2(P.Y, nv));
    if (quad) { /* a tri6's sub-triangle: the point's master side is int psi_i N6_j over its pieces, not its node alone */
      const PetscReal w0[3] = {1, 0, 0};
      PetscReal       W[MBC_MAX_WEIGHT_NODES];
      nmw = MBCSurfaceFaceWeights(m, f, w0, mn, W);
    }
    /* seeds: the slave faces around the search candidates of the face's master nodes and the faces of their points */
    nface = 0;
    if (brute)
      for (PetscInt g = 0; g < s->nfaces; g++) PetscCall(FaceListAdd(&faces, &nface, &maxfaces, g));
    else
      for (PetscInt i = 0; i < nv; i++) {
        const PetscInt pr = pairOf[fv[i]];
        if (pointOf[fv[i]] >= 0 && mark[c->points[pointOf[fv[i]]].face] != f) {
          mark[c->points[pointOf[fv[i]]].face] = f;
          PetscCall(FaceListAdd(&faces, &nface, &maxfaces, c->points[pointOf[fv[i]]].face));
        }
        if (pr < 0) continue;
        for (PetscInt j = 0; j < c->pairs[pr].ncand; j++) {
          const PetscInt node = c->pairs[pr].cand[j];
          for (PetscInt k = s->n2foff[node]; k < s->n2foff[node + 1]; k++)
            if (mark[s->n2f[k]] != f) {
              mark[s->n2f[k]] = f;
              PetscCall(FaceListAdd(&faces, &nface, &maxfaces, s->n2f[k]));
            }
        }
      }
    for (PetscInt q = 0; q < nface; q++) {
      const PetscInt  g = faces[q], ng = s->fnv[g], *gv = &s->fnode[MBC_MAX_FACE_NODES * g];
      PetscReal       Z[MBC_MAX_FACE_NODES][2], W[MBC_MAX_CLIP][2], e[3], apiece, sw[MBC_MAX_FACE_NODES][MBC_MAX_WEIGHT_NODES];
      PetscBool       hit[MBC_MAX_FACE_NODES][MBC_MAX_WEIGHT_NODES];
      PetscInt        nw = nv, gn[MBC_MAX_WEIGHT_NODES], ngw;
      MBCFacePlane    Pg;

      if (!(MBCDot(&s->fnormal[3 * g], P.n) < 0)) continue; /* the slave face must face the master face */
      MBCSub(&s->fcenter[3 * g], P.c, e);
      if (PetscAbsReal(MBCDot(e, P.n)) > 2 * c->h) continue; /* a face of the slave surface far behind or ahead */
      for (PetscInt i = 0; i < ng; i++) MBCFacePlaneCoords(&P, &s->x[3 * gv[ng - 1 - i]], Z[i]); /* reversed: counter-clockwise seen along -n */
      if (!(PolyArea2(Z, ng) > 1e-12 * amaster)) continue;                         /* edge-on */
      for (PetscInt i = 0; i < nv; i++) W[i][0] = P.Y[i][0], W[i][1] = P.Y[i][1];
      Clip(W, &nw, Z, ng);
      apiece = nw >= 3 ? PolyArea2(W, nw) : 0;
      /* no overlap, or a sliver along a shared edge: below 1e-6 of the face it changes the
         constraint by less than that, and keeping it would add and drop slave nodes (a rebuild of
         D) as the sliver comes and goes with rounding and vibration */
      if (!(apiece > 1e-6 * amaster)) continue;
      if (!brute)
        for (PetscInt i = 0; i < ng; i++) /* flood: the faces around the vertices of a face that cuts this one */
          for (PetscInt k = s->n2foff[gv[i]]; k < s->n2foff[gv[i] + 1]; k++)
            if (mark[s->n2f[k]] != f) {
              mark[s->n2f[k]] = f;
              PetscCall(FaceListAdd(&faces, &nface, &maxfaces, s->n2f[k]));
            }
      /* triangles (G, Wt, Wt+1) from the piece's area centroid G: the same triangles whatever
         vertex the clipping starts from and whether it doubles a vertex on an edge, both a matter
         of rounding. The integrand (the gap along the interpolated normal, clamped weights) is
         not a polynomial, so a fan from W0 made the integrated gap depend on that rounding: an
         open point 0.63 mm off (Hertz, 4 ranks) moved by 1.7e-4 between runs. */
      PetscReal G[2] = {0, 0}, g2 = 0;
      for (PetscInt t = 0; t < nw; t++) {
        const PetscReal *p0 = W[t], *p1 = W[(t + 1) % nw], cr = p0[0] * p1[1] - p1[0] * p0[1];
        g2 += cr, G[0] += (p0[0] + p1[0]) * cr, G[1] += (p0[1] + p1[1]) * cr;
      }
      G[0] /= 3 * g2, G[1] /= 3 * g2;
      /* the slave weights of the piece summed here, entered once per (point, slave node) */
      MBCSurfaceFacePlane(s, g, &Pg);
      {
        const PetscReal w0[MBC_MAX_FACE_NODES] = {1, 0, 0, 0};
        PetscReal       Wg[MBC_MAX_WEIGHT_NODES];
        ngw = MBCSurfaceFaceWeights(s, g, w0, gn, Wg); /* the slave nodes the piece's weights reach */
      }
      for (PetscInt i = 0; i < nv; i++)
        for (PetscInt j = 0; j < ngw; j++) sw[i][j] = 0, hit[i][j] = PETSC_FALSE;
      for (PetscInt t = 0; t < nw; t++) {
        const PetscReal *w0 = W[t], *w1 = W[(t + 1) % nw];
        const PetscReal  a2 = (w0[0] - G[0]) * (w1[1] - G[1]) - (w1[0] - G[0]) * (w0[1] - G[1]);
        for (PetscInt a = 0; a < nq; a++)
          for (PetscInt b = 0; b < nq; b++) {
            const PetscReal ua = xq[a], vb = xq[b] * (1 - xq[a]);
            PetscReal       y[2], N[4], psi[4], x[3], nrm[3], ratio, dA, qual, Ws[MBC_MAX_WEIGHT_NODES], Wm[MBC_MAX_WEIGHT_NODES];
            PetscInt        ns[MBC_MAX_WEIGHT_NODES];
            MBCContactPoint cp;
            for (PetscInt d = 0; d < 2; d++) y[d] = G[d] + ua * (w0[d] - G[d]) + vb * (w1[d] - G[d]);
            MasterAt(m, f, &P, y, N, x, nrm, &ratio);
            dA = wq[a] * wq[b] * (1 - xq[a]) * a2 * ratio;
            if (!MBCCoupleProjectOnFacePlane(c, x, nrm, g, &Pg, PETSC_TRUE, &cp, &qual)) continue;
            (void)MBCSurfaceFaceWeights(s, g, cp.w, ns, Ws);
            if (quad) (void)MBCSurfaceFaceWeights(m, f, N, mn, Wm);
            if (quad || ngw == 6) { /* the gap between the quadratic faces' points the weights give */
              PetscReal xm[3];
              for (PetscInt d = 0; d < 3; d++) {
                xm[d] = quad ? 0 : x[d];
                for (PetscInt j = 0; j < nmw; j++) xm[d] += Wm[j] * m->x[3 * mn[j] + d];
              }
              cp.gap = SlavePointGap(s, ngw, ns, Ws, xm, cp.n);
            }
            for (PetscInt i = 0; i < nv; i++) {
              psi[i] = 0;
              for (PetscInt j = 0; j < nv; j++) psi[i] += C[MBC_MAX_FACE_NODES * i + j] * N[j];
            }
            for (PetscInt i = 0; i < nv; i++) {
              const PetscInt k = pointOf[fv[i]];
              if (k < 0) continue;
              if (qmin && N[i] > 0) qmin[k] = PetscMin(qmin[k], cp.gap);
              nsum[k] += N[i] * dA * rf; /* reference area */
              covered[k] += psi[i] * dA;
              gsum[k] += psi[i] * dA * cp.gap;
              for (PetscInt j = 0; j < ngw; j++)
                if (Ws[j] != 0) sw[i][j] += psi[i] * Ws[j] * dA, hit[i][j] = PETSC_TRUE;
              for (PetscInt j = 0; j < nmw; j++) mw[i][j] += psi[i] * Wm[j] * dA;
            }
          }
      }
      for (PetscInt i = 0; i < nv; i++)
        for (PetscInt j = 0; j < ngw; j++)
          if (hit[i][j]) PetscCall(EntryAdd(sl, (PetscInt64)pointOf[fv[i]] * s->nnodes + gn[j], sw[i][j]));
    }
    for (PetscInt i = 0; i < nv && mq; i++)
      if (pointOf[fv[i]] >= 0)
        for (PetscInt j = 0; j < nmw; j++)
          if (mw[i][j] != 0) PetscCall(EntryAdd(mq, (PetscInt64)pointOf[fv[i]] * m->nnodes + mn[j], mw[i][j]));
  }
  PetscCall(PetscFree(faces));
  PetscCall(PetscFree2(xq, wq));
  PetscCall(PetscFree3(pointOf, pairOf, mark));
  PetscFunctionReturn(0);
}

/* A point whose share of the surface is mostly uncovered (the dual weights lose their meaning
   there) keeps the collocation at its node. */
static inline PetscBool PointIntegrated(PetscReal covered, PetscReal area)
{
  return (PetscBool)(covered >= 0.25 * area && area > 0);
}

PetscErrorCode MBCCoupleIntegrate(MBCCouple *c, PetscBool integrate, PetscInt nq)
{
  MBCSurface *m = &c->master, *s = &c->slave;
  PetscReal  *area, *covered, *nsum, *gsum;
  PetscBool  *quad;
  EntryList   ml = {NULL, 0, 0}, sl = {NULL, 0, 0}, mq = {NULL, 0, 0};

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_ContactIntegrate, 0, 0, 0, 0));
  PetscCall(MBCCoupleIntegrateReset(c));
  PetscCall(PetscCalloc4(c->npoints + 1, &area, c->npoints + 1, &covered, c->npoints + 1, &gsum, c->npoints + 1, &nsum));
  PetscCall(Integrate(c, integrate, nq, PETSC_FALSE, area, covered, gsum, nsum, &sl, &mq, NULL));
  /* a point kept at its node (PointIntegrated): its integrated entries are dropped */
  for (size_t e = 0; e < sl.cap; e++) {
    const PetscInt k = sl.e[e].key < 0 ? -1 : (PetscInt)(sl.e[e].key / s->nnodes);
    if (k >= 0 && !PointIntegrated(covered[k], area[k])) sl.e[e].w = 0;
  }
  /* a tri6's point: its master side is the quadratic face's (the entries sum to covered[k]) */
  PetscCall(PetscCalloc1(c->npoints + 1, &quad));
  for (size_t e = 0; e < mq.cap; e++) {
    const PetscInt k = mq.e[e].key < 0 ? -1 : (PetscInt)(mq.e[e].key / m->nnodes);
    if (k < 0 || !PointIntegrated(covered[k], area[k])) continue;
    quad[k] = PETSC_TRUE;
    PetscCall(EntryAdd(&ml, mq.e[e].key, mq.e[e].w));
  }
  for (PetscInt k = 0; k < c->npoints; k++) { /* master side: the node alone (dual basis) */
    MBCContactPoint *p = &c->points[k];
    const PetscBool  integrated = PointIntegrated(covered[k], area[k]);
    p->area                     = nsum[k] > 0 ? nsum[k] : area[k];
    if (!quad[k]) PetscCall(EntryAdd(&ml, (PetscInt64)k * m->nnodes + p->master, integrated ? covered[k] : area[k]));
    if (integrated) continue;
    covered[k] = area[k];
    { /* at the node: the slave weights at its projection (a tri6's quadratic ones, the gap to that point) */
      PetscInt  wn[MBC_MAX_WEIGHT_NODES];
      PetscReal W[MBC_MAX_WEIGHT_NODES], gap = p->gap;
      const PetscInt nw = MBCSurfaceFaceWeights(s, p->face, p->w, wn, W);
      if (nw == 6) gap = SlavePointGap(s, nw, wn, W, &m->x[3 * p->master], p->n);
      for (PetscInt j = 0; j < nw; j++) PetscCall(EntryAdd(&sl, (PetscInt64)k * s->nnodes + wn[j], W[j] * area[k]));
      gsum[k] = gap * area[k];
    }
  }
  for (PetscInt k = 0; k < c->npoints; k++) PetscCheck(covered[k] > 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Contact point %" PetscInt_FMT " of couple %" PetscInt_FMT " has no area", k, c->k);
  PetscCall(EntryCSR(&ml, c->npoints, m->nnodes, covered, &c->moff, &c->mnode, &c->mw));
  PetscCall(EntryCSR(&sl, c->npoints, s->nnodes, covered, &c->soff, &c->snode, &c->sw));
  PetscCall(PetscMalloc1(c->npoints + 1, &c->igap));
  for (PetscInt k = 0; k < c->npoints; k++) c->igap[k] = gsum[k] / covered[k];
  PetscCall(PetscFree(ml.e));
  PetscCall(PetscFree(sl.e));
  PetscCall(PetscFree(mq.e));
  PetscCall(PetscFree(quad));
  PetscCall(PetscFree4(area, covered, gsum, nsum));
  PetscCall(PetscLogEventEnd(MBC_ContactIntegrate, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* -mbc_contact_check_search: the integration again over every slave face; *missed is the first
   point whose covered share differs from the flood's by more than 1e-9 of its share (-1 if none). */
PetscErrorCode MBCCoupleCheckIntegrate(MBCCouple *c, PetscInt nq, PetscInt *missed, PetscReal *flood, PetscReal *brute)
{
  PetscReal *area, *covered, *nsum, *gsum, *area2, *covered2, *nsum2, *gsum2;
  EntryList  sl = {NULL, 0, 0}, sl2 = {NULL, 0, 0};

  PetscFunctionBegin;
  *missed = -1;
  PetscCall(PetscCalloc4(c->npoints + 1, &area, c->npoints + 1, &covered, c->npoints + 1, &gsum, c->npoints + 1, &nsum));
  PetscCall(PetscCalloc4(c->npoints + 1, &area2, c->npoints + 1, &covered2, c->npoints + 1, &gsum2, c->npoints + 1, &nsum2));
  PetscCall(Integrate(c, PETSC_TRUE, nq, PETSC_FALSE, area, covered, gsum, nsum, &sl, NULL, NULL));
  PetscCall(Integrate(c, PETSC_TRUE, nq, PETSC_TRUE, area2, covered2, gsum2, nsum2, &sl2, NULL, NULL));
  for (PetscInt k = 0; k < c->npoints && *missed < 0; k++)
    if (PetscAbsReal(covered[k] - covered2[k]) > 1e-9 * area[k]) {
      *missed = k;
      *flood  = covered[k] / area[k];
      *brute  = covered2[k] / area[k];
    }
  PetscCall(PetscFree(sl.e));
  PetscCall(PetscFree(sl2.e));
  PetscCall(PetscFree4(area, covered, gsum, nsum));
  PetscCall(PetscFree4(area2, covered2, gsum2, nsum2));
  PetscFunctionReturn(0);
}

/* The initial-interference check (contact.c): per point, the deepest interpenetration of the two
   faceted surfaces over its master node's faces, *qmin[k] = min(node-to-face gap, mortar gap, the
   gap at every mortar quadrature point of the faces around the node), whatever
   -mbc_contact_integrate. Two independently meshed polygons inscribed in one circle cross each
   other between their vertices: the node and mortar gaps may both read open (the convex side as
   slave) while the facets interpenetrate by a fraction of their sagitta
   (docs/stability.md). */
PetscErrorCode MBCCoupleInterference(MBCCouple *c, PetscInt nq, PetscReal qmin[])
{
  PetscReal *area, *covered, *nsum, *gsum;
  EntryList  sl = {NULL, 0, 0};

  PetscFunctionBegin;
  PetscCall(PetscCalloc4(c->npoints + 1, &area, c->npoints + 1, &covered, c->npoints + 1, &gsum, c->npoints + 1, &nsum));
  for (PetscInt k = 0; k < c->npoints; k++) qmin[k] = c->points[k].gap;
  PetscCall(Integrate(c, PETSC_TRUE, nq, PETSC_FALSE, area, covered, gsum, nsum, &sl, NULL, qmin));
  for (PetscInt k = 0; k < c->npoints; k++)
    if (PointIntegrated(covered[k], area[k])) qmin[k] = PetscMin(qmin[k], gsum[k] / covered[k]);
  PetscCall(PetscFree(sl.e));
  PetscCall(PetscFree4(area, covered, gsum, nsum));
  PetscFunctionReturn(0);
}
