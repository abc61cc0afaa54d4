/* The time integrator of a dynamic step: generalized-alpha (Chung and Hulbert 1993), with Newmark
   (alpha_m = alpha_f = 0) and HHT-alpha (alpha_m = 0, alpha_f = -alpha, Code_Aster's and Hilber's
   alpha <= 0) as its special cases. The equation of motion holds at t_n+1-alpha_f with the
   acceleration weighted by alpha_m,
     M a_n+1-am + C v_n+1-af + K u_n+1-af = F_n+1-af + H lambda_n+1-af,   x_n+1-a = (1 - a) x_n+1 + a x_n,
   and Newmark's updates of u and v with gamma = 1/2 - alpha_m + alpha_f, beta = (1 - alpha_m +
   alpha_f)^2 / 4 (second order, unconditionally stable for alpha_m <= alpha_f <= 1/2). In the
   incremental form of the paper, divided by 1 - alpha_f:
     (K + a0' M + a1 C) du = F_n+1 + cf F_n - (1 + cf) K u + M ((1 - am) (a2 v + a3 a) - am a) / (1 - af)
                             + C (a4 v + a5 a - cf v) + H (lambda_n+1 + cf lambda_n),
   cf = af / (1 - af), a0' = a0 (1 - am) / (1 - af): the operator is Newmark's with a0 scaled,
   factored once per step size; Newmark's a0..a7 as before. The spectral radius at infinite
   frequency rho_inf sets am = (2 rho - 1) / (rho + 1), af = rho / (rho + 1): rho 1 is the
   trapezoidal rule, rho 0 damps the highest modes in one step. */
#include <mbc/private/solverimpl.h>

const char *const MBCSchemeTypes[] = {"newmark", "hht", "generalized_alpha", "MBCSchemeType", "MBC_SCHEME_", NULL};

MBCTimeCoefficients MBCTimeScheme(PetscReal h, PetscReal beta, PetscReal gamma, PetscReal am, PetscReal af)
{
  MBCTimeCoefficients c;
  c.h = h, c.am = am, c.af = af, c.cf = af / (1 - af);
  c.a0 = 1 / (beta * h * h), c.a1 = gamma / (beta * h), c.a2 = 1 / (beta * h), c.a3 = 1 / (2 * beta) - 1;
  c.a4 = gamma / beta - 1, c.a5 = h / 2 * (gamma / beta - 2), c.a6 = h * (1 - gamma), c.a7 = gamma * h;
  c.aM = c.a0 * (1 - am) / (1 - af);
  return c;
}

/* The weight theta of lambda_n+1 in the step's mean contact force z = theta lambda_n+1 + (1 - theta)
   lambda_n on which the contacts' complementarity is imposed (docs/design.md): the share of the new
   force in the step's impulse, M dv = h M ((1 - gamma) a_n + gamma a_n+1) with (1 - am) M a_n+1 =
   (1 - af) H lambda_n+1 + ...: theta = gamma (1 - af) / (1 - am). Newmark's gamma; 1/2 for the
   trapezoidal rule (rho_inf 1), where z is the force the balance of energy sees (docs/design.md,
   "The mean force under generalized-alpha", with the energy measured on two bars parting). */
PetscReal MBCTimeContactWeight(PetscReal gamma, PetscReal am, PetscReal af)
{
  return gamma * (1 - af) / (1 - am);
}

/* Whether lambda_n enters a step only through the acceleration a_n (alpha_f = 0: Newmark, HHT
   with alpha 0), not explicitly on its right side: then the points that leave the contact set go
   on with an open point's force (src/interface/interfacerelease.c), else a_n would hold their
   last force without its partner and give the parted bodies a kick. */
PetscBool MBCTimeContactThroughAcceleration(PetscReal af)
{
  return (PetscBool)(af == 0);
}

/* -mbc_scheme, -mbc_hht_alpha, -mbc_galpha_rho_inf: the integrator of a scene without stages,
   overriding its own; beta, gamma, am, af of the solver set from them. *set: some was given. */
PetscErrorCode MBCSolverSchemeSetFromOptions(MBCSolver s, PetscOptionItems *PetscOptionsObject, PetscBool *set)
{
  PetscEnum scheme = (PetscEnum)s->scheme;
  PetscReal alpha = -0.3, rho = 0.8;
  PetscBool sets[3] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBegin;
  if (s->scheme == MBC_SCHEME_HHT) alpha = -s->af;
  if (s->scheme == MBC_SCHEME_GALPHA) rho = s->af / (1 - s->af);
  PetscCall(PetscOptionsEnum("-mbc_scheme", "Time integrator: Newmark (-mbc_newmark_beta, _gamma), HHT-alpha (-mbc_hht_alpha) or generalized-alpha (-mbc_galpha_rho_inf)", "MBCSolverSetFromOptions", MBCSchemeTypes, scheme, &scheme, &sets[0]));
  PetscCall(PetscOptionsReal("-mbc_hht_alpha", "HHT's alpha in [-1/3, 0] (Code_Aster's sign; 0: the trapezoidal rule)", "MBCSolverSetFromOptions", alpha, &alpha, &sets[1]));
  PetscCall(PetscOptionsReal("-mbc_galpha_rho_inf", "Generalized-alpha's spectral radius at infinite frequency, in [0, 1]", "MBCSolverSetFromOptions", rho, &rho, &sets[2]));
  *set = (PetscBool)(sets[0] || sets[1] || sets[2]);
  if (!*set) PetscFunctionReturn(0);
  s->scheme = (MBCSchemeType)scheme;
  PetscCheck(!sets[1] || s->scheme == MBC_SCHEME_HHT, s->comm, PETSC_ERR_ARG_INCOMP, "-mbc_hht_alpha is HHT's: give -mbc_scheme hht (the scheme is %s)", MBCSchemeTypes[s->scheme]);
  PetscCheck(!sets[2] || s->scheme == MBC_SCHEME_GALPHA, s->comm, PETSC_ERR_ARG_INCOMP, "-mbc_galpha_rho_inf is generalized-alpha's: give -mbc_scheme generalized_alpha (the scheme is %s)", MBCSchemeTypes[s->scheme]);
  if (s->scheme == MBC_SCHEME_NEWMARK) {
    s->am = s->af = 0;
    PetscFunctionReturn(0); /* beta and gamma: the scene's or -mbc_newmark_* */
  }
  if (s->scheme == MBC_SCHEME_HHT) {
    PetscCheck(alpha >= -1.0 / 3.0 - 1e-12 && alpha <= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_hht_alpha %g: must lie in [-1/3, 0]", (double)alpha);
    s->am = 0, s->af = -alpha;
  } else {
    PetscCheck(rho >= 0 && rho <= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_galpha_rho_inf %g: must lie in [0, 1]", (double)rho);
    s->am = (2 * rho - 1) / (rho + 1), s->af = rho / (rho + 1);
  }
  s->gamma = 0.5 - s->am + s->af;
  s->beta  = 0.25 * (1 - s->am + s->af) * (1 - s->am + s->af);
  PetscFunctionReturn(0);
}

/* The scheme's name of a scene's string (the prep writes newmark, hht, generalized_alpha). */
MBCSchemeType MBCSchemeFromName(const char *name)
{
  for (PetscInt i = 0; i < 3; i++)
    if (!strcmp(name, MBCSchemeTypes[i])) return (MBCSchemeType)i;
  return MBC_SCHEME_NEWMARK;
}
