/* The elements of mixed and quadratic meshes: the 6-node prism (wedge6), the 5-node pyramid (pyr5,
   the hex8 with its top face collapsed onto the apex) and the 10-node tetrahedron (tet10), as
   Code_Aster's PENTA6, PYRAM5 and TETRA10 or Abaqus' C3D6, C3D10. Nodes in the order
   MBCBodyCellVertices gives: PETSc's closure order of the vertices, then tet10's midside nodes of
   the edges (0 1) (1 2) (2 0) (0 3) (1 3) (2 3). Each kernel's reference coordinates make a
   correctly oriented cell's Jacobian positive (MBCElementJacobian, the geometry check). */
#include <mbc/private/element.h>
#include <petscmath.h>

/* The wedge's reference nodes in PETSc's prism order: the first triangle at zeta = -1 wound the
   other way from Gmsh's, the second over (0, 2, 1) at zeta = +1. */
static const PetscReal WedgeNode[6][3] = {
  {0, 0, -1},
  {0, 1, -1},
  {1, 0, -1},
  {0, 0, 1 },
  {1, 0, 1 },
  {0, 1, 1 }
};

/* The tet10's corners in PETSc's closure order (x = xi q0 + (1 - xi - eta - zeta) q1 + eta q2 + zeta q3). */
static const PetscInt Tet10Edge[6][2] = {
  {0, 1},
  {1, 2},
  {2, 0},
  {0, 3},
  {1, 3},
  {2, 3}
};

static PetscReal Det3(const PetscReal J[9])
{
  return J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
}

/* G[a] = dN[a] J^-1 (J_ik = d x_i / d xi_k) for n functions; returns det J. */
static PetscReal MapGradients(PetscInt n, const PetscReal X[], const PetscReal dN[][3], PetscReal G[][3])
{
  PetscReal J[9] = {0}, Ji[9], det;

  for (PetscInt a = 0; a < n; a++)
    for (PetscInt i = 0; i < 3; i++)
      for (PetscInt k = 0; k < 3; k++) J[i * 3 + k] += X[3 * a + i] * dN[a][k];
  det   = Det3(J);
  Ji[0] = (J[4] * J[8] - J[5] * J[7]) / det;
  Ji[1] = (J[2] * J[7] - J[1] * J[8]) / det;
  Ji[2] = (J[1] * J[5] - J[2] * J[4]) / det;
  Ji[3] = (J[5] * J[6] - J[3] * J[8]) / det;
  Ji[4] = (J[0] * J[8] - J[2] * J[6]) / det;
  Ji[5] = (J[2] * J[3] - J[0] * J[5]) / det;
  Ji[6] = (J[3] * J[7] - J[4] * J[6]) / det;
  Ji[7] = (J[1] * J[6] - J[0] * J[7]) / det;
  Ji[8] = (J[0] * J[4] - J[1] * J[3]) / det;
  for (PetscInt a = 0; a < n; a++)
    for (PetscInt k = 0; k < 3; k++) G[a][k] = dN[a][0] * Ji[0 * 3 + k] + dN[a][1] * Ji[1 * 3 + k] + dN[a][2] * Ji[2 * 3 + k];
  return det;
}

/* Adds w * (elasticity + rho * mass) at one point, as bodyelement.c's AddPoint. */
static void AddPoint(PetscInt nb, const PetscReal G[][3], const PetscReal N[], PetscReal w, PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscInt n = 3 * nb;
  for (PetscInt a = 0; a < nb; a++)
    for (PetscInt b = 0; b < nb; b++) {
      const PetscReal dot = G[a][0] * G[b][0] + G[a][1] * G[b][1] + G[a][2] * G[b][2];
      for (PetscInt i = 0; i < 3; i++) {
        if (Ke)
          for (PetscInt j = 0; j < 3; j++) Ke[(3 * a + i) * n + 3 * b + j] += w * (lambda * G[a][i] * G[b][j] + mu * G[a][j] * G[b][i] + (i == j ? mu * dot : 0.0));
        if (Me) Me[(3 * a + i) * n + 3 * b + i] += w * rho * N[a] * N[b];
      }
    }
}

/* ---------------------------------------------------------------- wedge6 */

static void WedgeShape(const PetscReal xi[3], PetscReal N[6], PetscReal dN[6][3])
{
  for (PetscInt a = 0; a < 6; a++) {
    const PetscReal *r = WedgeNode[a];
    const PetscReal  s = 0.5 * (1 + r[2] * xi[2]); /* the linear factor along zeta */
    PetscReal        L, dL[2];
    if (r[0] == 1) L = xi[0], dL[0] = 1, dL[1] = 0;
    else if (r[1] == 1) L = xi[1], dL[0] = 0, dL[1] = 1;
    else L = 1 - xi[0] - xi[1], dL[0] = -1, dL[1] = -1;
    N[a]     = L * s;
    dN[a][0] = dL[0] * s;
    dN[a][1] = dL[1] * s;
    dN[a][2] = L * 0.5 * r[2];
  }
}

/* 3 points of degree 2 on the triangle times 2 Gauss points along zeta: exact for the mass of a
   straight prism and for its stiffness when its triangles are parallel. */
static const PetscReal WedgeTri[3][2] = {
  {1.0 / 6, 1.0 / 6},
  {2.0 / 3, 1.0 / 6},
  {1.0 / 6, 2.0 / 3}
};

void MBCElementWedge6(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscReal g = 1.0 / PetscSqrtReal(3.0);
  for (PetscInt t = 0; t < 3; t++)
    for (PetscInt z = 0; z < 2; z++) {
      const PetscReal xi[3] = {WedgeTri[t][0], WedgeTri[t][1], z ? g : -g};
      PetscReal       N[6], dN[6][3], G[6][3], det;
      WedgeShape(xi, N, dN);
      det = MapGradients(6, X, dN, G);
      AddPoint(6, G, N, PetscAbsReal(det) / 6.0, lambda, mu, rho, Ke, Me);
    }
}

/* ---------------------------------------------------------------- pyr5 */

static void PyramidAsHex(const PetscReal X[], PetscReal X8[24])
{
  for (PetscInt a = 0; a < 8; a++)
    for (PetscInt i = 0; i < 3; i++) X8[3 * a + i] = X[3 * PetscMin(a, 4) + i];
}

/* The hex8 kernel on the pyramid seen as a hex whose top four corners are its apex: the
   collapsed brick. On each triangular face its interpolation is linear in the physical
   coordinates, so it is conforming with tet4 and wedge6 neighbours; the 2 x 2 x 2 Gauss points
   lie inside, away from the apex where det J vanishes. */
void MBCElementPyr5(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  PetscReal X8[24], K8[576] = {0}, M8[576] = {0};

  PyramidAsHex(X, X8);
  MBCElementHex8(X8, lambda, mu, rho, K8, Me ? M8 : NULL);
  for (PetscInt a = 0; a < 8; a++)
    for (PetscInt b = 0; b < 8; b++) {
      const PetscInt A = PetscMin(a, 4), B = PetscMin(b, 4);
      for (PetscInt i = 0; i < 3; i++)
        for (PetscInt j = 0; j < 3; j++) {
          if (Ke) Ke[(3 * A + i) * 15 + 3 * B + j] += K8[(3 * a + i) * 24 + 3 * b + j];
          if (Me) Me[(3 * A + i) * 15 + 3 * B + j] += M8[(3 * a + i) * 24 + 3 * b + j];
        }
    }
}

/* ---------------------------------------------------------------- tet10 */

/* Barycentric coordinates of the corners q0 .. q3 at xi, and their (constant) derivatives. */
static void TetBary(const PetscReal xi[3], PetscReal L[4], PetscReal dL[4][3])
{
  static const PetscReal d[4][3] = {
    {1,  0,  0 },
    {-1, -1, -1},
    {0,  1,  0 },
    {0,  0,  1 }
  };
  L[0] = xi[0], L[1] = 1 - xi[0] - xi[1] - xi[2], L[2] = xi[1], L[3] = xi[2];
  for (PetscInt a = 0; a < 4; a++)
    for (PetscInt k = 0; k < 3; k++) dL[a][k] = d[a][k];
}

static void Tet10Shape(const PetscReal xi[3], PetscReal N[10], PetscReal dN[10][3])
{
  PetscReal L[4], dL[4][3];
  TetBary(xi, L, dL);
  for (PetscInt a = 0; a < 4; a++) {
    N[a] = L[a] * (2 * L[a] - 1);
    for (PetscInt k = 0; k < 3; k++) dN[a][k] = (4 * L[a] - 1) * dL[a][k];
  }
  for (PetscInt m = 0; m < 6; m++) {
    const PetscInt a = Tet10Edge[m][0], b = Tet10Edge[m][1];
    N[4 + m] = 4 * L[a] * L[b];
    for (PetscInt k = 0; k < 3; k++) dN[4 + m][k] = 4 * (dL[a][k] * L[b] + L[a] * dL[b][k]);
  }
}

/* The 4-point rule of degree 2 on the unit tet (stiffness: exact on straight tet10s, the rule of
   Abaqus' C3D10) and the collapsed 4 x 4 x 4 Gauss rule of degree 7 along each collapsed direction
   (mass: its degree-4 integrand exactly). */
static void Tet4PointRule(PetscInt q, PetscReal xi[3], PetscReal *w)
{
  const PetscReal a = 0.5854101966249685, b = 0.1381966011250105;
  xi[0] = q == 0 ? a : b, xi[1] = q == 1 ? a : b, xi[2] = q == 2 ? a : b;
  *w = 1.0 / 24.0;
}

static void TetCollapsedRule(PetscInt q, PetscReal xi[3], PetscReal *w)
{
  static const PetscReal x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
  static const PetscReal gw[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
  const PetscInt         i = q / 16, j = (q / 4) % 4, k = q % 4;
  const PetscReal        a = 0.5 * (1 + x[i]), b = 0.5 * (1 + x[j]), c = 0.5 * (1 + x[k]);
  xi[0] = a, xi[1] = b * (1 - a), xi[2] = c * (1 - a) * (1 - b);
  *w    = 0.125 * gw[i] * gw[j] * gw[k] * (1 - a) * (1 - a) * (1 - b);
}

void MBCElementTet10(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  for (PetscInt q = 0; Ke && q < 4; q++) {
    PetscReal xi[3], w, N[10], dN[10][3], G[10][3], det;
    Tet4PointRule(q, xi, &w);
    Tet10Shape(xi, N, dN);
    det = MapGradients(10, X, dN, G);
    AddPoint(10, G, N, w * PetscAbsReal(det), lambda, mu, 0, Ke, NULL);
  }
  for (PetscInt q = 0; Me && q < 64; q++) {
    PetscReal xi[3], w, N[10], dN[10][3], G[10][3], det;
    TetCollapsedRule(q, xi, &w);
    Tet10Shape(xi, N, dN);
    det = MapGradients(10, X, dN, G);
    AddPoint(10, G, N, w * PetscAbsReal(det), 0, 0, rho, NULL, Me);
  }
}

/* ---------------------------------------------------------------- shared */

/* The reference point, shape functions and derivatives of the n-node element (5, 6, 10) at xi. */
static void Shape(PetscInt n, const PetscReal xi[3], PetscReal N[], PetscReal dN[][3])
{
  if (n == 6) WedgeShape(xi, N, dN);
  else Tet10Shape(xi, N, dN);
}

/* w[a] = int N_a dV over the cell (wedge6, tet10: their own rules of degree >= 2; a pyramid by the
   collapsed hex). */
void MBCElementNodalWeightsMixed(PetscInt nv, const PetscReal X[], PetscReal w[])
{
  for (PetscInt a = 0; a < nv; a++) w[a] = 0;
  if (nv == 6) {
    const PetscReal g = 1.0 / PetscSqrtReal(3.0);
    for (PetscInt t = 0; t < 3; t++)
      for (PetscInt z = 0; z < 2; z++) {
        const PetscReal xi[3] = {WedgeTri[t][0], WedgeTri[t][1], z ? g : -g};
        PetscReal       N[6], dN[6][3], G[6][3], det;
        WedgeShape(xi, N, dN);
        det = MapGradients(6, X, dN, G);
        for (PetscInt a = 0; a < 6; a++) w[a] += N[a] * PetscAbsReal(det) / 6.0;
      }
  } else if (nv == 10) {
    for (PetscInt q = 0; q < 64; q++) {
      PetscReal xi[3], wq, N[10], dN[10][3], G[10][3], det;
      TetCollapsedRule(q, xi, &wq);
      Tet10Shape(xi, N, dN);
      det = MapGradients(10, X, dN, G);
      for (PetscInt a = 0; a < 10; a++) w[a] += N[a] * wq * PetscAbsReal(det);
    }
  }
}

/* gu[3 i + k] = d u_i / d x_k at the reference centre of a wedge6 (xi = 1/3, 1/3, 0) or tet10
   (the centroid). */
void MBCElementCentreGradientMixed(PetscInt nv, const PetscReal X[], const PetscReal U[], PetscReal gu[9])
{
  const PetscReal xi[3] = {nv == 6 ? 1.0 / 3 : 0.25, nv == 6 ? 1.0 / 3 : 0.25, nv == 6 ? 0 : 0.25};
  PetscReal       N[10], dN[10][3], G[10][3];

  Shape(nv, xi, N, dN);
  (void)MapGradients(nv, X, dN, G);
  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt k = 0; k < 3; k++) {
      gu[3 * i + k] = 0;
      for (PetscInt a = 0; a < nv; a++) gu[3 * i + k] += U[3 * a + i] * G[a][k];
    }
}

/* The smallest Jacobian determinant of a wedge6 or tet10 over its quadrature points and corners,
   in the orientation its reference coordinates give a valid cell (> 0). */
PetscReal MBCElementMinJacobianMixed(PetscInt nv, const PetscReal X[])
{
  PetscReal dmin = PETSC_MAX_REAL;

  if (nv == 6) {
    const PetscReal g = 1.0 / PetscSqrtReal(3.0);
    for (PetscInt q = 0; q < 12; q++) {
      const PetscReal xi[3] = {q < 6 ? WedgeTri[q % 3][0] : WedgeNode[q - 6][0], q < 6 ? WedgeTri[q % 3][1] : WedgeNode[q - 6][1], q < 6 ? (q < 3 ? -g : g) : WedgeNode[q - 6][2]};
      PetscReal       N[6], dN[6][3], G[6][3];
      WedgeShape(xi, N, dN);
      dmin = PetscMin(dmin, MapGradients(6, X, dN, G));
    }
  } else {
    static const PetscReal corner[4][3] = {
      {1, 0, 0},
      {0, 0, 0},
      {0, 1, 0},
      {0, 0, 1}
    };
    for (PetscInt q = 0; q < 8; q++) {
      PetscReal xi[3], w, N[10], dN[10][3], G[10][3];
      if (q < 4) Tet4PointRule(q, xi, &w);
      else xi[0] = corner[q - 4][0], xi[1] = corner[q - 4][1], xi[2] = corner[q - 4][2];
      Tet10Shape(xi, N, dN);
      dmin = PetscMin(dmin, MapGradients(10, X, dN, G));
    }
  }
  return dmin;
}

/* A pyramid as its collapsed hex, for the shared hex8 helpers. */
void MBCElementPyr5AsHex(const PetscReal X[], PetscReal X8[24])
{
  PyramidAsHex(X, X8);
}
