/* Private: the solver, the bodies of a scene and their time stepping. */
#pragma once

#include <mbc/private/contactimpl.h>
#include <mbc/private/pgsimpl.h>

typedef struct {
  PetscInt  body;         /* body holding the nearest vertex */
  PetscInt  rank;         /* world rank owning it */
  PetscInt  row;          /* its first global row in the body's displacement Vec (on that rank) */
  PetscReal distance, xv[3];
} MBCPointLocation;

struct _n_MBCSolver {
  MPI_Comm  comm;
  MBCScene  scene;        /* owned */
  PetscBool setupcalled;

  MBCAnalysisType analysis;
  MBCMassType     mass;
  PetscReal       dt, final_time, beta, gamma;
  PetscInt        nsteps, step;
  PetscReal       time;

  PetscInt  nbodies;
  MBCBody  *bodies;       /* NULL where this rank is not in the body */
  PetscMPIInt *body_first_rank, *body_nranks;

  /* output */
  char      output[PETSC_MAX_PATH_LEN];
  PetscInt  output_every, noutputs;
  PetscReal *output_times;
  PetscViewer *h5;        /* per body, NULL where the rank is not in the body */
  FILE     *points_csv, *energy_csv;
  MBCPointLocation *points;
  PetscBool monitor, view;

  MBCContact contact;     /* NULL when the scene has no couples */
  Mat       *H, *X;       /* per body: contact matrix and A^-1 H (NULL off the body) */
  MBCFrictionProblem fp;  /* D, q, mu of the multiplier problem, replicated on every rank */
  MBCPGS     pgs;
  PetscReal  dscale;      /* D is scaled by 1/dscale for the PGS: lambda = r / dscale */
  Vec        lambda, ucontact;
  PetscInt   npairs_built, *pairs_built; /* (couple, master, face) of each point when D was built */
  PetscBool  search_only;

  /* energy bookkeeping (dynamic) */
  PetscReal work, dissipated;
};

PETSC_INTERN PetscErrorCode MBCSolverOutputOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverEnergy(MBCSolver, PetscReal[4]);
PETSC_INTERN PetscErrorCode MBCSolverContactSetUp(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactSolve(MBCSolver);
