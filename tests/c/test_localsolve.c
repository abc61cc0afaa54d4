/* The exact one-contact solver: on random SPD 3x3 blocks with strong normal-tangent coupling
   its natural-map residual (De Saxce) is at rounding level in every regime (separation, stick,
   slip), while "solve the block, clamp r_n, scale r_t onto the disk" is not exact. */
#include <mbc/private/multiplierimpl.h>

static PetscReal Residual(const PetscReal A[9], const PetscReal b[3], PetscReal mu, const PetscReal r[3])
{
  PetscReal u[3], x[3], p[3], t, e = 0, ut;
  for (int i = 0; i < 3; i++) u[i] = A[3 * i] * r[0] + A[3 * i + 1] * r[1] + A[3 * i + 2] * r[2] + b[i];
  ut   = PetscSqrtReal(u[1] * u[1] + u[2] * u[2]);
  x[0] = r[0] - (u[0] + mu * ut), x[1] = r[1] - u[1], x[2] = r[2] - u[2];
  t    = PetscSqrtReal(x[1] * x[1] + x[2] * x[2]);
  if (t <= mu * x[0]) p[0] = x[0], p[1] = x[1], p[2] = x[2];
  else if (mu * t <= -x[0]) p[0] = p[1] = p[2] = 0;
  else {
    const PetscReal a = (x[0] + mu * t) / (1 + mu * mu);
    p[0] = a, p[1] = mu * a * x[1] / t, p[2] = mu * a * x[2] / t;
  }
  for (int d = 0; d < 3; d++) e += (r[d] - p[d]) * (r[d] - p[d]);
  return PetscSqrtReal(e);
}

int main(int argc, char **argv)
{
  PetscRandom rnd;
  PetscInt    counts[3] = {0, 0, 0}, clampWrong = 0, ntrials = 20000;
  PetscReal   worst = 0;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscRandomCreate(PETSC_COMM_SELF, &rnd));
  PetscCall(PetscRandomSetInterval(rnd, -1, 1));
  for (PetscInt trial = 0; trial < ntrials; trial++) {
    PetscReal B[9], A[9], b[3], r[3], mu, scale, coupling, rc[3], t, det, Ai[9];
    for (int k = 0; k < 9; k++) PetscCall(PetscRandomGetValueReal(rnd, &B[k]));
    for (int k = 0; k < 3; k++) PetscCall(PetscRandomGetValueReal(rnd, &b[k]));
    PetscCall(PetscRandomGetValueReal(rnd, &mu));
    mu = 0.05 + PetscAbsReal(mu);
    for (int i = 0; i < 3; i++) /* A = B B^T + 0.05 I: SPD, normal-tangent coupling up to ~0.9 */
      for (int j = 0; j < 3; j++) {
        A[3 * i + j] = (i == j) ? 0.05 : 0;
        for (int k = 0; k < 3; k++) A[3 * i + j] += B[3 * i + k] * B[3 * j + k];
      }
    coupling = PetscMax(PetscAbsReal(A[1]), PetscAbsReal(A[2])) / PetscSqrtReal(A[0] * PetscMax(A[4], A[8]));
    PetscCall(MBCContactLocalSolve(A, b, mu, r));
    scale = 1 + PetscSqrtReal(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    worst = PetscMax(worst, Residual(A, b, mu, r) / scale);
    if (b[0] >= 0) counts[0]++;
    else if (PetscSqrtReal(r[1] * r[1] + r[2] * r[2]) < mu * r[0] * (1 - 1e-9)) counts[1]++;
    else counts[2]++;
    /* the shortcut: unconstrained block solve, clamp and scale */
    det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
    Ai[0] = (A[4] * A[8] - A[5] * A[7]) / det, Ai[1] = (A[2] * A[7] - A[1] * A[8]) / det, Ai[2] = (A[1] * A[5] - A[2] * A[4]) / det;
    Ai[3] = (A[5] * A[6] - A[3] * A[8]) / det, Ai[4] = (A[0] * A[8] - A[2] * A[6]) / det, Ai[5] = (A[2] * A[3] - A[0] * A[5]) / det;
    Ai[6] = (A[3] * A[7] - A[4] * A[6]) / det, Ai[7] = (A[1] * A[6] - A[0] * A[7]) / det, Ai[8] = (A[0] * A[4] - A[1] * A[3]) / det;
    for (int i = 0; i < 3; i++) rc[i] = -(Ai[3 * i] * b[0] + Ai[3 * i + 1] * b[1] + Ai[3 * i + 2] * b[2]);
    rc[0] = PetscMax(rc[0], 0);
    t     = PetscSqrtReal(rc[1] * rc[1] + rc[2] * rc[2]);
    if (t > mu * rc[0]) rc[1] *= mu * rc[0] / t, rc[2] *= mu * rc[0] / t;
    if (b[0] < 0 && coupling > 0.35 && Residual(A, b, mu, rc) / scale > 1e-6) clampWrong++;
  }
  PetscCall(PetscRandomDestroy(&rnd));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "%" PetscInt_FMT " blocks: %" PetscInt_FMT " separated, %" PetscInt_FMT " stick, %" PetscInt_FMT " slip; worst residual %.2e; solve-then-clamp wrong on %" PetscInt_FMT "\n", ntrials, counts[0], counts[1], counts[2], (double)worst, clampWrong));
  PetscCheck(worst < 1e-10, PETSC_COMM_SELF, PETSC_ERR_PLIB, "local solve residual %g", (double)worst);
  PetscCheck(counts[0] > 1000 && counts[1] > 1000 && counts[2] > 1000, PETSC_COMM_SELF, PETSC_ERR_PLIB, "every regime must be exercised");
  PetscCheck(clampWrong > 500, PETSC_COMM_SELF, PETSC_ERR_PLIB, "the shortcut should fail on coupled blocks (it did %" PetscInt_FMT " times)", clampWrong);
  PetscCall(PetscFinalize());
  return 0;
}
