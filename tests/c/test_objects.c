/* The objects as PETSc objects: the solver takes a reference to its scene (the caller may
   destroy its own at once, or keep using it after the solver is gone), options prefixes,
   PetscObjectGetComm, class ids. Before they were PETSc objects, MBCSolverSetScene took the
   scene over and destroying the scene after the solver freed it twice. */
#include <mbcontact.h>

int main(int argc, char **argv)
{
  MBCScene    scene, got;
  MBCSolver   solver;
  PetscInt    refct, nsteps;
  MPI_Comm    comm;
  PetscMPIInt cmp;
  PetscClassId id;
  const char  *prefix, *file;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(MBCSceneCreateEmpty(PETSC_COMM_WORLD, &scene)); /* dt 1, final time 1 */
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, &solver));
  PetscCall(PetscObjectGetClassId((PetscObject)solver, &id));
  PetscCheck(id == MBC_SOLVER_CLASSID, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "solver class id %d, expected MBC_SOLVER_CLASSID %d", (int)id, (int)MBC_SOLVER_CLASSID);
  PetscCall(PetscObjectGetComm((PetscObject)solver, &comm));
  PetscCallMPI(MPI_Comm_compare(comm, PETSC_COMM_WORLD, &cmp));
  PetscCheck(cmp == MPI_CONGRUENT || cmp == MPI_IDENT, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "PetscObjectGetComm(solver) is not the communicator it was created on");

  PetscCall(MBCSolverSetScene(solver, scene));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &refct));
  PetscCheck(refct == 2, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "scene reference count %" PetscInt_FMT " after MBCSolverSetScene, expected 2 (caller and solver)", refct);
  PetscCall(MBCSolverSetScene(solver, scene)); /* setting the same scene again takes no second reference */
  PetscCall(PetscObjectGetReference((PetscObject)scene, &refct));
  PetscCheck(refct == 2, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "scene reference count %" PetscInt_FMT " after a second MBCSolverSetScene, expected 2", refct);

  /* options under the solver's prefix only */
  PetscCall(MBCSolverSetOptionsPrefix(solver, "a_"));
  PetscCall(MBCSolverGetOptionsPrefix(solver, &prefix));
  PetscCheck(prefix && !strcmp(prefix, "a_"), PETSC_COMM_WORLD, PETSC_ERR_PLIB, "options prefix '%s', expected 'a_'", prefix ? prefix : "(null)");
  PetscCall(PetscOptionsSetValue(NULL, "-a_mbc_dt", "0.25"));
  PetscCall(PetscOptionsSetValue(NULL, "-mbc_dt", "0.5")); /* another solver's */
  PetscCall(MBCSolverSetFromOptions(solver));
  PetscCall(MBCSolverGetStep(solver, NULL, &nsteps, NULL));
  PetscCheck(nsteps == 4, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "%" PetscInt_FMT " steps with -a_mbc_dt 0.25 to t = 1, expected 4", nsteps);

  /* the caller lets go first, then the solver: the scene lives until the last reference goes */
  PetscCall(MBCSceneDestroy(&scene));
  PetscCheck(!scene, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "MBCSceneDestroy did not zero the caller's handle");
  PetscCall(MBCSolverGetScene(solver, &got));
  PetscCall(MBCSceneGetFilename(got, &file));
  PetscCheck(!strcmp(file, "scene.h5"), PETSC_COMM_WORLD, PETSC_ERR_PLIB, "scene file name '%s' after the caller's destroy, expected scene.h5", file);
  PetscCall(MBCSolverDestroy(&solver));

  /* the other order: the solver goes first, the caller's scene is still whole */
  PetscCall(MBCSceneCreateEmpty(PETSC_COMM_WORLD, &scene));
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, &solver));
  PetscCall(MBCSolverSetScene(solver, scene));
  PetscCall(MBCSolverDestroy(&solver));
  PetscCall(PetscObjectGetReference((PetscObject)scene, &refct));
  PetscCheck(refct == 1, PETSC_COMM_WORLD, PETSC_ERR_PLIB, "scene reference count %" PetscInt_FMT " after the solver is destroyed, expected 1", refct);
  PetscCall(MBCSceneGetFilename(scene, &file));
  PetscCheck(!strcmp(file, "scene.h5"), PETSC_COMM_WORLD, PETSC_ERR_PLIB, "scene file name '%s' after the solver's destroy, expected scene.h5", file);
  PetscCall(MBCSceneDestroy(&scene));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "objects ok\n"));
  PetscCall(PetscFinalize()); /* with -malloc_debug: reports anything left allocated */
  return 0;
}
