/* Private: element matrices of linear elasticity. X: vertex coordinates in closure order
   (3 per vertex); Ke, Me: (3 nv)^2 row-major, DOF 3a + i = component i of vertex a; they are
   added to, so zero them first; Me may be NULL. */
#pragma once

#include <petscsys.h>

PETSC_EXTERN void MBCElementTet4(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
/* MBCElementHex8I: hex8 with incompatible modes, condensed (bodyelement.c); PETSC_FALSE if the
   cell is degenerate. */
PETSC_EXTERN void MBCElementHex8(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
PETSC_EXTERN PetscBool MBCElementHex8I(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
/* MBCElementHex8B: hex8 with B-bar (mean dilatation); MBCElementHex8Dilatation(X, U, &centre,
   &mean): div u at the centre and its cell mean over the 2x2x2 rule (hex8b's stress). */
PETSC_EXTERN void MBCElementHex8B(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
PETSC_EXTERN void MBCElementHex8Dilatation(const PetscReal[], const PetscReal[], PetscReal *, PetscReal *);
/* MBCElementCentreGradient(nv, X, U, gu): grad u at the cell's reference centre, gu[3 i + k] = d u_i / d x_k. */
PETSC_EXTERN void MBCElementCentreGradient(PetscInt, const PetscReal[], const PetscReal[], PetscReal[9]);
