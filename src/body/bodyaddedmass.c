/* The reservoir's hydrodynamic pressure as Westergaard's added mass (docs/scene.md, added_mass;
   docs/dam.md): a wetted face accelerated by a_n along its outward normal carries
   p = (7/8) rho_w a_n sqrt(H s), s the depth below the level, H the reservoir's depth (level -
   floor), so its nodes get the lumped masses m_i = integral of N_i (7/8) rho_w sqrt(H s) dA along
   the face normal, m_i n n^T (generalised to inclined and curved faces as Kuo's: mass along each
   face's normal, bodysurface.c). M + M_a enters Newmark's operator and the ground motion's load
   -(M + M_a) a_g (bodyabsorbing.c): the pressure acts on the face's total normal acceleration.

   The integral is exact where the depth is affine along one parametric direction of the face
   (every face of a structured mesh; a triangle cut at its middle vertex's depth): along that
   direction the integrand is a
   polynomial times sqrt(linear), integrated by Gauss in w = sqrt(s) (a polynomial there); across
   it Gauss on the pieces between the level's crossings of the face's edges. */
#include <mbc/private/bodyimpl.h>

static const PetscReal g5x[5] = {-0.90617984593866399280, -0.53846931010568309104, 0.0, 0.53846931010568309104, 0.90617984593866399280};
static const PetscReal g5w[5] = {0.23692688505618908751, 0.47862867049936646804, 0.56888888888888888889, 0.47862867049936646804, 0.23692688505618908751};
static const PetscReal g6x[6] = {-0.93246951420315202781, -0.66120938646626451366, -0.23861918608319690863, 0.23861918608319690863, 0.66120938646626451366, 0.93246951420315202781};
static const PetscReal g6w[6] = {0.17132449237917034504, 0.36076157304813860757, 0.46791393457269104739, 0.46791393457269104739, 0.36076157304813860757, 0.17132449237917034504};

typedef struct {
  PetscReal level, H, coef; /* coef = 7/8 rho_w sqrt(H) */
  PetscInt  axis;
} Westergaard;

/* The bilinear quad of [-1, 1]^2 (a triangle is the quad with its last vertex repeated): shape
   functions and the area element at (xi, eta). */
static void QuadPoint(const PetscReal Q[4][3], PetscReal xi, PetscReal eta, PetscReal N[4], PetscReal *J)
{
  static const PetscReal sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  PetscReal              dxi[3] = {0, 0, 0}, deta[3] = {0, 0, 0}, c[3];
  for (PetscInt v = 0; v < 4; v++) {
    N[v] = 0.25 * (1 + sx[v] * xi) * (1 + sy[v] * eta);
    for (PetscInt k = 0; k < 3; k++) {
      dxi[k] += 0.25 * sx[v] * (1 + sy[v] * eta) * Q[v][k];
      deta[k] += 0.25 * sy[v] * (1 + sx[v] * xi) * Q[v][k];
    }
  }
  c[0] = dxi[1] * deta[2] - dxi[2] * deta[1];
  c[1] = dxi[2] * deta[0] - dxi[0] * deta[2];
  c[2] = dxi[0] * deta[1] - dxi[1] * deta[0];
  *J   = PetscSqrtReal(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
}

/* wq_q = integral of N_q coef sqrt(s) dA over the wet part (s > 0) of the bilinear quad Q with
   depths s at its vertices; inner: the parametric direction (0: xi, 1: eta) to integrate exactly,
   -1: the one the depth varies most along. */
static void QuadWestergaard(const Westergaard *wg, const PetscReal Q[4][3], const PetscReal s[4], PetscInt inner, PetscReal wq[4])
{
  PetscReal brk[4] = {-1, 1, 0, 0};
  PetscInt  nbrk = 2;

  for (PetscInt v = 0; v < 4; v++) wq[v] = 0;
  if (inner < 0) inner = PetscAbsReal(-s[0] + s[1] + s[2] - s[3]) >= PetscAbsReal(-s[0] - s[1] + s[2] + s[3]) ? 0 : 1;
  { /* outer coordinate u where the level crosses the edges r = -1 and r = +1 */
    PetscReal ea[2], eb[2]; /* depth at u = -1 and u = +1 on the edges r = -1, +1 */
    if (inner == 0) ea[0] = s[0], eb[0] = s[3], ea[1] = s[1], eb[1] = s[2];
    else ea[0] = s[0], eb[0] = s[1], ea[1] = s[3], eb[1] = s[2];
    for (PetscInt e = 0; e < 2; e++)
      if ((ea[e] > 0 && eb[e] < 0) || (ea[e] < 0 && eb[e] > 0)) brk[nbrk++] = (ea[e] + eb[e]) / (ea[e] - eb[e]);
    for (PetscInt i = 1; i < nbrk; i++)
      for (PetscInt j = i; j > 0 && brk[j] < brk[j - 1]; j--) {
        PetscReal t = brk[j];
        brk[j] = brk[j - 1], brk[j - 1] = t;
      }
  }
  for (PetscInt piece = 0; piece + 1 < nbrk; piece++) {
    const PetscReal ua = brk[piece], ub = brk[piece + 1];
    if (!(ub > ua)) continue;
    for (PetscInt qo = 0; qo < 6; qo++) {
      const PetscReal u = 0.5 * (ua + ub) + 0.5 * (ub - ua) * g6x[qo], wu = 0.5 * (ub - ua) * g6w[qo];
      PetscReal       sa, sb, sm, k, rlo, rhi;
      /* depth along the inner coordinate r at this u: s(r) = sm + k r */
      if (inner == 0) sa = 0.5 * (1 - u) * s[0] + 0.5 * (1 + u) * s[3], sb = 0.5 * (1 - u) * s[1] + 0.5 * (1 + u) * s[2];
      else sa = 0.5 * (1 - u) * s[0] + 0.5 * (1 + u) * s[1], sb = 0.5 * (1 - u) * s[3] + 0.5 * (1 + u) * s[2];
      sm = 0.5 * (sa + sb), k = 0.5 * (sb - sa);
      if (sa <= 0 && sb <= 0) continue;
      if (PetscAbsReal(k) <= 1e-14 * (PetscAbsReal(sm) + wg->H)) { /* constant depth: plain Gauss */
        for (PetscInt qi = 0; qi < 5; qi++) {
          const PetscReal r = g5x[qi], xi = inner == 0 ? r : u, eta = inner == 0 ? u : r;
          PetscReal       N[4], J;
          QuadPoint(Q, xi, eta, N, &J);
          for (PetscInt v = 0; v < 4; v++) wq[v] += wu * g5w[qi] * N[v] * J * wg->coef * PetscSqrtReal(sm);
        }
        continue;
      }
      rlo = -1, rhi = 1;
      if (sa <= 0) rlo = -sm / k;
      if (sb <= 0) rhi = -sm / k;
      { /* w = sqrt(s) from sqrt(s(rlo)) to sqrt(s(rhi)); dr = 2 w dw / k */
        const PetscReal w0 = PetscSqrtReal(PetscMax(sm + k * rlo, 0)), w1 = PetscSqrtReal(PetscMax(sm + k * rhi, 0));
        for (PetscInt qi = 0; qi < 5; qi++) {
          const PetscReal ww = 0.5 * (w0 + w1) + 0.5 * (w1 - w0) * g5x[qi], r = (ww * ww - sm) / k;
          const PetscReal weight = wu * g5w[qi] * 0.5 * (w1 - w0) * 2 * ww / k, xi = inner == 0 ? r : u, eta = inner == 0 ? u : r;
          PetscReal       N[4], J;
          QuadPoint(Q, xi, eta, N, &J);
          for (PetscInt v = 0; v < 4; v++) wq[v] += weight * N[v] * J * wg->coef * ww;
        }
      }
    }
  }
}

/* w_i = integral of N_i coef sqrt(s) dA over the wet part (s > 0) of the face. A triangle is cut
   at its middle vertex's depth into two triangles with an edge of constant depth, each the quad
   (edge, apex, apex) integrated exactly along the apex's direction; its shape functions are the
   face's barycentrics, affine in the sub-triangles' too. */
static PetscErrorCode WestergaardWeights(PetscInt nv, const PetscReal X[4][3], void *ctx, PetscReal w[4])
{
  const Westergaard *wg = (const Westergaard *)ctx;
  PetscReal          s[4], smax = 0, wq[4];

  PetscFunctionBegin;
  for (PetscInt v = 0; v < 4; v++) w[v] = 0;
  for (PetscInt v = 0; v < nv; v++) {
    s[v] = PetscMin(wg->level - X[v][wg->axis], wg->H); /* the floor is the lowest wet point (prep) */
    smax = PetscMax(smax, s[v]);
  }
  if (smax <= 0) PetscFunctionReturn(0);
  if (nv == 4) {
    QuadWestergaard(wg, X, s, -1, w);
    PetscFunctionReturn(0);
  }
  {
    PetscInt  o[3] = {0, 1, 2};
    PetscReal P[3], sP, t, LP[3] = {0, 0, 0};
    for (PetscInt i = 1; i < 3; i++) /* o: the vertices by depth */
      for (PetscInt j = i; j > 0 && s[o[j]] < s[o[j - 1]]; j--) {
        PetscInt tmp = o[j];
        o[j] = o[j - 1], o[j - 1] = tmp;
      }
    /* P on edge o0-o2 at the depth of o1 */
    t  = s[o[2]] > s[o[0]] ? (s[o[1]] - s[o[0]]) / (s[o[2]] - s[o[0]]) : 0.5;
    sP = s[o[1]];
    for (PetscInt k = 0; k < 3; k++) P[k] = (1 - t) * X[o[0]][k] + t * X[o[2]][k];
    LP[o[0]] = 1 - t, LP[o[2]] = t;
    for (PetscInt half = 0; half < 2; half++) { /* apex o0, then o2 */
      const PetscInt apex = half ? o[2] : o[0];
      PetscReal      Q[4][3], sq[4] = {s[o[1]], sP, s[apex], s[apex]}, L[4][3];
      for (PetscInt k = 0; k < 3; k++) {
        Q[0][k] = X[o[1]][k], Q[1][k] = P[k], Q[2][k] = Q[3][k] = X[apex][k];
        L[0][k] = k == o[1], L[1][k] = LP[k], L[2][k] = L[3][k] = k == apex;
      }
      QuadWestergaard(wg, (const PetscReal(*)[3])Q, sq, 1, wq);
      for (PetscInt q = 0; q < 4; q++)
        for (PetscInt k = 0; k < 3; k++) w[k] += wq[q] * L[q][k];
    }
  }
  PetscFunctionReturn(0);
}

/* M += the added mass of every added_mass entry on this body's faces (the surface on another
   body adds nothing here). Collective on the body (the assembly). */
PetscErrorCode MBCBodyAddedMass(MBCBody body)
{
  MBCScene scene = body->scene;

  PetscFunctionBegin;
  if (!scene->naddedmass || !body->M) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < scene->naddedmass; i++) {
    MBCAddedMassDesc *m = &scene->addedmass[i];
    Westergaard       wg;
    wg.level = m->level;
    wg.H     = m->level - m->bottom;
    wg.axis  = m->axis;
    wg.coef  = 7.0 / 8.0 * m->density * PetscSqrtReal(wg.H);
    PetscCall(MBCBodySurfaceBlocks(body, m->surface_id, WestergaardWeights, &wg, 1.0, 0.0, body->M));
  }
  PetscCall(MatAssemblyBegin(body->M, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(body->M, MAT_FINAL_ASSEMBLY));
  PetscFunctionReturn(0);
}
