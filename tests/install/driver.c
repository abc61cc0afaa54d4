/* A user's program built against the installed mbcontact (pkg-config mbcontact, or
   find_package(mbcontact)): load a scene, solve, print each body's smallest displacement
   component. The scene is destroyed right after the solver takes it (it holds a reference). */
#include <mbcontact.h>

int main(int argc, char **argv)
{
  char      file[PETSC_MAX_PATH_LEN];
  MBCScene  scene;
  MBCSolver solver;
  PetscInt  nbodies;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-scene", file, sizeof(file), NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "mbcontact %s\n", MBC_VERSION_STRING));
  PetscCall(MBCSceneLoad(PETSC_COMM_WORLD, file, &scene));
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, &solver));
  PetscCall(MBCSolverSetScene(solver, scene));
  PetscCall(MBCSceneDestroy(&scene));
  PetscCall(MBCSolverSetFromOptions(solver));
  PetscCall(MBCSolverSolve(solver));
  PetscCall(MBCSolverGetNumBodies(solver, &nbodies));
  for (PetscInt b = 0; b < nbodies; b++) {
    MBCBody     body;
    Vec         u;
    const char *name;
    PetscReal   umin;
    PetscCall(MBCSolverGetBody(solver, b, &body));
    if (!body) continue; /* not on this rank */
    PetscCall(MBCBodyGetName(body, &name));
    PetscCall(MBCBodyGetDisplacement(body, &u));
    PetscCall(VecMin(u, NULL, &umin));
    PetscCall(PetscPrintf(PetscObjectComm((PetscObject)u), "body %s min u %.17g\n", name, (double)umin));
  }
  PetscCall(MBCSolverDestroy(&solver));
  PetscCall(PetscFinalize());
  return 0;
}
