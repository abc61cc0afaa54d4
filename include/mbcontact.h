/* mbcontact: distributed-memory finite-element multibody contact with Coulomb friction.
   Public interface. Objects follow PETSc's lifecycle:
   Create / SetFromOptions / SetUp / Solve / View / Destroy. */
#pragma once

#include <petscdmplex.h>
#include <petscksp.h>

#define MBC_VERSION_MAJOR 0
#define MBC_VERSION_MINOR 1

/* Scene: what mbcontact-prep wrote to the scene file (materials, couples, loads, ...). */
typedef struct _n_MBCScene *MBCScene;
/* Body: one contact body, a DMPlex on its own sub-communicator with its factored stiffness. */
typedef struct _n_MBCBody *MBCBody;
/* Solver: the bodies of a scene, time stepping and output. */
typedef struct _n_MBCSolver *MBCSolver;

typedef enum {
  MBC_ANALYSIS_STATIC,
  MBC_ANALYSIS_DYNAMIC
} MBCAnalysisType;
PETSC_EXTERN const char *const MBCAnalysisTypes[];

typedef enum {
  MBC_MASS_CONSISTENT,
  MBC_MASS_LUMPED
} MBCMassType;
PETSC_EXTERN const char *const MBCMassTypes[];

PETSC_EXTERN PetscLogEvent MBC_SceneLoad, MBC_BodyLoad, MBC_BodyAssemble, MBC_BodyFactor, MBC_BodySolve, MBC_Output;
PETSC_EXTERN PetscErrorCode MBCInitializePackage(void);
PETSC_EXTERN PetscErrorCode MBCFileOpenWrite(const char[], FILE **);

/* Stopping short (src/sys/stop.c): signals checked between steps, errors on all ranks or some. */
PETSC_EXTERN PetscErrorCode MBCStopInitialize(MPI_Comm);
PETSC_EXTERN PetscErrorCode MBCStopFinalize(void);
PETSC_EXTERN int            MBCStopGetSignal(void);
PETSC_EXTERN PetscErrorCode MBCStopSignalled(MPI_Comm, int *);
PETSC_EXTERN PetscErrorCode MBCStopErrorIsCollective(PetscReal, PetscBool *);

PETSC_EXTERN PetscErrorCode MBCSceneLoad(MPI_Comm, const char[], MBCScene *);
PETSC_EXTERN PetscErrorCode MBCSceneCreateEmpty(MBCScene *);
PETSC_EXTERN PetscErrorCode MBCSceneView(MBCScene, PetscViewer);
PETSC_EXTERN PetscErrorCode MBCSceneDestroy(MBCScene *);

PETSC_EXTERN PetscErrorCode MBCSolverCreate(MPI_Comm, MBCSolver *);
PETSC_EXTERN PetscErrorCode MBCSolverSetScene(MBCSolver, MBCScene);
PETSC_EXTERN PetscErrorCode MBCSolverSetFromOptions(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverSetUp(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverSolve(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverView(MBCSolver, PetscViewer);
PETSC_EXTERN PetscErrorCode MBCSolverDestroy(MBCSolver *);
PETSC_EXTERN PetscErrorCode MBCSolverOutputAbort(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverHelp(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverGetNumBodies(MBCSolver, PetscInt *);
PETSC_EXTERN PetscErrorCode MBCSolverGetBody(MBCSolver, PetscInt, MBCBody *);

/* A body's handle is NULL on ranks outside its communicator. */
PETSC_EXTERN PetscErrorCode MBCBodyGetName(MBCBody, const char **);
PETSC_EXTERN PetscErrorCode MBCBodyGetDM(MBCBody, DM *);
PETSC_EXTERN PetscErrorCode MBCBodyGetDisplacement(MBCBody, Vec *);
PETSC_EXTERN PetscErrorCode MBCBodyGetKSP(MBCBody, KSP *);
