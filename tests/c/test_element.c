/* Element kernels: rigid-body motions carry no energy, a uniform strain carries exactly
   V/2 eps:C:eps, the mass matrix totals rho V per component, both matrices are symmetric. */
#include <mbc/private/element.h>

static const PetscReal HexRef[8][3] = {{-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};

static PetscErrorCode Check(const char *name, PetscInt nv, const PetscReal X[], PetscReal V, PetscBool affine)
{
  const PetscReal lambda = 1.3e10, mu = 0.9e10, rho = 2400;
  const PetscInt  n      = 3 * nv;
  PetscReal       Ke[576] = {0}, Me[576] = {0}, u[24], Ku[24], kmax = 0, mass = 0;

  PetscFunctionBegin;
  if (nv == 4) MBCElementTet4(X, lambda, mu, rho, Ke, Me);
  else MBCElementHex8(X, lambda, mu, rho, Ke, Me);
  for (PetscInt i = 0; i < n * n; i++) kmax = PetscMax(kmax, PetscAbsReal(Ke[i]));
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt j = 0; j < n; j++) {
      PetscCheck(PetscAbsReal(Ke[i * n + j] - Ke[j * n + i]) <= 1e-12 * kmax, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: K not symmetric", name);
      PetscCheck(PetscAbsReal(Me[i * n + j] - Me[j * n + i]) <= 1e-12 * rho * V, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: M not symmetric", name);
      if (i % 3 == 0 && j % 3 == 0) mass += Me[i * n + j];
    }
  PetscCheck(PetscAbsReal(mass / (rho * V) - 1) < 1e-12, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: mass %g, expected rho V = %g", name, (double)mass, (double)(rho * V));
  /* six rigid-body modes: translations e_k and rotations e_k x (x - x0) */
  for (PetscInt mode = 0; mode < 6; mode++) {
    for (PetscInt a = 0; a < nv; a++) {
      const PetscReal *x = &X[3 * a];
      PetscReal        r[3] = {0, 0, 0};
      if (mode < 3) r[mode] = 1;
      else {
        const PetscInt k = mode - 3, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        r[k1] = -x[k2];
        r[k2] = x[k1];
      }
      for (PetscInt i = 0; i < 3; i++) u[3 * a + i] = r[i];
    }
    for (PetscInt i = 0; i < n; i++) {
      Ku[i] = 0;
      for (PetscInt j = 0; j < n; j++) Ku[i] += Ke[i * n + j] * u[j];
      PetscCheck(PetscAbsReal(Ku[i]) < 1e-9 * kmax, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: rigid mode %" PetscInt_FMT " gives force %g", name, mode, (double)Ku[i]);
    }
  }
  /* uniform strain u = E x: energy V (lambda tr(E)^2 / 2 + mu E:E) (exact for affine cells) */
  if (affine) {
    const PetscReal E[3][3] = {{1e-3, 2e-4, 0}, {2e-4, -5e-4, 3e-4}, {0, 3e-4, 2e-4}};
    PetscReal       energy = 0, exact, tr = E[0][0] + E[1][1] + E[2][2], EE = 0;
    for (PetscInt a = 0; a < nv; a++)
      for (PetscInt i = 0; i < 3; i++) u[3 * a + i] = E[i][0] * X[3 * a] + E[i][1] * X[3 * a + 1] + E[i][2] * X[3 * a + 2];
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt j = 0; j < n; j++) energy += 0.5 * u[i] * Ke[i * n + j] * u[j];
    for (PetscInt i = 0; i < 3; i++)
      for (PetscInt j = 0; j < 3; j++) EE += E[i][j] * E[i][j];
    exact = V * (0.5 * lambda * tr * tr + mu * EE);
    PetscCheck(PetscAbsReal(energy / exact - 1) < 1e-12, PETSC_COMM_SELF, PETSC_ERR_PLIB, "%s: strain energy %.15g, exact %.15g", name, (double)energy, (double)exact);
  }
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "%s: ok\n", name));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  /* an affine (sheared, stretched) hexahedron x = x0 + A xi, volume 8 |det A| */
  const PetscReal A[3][3] = {{0.7, 0.2, 0.1}, {-0.1, 1.1, 0.3}, {0.05, 0.0, 0.4}}, x0[3] = {3, -2, 1};
  const PetscReal detA = A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) - A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) + A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
  PetscReal       Xh[24], Xd[24], Xt[12] = {0, 0, 0, 2, 0, 0, 0.5, 1.5, 0, 0.3, 0.4, 1.2};
  PetscRandom     rnd;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  for (PetscInt a = 0; a < 8; a++)
    for (PetscInt i = 0; i < 3; i++) Xh[3 * a + i] = x0[i] + A[i][0] * HexRef[a][0] + A[i][1] * HexRef[a][1] + A[i][2] * HexRef[a][2];
  PetscCall(Check("hex8 affine", 8, Xh, 8 * detA, PETSC_TRUE));
  /* a trilinear (warped) hexahedron: rigid modes and symmetry; its volume from the 8 corner tets
     is not exact, so the mass total is checked against the affine case only */
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -0.15, 0.15));
  for (PetscInt i = 0; i < 24; i++) {
    PetscReal r;
    PetscCall(PetscRandomGetValueReal(rnd, &r));
    Xd[i] = HexRef[i / 3][i % 3] + r;
  }
  PetscCall(PetscRandomDestroy(&rnd));
  {
    PetscReal Ke[576] = {0}, Me[576] = {0}, V = 0;
    MBCElementHex8(Xd, 0, 0, 1.0, Ke, Me); /* rho = 1: the mass total is the quadrature volume */
    for (PetscInt i = 0; i < 24; i += 3)
      for (PetscInt j = 0; j < 24; j += 3) V += Me[i * 24 + j];
    PetscCall(Check("hex8 warped", 8, Xd, V, PETSC_FALSE));
  }
  PetscCall(Check("tet4", 4, Xt, 2 * 1.5 * 1.2 / 6, PETSC_TRUE));
  PetscCall(PetscFinalize());
  return 0;
}
