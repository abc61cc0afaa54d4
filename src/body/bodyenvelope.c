/* The envelope of the largest principal stress (output field `envelope`, docs/scene.md): per
   cell the largest value over every step so far of the cell stress's largest principal value
   (tension positive) and the time it occurred. Updated after every step, not only at outputs: a
   peak between two outputs is kept. */
#include <mbc/private/bodyimpl.h>

/* Largest eigenvalue of the symmetric tensor in Voigt order xx yy zz xy yz xz (trigonometric
   form of the cubic's roots: no iteration, exact to rounding). */
static PetscReal LargestPrincipal(const PetscScalar sv[6])
{
  const PetscReal xx = PetscRealPart(sv[0]), yy = PetscRealPart(sv[1]), zz = PetscRealPart(sv[2]);
  const PetscReal xy = PetscRealPart(sv[3]), yz = PetscRealPart(sv[4]), xz = PetscRealPart(sv[5]);
  const PetscReal q = (xx + yy + zz) / 3, off = xy * xy + yz * yz + xz * xz;
  PetscReal       p, r, phi, b[6];

  p = PetscSqrtReal((PetscSqr(xx - q) + PetscSqr(yy - q) + PetscSqr(zz - q) + 2 * off) / 6);
  if (p <= 1e-15 * (PetscAbsReal(q) + PETSC_SMALL)) return q; /* isotropic */
  b[0] = (xx - q) / p, b[1] = (yy - q) / p, b[2] = (zz - q) / p, b[3] = xy / p, b[4] = yz / p, b[5] = xz / p;
  r    = 0.5 * (b[0] * (b[1] * b[2] - b[4] * b[4]) - b[3] * (b[3] * b[2] - b[4] * b[5]) + b[5] * (b[3] * b[4] - b[1] * b[5]));
  r    = PetscMax(-1.0, PetscMin(1.0, r));
  phi  = PetscAcosReal(r) / 3;
  return q + 2 * p * PetscCosReal(phi);
}

/* envelope = max(envelope, the largest principal stress of u) cell by cell, with the time t. */
PetscErrorCode MBCBodyEnvelopeUpdate(MBCBody body, PetscReal t)
{
  Vec                stress;
  const PetscScalar *sa;
  PetscScalar       *ea;
  PetscInt           n;

  PetscFunctionBegin;
  if (!body->envelope) {
    PetscCall(DMCreateGlobalVector(body->dmStress, &body->envelope));
    PetscCall(VecGetLocalSize(body->envelope, &n));
    PetscCall(VecGetArray(body->envelope, &ea));
    for (PetscInt i = 0; i < n; i += 6) ea[i] = PETSC_MIN_REAL, ea[i + 1] = t;
    PetscCall(VecRestoreArray(body->envelope, &ea));
  }
  PetscCall(DMGetGlobalVector(body->dmStress, &stress));
  PetscCall(MBCBodyComputeStress(body, body->u, stress));
  PetscCall(VecGetLocalSize(stress, &n));
  PetscCall(VecGetArrayRead(stress, &sa));
  PetscCall(VecGetArray(body->envelope, &ea));
  for (PetscInt i = 0; i < n; i += 6) {
    const PetscReal s1 = LargestPrincipal(&sa[i]);
    if (s1 > PetscRealPart(ea[i])) ea[i] = s1, ea[i + 1] = t;
  }
  PetscCall(VecRestoreArray(body->envelope, &ea));
  PetscCall(VecRestoreArrayRead(stress, &sa));
  PetscCall(DMRestoreGlobalVector(body->dmStress, &stress));
  PetscFunctionReturn(0);
}

/* The envelope (per cell, stress layout: the largest principal stress so far [0] and its time [1]);
   that of t = 0 where the body was not stepped yet. */
PetscErrorCode MBCBodyGetEnvelope(MBCBody body, Vec *envelope)
{
  PetscFunctionBegin;
  if (!body->envelope) PetscCall(MBCBodyEnvelopeUpdate(body, 0.0));
  *envelope = body->envelope;
  PetscFunctionReturn(0);
}
