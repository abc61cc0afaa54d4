/* The frictional contact problem u = W r + q, r in K = {|r_t| <= mu r_n}, with De Saxce's
   complementarity K* ∋ u + mu |u_t| e_n ⟂ r: its blocks, the velocity, the FCLIB merit, and
   the exact solve of one contact that the Gauss-Seidel sweeps use. */
#include <mbc/private/multiplierimpl.h>

/* Projection onto K_mu = {|x_t| <= mu x_n}. */
void MBCProjectCone(const PetscReal x[3], PetscReal mu, PetscReal p[3])
{
  const PetscReal t = PetscSqrtReal(x[1] * x[1] + x[2] * x[2]);
  if (t <= mu * x[0]) {
    p[0] = x[0], p[1] = x[1], p[2] = x[2];
  } else if (mu * t <= -x[0]) {
    p[0] = p[1] = p[2] = 0;
  } else {
    const PetscReal a = (x[0] + mu * t) / (1 + mu * mu);
    p[0] = a;
    p[1] = mu * a * x[1] / t;
    p[2] = mu * a * x[2] / t;
  }
}

/* |r - proj_K(r - (u + mu |u_t| e_n))|^2: the natural map of one contact with De Saxce's
   modified velocity (FCLIB's fcmer.c). */
PetscReal MBCContactNaturalMap2(const PetscReal r[3], const PetscReal u[3], PetscReal mu)
{
  const PetscReal ut = PetscSqrtReal(u[1] * u[1] + u[2] * u[2]);
  PetscReal       x[3], p[3], e = 0;
  x[0] = r[0] - (u[0] + mu * ut);
  x[1] = r[1] - u[1];
  x[2] = r[2] - u[2];
  MBCProjectCone(x, mu, p);
  for (int d = 0; d < 3; d++) e += (r[d] - p[d]) * (r[d] - p[d]);
  return e;
}

/* u = W r + q (+ G^T alpha when the problem has equilibrium constraints). */
PetscErrorCode MBCFrictionVelocity(MBCFrictionProblem *fp, Vec r, Vec u)
{
  PetscFunctionBegin;
  PetscCall(MatMultAdd(fp->W, r, fp->q, u));
  if (fp->G) PetscCall(MatMultTransposeAdd(fp->G, fp->alpha, u, u));
  PetscFunctionReturn(0);
}

/* |G r - e|^2: how far r is from the free bodies' equilibrium (0 without constraints). */
PetscErrorCode MBCFrictionEquilibriumResidual2(MBCFrictionProblem *fp, Vec r, PetscReal *g2)
{
  Vec       g;
  PetscReal gn;

  PetscFunctionBegin;
  *g2 = 0;
  if (!fp->G) PetscFunctionReturn(0);
  PetscCall(VecDuplicate(fp->e, &g));
  PetscCall(MatMult(fp->G, r, g));
  PetscCall(VecAXPY(g, -1.0, fp->e));
  PetscCall(VecNorm(g, NORM_2, &gn));
  PetscCall(VecDestroy(&g));
  *g2 = gn * gn;
  PetscFunctionReturn(0);
}

/* FCLIB merit of (r, u) as fclib_merit_local (fcmer.c) defines it:
   sqrt(sum over contacts of |r - proj_K(r - (u + mu |u_t| e_n))|^2) / (1 + sqrt(|q|_2)).
   A frictionless 1-block contributes (r_n - max(0, r_n - u_n))^2, what its 3-block with mu = 0
   and r_t = 0 would. With equilibrium constraints |G r - e|^2 joins the sum. u is taken as
   given (no product); sums over the ranks. */
PetscErrorCode MBCFrictionMerit(MBCFrictionProblem *fp, Vec r, Vec u, PetscReal *merit)
{
  const PetscScalar *rv, *uv;
  PetscReal          e = 0, qn;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(r, &rv));
  PetscCall(VecGetArrayRead(u, &uv));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i];
    if (fp->off[i + 1] - o == 1) {
      const PetscReal p = PetscMax(0, PetscRealPart(rv[o] - uv[o]));
      e += PetscSqr(PetscRealPart(rv[o]) - p);
    } else e += MBCContactNaturalMap2(&rv[o], &uv[o], fp->mu[i]);
  }
  PetscCall(VecRestoreArrayRead(u, &uv));
  PetscCall(VecRestoreArrayRead(r, &rv));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &e, 1, MPIU_REAL, MPIU_SUM, PetscObjectComm((PetscObject)fp->W)));
  if (fp->G) {
    PetscReal g2;
    PetscCall(MBCFrictionEquilibriumResidual2(fp, r, &g2));
    e += g2;
  }
  PetscCall(VecNorm(fp->q, NORM_2, &qn));
  *merit = PetscSqrtReal(e) / (1 + PetscSqrtReal(qn));
  PetscFunctionReturn(0);
}

/* Slip: r = rn (1, mu cos f, mu sin f) with u_n = 0 gives rn(f) = -b_n / den(f); the tangential
   velocity must point against the friction direction d(f): u_t(f) x d(f) = 0, u_t . d <= 0.
   Multiplied by den, G(f) = den u_t x d = ((-b_n A_tn + A_nn b_t) + M d) x d is a trigonometric
   polynomial of degree 2 (at most 4 roots) without the poles of rn: sign changes bracket them. */
static PetscReal SlipResidual(const PetscReal A[9], const PetscReal b[3], PetscReal mu, PetscReal f, PetscReal r[3], PetscReal *along, PetscReal *den)
{
  const PetscReal c = PetscCosReal(f), s = PetscSinReal(f);
  PetscReal       w[2]; /* den * u_t */
  *den = A[0] + mu * (A[1] * c + A[2] * s);
  w[0] = -b[0] * (A[3] + mu * (A[4] * c + A[5] * s)) + *den * b[1];
  w[1] = -b[0] * (A[6] + mu * (A[7] * c + A[8] * s)) + *den * b[2];
  r[0] = -b[0] / *den, r[1] = mu * r[0] * c, r[2] = mu * r[0] * s;
  *along = (w[0] * c + w[1] * s) / *den; /* u_t . d */
  return w[0] * s - w[1] * c;
}

/* Exact solution of one contact: u = A r + b (A row-major 3x3, the diagonal block of W). */
PetscErrorCode MBCContactLocalSolve(const PetscReal A[9], const PetscReal b[3], PetscReal mu, PetscReal r[3])
{
  PetscReal Ai[9], det;

  PetscFunctionBegin;
  if (b[0] >= 0 || !(A[0] > 0)) { /* separation, or no free DOF along the normal (all prescribed) */
    r[0] = r[1] = r[2] = 0;
    PetscFunctionReturn(0);
  }
  if (mu == 0) { /* frictionless: only the normal component */
    r[0] = -b[0] / A[0];
    r[1] = r[2] = 0;
    PetscFunctionReturn(0);
  }
  r[0] = r[1] = r[2] = 0;
  det = A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) + A[2] * (A[3] * A[7] - A[4] * A[6]);
  if (det != 0) { /* stick: u = 0 */
    Ai[0] = (A[4] * A[8] - A[5] * A[7]) / det, Ai[1] = (A[2] * A[7] - A[1] * A[8]) / det, Ai[2] = (A[1] * A[5] - A[2] * A[4]) / det;
    Ai[3] = (A[5] * A[6] - A[3] * A[8]) / det, Ai[4] = (A[0] * A[8] - A[2] * A[6]) / det, Ai[5] = (A[2] * A[3] - A[0] * A[5]) / det;
    Ai[6] = (A[3] * A[7] - A[4] * A[6]) / det, Ai[7] = (A[1] * A[6] - A[0] * A[7]) / det, Ai[8] = (A[0] * A[4] - A[1] * A[3]) / det;
    for (int i = 0; i < 3; i++) r[i] = -(Ai[3 * i] * b[0] + Ai[3 * i + 1] * b[1] + Ai[3 * i + 2] * b[2]);
    if (r[0] >= 0 && PetscSqrtReal(r[1] * r[1] + r[2] * r[2]) <= mu * r[0] * (1 + 1e-14)) PetscFunctionReturn(0);
  }
  { /* slip: sample G over the direction, bisect its sign changes, keep valid roots (den > 0,
       u_t . d <= 0); among several, the one whose friction force is closest to the stick trial's */
    const int N = 72;
    PetscReal best[3] = {0, 0, 0}, bestScore = PETSC_MAX_REAL, f0 = 0, G0, along, den, rr[3];
    G0 = SlipResidual(A, b, mu, f0, rr, &along, &den);
    for (int k = 1; k <= N; k++) {
      PetscReal f1 = 2 * PETSC_PI * k / N, G1 = SlipResidual(A, b, mu, f1, rr, &along, &den);
      if ((G0 <= 0 && G1 >= 0) || (G0 >= 0 && G1 <= 0)) {
        PetscReal lo = f0, hi = f1, Glo = G0, fm = f0;
        for (int it = 0; it < 200 && hi - lo > 4 * PETSC_MACHINE_EPSILON; it++) {
          PetscReal Gm;
          fm = 0.5 * (lo + hi);
          Gm = SlipResidual(A, b, mu, fm, rr, &along, &den);
          if ((Glo <= 0 && Gm <= 0) || (Glo >= 0 && Gm >= 0)) lo = fm, Glo = Gm;
          else hi = fm;
        }
        (void)SlipResidual(A, b, mu, fm, rr, &along, &den);
        if (den > 0 && along <= 0) {
          const PetscReal score = PetscSqr(rr[1] - r[1]) + PetscSqr(rr[2] - r[2]);
          if (score < bestScore) {
            bestScore = score;
            best[0] = rr[0], best[1] = rr[1], best[2] = rr[2];
          }
        }
      }
      f0 = f1, G0 = G1;
    }
    if (bestScore < PETSC_MAX_REAL) {
      r[0] = best[0], r[1] = best[1], r[2] = best[2];
      PetscFunctionReturn(0);
    }
  }
  /* no exact slip state (a singular or strongly non-symmetric block): projected fixed point */
  {
    PetscReal rho = 1.0 / PetscMax(PetscMax(A[0], A[4]), A[8]), x[3], u[3];
    for (int it = 0; it < 200; it++) {
      for (int i = 0; i < 3; i++) u[i] = A[3 * i] * r[0] + A[3 * i + 1] * r[1] + A[3 * i + 2] * r[2] + b[i];
      x[0] = r[0] - rho * (u[0] + mu * PetscSqrtReal(u[1] * u[1] + u[2] * u[2]));
      x[1] = r[1] - rho * u[1];
      x[2] = r[2] - rho * u[2];
      MBCProjectCone(x, mu, r);
    }
  }
  PetscFunctionReturn(0);
}

/* The diagonal 3x3 (1x1) blocks of this rank's contacts, row-major dim x dim, 9 slots each;
   Wd is W's diagonal part (its own rows and columns). */
PetscErrorCode MBCMultiplierDiagonalBlocks(MBCFrictionProblem *fp, Mat Wd, PetscReal **diag)
{
  PetscFunctionBegin;
  PetscCall(PetscMalloc1(9 * fp->nc + 1, diag));
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o, idx[3] = {o, o + 1, o + 2};
    PetscScalar    v[9];
    PetscCall(MatGetValues(Wd, dim, idx, dim, idx, v));
    for (PetscInt k = 0; k < dim * dim; k++) (*diag)[9 * i + k] = PetscRealPart(v[k]);
  }
  PetscFunctionReturn(0);
}

/* Block layout: dims[i] rows (1 or 3) for contact i, or 3 each when dims is NULL. */
PetscErrorCode MBCFrictionProblemSetBlocks(MBCFrictionProblem *fp, const PetscInt dims[])
{
  PetscFunctionBegin;
  PetscCall(PetscFree(fp->off));
  PetscCall(PetscMalloc1(fp->nc + 1, &fp->off));
  fp->off[0] = 0;
  for (PetscInt i = 0; i < fp->nc; i++) fp->off[i + 1] = fp->off[i] + (dims ? dims[i] : 3);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCFrictionProblemDestroy(MBCFrictionProblem *fp)
{
  PetscFunctionBegin;
  PetscCall(PetscFree(fp->off));
  PetscCall(MatDestroy(&fp->W));
  PetscCall(MatDestroy(&fp->Winv));
  PetscCall(VecDestroy(&fp->q));
  PetscCall(PetscFree(fp->mu));
  PetscCall(MatDestroy(&fp->G));
  PetscCall(VecDestroy(&fp->e));
  PetscCall(VecDestroy(&fp->alpha));
  PetscFunctionReturn(0);
}
