/* The bilinear map's inverse (MBCBilinearInverse: the slave weights and the master points of the
   mortar integration): on random convex quads, from trapezoids to strongly distorted ones, the
   (u, v) of random points of the face is found to 1e-13 from the centre, although Newton stops
   after the first step below 1e-9. */
#include <mbc/private/contactimpl.h>

static void Map(const PetscReal B[4][2], PetscReal u, PetscReal v, PetscReal y[2])
{
  for (int d = 0; d < 2; d++) y[d] = B[0][d] + B[1][d] * u + B[2][d] * v + B[3][d] * u * v;
}

int main(int argc, char **argv)
{
  PetscRandom rnd;
  PetscReal   worst = 0;
  PetscInt    nquads = 0, failed = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, 0, 1));
  while (nquads < 2000) {
    PetscReal Y[4][2], B[4][2], r[8], scale;
    PetscBool convex = PETSC_TRUE;
    for (int k = 0; k < 8; k++) PetscCall(PetscRandomGetValueReal(rnd, &r[k]));
    scale = PetscPowReal(10.0, 6 * r[0] - 3); /* faces of 1 mm to 1 km */
    /* the unit square's corners moved by up to 0.45 of its edge, at a random scale and offset */
    Y[0][0] = 0 + 0.9 * (r[1] - 0.5), Y[0][1] = 0 + 0.9 * (r[2] - 0.5);
    Y[1][0] = 1 + 0.9 * (r[3] - 0.5), Y[1][1] = 0 + 0.9 * (r[4] - 0.5);
    Y[2][0] = 1 + 0.9 * (r[5] - 0.5), Y[2][1] = 1 + 0.9 * (r[6] - 0.5);
    Y[3][0] = 0 + 0.9 * (r[7] - 0.5), Y[3][1] = 1;
    for (int i = 0; i < 4; i++) {
      const PetscReal *a = Y[i], *b = Y[(i + 1) % 4], *c = Y[(i + 2) % 4];
      const PetscReal  cr = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
      if (!(cr > 0.05)) convex = PETSC_FALSE;
    }
    if (!convex) continue;
    for (int i = 0; i < 4; i++)
      for (int d = 0; d < 2; d++) Y[i][d] = scale * (Y[i][d] + 7.0 * (d + 1));
    for (int d = 0; d < 2; d++) {
      B[0][d] = Y[0][d];
      B[1][d] = Y[1][d] - Y[0][d];
      B[2][d] = Y[3][d] - Y[0][d];
      B[3][d] = Y[0][d] - Y[1][d] + Y[2][d] - Y[3][d];
    }
    nquads++;
    for (int p = 0; p < 20; p++) {
      PetscReal u0, v0, y[2], u = 0.5, v = 0.5;
      PetscCall(PetscRandomGetValueReal(rnd, &u0));
      PetscCall(PetscRandomGetValueReal(rnd, &v0));
      Map(B, u0, v0, y);
      if (!MBCBilinearInverse(B, y, &u, &v)) failed++;
      worst = PetscMax(worst, PetscAbsReal(u - u0) + PetscAbsReal(v - v0));
    }
  }
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "bilinear inverse: %" PetscInt_FMT " convex quads, 20 points each: worst |du| + |dv| %g, %" PetscInt_FMT " not converged\n", nquads, (double)worst, failed));
  PetscCheck(failed == 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the inverse did not converge %" PetscInt_FMT " times", failed);
  PetscCheck(worst < 1e-13, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the inverse is off by %g", (double)worst);
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(PetscFinalize());
  return 0;
}
