/* Private: the frictional contact problem (FCLIB "local" form) and the multiplier solve object. */
#pragma once

#include <mbcmultiplier.h>
#include <petsc/private/petscimpl.h>
#include <petscksp.h>

/* u = W r + q (+ G^T alpha), r in the Coulomb cones, G r = e. A contact is a 3-block (normal,
   tangent 1, tangent 2), or a 1-block (normal only) when frictionless; in mbcontact W = D,
   q = -Q. Distributed: each rank holds the rows of its contacts (nc, off, mu are this rank's;
   W is SeqAIJ on one rank, MPIAIJ on several, its row layout that of q). G and e (optional,
   NULL when absent) are the equilibrium conditions of bodies their supports leave free in a
   static analysis (FETI's natural coarse space G = R^T H): alpha, their rigid-body amplitudes,
   is the unknown that goes with them. */
struct _n_MBCFrictionProblem {
  PetscInt   nc;   /* contacts on this rank */
  PetscInt  *off;  /* nc + 1: first local row of each contact; off[i+1] - off[i] is 3, or 1 (frictionless) */
  Mat        W;
  Mat        Winv; /* with W a shell (the matrix-free D): a sparse approximation of W^-1, FETI's lumped
                      preconditioner; W has no rows then, so only the newton type solves (NULL otherwise) */
  Vec        q;
  PetscReal *mu;
  Mat        G;     /* rigid modes x multipliers, or NULL */
  Vec        e, alpha; /* G's row layout */
  PetscInt   nco;   /* with W a shell: columns of the coarse space Phi of the Krylov steps (0: none) */
  PetscInt  *cocol; /* per local row: its column of Phi (-1: none), one nonzero per row */
  PetscReal *cow;   /*   and its value there */
  Mat        WPhi;  /* W Phi, dense, W's row layout */
  char       title[256];
  char       description[512]; /* written to an FCLIB file's info group when not empty (what a bonded point's row holds) */
};

typedef struct _MBCMultiplierOps *MBCMultiplierOps;
struct _MBCMultiplierOps {
  PetscErrorCode (*setfromoptions)(MBCMultiplier, PetscOptionItems *);
  PetscErrorCode (*setup)(MBCMultiplier);
  PetscErrorCode (*solve)(MBCMultiplier, Vec, Vec);
  PetscErrorCode (*view)(MBCMultiplier, PetscViewer);
  PetscErrorCode (*reset)(MBCMultiplier);
  PetscErrorCode (*destroy)(MBCMultiplier);
};

struct _p_MBCMultiplier {
  PETSCHEADER(struct _MBCMultiplierOps);
  MBCFrictionProblem          *fp;      /* borrowed */
  Mat                          Wsetup;  /* the W the set-up belongs to (a reference) */
  PetscObjectState             Wstate;
  PetscBool                    setupcalled;
  PetscReal                    rtol;
  PetscInt                     max_it, its;
  MBCMultiplierConvergedReason reason;
  PetscReal                    merit;   /* FCLIB merit at exit */
  PetscLogDouble               time;    /* of the last solve */
  PetscBool                    monitor, converged_reason;
  void                        *data;
};

/* Shared by the types: the cone, the natural map, the exact one-contact solve. */
PETSC_INTERN PetscLogEvent  MBC_NewtonInverse, MBC_NewtonLowRank, MBC_NewtonLowRankFactor; /* the Newton type's kept inverse: its build, its steps, a step's correction M and its LU */
PETSC_INTERN void           MBCProjectCone(const PetscReal[3], PetscReal, PetscReal[3]);
PETSC_INTERN PetscReal      MBCContactNaturalMap2(const PetscReal[3], const PetscReal[3], PetscReal);
PETSC_EXTERN PetscErrorCode MBCContactLocalSolve(const PetscReal[9], const PetscReal[3], PetscReal, PetscReal[3]);
PETSC_EXTERN PetscErrorCode MBCFrictionMerit(MBCFrictionProblem *, Vec, Vec, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCFrictionVelocity(MBCFrictionProblem *, Vec, Vec);
PETSC_EXTERN PetscErrorCode MBCFrictionEquilibriumResidual2(MBCFrictionProblem *, Vec, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCFrictionProblemSetBlocks(MBCFrictionProblem *, const PetscInt[]);
PETSC_EXTERN PetscErrorCode MBCFrictionProblemDestroy(MBCFrictionProblem *);
PETSC_EXTERN PetscErrorCode MBCFclibRead(const char[], MBCFrictionProblem *, PetscBool *);
PETSC_EXTERN PetscErrorCode MBCFclibReadSolution(const char[], Vec);
PETSC_EXTERN PetscErrorCode MBCFclibWriteLocal(const char[], MBCFrictionProblem *, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCMultiplierMonitorMerit(MBCMultiplier, PetscInt, PetscReal, const char[]);
PETSC_INTERN PetscErrorCode MBCMultiplierDiagonalBlocks(MBCFrictionProblem *, Mat, PetscReal **);

PETSC_EXTERN PetscErrorCode MBCMultiplierCreate_PGS(MBCMultiplier);
PETSC_INTERN PetscErrorCode MBCMultiplierPGSSetActiveSet(MBCMultiplier, PetscInt);
PETSC_EXTERN PetscErrorCode MBCMultiplierCreate_Newton(MBCMultiplier);
