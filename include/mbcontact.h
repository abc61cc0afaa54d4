/* mbcontact: distributed-memory finite-element multibody contact with Coulomb friction.
   Public interface. The objects are PETSc objects (cast to PetscObject for PetscObjectGetComm,
   PetscObjectReference, PetscObjectSetOptionsPrefix, ...) and follow PETSc's lifecycle:
   Create / SetFromOptions / SetUp / Solve / View / Destroy, with reference counting. */
#pragma once

#include <petscdmplex.h>
#include <petscksp.h>
#include <mbcversion.h>

/* Scene: what mbcontact-prep wrote to the scene file (materials, couples, loads, ...). */
typedef struct _n_MBCScene *MBCScene;
/* Body: one contact body, a DMPlex on its own sub-communicator with its factored stiffness. */
typedef struct _n_MBCBody *MBCBody;
/* Solver: the bodies of a scene, time stepping and output. */
typedef struct _n_MBCSolver *MBCSolver;

typedef enum {
  MBC_ANALYSIS_STATIC,
  MBC_ANALYSIS_DYNAMIC,
  MBC_ANALYSIS_MODAL /* the lowest natural frequencies and modes (SLEPc; src/solver/solvermodal.c) */
} MBCAnalysisType;
PETSC_EXTERN const char *const MBCAnalysisTypes[];

typedef enum {
  MBC_MASS_CONSISTENT,
  MBC_MASS_LUMPED
} MBCMassType;
PETSC_EXTERN const char *const MBCMassTypes[];

PETSC_EXTERN PetscClassId MBC_SCENE_CLASSID, MBC_SOLVER_CLASSID, MBC_BODY_CLASSID;
PETSC_EXTERN PetscLogEvent MBC_SceneLoad, MBC_BodyLoad, MBC_BodyAssemble, MBC_BodyFactor, MBC_BodySolve, MBC_Output;
PETSC_EXTERN PetscErrorCode MBCInitializePackage(void);
PETSC_EXTERN PetscErrorCode MBCFileOpenWrite(const char[], FILE **);

/* MB this rank may still take: its share of its node's available memory, 0 where unknown (src/sys/memory.c). Collective. */
PETSC_EXTERN PetscErrorCode MBCMemoryAvailable(MPI_Comm, PetscReal *);

/* Stopping short (src/sys/stop.c): signals checked between steps, errors on all ranks or some. */
PETSC_EXTERN PetscErrorCode MBCStopInitialize(MPI_Comm);
PETSC_EXTERN PetscErrorCode MBCStopFinalize(void);
PETSC_EXTERN int            MBCStopGetSignal(void);
PETSC_EXTERN PetscErrorCode MBCStopSignalled(MPI_Comm, int *);
PETSC_EXTERN PetscErrorCode MBCStopErrorIsCollective(PetscReal, PetscBool *);

PETSC_EXTERN PetscErrorCode MBCSceneLoad(MPI_Comm, const char[], MBCScene *);
PETSC_EXTERN PetscErrorCode MBCSceneCreateEmpty(MPI_Comm, MBCScene *);
PETSC_EXTERN PetscErrorCode MBCSceneView(MBCScene, PetscViewer);
PETSC_EXTERN PetscErrorCode MBCSceneGetFilename(MBCScene, const char **);
PETSC_EXTERN PetscErrorCode MBCSceneGetNumBodies(MBCScene, PetscInt *);
PETSC_EXTERN PetscErrorCode MBCSceneGetBodyName(MBCScene, PetscInt, const char **);
PETSC_EXTERN PetscErrorCode MBCSceneDestroy(MBCScene *);

PETSC_EXTERN PetscErrorCode MBCSolverCreate(MPI_Comm, MBCSolver *);
/* The solver takes a reference to the scene: the caller may destroy its own at once. */
PETSC_EXTERN PetscErrorCode MBCSolverSetScene(MBCSolver, MBCScene);
PETSC_EXTERN PetscErrorCode MBCSolverGetScene(MBCSolver, MBCScene *);
PETSC_EXTERN PetscErrorCode MBCSolverSetOptionsPrefix(MBCSolver, const char[]);
PETSC_EXTERN PetscErrorCode MBCSolverAppendOptionsPrefix(MBCSolver, const char[]);
PETSC_EXTERN PetscErrorCode MBCSolverGetOptionsPrefix(MBCSolver, const char *[]);
PETSC_EXTERN PetscErrorCode MBCSolverSetFromOptions(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverSetUp(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverSolve(MBCSolver);
/* One time (or load) step of what MBCSolverSolve does; the first call sets up, searches contact
   and opens the result files (a dynamic analysis first computes its initial state, step 0); the
   call doing the last step closes them. */
PETSC_EXTERN PetscErrorCode MBCSolverStep(MBCSolver);
PETSC_EXTERN PetscErrorCode MBCSolverGetStep(MBCSolver, PetscInt *, PetscInt *, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCSolverMonitorSet(MBCSolver, PetscErrorCode (*)(MBCSolver, PetscInt, PetscReal, void *), void *, PetscErrorCode (*)(void **));
/* The contact multipliers of the last step (forces lambda_n+1: normal, t1, t2 per point, rank
   order; a new Vec whenever the contact points change, so get it again after a step) and the contact points
   of the last step in couple order, replicated on every rank (pointers owned by the solver,
   valid until the next step); state: 0 separated, 1 stick, 2 slip. */
PETSC_EXTERN PetscErrorCode MBCSolverGetMultipliers(MBCSolver, Vec *);
PETSC_EXTERN PetscErrorCode MBCSolverGetContactPoints(MBCSolver, PetscInt *, const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscInt *[]);
PETSC_EXTERN PetscErrorCode MBCSolverGetContactJoints(MBCSolver, PetscInt *, const PetscInt *[], const PetscReal *[]);
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
/* The body's stiffness K, mass M (with the reservoir's added mass; NULL in a static analysis) and
   absorbing boundaries' dashpots Cb (NULL without), unconstrained, after MBCSolverSetUp. */
PETSC_EXTERN PetscErrorCode MBCBodyGetOperators(MBCBody, Mat *, Mat *, Mat *);
PETSC_EXTERN PetscErrorCode MBCBodyView(MBCBody, PetscViewer);
PETSC_EXTERN PetscErrorCode MBCBodyGetVelocity(MBCBody, Vec *);
/* The initial displacement and velocity of a dynamic analysis (copies; NULL: the scene's), in the
   layout of MBCBodyGetDisplacement's Vec: after MBCSolverSetUp, before the first MBCSolverStep. */
PETSC_EXTERN PetscErrorCode MBCBodySetInitialState(MBCBody, Vec, Vec);
PETSC_EXTERN PetscErrorCode MBCBodyGetStressDM(MBCBody, DM *);
PETSC_EXTERN PetscErrorCode MBCBodyCreateStress(MBCBody, Vec *);
