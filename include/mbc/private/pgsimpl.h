/* Private: the frictional contact problem u = W r + q (FCLIB "local" form; a contact is a 3-block
   normal, tangent 1, tangent 2, or a 1-block (normal only) when frictionless; in mbcontact
   W = D, q = -Q) and its projected Gauss-Seidel. */
#pragma once

#include <mbcontact.h>
#include <petscblaslapack.h>

/* Distributed: each rank holds the rows of its contacts (nc, off, mu are this rank's; W is
   SeqAIJ on one rank, MPIAIJ on several, its row layout that of q). */
typedef struct {
  PetscInt   nc;   /* contacts on this rank */
  PetscInt  *off;  /* nc + 1: first local row of each contact; off[i+1] - off[i] is 3, or 1 (frictionless) */
  Mat        W;
  Vec        q;
  PetscReal *mu;
  char       title[256];
} MBCFrictionProblem;

typedef enum {
  MBC_PGS_ITERATING       = 0,
  MBC_PGS_CONVERGED_RTOL  = 1,
  MBC_PGS_DIVERGED_ITS    = -1,
  MBC_PGS_DIVERGED_NANORINF = -2
} MBCPGSReason;

typedef struct {
  PetscReal    rtol, omega;
  PetscInt     max_it, its, active_set;
  PetscBool    monitor;
  MBCPGSReason reason;
  PetscReal    error;          /* FCLIB merit at exit */
  PetscLogDouble time;
  PetscInt       sweeps_local; /* -mbc_pgs_local_sweeps: Gauss-Seidel sweeps over a rank's contacts between exchanges */
  /* per W: its diagonal and off-diagonal parts (MPIAIJ), the other ranks' r it needs */
  Mat            Wc, Ad, Ao;   /* Wc: a reference to the W these belong to */
  Vec            rg, cg, eg;   /* ghost values of r, of the active-set column map and coefficients */
  VecScatter     gsc;
  PetscReal     *diag;
  /* the last factor of the active-set step with no contact slipping, kept for the next steps */
  KSP            ksp;
  PetscInt      *luS, lun;
  PetscBool      kept;
  PetscReal      shift;        /* the diagonal shift of the kept factor */
} MBCPGS;

PETSC_EXTERN PetscLogEvent MBC_PGSSolve, MBC_FlexibilityAssemble;

PETSC_EXTERN PetscErrorCode MBCPGSSetFromOptions(MBCPGS *);
PETSC_EXTERN PetscErrorCode MBCPGSSolve(MBCPGS *, MBCFrictionProblem *, Vec, Vec);
PETSC_EXTERN PetscErrorCode MBCPGSReset(MBCPGS *);
PETSC_EXTERN PetscErrorCode MBCFrictionError(MBCFrictionProblem *, Vec, Vec, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCContactLocalSolve(const PetscReal[9], const PetscReal[3], PetscReal, PetscReal[3]);
PETSC_EXTERN PetscErrorCode MBCFrictionProblemSetBlocks(MBCFrictionProblem *, const PetscInt[]);
PETSC_EXTERN PetscErrorCode MBCFrictionProblemDestroy(MBCFrictionProblem *);
PETSC_EXTERN PetscErrorCode MBCFclibRead(const char[], MBCFrictionProblem *, PetscBool *);
PETSC_EXTERN PetscErrorCode MBCFclibReadSolution(const char[], Vec);
PETSC_EXTERN PetscErrorCode MBCFclibWriteLocal(const char[], MBCFrictionProblem *, Vec, Vec);
PETSC_EXTERN const char *MBCPGSReasonName(MBCPGSReason);
