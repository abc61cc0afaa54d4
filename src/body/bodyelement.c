/* Element stiffness and mass of linear elasticity for tet4 and hex8 cells, and their assembly.
   Hand-written because PETSc 3.18's generic PetscFE integration costs ~2 ms per hex8 cell for a
   3-component field (measured; 12x the scalar cost), i.e. minutes per matrix at a million DOFs;
   these kernels take microseconds. Loads, stress recovery and geometry checks stay with PetscFE. */
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

/* Adds w * (elasticity + rho * mass) terms of one integration point with gradients G (nb x 3) and values N. */
static void AddPoint(PetscInt nb, const PetscReal G[][3], const PetscReal N[], PetscReal w, PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscInt n = 3 * nb;

  for (PetscInt a = 0; a < nb; a++) {
    for (PetscInt b = 0; b < nb; b++) {
      const PetscReal dot = G[a][0] * G[b][0] + G[a][1] * G[b][1] + G[a][2] * G[b][2];
      for (PetscInt i = 0; i < 3; i++) {
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

/* tet4: constant gradients; the mass integrand is quadratic, so use the 4-point rule of degree 2. */
void MBCElementTet4(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  PetscReal       J[9], Ji[9], G[4][3], det, vol;
  const PetscReal a = 0.5854101966249685, b = 0.1381966011250105; /* (5 + 3 sqrt 5)/20, (5 - sqrt 5)/20 */

  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt k = 0; k < 3; k++) J[i * 3 + k] = X[3 * (k + 1) + i] - X[i]; /* J_ik = d x_i / d xi_k */
  det = Invert3(J, Ji);
  vol = PetscAbsReal(det) / 6.0;
  for (PetscInt k = 0; k < 3; k++) {
    G[0][k] = 0;
    for (PetscInt c = 1; c < 4; c++) {
      G[c][k] = Ji[(c - 1) * 3 + k];
      G[0][k] -= G[c][k];
    }
  }
  AddPoint(4, G, NULL, vol, lambda, mu, rho, Ke, NULL);
  if (Me) {
    for (PetscInt q = 0; q < 4; q++) {
      PetscReal N[4] = {b, b, b, b};
      N[q]           = a;
      AddPoint(4, G, N, 0.25 * vol, 0, 0, rho, Ke, Me);
    }
  }
}

/* hex8: trilinear map, 2x2x2 Gauss points. */
void MBCElementHex8(const PetscReal X[], PetscReal lambda, PetscReal mu, PetscReal rho, PetscReal *Ke, PetscReal *Me)
{
  const PetscReal g = 1.0 / PetscSqrtReal(3.0);

  for (PetscInt q = 0; q < 8; q++) {
    const PetscReal xi[3] = {HexCorner[q][0] * g, HexCorner[q][1] * g, HexCorner[q][2] * g};
    PetscReal       dN[8][3], N[8], G[8][3], J[9] = {0}, Ji[9], det;

    for (PetscInt a = 0; a < 8; a++) {
      const PetscReal *c = HexCorner[a];
      const PetscReal  f[3] = {1 + c[0] * xi[0], 1 + c[1] * xi[1], 1 + c[2] * xi[2]};
      N[a]     = f[0] * f[1] * f[2] / 8;
      dN[a][0] = c[0] * f[1] * f[2] / 8;
      dN[a][1] = f[0] * c[1] * f[2] / 8;
      dN[a][2] = f[0] * f[1] * c[2] / 8;
      for (PetscInt i = 0; i < 3; i++)
        for (PetscInt k = 0; k < 3; k++) J[i * 3 + k] += X[3 * a + i] * dN[a][k];
    }
    det = Invert3(J, Ji);
    for (PetscInt a = 0; a < 8; a++)
      for (PetscInt k = 0; k < 3; k++) G[a][k] = dN[a][0] * Ji[0 * 3 + k] + dN[a][1] * Ji[1 * 3 + k] + dN[a][2] * Ji[2 * 3 + k];
    AddPoint(8, G, N, PetscAbsReal(det), lambda, mu, rho, Ke, Me);
  }
}

/* Assembles K (and M, unit factors times density, when M != NULL) over the body's cells, with
   the vertices of each cell in closure order for both coordinates and DOFs. */
PetscErrorCode MBCBodyAssembleElasticity(MBCBody body, Mat K, Mat M)
{
  DM           cdm;
  PetscSection lsec, csec;
  Vec          coords;
  const PetscScalar *x;
  PetscInt     cStart, cEnd, vStart, vEnd;
  PetscReal    Ke[576], Me[576], X[24];
  PetscInt     idx[24];

  PetscFunctionBegin;
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(DMGetCoordinateDM(body->dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
  for (PetscInt c = cStart; c < cEnd; c++) {
    PetscInt *closure = NULL, nclosure, nv = 0;

    PetscCall(DMPlexGetTransitiveClosure(body->dm, c, PETSC_TRUE, &nclosure, &closure));
    for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
      PetscInt v = closure[p], off, coff;
      if (v < vStart || v >= vEnd) continue;
      PetscCheck(nv < 8, PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': cell with more than 8 vertices", body->name);
      PetscCall(PetscSectionGetOffset(lsec, v, &off));
      PetscCall(PetscSectionGetOffset(csec, v, &coff));
      for (PetscInt i = 0; i < 3; i++) {
        idx[3 * nv + i] = off + i;
        X[3 * nv + i]   = PetscRealPart(x[coff + i]);
      }
      nv++;
    }
    PetscCall(DMPlexRestoreTransitiveClosure(body->dm, c, PETSC_TRUE, &nclosure, &closure));
    PetscCheck(nv == 4 || nv == 8, PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': cell with %" PetscInt_FMT " vertices; only tet4 and hex8 are supported", body->name, nv);
    PetscCall(PetscArrayzero(Ke, 9 * nv * nv));
    if (M) PetscCall(PetscArrayzero(Me, 9 * nv * nv));
    if (nv == 4) MBCElementTet4(X, body->lambda, body->mu, body->desc.density, Ke, M ? Me : NULL);
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
