/* Hydrostatic pressure on a surface: p = unit_weight (level - x_axis) below the level, 0 above,
   acting against the outward normal (pushing into the body), integrated face by face with the
   wet part of each face cut out, so a face crossed by the water level carries exactly its wet
   share (docs/scene.md, kind "hydrostatic").

   quad4: the face is the bilinear map of [-1, 1]^2. For fixed xi the depth is linear in eta, so
   the wet eta-range is [-1, eta*] or [eta*, 1] and the integrand p N_i (x_xi x x_eta) is a cubic
   in eta: 2 Gauss points on the wet range are exact. Over xi the range splits where the level
   crosses the edges eta = -1 and eta = 1; 4 Gauss points per piece integrate exactly when the
   depth is affine in (xi, eta) (any parallelogram, or a face whose level direction varies along
   one parametric direction: every structured-mesh face), and to high order otherwise.
   tri3: the depth is linear, the wet part a polygon cut in the reference triangle, fanned into
   triangles with the edge-midpoint rule (exact: the integrand is quadratic). */
#include <mbc/private/bodyimpl.h>

#define HYD_MAX_BREAKS 4

static const PetscReal gauss2_x[2] = {-0.57735026918962576451, 0.57735026918962576451};
static const PetscReal gauss2_w[2] = {1.0, 1.0};
static const PetscReal gauss4_x[4] = {-0.86113631159405257522, -0.33998104358485626480, 0.33998104358485626480, 0.86113631159405257522};
static const PetscReal gauss4_w[4] = {0.34785484513745385737, 0.65214515486254614263, 0.65214515486254614263, 0.34785484513745385737};

/* Adds the consistent nodal forces of the hydrostatic pressure on one quad (vertices X,
   counter-clockwise seen from outside; d = depth at each vertex) to f[4][3]. */
static void QuadHydrostatic(const PetscReal X[4][3], const PetscReal d[4], PetscReal gamma, PetscReal f[4][3])
{
  static const PetscReal sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  PetscReal              brk[HYD_MAX_BREAKS] = {-1, 1, 0, 0};
  PetscInt               nbrk = 2;

  /* xi where the level crosses the edge eta = -1 (vertices 0, 1) and eta = +1 (vertices 3, 2) */
  {
    const PetscReal da[2] = {d[0], d[3]}, db[2] = {d[1], d[2]};
    for (PetscInt e = 0; e < 2; e++)
      if ((da[e] > 0 && db[e] < 0) || (da[e] < 0 && db[e] > 0)) brk[nbrk++] = (da[e] + db[e]) / (da[e] - db[e]);
  }
  for (PetscInt i = 1; i < nbrk; i++) /* sort the few break points */
    for (PetscInt j = i; j > 0 && brk[j] < brk[j - 1]; j--) {
      PetscReal t = brk[j];
      brk[j]      = brk[j - 1];
      brk[j - 1]  = t;
    }
  for (PetscInt s = 0; s + 1 < nbrk; s++) {
    const PetscReal a = brk[s], b = brk[s + 1];
    if (!(b > a)) continue;
    for (PetscInt qx = 0; qx < 4; qx++) {
      const PetscReal xi = 0.5 * (a + b) + 0.5 * (b - a) * gauss4_x[qx], wx = 0.5 * (b - a) * gauss4_w[qx];
      const PetscReal dm = 0.5 * (1 - xi) * d[0] + 0.5 * (1 + xi) * d[1]; /* depth at eta = -1 */
      const PetscReal dp = 0.5 * (1 - xi) * d[3] + 0.5 * (1 + xi) * d[2]; /* depth at eta = +1 */
      PetscReal       lo, hi;

      if (dm <= 0 && dp <= 0) continue;
      if (dm > 0 && dp > 0) lo = -1, hi = 1;
      else {
        const PetscReal eta = -1 + 2 * dm / (dm - dp);
        if (dm > 0) lo = -1, hi = eta;
        else lo = eta, hi = 1;
      }
      for (PetscInt qy = 0; qy < 2; qy++) {
        const PetscReal eta = 0.5 * (lo + hi) + 0.5 * (hi - lo) * gauss2_x[qy], w = wx * 0.5 * (hi - lo) * gauss2_w[qy];
        PetscReal       N[4], dxi[3] = {0, 0, 0}, deta[3] = {0, 0, 0}, nA[3], p = 0;
        for (PetscInt v = 0; v < 4; v++) {
          N[v] = 0.25 * (1 + sx[v] * xi) * (1 + sy[v] * eta);
          p += N[v] * d[v];
          for (PetscInt c = 0; c < 3; c++) {
            dxi[c] += 0.25 * sx[v] * (1 + sy[v] * eta) * X[v][c];
            deta[c] += 0.25 * sy[v] * (1 + sx[v] * xi) * X[v][c];
          }
        }
        if (p <= 0) continue; /* rounding at the cut */
        nA[0] = dxi[1] * deta[2] - dxi[2] * deta[1];
        nA[1] = dxi[2] * deta[0] - dxi[0] * deta[2];
        nA[2] = dxi[0] * deta[1] - dxi[1] * deta[0];
        for (PetscInt v = 0; v < 4; v++)
          for (PetscInt c = 0; c < 3; c++) f[v][c] -= w * gamma * p * N[v] * nA[c];
      }
    }
  }
}

/* The same for a triangle: the wet polygon in reference coordinates (at most 4 vertices). */
static void TriHydrostatic(const PetscReal X[3][3], const PetscReal d[3], PetscReal gamma, PetscReal f[3][3])
{
  const PetscReal ref[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  PetscReal       poly[4][3], nA[3], e1[3], e2[3]; /* (xi, eta, depth) */
  PetscInt        np = 0;

  for (PetscInt v = 0; v < 3; v++) { /* Sutherland-Hodgman against depth > 0 */
    const PetscInt w = (v + 1) % 3;
    if (d[v] > 0) {
      poly[np][0] = ref[v][0], poly[np][1] = ref[v][1], poly[np][2] = d[v];
      np++;
    }
    if ((d[v] > 0 && d[w] < 0) || (d[v] < 0 && d[w] > 0)) {
      const PetscReal t = d[v] / (d[v] - d[w]);
      poly[np][0] = ref[v][0] + t * (ref[w][0] - ref[v][0]);
      poly[np][1] = ref[v][1] + t * (ref[w][1] - ref[v][1]);
      poly[np][2] = 0;
      np++;
    }
  }
  if (np < 3) return;
  for (PetscInt c = 0; c < 3; c++) e1[c] = X[1][c] - X[0][c], e2[c] = X[2][c] - X[0][c];
  nA[0] = e1[1] * e2[2] - e1[2] * e2[1]; /* twice the area times the unit normal: the map's Jacobian */
  nA[1] = e1[2] * e2[0] - e1[0] * e2[2];
  nA[2] = e1[0] * e2[1] - e1[1] * e2[0];
  for (PetscInt t = 1; t + 1 < np; t++) {
    const PetscReal *A = poly[0], *B = poly[t], *C = poly[t + 1];
    const PetscReal  area = 0.5 * PetscAbsReal((B[0] - A[0]) * (C[1] - A[1]) - (C[0] - A[0]) * (B[1] - A[1]));
    for (PetscInt m = 0; m < 3; m++) { /* edge midpoints, weight area / 3 each */
      const PetscReal *P = m == 0 ? A : (m == 1 ? B : C), *Q = m == 0 ? B : (m == 1 ? C : A);
      const PetscReal  xi = 0.5 * (P[0] + Q[0]), eta = 0.5 * (P[1] + Q[1]), p = 0.5 * (P[2] + Q[2]);
      const PetscReal  N[3] = {1 - xi - eta, xi, eta};
      for (PetscInt v = 0; v < 3; v++)
        for (PetscInt c = 0; c < 3; c++) f[v][c] -= area / 3 * gamma * p * N[v] * nA[c];
    }
  }
}

/* a hydrostatic load's forces on one face (its vertices: a tet10's midside nodes carry none of
   this linear load's); none where it is dry */
static PetscErrorCode HydrostaticForces(MBCBody body, PetscInt face, const PetscScalar x[], void *ctx, PetscInt vert[6], PetscReal f[6][3], PetscInt *n)
{
  const MBCLoadDesc *load = (const MBCLoadDesc *)ctx;
  PetscInt           nv;
  PetscReal          X[4][3], d[4], nrm[3], dmax = 0;
  char               what[MBC_NAME_LEN + 48];

  PetscFunctionBegin;
  *n = 0;
  PetscCall(PetscSNPrintf(what, sizeof(what), "hydrostatic load on surface '%s'", load->surface));
  PetscCall(MBCBodyFaceCorners(body, face, x, what, vert, X, &nv, nrm));
  for (PetscInt v = 0; v < nv; v++) {
    d[v] = load->level - X[v][load->axis];
    dmax = PetscMax(dmax, d[v]);
  }
  if (dmax <= 0) PetscFunctionReturn(0); /* dry face */
  if (nv == 4) QuadHydrostatic((const PetscReal(*)[3])X, d, load->unit_weight, f);
  else TriHydrostatic((const PetscReal(*)[3])X, d, load->unit_weight, f);
  *n = nv;
  PetscFunctionReturn(0);
}

/* F = the load vector of a hydrostatic load for a unit time factor (docs/scene.md). */
PetscErrorCode MBCBodyAssembleHydrostatic(MBCBody body, MBCLoadDesc *load, Vec F)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyAssembleFaces(body, load->surface_id, HydrostaticForces, load, F));
  PetscFunctionReturn(0);
}
