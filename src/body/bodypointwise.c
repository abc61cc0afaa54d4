/* Pointwise kernels for PetscFE: linear elasticity, loads and stress recovery. */
#include <mbc/private/bodyimpl.h>
#include <mbc/private/pointwise.h>

/* Isotropic elasticity C_ijkl = lambda d_ij d_kl + mu (d_ik d_jl + d_il d_jk);
   constants = {lambda, mu}; PETSc's layout is g3[((fc*Nc + gc)*dim + df)*dim + dg]. */
void MBCPointwiseElasticity_g3(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[], const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, PetscReal u_tShift, const PetscReal x[], PetscInt numConstants, const PetscScalar constants[], PetscScalar g3[])
{
  const PetscReal lambda = PetscRealPart(constants[0]), mu = PetscRealPart(constants[1]);

  for (PetscInt c = 0; c < dim; ++c) {
    for (PetscInt d = 0; d < dim; ++d) {
      g3[((c * dim + c) * dim + d) * dim + d] += mu;
      g3[((c * dim + d) * dim + d) * dim + c] += mu;
      g3[((c * dim + d) * dim + c) * dim + d] += lambda;
    }
  }
}

/* Surface load: traction constants[2..4] minus pressure constants[5] along the outward normal n. */
void MBCPointwiseTraction_f0(PetscInt dim, PetscInt Nf, PetscInt NfAux, const PetscInt uOff[], const PetscInt uOff_x[], const PetscScalar u[], const PetscScalar u_t[], const PetscScalar u_x[], const PetscInt aOff[], const PetscInt aOff_x[], const PetscScalar a[], const PetscScalar a_t[], const PetscScalar a_x[], PetscReal t, const PetscReal x[], const PetscReal n[], PetscInt numConstants, const PetscScalar constants[], PetscScalar f0[])
{
  for (PetscInt c = 0; c < dim; ++c) f0[c] = constants[2 + c] - constants[5] * n[c];
}
