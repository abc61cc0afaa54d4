static const char help[] = "mbcontact: finite-element multibody contact with Coulomb friction.\n"
                           "Usage: mpirun -n P mbcontact -scene SCENE.h5 [-mbc_monitor] [-mbc_view] [-log_view]\n"
                           "       mbcontact -fclib PROBLEM.hdf5 [-mbc_multiplier_type newton|pgs] [-mbc_multiplier_rtol 1e-8] [-fclib_write OUT.hdf5]\n"
                           "Make SCENE.h5 with mbcontact-prep SCENE.yaml -o SCENE.h5.\n\n";

#include <mbc/private/multiplierimpl.h>
#include <mbcontact.h>
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

/* mbcontact -fclib FILE: solve a public (or our own) friction-contact problem with our
   multiplier solve (-mbc_multiplier_type). Sets *converged; -fclib_write OUT writes it back as a
   local problem with its solution. */
static PetscErrorCode RunFclib(const char *file, PetscBool *converged)
{
  MBCFrictionProblem fp;
  MBCMultiplier      mult;
  MBCMultiplierType  type;
  PetscBool          global, set;
  Vec                r, u;
  char               out[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscMemzero(&fp, sizeof(fp)));
  PetscCall(MBCMultiplierCreate(PETSC_COMM_SELF, &mult));
  PetscCall(MBCMultiplierSetOptionsPrefix(mult, "mbc_"));
  PetscCall(MBCMultiplierSetFromOptions(mult));
  PetscCall(MBCFclibRead(file, &fp, &global));
  PetscCall(VecDuplicate(fp.q, &r));
  PetscCall(VecDuplicate(fp.q, &u));
  PetscCall(VecZeroEntries(r));
  PetscCall(PetscOptionsHasName(NULL, NULL, "-fclib_warm_start", &set));
  if (set) PetscCall(MBCFclibReadSolution(file, r));
  PetscCall(MBCMultiplierSetProblem(mult, &fp));
  PetscCall(MBCMultiplierSolve(mult, r, u));
  PetscCall(MBCMultiplierGetType(mult, &type));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "FCLIB %s: %s problem, %" PetscInt_FMT " contacts\n", file, global ? "global (condensed to local)" : "local", fp.nc));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "%s %s in %" PetscInt_FMT " iterations, %.4g s, FCLIB merit %.6e (rtol %.1e)\n", type, MBCMultiplierConvergedReasonName(mult->reason), mult->its, (double)mult->time, (double)mult->merit, (double)mult->rtol));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-fclib_write", out, sizeof(out), &set));
  if (set) PetscCall(MBCFclibWriteLocal(out, &fp, r, u));
  *converged = (PetscBool)(mult->reason > 0);
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&u));
  PetscCall(MBCMultiplierDestroy(&mult));
  PetscCall(MBCFrictionProblemDestroy(&fp));
  PetscFunctionReturn(0);
}

/* The program's own options, listed by -help like the solver's (read again where used). */
static PetscErrorCode ProgramOptions(char scene[], size_t len, PetscBool *set)
{
  char      fclib[PETSC_MAX_PATH_LEN] = "", out[PETSC_MAX_PATH_LEN] = "";
  PetscBool flag = PETSC_FALSE;

  PetscFunctionBegin;
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "mbcontact program options", NULL);
  PetscCall(PetscOptionsString("-scene", "Scene file made by mbcontact-prep", NULL, scene, scene, len, set));
  PetscCall(PetscOptionsString("-fclib", "Solve this FCLIB friction-contact problem with the PGS instead of a scene (exit status 2 if it does not converge)", NULL, fclib, fclib, sizeof(fclib), NULL));
  PetscCall(PetscOptionsString("-fclib_write", "With -fclib: write the problem back as a local problem with its solution", NULL, out, out, sizeof(out), NULL));
  PetscCall(PetscOptionsBool("-fclib_warm_start", "With -fclib: start from the file's /solution/r", NULL, flag, &flag, NULL));
  PetscCall(PetscOptionsBool("-mbc_error_traceback", "On an error, PETSc's full report instead of the one-line message", NULL, flag, &flag, NULL));
  PetscOptionsEnd();
  PetscFunctionReturn(0);
}

static PetscErrorCode Run(PetscInt *status, MBCSolver *solver)
{
  char      file[PETSC_MAX_PATH_LEN] = "";
  PetscBool set, help;
  MBCScene  scene;

  PetscFunctionBegin;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-fclib", file, sizeof(file), &set));
  if (set) {
    PetscBool converged;
    PetscCall(RunFclib(file, &converged));
    if (!converged) *status = 2; /* not an error of the input: say so through the exit status */
    PetscFunctionReturn(0);
  }
  PetscCall(ProgramOptions(file, sizeof(file), &set));
  PetscCall(PetscOptionsHasHelp(NULL, &help));
  if (help && !set) { /* list the solver's options with the defaults of an empty scene */
    PetscCall(MBCSceneCreateEmpty(PETSC_COMM_WORLD, &scene));
    PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, solver));
    PetscCall(MBCSolverSetScene(*solver, scene));
    PetscCall(MBCSceneDestroy(&scene)); /* the solver holds a reference */
    PetscCall(MBCSolverSetFromOptions(*solver));
    PetscCall(MBCSolverHelp(*solver));
    PetscCall(MBCSolverDestroy(solver));
    PetscFunctionReturn(0);
  }
  PetscCheck(set && file[0], PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT, "No scene file: give -scene SCENE.h5 (make one with mbcontact-prep)");
  PetscCall(MBCSceneLoad(PETSC_COMM_WORLD, file, &scene));
  PetscCall(MBCSolverCreate(PETSC_COMM_WORLD, solver));
  PetscCall(MBCSolverSetScene(*solver, scene));
  PetscCall(MBCSceneDestroy(&scene)); /* the solver holds a reference */
  PetscCall(MBCSolverSetFromOptions(*solver));
  if (help) PetscCall(MBCSolverHelp(*solver));
  PetscCall(MBCSolverSolve(*solver));
  PetscCall(MBCSolverDestroy(solver));
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

/* glibc's malloc backs its large blocks with transparent huge pages only when told so at start-up
   (GLIBC_TUNABLES=glibc.malloc.hugetlb=1, glibc >= 2.35; the kernel's THP mode "madvise", Debian's
   default): the factorizations' fresh workspace then faults 2 MB at a time instead of 4 kB. On
   the 198k dam, system time 10.0 -> 6.0 s, wall 38.1 -> 32.3 s. So, before MPI starts, the program
   runs itself again with it set, unless GLIBC_TUNABLES is set already (the user's choice, or this
   second start), MBC_HUGEPAGES=0, THP is off, or valgrind runs it. If exec fails it goes on. */
static void ReexecWithHugePages(char **argv)
{
  const char *off = getenv("MBC_HUGEPAGES"), *pre = getenv("LD_PRELOAD");
  char        mode[128] = "";
  FILE       *f;

  if (getenv("GLIBC_TUNABLES") || (off && !strcmp(off, "0")) || (pre && strstr(pre, "vgpreload"))) return;
  f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
  if (!f) return;
  if (!fgets(mode, sizeof(mode), f)) mode[0] = 0;
  fclose(f);
  if (!strstr(mode, "[madvise]") && !strstr(mode, "[always]")) return;
  if (setenv("GLIBC_TUNABLES", "glibc.malloc.hugetlb=1", 1)) return;
  execv("/proc/self/exe", argv);
  unsetenv("GLIBC_TUNABLES");
}

int main(int argc, char **argv)
{
  PetscErrorCode ierr;
  PetscBool      traceback = PETSC_FALSE, all;
  PetscInt       status    = 0;
  MBCSolver      solver    = NULL;
  int            sig;

  ReexecWithHugePages(argv);
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  if (getenv("GLIBC_TUNABLES") && strstr(getenv("GLIBC_TUNABLES"), "glibc.malloc.hugetlb=1")) PetscCall(PetscInfo(NULL, "malloc: transparent huge pages (GLIBC_TUNABLES %s)\n", getenv("GLIBC_TUNABLES")));
  PetscCall(PetscOptionsGetBool(NULL, NULL, "-mbc_error_traceback", &traceback, NULL));
  if (!traceback) PetscCall(PetscPushErrorHandler(MBCErrorHandler, NULL));
  PetscCall(MBCStopInitialize(PETSC_COMM_WORLD));
  ierr = Run(&status, &solver);
  sig  = MBCStopGetSignal();
  if (ierr) {
    /* The result files hold every completed output step (committed after each). Every rank
       stopped (a failed check on reduced values, a signal, a full disk): finish PETSc, so that
       -log_view is printed. A user error found on some ranks only: the others wait in a
       collective, so the job is aborted. */
    PetscCall(MBCStopErrorIsCollective(3.0, &all));
    MBCSolverOutputAbort(solver);
    if (!all) MPI_Abort(PETSC_COMM_WORLD, sig ? 128 + sig : 1);
    MBCStopFinalize();
    /* A result file whose close failed (the disk full) stays in HDF5's list, and HDF5 1.10 crashes
       closing it again inside MPI_Finalize: leave without finalising then. */
    if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_FILE) > 0) {
      (void)PetscLogViewFromOptions(); /* -log_view, which PetscFinalize would have printed */
      fflush(stdout);
      fflush(stderr);
      _exit(sig ? 128 + sig : 1);
    }
    PetscFinalize();
    return sig ? 128 + sig : 1;
  }
  PetscCall(WarnUnusedOptions());
  if (!traceback) PetscCall(PetscPopErrorHandler());
  PetscCall(MBCStopFinalize());
  PetscCall(PetscFinalize());
  return (int)status;
}
