/* MBCMultiplier: the contact multiplier solve u = W r + q, r in the Coulomb cones (De Saxce's
   complementarity), as one object with types in PETSc's pattern (KSP): the paper's projected
   Gauss-Seidel ("pgs") and a globalised semismooth Newton on the Alart-Curnier function
   ("newton", the default). Types need W assembled (MatGetRow for the sweeps, a sparse LU for
   the Newton steps). */
#pragma once

#include <petscksp.h>

typedef struct _p_MBCMultiplier *MBCMultiplier;
typedef struct _n_MBCFrictionProblem MBCFrictionProblem;

typedef const char *MBCMultiplierType;
#define MBCMULTIPLIERPGS    "pgs"
#define MBCMULTIPLIERNEWTON "newton"

typedef enum {
  MBC_MULTIPLIER_CONVERGED_RTOL      = 2,
  MBC_MULTIPLIER_ITERATING           = 0,
  MBC_MULTIPLIER_DIVERGED_ITS        = -3,
  MBC_MULTIPLIER_DIVERGED_NANORINF   = -4,
  MBC_MULTIPLIER_DIVERGED_LINE_SEARCH = -6,
  MBC_MULTIPLIER_DIVERGED_INFEASIBLE = -7 /* the equilibrium constraints of floating bodies cannot be met */
} MBCMultiplierConvergedReason;

PETSC_EXTERN PetscClassId  MBC_MULTIPLIER_CLASSID;
PETSC_EXTERN PetscFunctionList MBCMultiplierList;
PETSC_EXTERN PetscLogEvent MBC_MultiplierSolve, MBC_MultiplierSetUp;

PETSC_EXTERN PetscErrorCode MBCMultiplierInitializePackage(void);

/* The Newton type's dense LU on one rank: single precision refined in double (src/pc/mixedlu.c);
   -mbc_newton_dense_pc_type lu gives LAPACK's double LU */
#define PCMBCMIXEDLU "mbcmixedlu"
PETSC_EXTERN PetscErrorCode PCCreate_MBCMixedLU(PC);
PETSC_EXTERN PetscLogEvent  MBC_MixedLUFactor;
PETSC_EXTERN PetscErrorCode PCMBCMixedLUGetCounts(PC, PetscInt *, PetscInt *, PetscInt *);
PETSC_EXTERN PetscErrorCode MBCMultiplierRegister(const char[], PetscErrorCode (*)(MBCMultiplier));
PETSC_EXTERN PetscErrorCode MBCMultiplierCreate(MPI_Comm, MBCMultiplier *);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetType(MBCMultiplier, MBCMultiplierType);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetType(MBCMultiplier, MBCMultiplierType *);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetOptionsPrefix(MBCMultiplier, const char[]);
PETSC_EXTERN PetscErrorCode MBCMultiplierAppendOptionsPrefix(MBCMultiplier, const char[]);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetFromOptions(MBCMultiplier);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetProblem(MBCMultiplier, MBCFrictionProblem *);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetTolerances(MBCMultiplier, PetscReal, PetscInt);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetTolerances(MBCMultiplier, PetscReal *, PetscInt *);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetUp(MBCMultiplier);
PETSC_EXTERN PetscErrorCode MBCMultiplierSolve(MBCMultiplier, Vec, Vec);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetConvergedReason(MBCMultiplier, MBCMultiplierConvergedReason *);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetIterationNumber(MBCMultiplier, PetscInt *);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetMerit(MBCMultiplier, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetSolveTime(MBCMultiplier, PetscLogDouble *);
PETSC_EXTERN PetscErrorCode MBCMultiplierView(MBCMultiplier, PetscViewer);
PETSC_EXTERN PetscErrorCode MBCMultiplierGetRestartState(MBCMultiplier, Vec, PetscInt *, PetscBool *);
PETSC_EXTERN PetscErrorCode MBCMultiplierSetRestartState(MBCMultiplier, Vec, PetscInt);
PETSC_EXTERN PetscErrorCode MBCMultiplierReset(MBCMultiplier);
PETSC_EXTERN PetscErrorCode MBCMultiplierDestroy(MBCMultiplier *);
PETSC_EXTERN const char *const MBCMultiplierConvergedReasons[];
PETSC_EXTERN const char       *MBCMultiplierConvergedReasonName(MBCMultiplierConvergedReason);
