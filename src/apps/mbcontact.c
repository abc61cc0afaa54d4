static const char help[] = "mbcontact: finite-element multibody contact with Coulomb friction.\n"
                           "Usage: mpirun -n P mbcontact -scene SCENE.h5 [-mbc_monitor] [-mbc_view] [-log_view]\n"
                           "Make SCENE.h5 with mbcontact-prep SCENE.yaml -o SCENE.h5.\n\n";

#include <mbcontact.h>

/* User errors print one line that names the input; -mbc_error_traceback keeps PETSc's full report. */
static PetscErrorCode MBCErrorHandler(MPI_Comm comm, int line, const char *fun, const char *file, PetscErrorCode n, PetscErrorType p, const char *mess, void *ctx)
{
  PetscMPIInt rank = 0;

  if (p == PETSC_ERROR_INITIAL) {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (mess && mess[0]) fprintf(stderr, "[%d] mbcontact: error: %s\n", rank, mess);
    else {
      const char *text = NULL;
      PetscErrorMessage(n, &text, NULL);
      fprintf(stderr, "[%d] mbcontact: error: %s (in %s)\n", rank, text ? text : "unknown error", fun);
    }
    fflush(stderr);
  }
  return n;
}

static PetscErrorCode Run(void)
{
  char      file[PETSC_MAX_PATH_LEN] = "";
  PetscBool set, help;
  MBCScene  scene;
  MBCSolver solver;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-scene", file, sizeof(file), &set));
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  if (help && !set) { /* list the solver's options with the defaults of an empty scene */
    PetscCall(MBCSceneCreateEmpty(&scene));
    PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, &solver));
    PetscCall(MBCSolverSetScene(solver, scene));
    PetscCall(MBCSolverSetFromOptions(solver));
    PetscCall(MBCSolverDestroy(&solver));
    PetscFunctionReturn(0);
  }
  PetscCheck(set && file[0], PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "No scene file: give -scene SCENE.h5 (make one with mbcontact-prep)");
  PetscCall(MBCSceneLoad(PETSC_COMM_WORLD, file, &scene));
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, &solver));
  PetscCall(MBCSolverSetScene(solver, scene));
  PetscCall(MBCSolverSetFromOptions(solver));
  PetscCall(MBCSolverSolve(solver));
  PetscCall(MBCSolverDestroy(&solver));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscErrorCode ierr;
  PetscMPIInt    size;

  PetscBool      traceback = PETSC_FALSE;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-mbc_error_traceback", &traceback, NULL));
  if (!traceback) PetscCall(PetscPushErrorHandler(MBCErrorHandler, NULL));
  ierr = Run();
  if (ierr) {
    /* A user error may be found on some ranks only; the others must not wait in a collective. */
    PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
    if (size > 1) MPI_Abort(PETSC_COMM_WORLD, 1);
    PetscFinalize();
    return 1;
  }
  PetscCall(PetscFinalize());
  return 0;
}
