/* Uplift on a couple's faces (docs/scene.md, couples' `uplift`; docs/dam.md, Uplift): the water
   pressure in a joint, on both of its faces, as consistent nodal loads on the bodies' right-hand
   sides. Along s = (x - origin) . direction, 0 <= s <= L (0 outside: the joint ends there):

   - the heel-to-toe law (USACE EM 1110-2-2200, FERC chapter III, CADAM): heads H1 at the heel,
     H2 (tail water) at the toe, linear between; with a drain line at s = X of efficiency E the
     head there is H3 = H2 + (1 - E)(H1 - H2)(L - X)/(L - s0), linear H1 -> H3 -> H2;
   - or a table p(s), linear between its rows and constant beyond its ends;
   - with penetration, the wet length w (solveruplift.c: the joint open from the heel up to its
     first closed point) carries the reservoir's pressure at its depth, unit_weight (level - x_axis),
     and the law starts at s0 = w with H1 (the crack's tip takes the heel's head; past the drains
     they no longer act: H1 -> H2 linear), as the cracked-base analysis of USACE and FERC. The
     wet length is per zone, the master bodies' ranges across the direction (a monolith's base).

   Across the direction the pressure acts where the master faces are (the prep's lateral range), so
   a foundation's slave surface reaching beyond the footprint is loaded only under the joint.
   The field is piecewise linear in s with jumps at the joint's ends: each face is cut at them
   exactly (UpliftFace), so the two sides' meshes need not match and still carry equal and
   opposite resultants. */
#include <mbc/private/bodyimpl.h>


/* The law's head along s from s0 (the heel, or the wet length's end). */
static PetscReal UpliftLawHead(const MBCUpliftDesc *u, PetscReal s0, PetscReal s)
{
  const PetscReal H1 = u->heel_head, H2 = u->tail_head, L = u->length;

  if (s <= s0) return H1;
  if (s0 >= L) return H1;
  if (u->drain > s0 && u->drain < L) {
    const PetscReal X = u->drain, H3 = H2 + (1 - u->efficiency) * (H1 - H2) * (L - X) / (L - s0);
    if (s <= X) return H1 + (H3 - H1) * (s - s0) / (X - s0);
    return H3 + (H2 - H3) * (s - X) / (L - X);
  }
  return H1 + (H2 - H1) * (s - s0) / (L - s0);
}

/* The uplift pressure at x in the piece between break points whose mean position is sp: the wet
   part or the law is the piece's, not decided by the rounding of a point's s at its border. */
static PetscReal UpliftPiecePressure(const MBCUpliftDesc *u, PetscReal w, const PetscReal x[3], PetscReal sp)
{
  const PetscReal s = MBCUpliftAlong(u, u->direction, x);

  if (u->penetration && sp < w) return u->unit_weight * PetscMax(u->level - x[u->axis], 0);
  if (u->ntable > 0) {
    const PetscReal *T = u->table;
    const PetscInt   n = u->ntable;
    if (s <= T[0]) return T[1];
    if (s >= T[2 * (n - 1)]) return T[2 * n - 1];
    for (PetscInt r = 1; r < n; r++)
      if (s <= T[2 * r]) return T[2 * r - 1] + (T[2 * r + 1] - T[2 * r - 1]) * (s - T[2 * r - 2]) / (T[2 * r] - T[2 * r - 2]);
  }
  return u->unit_weight * PetscMax(UpliftLawHead(u, u->penetration ? PetscMin(w, u->length) : 0, s), 0);
}

/* The uplift pressure at x, the wet lengths w[] from the heel per zone (0 off the joint and
   between the zones). */
PetscReal MBCUpliftPressure(const MBCUpliftDesc *u, const PetscReal w[], const PetscReal x[3])
{
  const PetscReal s = MBCUpliftAlong(u, u->direction, x);
  const PetscReal y = MBCUpliftAlong(u, u->lateral, x);

  if (s < 0 || s > u->length) return 0;
  for (PetscInt z = 0; z < u->nzones; z++)
    if (y >= u->zones[2 * z] && y <= u->zones[2 * z + 1]) return UpliftPiecePressure(u, w[z], x, s);
  return 0;
}

#define UPLIFT_MAX_POLY 16

/* Clips the polygon P (n vertices (xi, eta, s, y)) to sign (v[c] - b) >= 0, c = 2 (s) or 3 (y);
   new vertices by linear interpolation along the edges (exact where s and y are affine in the
   reference coordinates: triangles and parallelograms). */
static PetscInt UpliftClip(PetscReal P[][4], PetscInt n, PetscInt c, PetscReal b, PetscReal sign)
{
  PetscReal Q[UPLIFT_MAX_POLY][4];
  PetscInt  m = 0;

  for (PetscInt i = 0; i < n; i++) {
    const PetscReal *A = P[i], *B = P[(i + 1) % n], da = sign * (A[c] - b), db = sign * (B[c] - b);
    if (da >= 0 && m < UPLIFT_MAX_POLY) {
      for (PetscInt k = 0; k < 4; k++) Q[m][k] = A[k];
      m++;
    }
    if (((da > 0 && db < 0) || (da < 0 && db > 0)) && m < UPLIFT_MAX_POLY) {
      const PetscReal t = da / (da - db);
      for (PetscInt k = 0; k < 4; k++) Q[m][k] = A[k] + t * (B[k] - A[k]);
      m++;
    }
  }
  for (PetscInt i = 0; i < m; i++)
    for (PetscInt k = 0; k < 4; k++) P[i][k] = Q[i][k];
  return m;
}

/* Adds the nodal forces of the uplift on one face (nv nodes X, nc corners, outward winding) to f,
   and the face's share of int p dA and int p x dA to r[4]. The reference face is cut exactly at
   the field's kinks and jumps (the joint's ends along s and across it, the wet length, the drain
   line, the table's rows) into polygons on which p is linear, each fanned into triangles with a
   7-point rule of degree 5 (Dunavant): exact on triangles and parallelograms. */
static void UpliftFace(const MBCUpliftDesc *u, const PetscReal wz[], PetscInt nv, const PetscReal X[6][3], PetscInt nc, PetscReal f[6][3], PetscReal r[4])
{
  static const PetscReal q[7][4] = { /* barycentric a, b, c and weight */
    {1.0 / 3,           1.0 / 3,           1.0 / 3,           0.225            },
    {0.059715871789770, 0.470142064105115, 0.470142064105115, 0.132394152788506},
    {0.470142064105115, 0.059715871789770, 0.470142064105115, 0.132394152788506},
    {0.470142064105115, 0.470142064105115, 0.059715871789770, 0.132394152788506},
    {0.797426985353087, 0.101286507323456, 0.101286507323456, 0.125939180544827},
    {0.101286507323456, 0.797426985353087, 0.101286507323456, 0.125939180544827},
    {0.101286507323456, 0.101286507323456, 0.797426985353087, 0.125939180544827}
  };
  static const PetscReal sq[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}, tr[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  PetscReal              C[4][4], ymin = PETSC_MAX_REAL, ymax = PETSC_MIN_REAL;

  for (PetscInt i = 0; i < nc; i++) { /* the corners: reference coordinates, s and lateral y */
    PetscReal N[6], dN[6][2], x[3] = {0, 0, 0};
    C[i][0] = nc == 4 ? sq[i][0] : tr[i][0], C[i][1] = nc == 4 ? sq[i][1] : tr[i][1];
    MBCFaceShape(nv, C[i][0], C[i][1], N, dN);
    for (PetscInt j = 0; j < nv; j++)
      for (PetscInt c = 0; c < 3; c++) x[c] += N[j] * X[j][c];
    C[i][2] = MBCUpliftAlong(u, u->direction, x);
    C[i][3] = MBCUpliftAlong(u, u->lateral, x);
    ymin = PetscMin(ymin, C[i][3]), ymax = PetscMax(ymax, C[i][3]);
  }
  for (PetscInt z = 0; z < u->nzones; z++) { /* each zone with its wet length */
    const PetscReal w = wz[z], ylo = u->zones[2 * z], yhi = u->zones[2 * z + 1];
    PetscReal       brk[72];
    PetscInt        nbrk = 0;
    if (ymax < ylo || ymin > yhi) continue;
    brk[nbrk++] = 0;
    if (u->penetration && w > 0 && w < u->length) brk[nbrk++] = w;
    if (u->drain > 0 && u->drain < u->length) brk[nbrk++] = u->drain;
    for (PetscInt k = 0; k < u->ntable && nbrk < 71; k++)
      if (u->table[2 * k] > 0 && u->table[2 * k] < u->length) brk[nbrk++] = u->table[2 * k];
    brk[nbrk++] = u->length;
    for (PetscInt i = 1; i < nbrk; i++) /* sort the few break points */
      for (PetscInt j = i; j > 0 && brk[j] < brk[j - 1]; j--) {
        PetscReal t = brk[j];
        brk[j] = brk[j - 1], brk[j - 1] = t;
      }
    for (PetscInt k = 0; k + 1 < nbrk; k++) {
      PetscReal P[UPLIFT_MAX_POLY][4];
      PetscInt  n = nc;
      if (!(brk[k + 1] > brk[k])) continue;
      for (PetscInt i = 0; i < nc; i++)
        for (PetscInt c = 0; c < 4; c++) P[i][c] = C[i][c];
      n = UpliftClip(P, n, 2, brk[k], 1);
      if (n >= 3) n = UpliftClip(P, n, 2, brk[k + 1], -1);
      if (n >= 3) n = UpliftClip(P, n, 3, ylo, 1);
      if (n >= 3) n = UpliftClip(P, n, 3, yhi, -1);
      for (PetscInt t = 1; t + 1 < n; t++) {
        const PetscReal *A = P[0], *B = P[t], *D = P[t + 1];
        const PetscReal  area = 0.5 * PetscAbsReal((B[0] - A[0]) * (D[1] - A[1]) - (D[0] - A[0]) * (B[1] - A[1]));
        if (area == 0) continue;
        for (PetscInt g = 0; g < 7; g++) {
          const PetscReal a = q[g][0] * A[0] + q[g][1] * B[0] + q[g][2] * D[0], b = q[g][0] * A[1] + q[g][1] * B[1] + q[g][2] * D[1];
          PetscReal       N[6], xa[3], xb[3], x[3], nA[3], p, dA, wq;
          MBCFaceMap(nv, X, a, b, N, x, xa, xb);
          p = UpliftPiecePressure(u, w, x, 0.5 * (brk[k] + brk[k + 1]));
          if (p == 0) continue;
          nA[0] = xa[1] * xb[2] - xa[2] * xb[1];
          nA[1] = xa[2] * xb[0] - xa[0] * xb[2];
          nA[2] = xa[0] * xb[1] - xa[1] * xb[0];
          dA    = PetscSqrtReal(nA[0] * nA[0] + nA[1] * nA[1] + nA[2] * nA[2]);
          wq    = q[g][3] * area;
          for (PetscInt i = 0; i < nv; i++)
            for (PetscInt c = 0; c < 3; c++) f[i][c] -= wq * p * N[i] * nA[c];
          r[0] += wq * p * dA;
          for (PetscInt c = 0; c < 3; c++) r[1 + c] += wq * p * dA * x[c];
        }
      }
    }
  }
}

typedef struct {
  const MBCUpliftDesc *u;
  const PetscReal     *w;
  PetscReal           *r;
} UpliftCtx;

/* an uplift's forces on one face: none where the face lies off the joint along or across it */
static PetscErrorCode UpliftForces(MBCBody body, PetscInt face, const PetscScalar x[], void *ctx, PetscInt pts[6], PetscReal f[6][3], PetscInt *n)
{
  const UpliftCtx     *uc = (const UpliftCtx *)ctx;
  const MBCUpliftDesc *u  = uc->u;
  PetscInt             nv, nc;
  PetscReal            X[6][3], smin = PETSC_MAX_REAL, smax = PETSC_MIN_REAL, ymin = PETSC_MAX_REAL, ymax = PETSC_MIN_REAL;

  PetscFunctionBegin;
  *n = 0;
  PetscCall(MBCBodyFaceNodes(body, face, x, pts, X, &nv, &nc));
  for (PetscInt v = 0; v < nv; v++) {
    const PetscReal s = MBCUpliftAlong(u, u->direction, X[v]);
    const PetscReal y = MBCUpliftAlong(u, u->lateral, X[v]);
    smin = PetscMin(smin, s), smax = PetscMax(smax, s);
    ymin = PetscMin(ymin, y), ymax = PetscMax(ymax, y);
  }
  if (smax < 0 || smin > u->length || ymax < u->lateral[3] || ymin > u->lateral[4]) PetscFunctionReturn(0);
  UpliftFace(u, uc->w, nv, (const PetscReal(*)[3])X, nc, f, uc->r);
  *n = nv;
  PetscFunctionReturn(0);
}

/* F: the nodal forces of an uplift load for a unit time factor at the wet lengths w[] (per zone);
   r[4] (this rank's owned faces): int p dA and int p x dA over the load's faces. */
PetscErrorCode MBCBodyAssembleUplift(MBCBody body, MBCLoadDesc *load, const PetscReal w[], Vec F, PetscReal r[4])
{
  UpliftCtx uc = {&body->scene->couples[load->couple].uplift, w, r};

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(r, 4));
  PetscCall(MBCBodyAssembleFaces(body, load->surface_id, UpliftForces, &uc, F));
  PetscFunctionReturn(0);
}

/* The body's uplift loads again for the wet lengths w[off[i]..] (per zone of couple i of the
   scene); r[4 * couple] gets this rank's int p dA and int p x dA over the master faces of each
   couple (for a unit time factor). A rigid body's faces load it as a pressure does. */
PetscErrorCode MBCBodyUpliftUpdate(MBCBody body, const PetscReal w[], const PetscInt off[], PetscReal r[])
{
  MBCScene scene = body->scene;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < body->nloads; i++) {
    MBCLoadDesc *load = &scene->loads[body->load_index[i]];
    PetscReal    rl[4];
    if (load->kind != MBC_LOAD_UPLIFT) continue;
    PetscCall(MBCBodyAssembleUplift(body, load, &w[off[load->couple]], body->load[i], rl));
    if (load->side == 0) /* the couple's resultant is its master side's */
      for (PetscInt k = 0; k < 4; k++) r[4 * load->couple + k] += rl[k];
  }
  PetscFunctionReturn(0);
}
