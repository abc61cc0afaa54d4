# Declarations of the C API (include/mbcontact.h) for the binding (_core.pyx), in the pattern
# of slepc4py: PETSc's types come from petsc4py's PETSc.pxd.
from petsc4py.PETSc cimport PetscObject, PetscVec, PetscDM, PetscKSP, PetscMat, PetscViewer, MPI_Comm

cdef extern from "mbcontact.h" nogil:
    ctypedef int PetscErrorCode
    ctypedef long PetscInt
    ctypedef double PetscReal

    ctypedef struct _n_MBCScene
    ctypedef _n_MBCScene* MBCScene
    ctypedef struct _n_MBCBody
    ctypedef _n_MBCBody* MBCBody
    ctypedef struct _n_MBCSolver
    ctypedef _n_MBCSolver* MBCSolver

    const char MBC_VERSION_STRING[]

    PetscErrorCode MBCInitializePackage()
    PetscErrorCode MBCSceneLoad(MPI_Comm, const char[], MBCScene *)
    PetscErrorCode MBCSceneView(MBCScene, PetscViewer)
    PetscErrorCode MBCSceneGetFilename(MBCScene, const char **)
    PetscErrorCode MBCSceneGetNumBodies(MBCScene, PetscInt *)
    PetscErrorCode MBCSceneGetBodyName(MBCScene, PetscInt, const char **)
    PetscErrorCode MBCSceneDestroy(MBCScene *)

    PetscErrorCode MBCSolverCreate(MPI_Comm, MBCSolver *)
    PetscErrorCode MBCSolverSetScene(MBCSolver, MBCScene)
    PetscErrorCode MBCSolverGetScene(MBCSolver, MBCScene *)
    PetscErrorCode MBCSolverSetOptionsPrefix(MBCSolver, const char[])
    PetscErrorCode MBCSolverGetOptionsPrefix(MBCSolver, const char *[])
    PetscErrorCode MBCSolverSetFromOptions(MBCSolver)
    PetscErrorCode MBCSolverSetUp(MBCSolver)
    PetscErrorCode MBCSolverStep(MBCSolver)
    PetscErrorCode MBCSolverSolve(MBCSolver)
    PetscErrorCode MBCSolverGetStep(MBCSolver, PetscInt *, PetscInt *, PetscReal *)
    PetscErrorCode MBCSolverMonitorSet(MBCSolver, PetscErrorCode (*)(MBCSolver, PetscInt, PetscReal, void *) except? -1, void *, PetscErrorCode (*)(void **))
    PetscErrorCode MBCSolverView(MBCSolver, PetscViewer)
    PetscErrorCode MBCSolverDestroy(MBCSolver *)
    PetscErrorCode MBCSolverGetNumBodies(MBCSolver, PetscInt *)
    PetscErrorCode MBCSolverGetBody(MBCSolver, PetscInt, MBCBody *)
    PetscErrorCode MBCSolverGetMultipliers(MBCSolver, PetscVec *)
    PetscErrorCode MBCSolverGetContactPoints(MBCSolver, PetscInt *, const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscReal *[], const PetscInt *[])
    PetscErrorCode MBCSolverGetContactJoints(MBCSolver, PetscInt *, const PetscInt *[], const PetscReal *[])

    PetscErrorCode MBCBodyGetName(MBCBody, const char **)
    PetscErrorCode MBCBodyGetDM(MBCBody, PetscDM *)
    PetscErrorCode MBCBodyGetStressDM(MBCBody, PetscDM *)
    PetscErrorCode MBCBodyGetDisplacement(MBCBody, PetscVec *)
    PetscErrorCode MBCBodyGetVelocity(MBCBody, PetscVec *)
    PetscErrorCode MBCBodySetInitialState(MBCBody, PetscVec, PetscVec)
    PetscErrorCode MBCBodyCreateStress(MBCBody, PetscVec *)
    PetscErrorCode MBCBodyGetKSP(MBCBody, PetscKSP *)
    PetscErrorCode MBCBodyGetOperators(MBCBody, PetscMat *, PetscMat *, PetscMat *)
    PetscErrorCode MBCBodyView(MBCBody, PetscViewer)
    PetscErrorCode MBCBodyDestroy(MBCBody *)

cdef extern from "petsc.h" nogil:
    PetscErrorCode PetscObjectReference(PetscObject)
    bint PetscFinalizeCalled
    PetscErrorCode PetscObjectGetComm(PetscObject, MPI_Comm *)
    PetscErrorCode PetscErrorMessage(int, const char *[], char **)
