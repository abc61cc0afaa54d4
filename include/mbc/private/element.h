/* Private: element matrices of linear elasticity. X: node coordinates in the order
   MBCBodyCellVertices gives (3 per node); Ke, Me: (3 nv)^2 row-major, DOF 3a + i = component i of
   node a; they are added to, so zero them first; Me may be NULL. The node count tells the
   element: 4 tet4, 5 pyr5, 6 wedge6, 8 hex8 (and its variants), 10 tet10. */
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
/* MBCElementNodalWeights(nv, X, w): w[a] = int N_a dV; MBCElementMinJacobian(nv, X, &L): the
   smallest Jacobian determinant over the element's quadrature points (> 0 for a valid cell) and
   its longest edge L. */
PETSC_EXTERN void      MBCElementNodalWeights(PetscInt, const PetscReal[], PetscReal[]);
PETSC_EXTERN PetscReal MBCElementMinJacobian(PetscInt, const PetscReal[], PetscReal *);
/* bodyelementmixed.c: wedge6, pyr5 (a collapsed hex8) and tet10 */
PETSC_EXTERN void      MBCElementWedge6(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
PETSC_EXTERN void      MBCElementPyr5(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
PETSC_EXTERN void      MBCElementTet10(const PetscReal[], PetscReal, PetscReal, PetscReal, PetscReal *, PetscReal *);
PETSC_EXTERN void      MBCElementNodalWeightsMixed(PetscInt, const PetscReal[], PetscReal[]);
PETSC_EXTERN void      MBCElementCentreGradientMixed(PetscInt, const PetscReal[], const PetscReal[], PetscReal[9]);
PETSC_EXTERN PetscReal MBCElementMinJacobianMixed(PetscInt, const PetscReal[]);
PETSC_EXTERN void      MBCElementPyr5AsHex(const PetscReal[], PetscReal[24]);
#define MBC_MAX_CELL_NODES 10
