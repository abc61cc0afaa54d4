/* Private: PetscFE pointwise kernels. Constants: {lambda, mu, f_x, f_y, f_z, pressure}. */
#pragma once

#include <petscsystypes.h>

#define MBC_NUM_CONSTANTS 6

PETSC_INTERN void MBCPointwiseElasticity_g3(PetscInt, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[], const PetscScalar[], PetscReal, PetscReal, const PetscReal[], PetscInt, const PetscScalar[], PetscScalar[]);
PETSC_INTERN void MBCPointwiseTraction_f0(PetscInt, PetscInt, PetscInt, const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[], const PetscScalar[], const PetscInt[], const PetscInt[], const PetscScalar[], const PetscScalar[], const PetscScalar[], PetscReal, const PetscReal[], const PetscReal[], PetscInt, const PetscScalar[], PetscScalar[]);
