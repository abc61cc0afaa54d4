static const char help[] = "mbcontact: finite-element multibody contact with Coulomb friction.\n"
                           "Usage: mpirun -n P mbcontact -scene SCENE.h5 [-mbc_monitor] [-mbc_view] [-log_view]\n"
                           "       mbcontact -fclib PROBLEM.hdf5 [-mbc_pgs_rtol 1e-8] [-fclib_write OUT.hdf5]\n"
                           "Make SCENE.h5 with mbcontact-prep SCENE.yaml -o SCENE.h5.\n\n";

#include <mbc/private/pgsimpl.h>
#include <hdf5.h>
#include <unistd.h>

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

/* mbcontact -fclib FILE: solve a public (or our own) friction-contact problem with our PGS.
   Sets *converged; -fclib_write OUT writes it back as a local problem with its solution. */
static PetscErrorCode RunFclib(const char *file, PetscBool *converged)
{
  MBCFrictionProblem fp;
  MBCPGS             pgs;
  PetscBool          global, set;
  Vec                r, u;
  char               out[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&pgs, sizeof(pgs)));
  PetscCall(MBCPGSSetFromOptions(&pgs));
  PetscCall(MBCFclibRead(file, &fp, &global));
  PetscCall(VecDuplicate(fp.q, &r));
  PetscCall(VecDuplicate(fp.q, &u));
  PetscCall(VecZeroEntries(r));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-fclib_warm_start", &set));
  if (set) PetscCall(MBCFclibReadSolution(file, r));
  PetscCall(MBCPGSSolve(&pgs, &fp, r, u));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "FCLIB %s: %s problem, %" PetscInt_FMT " contacts\n", file, global ? "global (condensed to local)" : "local", fp.nc));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "PGS %s in %" PetscInt_FMT " sweeps, %.4g s, FCLIB error %.6e (rtol %.1e)\n", MBCPGSReasonName(pgs.reason), pgs.its, (double)pgs.time, (double)pgs.error, (double)pgs.rtol));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-fclib_write", out, sizeof(out), &set));
  if (set) PetscCall(MBCFclibWriteLocal(out, &fp, r, u));
  *converged = (PetscBool)(pgs.reason > 0);
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&u));
  PetscCall(MBCPGSReset(&pgs));
  PetscCall(MBCFrictionProblemDestroy(&fp));
  PetscFunctionReturn(0);
}

/* The solver is main's: after an error it is destroyed there, which closes its files. */
static PetscErrorCode Run(PetscInt *status, MBCSolver *solverp)
{
  char      file[PETSC_MAX_PATH_LEN] = "";
  PetscBool set, help;
  MBCScene  scene;
  MBCSolver solver;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-fclib", file, sizeof(file), &set));
  if (set) {
    PetscBool converged;
    PetscCall(RunFclib(file, &converged));
    if (!converged) *status = 2; /* not an error of the input: say so through the exit status */
    PetscFunctionReturn(0);
  }
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
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, solverp));
  solver = *solverp;
  PetscCall(MBCSolverSetScene(solver, scene));
  PetscCall(MBCSolverSetFromOptions(solver));
  PetscCall(MBCSolverSolve(solver));
  PetscCall(MBCSolverDestroy(solverp));
  PetscFunctionReturn(0);
}

/* Like -options_left, for our own options only: an -mbc_ option nothing read is a typo
   (-mbc_dtt 1) or an option of another mode; a warning after the run, on rank 0. */
static PetscErrorCode WarnUnusedOptions(void)
{
  PetscInt  n;
  char    **names, **values;
  PetscBool help;

  PetscFunctionBegin;
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  if (help) PetscFunctionReturn(0);
  PetscCall(PetscOptionsLeftGet(NULL, &n, &names, &values));
  for (PetscInt i = 0; i < n; i++) {
    PetscBool ours;
    PetscCall(PetscStrncmp(names[i], "mbc_", 4, &ours));
    if (ours) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "mbcontact: warning: option -%s%s%s was not used (misspelt, or not an option of this run; -help lists them)\n", names[i], values[i] ? " " : "", values[i] ? values[i] : ""));
  }
  PetscCall(PetscOptionsLeftRestore(NULL, &n, &names, &values));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscErrorCode ierr;
  PetscMPIInt    size;

  PetscBool      traceback = PETSC_FALSE;
  PetscInt       status    = 0;
  MBCSolver      solver    = NULL;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-mbc_error_traceback", &traceback, NULL));
  if (!traceback) PetscCall(PetscPushErrorHandler(MBCErrorHandler, NULL));
  ierr = Run(&status, &solver);
  if (ierr) {
    /* A user error may be found on some ranks only; the others must not wait in a collective. */
    PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
    if (size > 1) MPI_Abort(PETSC_COMM_WORLD, 1);
    /* One rank: close the files (a result file left open is flushed by HDF5 at exit, after
       MPI_Finalize: a segfault); a second error (the disk still full) is not reported again. */
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    (void)MBCSolverDestroy(&solver);
    PetscCall(PetscPopErrorHandler());
    /* A result file whose close failed (the disk full) stays in HDF5's list, and HDF5 1.10 crashes
       closing it again inside MPI_Finalize: leave without finalising then. */
    if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE) > 0) {
      fflush(stdout);
      fflush(stderr);
      _exit(1);
    }
    PetscFinalize();
    return 1;
  }
  PetscCall(WarnUnusedOptions());
  if (!traceback) PetscCall(PetscPopErrorHandler());
  PetscCall(PetscFinalize());
  return (int)status;
}
