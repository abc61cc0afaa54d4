/* Element stiffness and mass of linear elasticity for tet4 and hex8 cells (wedge6, pyr5, tet10:
   bodyelementmixed.c), volume loads, and their assembly. Hand-written because PETSc 3.18's generic
   PetscFE integration costs ~2 ms per hex8 cell for a 3-component field (measured; 12x the scalar
   cost), i.e. minutes per matrix at a million DOFs; these kernels take microseconds. The cell
   stress, the surface loads (bodyfaceload.c) and the geometry check use them too. */
#include <mbc/private/bodyimpl.h>
#include <mbc/private/element.h>

/* PETSc's reference hexahedron: the order in which a cell's closure lists its vertices. */
static const PetscReal HexCorner[8][3] = {
  {-1, -1, -1},
  {-1, 1,  -1},
  {1,  1,  -1},
  {1,  -1, -1},
  {-1, -1, 1 },
  {1,  -1, 1 },
  {1,  1,  1 },
  {-1, 1,  1 }
};

/* Adds w * (elasticity + rho * mass) terms of one integration point with gradients G (nb x 3) and
   values N; Ke or Me may be NULL. */
static void AddPoint(PetscInt nb, const PetscReal G[][3], const PetscReal N[], PetscReal w, PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscInt n = 3 * nb;

  for (PetscInt a = 0; a < nb; a++) {
    for (PetscInt b = 0; b < nb; b++) {
      const PetscReal dot = G[a][0] * G[b][0] + G[a][1] * G[b][1] + G[a][2] * G[b][2];
      for (PetscInt i = 0; i < 3; i++) {
        if (Ke)
          for (PetscInt j = 0; j < 3; j++) Ke[(3 * a + i) * n + 3 * b + j] += w * (lambda * G[a][i] * G[b][j] + mu * G[a][j] * G[b][i] + (i == j ? mu * dot : 0.0));
        if (Me) Me[(3 * a + i) * n + 3 * b + i] += w * rho * N[a] * N[b];
      }
    }
  }
}

/* Inverse and determinant of a 3x3 matrix (row-major). */
static PetscReal Invert3(const PetscReal J[9], PetscReal Ji[9])
{
  const PetscReal det = J[0] * (J[4] * J[8] - J[5] * J[7]) - J[1] * (J[3] * J[8] - J[5] * J[6]) + J[2] * (J[3] * J[7] - J[4] * J[6]);
  Ji[0] = (J[4] * J[8] - J[5] * J[7]) / det;
  Ji[1] = (J[2] * J[7] - J[1] * J[8]) / det;
  Ji[2] = (J[1] * J[5] - J[2] * J[4]) / det;
  Ji[3] = (J[5] * J[6] - J[3] * J[8]) / det;
  Ji[4] = (J[0] * J[8] - J[2] * J[6]) / det;
  Ji[5] = (J[2] * J[3] - J[0] * J[5]) / det;
  Ji[6] = (J[3] * J[7] - J[4] * J[6]) / det;
  Ji[7] = (J[1] * J[6] - J[0] * J[7]) / det;
  Ji[8] = (J[0] * J[4] - J[1] * J[3]) / det;
  return det;
}

/* The linear tet with vertices X: the constant physical gradients G of its 4 functions; returns
   its volume. */
static PetscReal Tet4Gradients(const PetscReal X[], PetscReal G[][3])
{
  PetscReal J[9], Ji[9], det;

  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt k = 0; k < 3; k++) J[i * 3 + k] = X[3 * (k + 1) + i] - X[i]; /* J_ik = d x_i / d xi_k */
  det = Invert3(J, Ji);
  for (PetscInt k = 0; k < 3; k++) {
    G[0][k] = 0;
    for (PetscInt c = 1; c < 4; c++) {
      G[c][k] = Ji[(c - 1) * 3 + k];
      G[0][k] -= G[c][k];
    }
  }
  return PetscAbsReal(det) / 6.0;
}

/* tet4: constant gradients; the mass integrand is quadratic, so use the 4-point rule of degree 2. */
void MBCElementTet4(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  PetscReal       G[4][3], vol = Tet4Gradients(X, G);
  const PetscReal a = 0.5854101966249685, b = 0.1381966011250105; /* (5 + 3 sqrt 5)/20, (5 - sqrt 5)/20 */

  AddPoint(4, G, NULL, vol, lambda, mu, rho, Ke, NULL);
  if (Me) {
    for (PetscInt q = 0; q < 4; q++) {
      PetscReal N[4] = {b, b, b, b};
      N[q]           = a;
      AddPoint(4, G, N, 0.25 * vol, 0, 0, rho, NULL, Me);
    }
  }
}

/* Trilinear shape functions N, their reference derivatives dN, the Jacobian J_ik = d x_i / d xi_k
   and its inverse Ji (Ji_kl = d xi_k / d x_l) of the hex with vertices X at the point xi;
   returns det J. */
static PetscReal HexMap(const PetscReal X[], const PetscReal xi[3], PetscReal N[8], PetscReal dN[8][3], PetscReal Ji[9])
{
  PetscReal J[9] = {0};

  for (PetscInt a = 0; a < 8; a++) {
    const PetscReal *c    = HexCorner[a];
    const PetscReal  f[3] = {1 + c[0] * xi[0], 1 + c[1] * xi[1], 1 + c[2] * xi[2]};
    N[a]                  = f[0] * f[1] * f[2] / 8;
    dN[a][0]              = c[0] * f[1] * f[2] / 8;
    dN[a][1]              = f[0] * c[1] * f[2] / 8;
    dN[a][2]              = f[0] * f[1] * c[2] / 8;
    for (PetscInt i = 0; i < 3; i++)
      for (PetscInt k = 0; k < 3; k++) J[i * 3 + k] += X[3 * a + i] * dN[a][k];
  }
  return Invert3(J, Ji);
}

/* G[a] = dN[a] Ji: physical gradients of n functions from their reference derivatives, scaled by s. */
static void PhysicalGradients(PetscInt n, const PetscReal dN[][3], const PetscReal Ji[9], PetscReal s, PetscReal G[][3])
{
  for (PetscInt a = 0; a < n; a++)
    for (PetscInt k = 0; k < 3; k++) G[a][k] = s * (dN[a][0] * Ji[0 * 3 + k] + dN[a][1] * Ji[1 * 3 + k] + dN[a][2] * Ji[2 * 3 + k]);
}

/* hex8: trilinear map, 2x2x2 Gauss points. */
void MBCElementHex8(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscReal g = 1.0 / PetscSqrtReal(3.0);

  for (PetscInt q = 0; q < 8; q++) {
    const PetscReal xi[3] = {HexCorner[q][0] * g, HexCorner[q][1] * g, HexCorner[q][2] * g};
    PetscReal       dN[8][3], N[8], G[8][3], Ji[9], det;

    det = HexMap(X, xi, N, dN, Ji);
    PhysicalGradients(8, dN, Ji, 1.0, G);
    AddPoint(8, G, N, PetscAbsReal(det), lambda, mu, rho, Ke, Me);
  }
}

/* Physical gradients G[q] of the 8 trilinear functions at the 2x2x2 Gauss points, the points'
   weights w[q] = |det J| and the cell-mean gradient Gm = sum_q w[q] G[q] / sum_q w[q]; returns
   the volume. N[q] (may be NULL): the shape functions at the points. */
static PetscReal HexGaussGradients(const PetscReal X[], PetscReal G[8][8][3], PetscReal w[8], PetscReal Gm[8][3], PetscReal N[8][8])
{
  const PetscReal g = 1.0 / PetscSqrtReal(3.0);
  PetscReal       vol = 0;

  for (PetscInt a = 0; a < 8; a++) Gm[a][0] = Gm[a][1] = Gm[a][2] = 0;
  for (PetscInt q = 0; q < 8; q++) {
    const PetscReal xi[3] = {HexCorner[q][0] * g, HexCorner[q][1] * g, HexCorner[q][2] * g};
    PetscReal       dN[8][3], Nq[8], Ji[9];

    w[q] = PetscAbsReal(HexMap(X, xi, Nq, dN, Ji));
    PhysicalGradients(8, dN, Ji, 1.0, G[q]);
    if (N)
      for (PetscInt a = 0; a < 8; a++) N[q][a] = Nq[a];
    for (PetscInt a = 0; a < 8; a++)
      for (PetscInt k = 0; k < 3; k++) Gm[a][k] += w[q] * G[q][a][k];
    vol += w[q];
  }
  for (PetscInt a = 0; a < 8; a++)
    for (PetscInt k = 0; k < 3; k++) Gm[a][k] /= vol;
  return vol;
}

/* hex8b: hex8 with B-bar, mean dilatation (Hughes 1980): the volumetric strain at every Gauss
   point is replaced by its cell mean, the deviatoric strain is hex8's. With the bulk modulus
   kappa = lambda + 2 mu / 3, the energy 2 mu dev(e):dev(e) + kappa tr(e)^2 splits into the
   isotropic form with lambda' = -2 mu / 3 at each Gauss point (the deviatoric part) plus
   kappa V Gm Gm^T with the cell-mean gradient Gm (one volumetric constraint per cell instead of
   eight: no volumetric locking as nu -> 1/2). The same 2x2x2 rule, the plain hex8 mass. A linear
   field has the same dilatation at every point, so the patch test holds on any mesh. */
void MBCElementHex8B(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  PetscReal G[8][8][3], w[8], Gm[8][3], N[8][8], vol;

  vol = HexGaussGradients(X, G, w, Gm, N);
  for (PetscInt q = 0; q < 8; q++) AddPoint(8, G[q], N[q], w[q], -2.0 * mu / 3.0, mu, rho, Ke, Me);
  AddPoint(8, Gm, NULL, vol, lambda + 2.0 * mu / 3.0, 0, 0, Ke, NULL);
}

/* The dilatation div u of the hex with vertices X and displacements U at the centre (*centre)
   and its cell mean over the 2x2x2 rule (*mean, hex8b's volumetric strain). */
void MBCElementHex8Dilatation(const PetscReal X[], const PetscReal U[], PetscReal *centre, PetscReal *mean)
{
  const PetscReal xi[3] = {0, 0, 0};
  PetscReal       G[8][8][3], w[8], Gm[8][3], N[8], dN[8][3], Ji[9], Gc[8][3];

  (void)HexGaussGradients(X, G, w, Gm, NULL);
  (void)HexMap(X, xi, N, dN, Ji);
  PhysicalGradients(8, dN, Ji, 1.0, Gc);
  *centre = *mean = 0;
  for (PetscInt a = 0; a < 8; a++)
    for (PetscInt k = 0; k < 3; k++) {
      *centre += Gc[a][k] * U[3 * a + k];
      *mean += Gm[a][k] * U[3 * a + k];
    }
}

/* gu[3 i + k] = d u_i / d x_k at the reference centre of the cell with vertices X and nodal
   displacements U (nv 4 or 8): tet4's constant gradient, a hex's at xi = 0 (hex8i's incompatible
   gradients vanish there, so it is the element's compatible part). */
void MBCElementCentreGradient(PetscInt nv, const PetscReal X[], const PetscReal U[], PetscReal gu[9])
{
  PetscReal G[8][3];

  if (nv == 6 || nv == 10) {
    MBCElementCentreGradientMixed(nv, X, U, gu);
    return;
  }
  if (nv == 5) { /* the collapsed hex's: the apex's gradient is the sum of the four collapsed corners' */
    PetscReal X8[24], U8[24];
    MBCElementPyr5AsHex(X, X8);
    MBCElementPyr5AsHex(U, U8);
    MBCElementCentreGradient(8, X8, U8, gu);
    return;
  }
  if (nv == 4) (void)Tet4Gradients(X, G);
  else {
    const PetscReal xi[3] = {0, 0, 0};
    PetscReal       N[8], dN[8][3], Ji[9];
    (void)HexMap(X, xi, N, dN, Ji);
    PhysicalGradients(8, dN, Ji, 1.0, G);
  }
  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt k = 0; k < 3; k++) {
      gu[3 * i + k] = 0;
      for (PetscInt a = 0; a < nv; a++) gu[3 * i + k] += U[3 * a + i] * G[a][k];
    }
}

/* In place Cholesky factor L (lower, row-major) of the SPD n x n matrix A; returns 0 if A is not
   positive definite. */
static PetscBool Cholesky(PetscInt n, PetscReal A[])
{
  for (PetscInt j = 0; j < n; j++) {
    for (PetscInt k = 0; k < j; k++) A[j * n + j] -= A[j * n + k] * A[j * n + k];
    if (!(A[j * n + j] > 0)) return PETSC_FALSE;
    A[j * n + j] = PetscSqrtReal(A[j * n + j]);
    for (PetscInt i = j + 1; i < n; i++) {
      for (PetscInt k = 0; k < j; k++) A[i * n + j] -= A[i * n + k] * A[j * n + k];
      A[i * n + j] /= A[j * n + j];
    }
  }
  return PETSC_TRUE;
}

/* hex8i: hex8 with Wilson's incompatible modes 1 - xi^2, 1 - eta^2, 1 - zeta^2 per component
   (9 internal DOFs, CalculiX's C3D8I) with Taylor's modification: their gradients use the
   Jacobian J0 of the centre, scaled by det J0 / det J, so that they integrate to zero over any
   cell and the element passes the constant-stress patch test on distorted meshes. The internal
   DOFs are condensed out at the element: Ke = Kcc - Kci Kii^-1 Kic. The mass is the plain hex8
   one (the internal modes carry none). The same 2x2x2 Gauss rule. The incompatible gradients vanish
   at the centre (d(1 - xi^2)/d xi = -2 xi), where the cellwise stress is evaluated, so the
   stress of the compatible part there is the element's (MBCBodyComputeStress).
   Returns PETSC_FALSE if Kii is not positive definite (a degenerate cell). */
PetscBool MBCElementHex8I(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscReal g = 1.0 / PetscSqrtReal(3.0), centre[3] = {0, 0, 0};
  PetscReal       K[33 * 33] = {0}, N[8], dN[8][3], J0i[9], det0;

  det0 = HexMap(X, centre, N, dN, J0i);
  for (PetscInt q = 0; q < 8; q++) {
    const PetscReal xi[3] = {HexCorner[q][0] * g, HexCorner[q][1] * g, HexCorner[q][2] * g};
    PetscReal       G[11][3], Ji[9], det, dP[3][3] = {{0}};

    det = HexMap(X, xi, N, dN, Ji);
    PhysicalGradients(8, dN, Ji, 1.0, G);
    for (PetscInt m = 0; m < 3; m++) dP[m][m] = -2 * xi[m]; /* d(1 - xi_m^2) / d xi */
    PhysicalGradients(3, dP, J0i, det0 / det, G + 8);
    AddPoint(11, G, NULL, PetscAbsReal(det), lambda, mu, 0, K, NULL);
    if (Me) AddPoint(8, G, N, PetscAbsReal(det), 0, 0, rho, NULL, Me);
  }
  /* Kii = L L^T; X = L^-1 Kic (9 x 24); Ke += Kcc - X^T X */
  {
    PetscReal Kii[81], Xm[9][24];
    for (PetscInt i = 0; i < 9; i++)
      for (PetscInt j = 0; j < 9; j++) Kii[i * 9 + j] = K[(24 + i) * 33 + 24 + j];
    if (!Cholesky(9, Kii)) return PETSC_FALSE;
    for (PetscInt c = 0; c < 24; c++)
      for (PetscInt i = 0; i < 9; i++) {
        PetscReal v = K[(24 + i) * 33 + c];
        for (PetscInt k = 0; k < i; k++) v -= Kii[i * 9 + k] * Xm[k][c];
        Xm[i][c] = v / Kii[i * 9 + i];
      }
    for (PetscInt r = 0; r < 24; r++)
      for (PetscInt c = 0; c < 24; c++) {
        PetscReal v = K[r * 33 + c];
        for (PetscInt k = 0; k < 9; k++) v -= Xm[k][r] * Xm[k][c];
        Ke[r * 24 + c] += v;
      }
  }
  return PETSC_TRUE;
}

/* w[a] = int N_a dV over the cell with nodes X: tet4 V/4; a hex (every variant: a load acts on
   the compatible trilinear functions) by the 2x2x2 rule, exact for N_a det J; a pyramid as its
   collapsed hex; wedge6 and tet10 by their rules. */
void MBCElementNodalWeights(PetscInt nv, const PetscReal X[], PetscReal w[])
{
  PetscReal Ji[9];

  if (nv == 6 || nv == 10) {
    MBCElementNodalWeightsMixed(nv, X, w);
    return;
  }
  if (nv == 5) {
    PetscReal X8[24], w8[8];
    MBCElementPyr5AsHex(X, X8);
    MBCElementNodalWeights(8, X8, w8);
    for (PetscInt a = 0; a < 4; a++) w[a] = w8[a];
    w[4] = w8[4] + w8[5] + w8[6] + w8[7];
    return;
  }

  if (nv == 4) {
    PetscReal G[4][3], vol = Tet4Gradients(X, G);
    for (PetscInt a = 0; a < 4; a++) w[a] = vol / 4.0;
    return;
  }
  for (PetscInt a = 0; a < 8; a++) w[a] = 0;
  for (PetscInt q = 0; q < 8; q++) {
    const PetscReal g = 1.0 / PetscSqrtReal(3.0), xi[3] = {HexCorner[q][0] * g, HexCorner[q][1] * g, HexCorner[q][2] * g};
    PetscReal       N[8], dN[8][3], det = PetscAbsReal(HexMap(X, xi, N, dN, Ji));
    for (PetscInt a = 0; a < 8; a++) w[a] += N[a] * det;
  }
}

/* The smallest Jacobian determinant over the element's quadrature points (the Gauss points of
   tet4 and hex8 kernels, the centre), positive for a valid cell, and the longest distance L
   between its corners (a cell with det J << L^3 is degenerate). */
PetscReal MBCElementMinJacobian(PetscInt nv, const PetscReal X[], PetscReal *L)
{
  const PetscInt nc = nv == 10 ? 4 : nv;
  PetscReal      dmin = PETSC_MAX_REAL;

  *L = 0;
  for (PetscInt a = 0; a < nc; a++)
    for (PetscInt b = a + 1; b < nc; b++) *L = PetscMax(*L, PetscSqrtReal(PetscSqr(X[3 * a] - X[3 * b]) + PetscSqr(X[3 * a + 1] - X[3 * b + 1]) + PetscSqr(X[3 * a + 2] - X[3 * b + 2])));
  if (nv == 6 || nv == 10) return MBCElementMinJacobianMixed(nv, X);
  if (nv == 4) { /* x = xi X0 + (1 - xi - eta - zeta) X1 + eta X2 + zeta X3: PETSc's tet swaps Gmsh's first two */
    PetscReal J[9], Ji[9];
    for (PetscInt i = 0; i < 3; i++) J[i * 3 + 0] = X[i] - X[3 + i], J[i * 3 + 1] = X[6 + i] - X[3 + i], J[i * 3 + 2] = X[9 + i] - X[3 + i];
    return Invert3(J, Ji);
  }
  {
    PetscReal       X8[24];
    const PetscReal g = 1.0 / PetscSqrtReal(3.0);
    if (nv == 5) MBCElementPyr5AsHex(X, X8);
    else PetscArraycpy(X8, X, 24);
    for (PetscInt q = 0; q < 9; q++) {
      const PetscReal xi[3] = {q < 8 ? HexCorner[q][0] * g : 0, q < 8 ? HexCorner[q][1] * g : 0, q < 8 ? HexCorner[q][2] * g : 0};
      PetscReal       N[8], dN[8][3], Ji[9];
      dmin = PetscMin(dmin, HexMap(X8, xi, N, dN, Ji));
    }
  }
  return dmin;
}

/* *K: the body's operator, preallocated from its cells' vertices (the pattern assembly fills) by
   a MATPREALLOCATOR. DMPlex's own preallocation walks the adjacency of every mesh point: 5.3 of
   the 8.2 s of assembly of the 198k dam. Collective on the body. */
PetscErrorCode MBCBodyCreateOperator(MBCBody body, Mat *K)
{
  Mat                    pre;
  ISLocalToGlobalMapping rl2g, cl2g;
  PetscInt               m, n, M, N, bs;

  PetscFunctionBegin;
  PetscCall(DMSetMatrixPreallocateSkip(body->dm, PETSC_TRUE));
  PetscCall(DMCreateMatrix(body->dm, K)); /* sizes, block size, type, local-to-global map */
  PetscCall(DMSetMatrixPreallocateSkip(body->dm, PETSC_FALSE));
  PetscCall(MatGetLocalSize(*K, &m, &n));
  PetscCall(MatGetSize(*K, &M, &N));
  PetscCall(MatGetBlockSize(*K, &bs));
  PetscCall(MatGetLocalToGlobalMapping(*K, &rl2g, &cl2g));
  PetscCall(MatCreate(PetscObjectComm((PetscObject)*K), &pre));
  PetscCall(MatSetType(pre, MATPREALLOCATOR));
  PetscCall(MatSetSizes(pre, m, n, M, N));
  PetscCall(MatSetBlockSize(pre, bs));
  PetscCall(MatSetLocalToGlobalMapping(pre, rl2g, cl2g));
  PetscCall(MatSetUp(pre));
  PetscCall(MBCBodyAssembleElasticity(body, pre, NULL)); /* the pattern only */
  PetscCall(MBCBodySpringPattern(body, pre));
  PetscCall(MatPreallocatorPreallocate(pre, PETSC_TRUE, *K));
  PetscCall(MatDestroy(&pre));
  PetscFunctionReturn(0);
}

/* Assembles K (and M, unit factors times density, when M != NULL) over the body's cells, with
   the vertices of each cell in closure order for both coordinates and DOFs; K a MATPREALLOCATOR:
   the pattern alone. */
PetscErrorCode MBCBodyAssembleElasticity(MBCBody body, Mat K, Mat M)
{
  Vec                coords;
  const PetscScalar *x;
  PetscInt           cStart, cEnd;
  PetscReal          Ke[900], Me[900], X[3 * MBC_MAX_CELL_NODES];
  PetscInt           idx[3 * MBC_MAX_CELL_NODES];
  PetscBool          pattern;

  PetscFunctionBegin;
  PetscCall(PetscObjectTypeCompare((PetscObject)K, MATPREALLOCATOR, &pattern));
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; c++) {
    PetscInt nv;

    PetscCall(MBCBodyCellVertices(body, c, x, X, idx, &nv));
    PetscCall(PetscArrayzero(Ke, 9 * nv * nv));
    if (pattern) {
      PetscCall(MatSetValuesLocal(K, 3 * nv, idx, 3 * nv, idx, Ke, INSERT_VALUES));
      continue;
    }
    if (M) PetscCall(PetscArrayzero(Me, 9 * nv * nv));
    if (nv == 4) MBCElementTet4(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    else if (nv == 5) MBCElementPyr5(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    else if (nv == 6) MBCElementWedge6(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    else if (nv == 10) MBCElementTet10(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    else if (body->element == MBC_ELEMENT_HEX8I) PetscCheck(MBCElementHex8I(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Body '%s': cell %" PetscInt_FMT " is degenerate (hex8i: its incompatible-mode stiffness is not positive definite)", body->name, c);
    else if (body->element == MBC_ELEMENT_HEX8B) MBCElementHex8B(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    else MBCElementHex8(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
    PetscCall(MatSetValuesLocal(K, 3 * nv, idx, 3 * nv, idx, Ke, ADD_VALUES));
    if (M) PetscCall(MatSetValuesLocal(M, 3 * nv, idx, 3 * nv, idx, Me, ADD_VALUES));
  }
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(MatAssemblyBegin(K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(K, MAT_FINAL_ASSEMBLY));
  if (M) {
    PetscCall(MatAssemblyBegin(M, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(M, MAT_FINAL_ASSEMBLY));
  }
  PetscFunctionReturn(0);
}

/* F = int f N dV over the body's cells: the nodal forces of the volume load f (force per volume).
   By hand as K is: PetscFE's residual took 1.0 s of the 198k dam's 3.1 s of assembly for gravity. */
PetscErrorCode MBCBodyAssembleVolumeLoad(MBCBody body, const PetscReal f[3], Vec F)
{
  Vec                coords, Floc;
  const PetscScalar *x;
  PetscScalar       *fl;
  PetscInt           cStart, cEnd;

  PetscFunctionBegin;
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(DMGetLocalVector(body->dm, &Floc));
  PetscCall(VecZeroEntries(Floc));
  PetscCall(VecGetArray(Floc, &fl));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; c++) {
    PetscReal X[3 * MBC_MAX_CELL_NODES], w[MBC_MAX_CELL_NODES];
    PetscInt  idx[3 * MBC_MAX_CELL_NODES], nv;

    PetscCall(MBCBodyCellVertices(body, c, x, X, idx, &nv));
    MBCElementNodalWeights(nv, X, w);
    for (PetscInt a = 0; a < nv; a++)
      for (PetscInt i = 0; i < 3; i++) fl[idx[3 * a + i]] += w[a] * f[i];
  }
  PetscCall(VecRestoreArray(Floc, &fl));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(VecZeroEntries(F));
  PetscCall(DMLocalToGlobal(body->dm, Floc, ADD_VALUES, F));
  PetscCall(DMRestoreLocalVector(body->dm, &Floc));
  PetscFunctionReturn(0);
}
