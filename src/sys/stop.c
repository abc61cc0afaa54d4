/* How a run stops short: SIGINT/SIGTERM only set a flag, which the solver checks between steps
   (MBCStopSignalled, collective), so that it ends the run after a completed step with its
   results written; and after an error, whether every rank has it (then the files can be closed
   collectively and -log_view printed) or only some (then the job must be aborted). */
#include <mbcontact.h>
#include <signal.h>
#include <time.h>

static volatile sig_atomic_t MBCStopSignal = 0;
static MPI_Comm              MBCStopComm   = MPI_COMM_NULL; /* private: its barrier never meets the solver's collectives */

static void MBCStopHandler(int sig)
{
  MBCStopSignal = sig; /* SA_RESETHAND: a second signal ends the process at once */
}

/* SIGINT and SIGTERM stop the run after the current step; SIGXFSZ (file-size limit) is ignored
   so that the write fails with EFBIG and is reported, instead of killing the process. Replaces
   PETSc's handler for these signals only. Collective on comm (dups it). */
PetscErrorCode MBCStopInitialize(MPI_Comm comm)
{
  struct sigaction sa;

  PetscFunctionBegin;
  if (MBCStopComm == MPI_COMM_NULL) PetscCallMPI(MPI_Comm_dup(comm, &MBCStopComm));
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = MBCStopHandler;
  sa.sa_flags   = SA_RESTART | SA_RESETHAND;
  sigemptyset(&sa.sa_mask);
  PetscCheck(!sigaction(SIGINT, &sa, NULL) && !sigaction(SIGTERM, &sa, NULL), PETSC_COMM_SELF, PETSC_ERR_SYS, "Cannot install the SIGINT/SIGTERM handler");
  signal(SIGXFSZ, SIG_IGN);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCStopFinalize(void)
{
  PetscFunctionBegin;
  if (MBCStopComm != MPI_COMM_NULL) PetscCallMPI(MPI_Comm_free(&MBCStopComm));
  PetscFunctionReturn(0);
}

/* The signal this rank received (0: none). Not collective. */
int MBCStopGetSignal(void)
{
  return (int)MBCStopSignal;
}

/* *sig: a signal some rank of comm received since the start (0: none). Collective: every rank
   stops at the same step. */
PetscErrorCode MBCStopSignalled(MPI_Comm comm, int *sig)
{
  int s = (int)MBCStopSignal;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Allreduce(&s, sig, 1, MPI_INT, MPI_MAX, comm));
  PetscFunctionReturn(0);
}

/* After an error on this rank: *all is true when every rank of the MBCStopInitialize
   communicator reports an error within wait seconds (a collective error: a failed check on
   reduced values, a signal, a full disk seen by all), false when some rank is still running (a
   local error: it may be waiting in a collective that will never complete). A non-blocking
   barrier on a private communicator, so it matches nothing the other ranks are in. */
PetscErrorCode MBCStopErrorIsCollective(PetscReal wait, PetscBool *all)
{
  MPI_Request    req;
  int            done = 0;
  PetscLogDouble t0, t;

  PetscFunctionBegin;
  *all = PETSC_FALSE;
  if (MBCStopComm == MPI_COMM_NULL) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Ibarrier(MBCStopComm, &req));
  PetscCall(PetscTime(&t0));
  for (t = t0; !done && t - t0 < wait;) {
    PetscCallMPI(MPI_Test(&req, &done, MPI_STATUS_IGNORE));
    if (!done) {
      struct timespec ts = {0, 10000000}; /* 10 ms */
      nanosleep(&ts, NULL);
    }
    PetscCall(PetscTime(&t));
  }
  *all = (PetscBool)done; /* an unfinished request is left: the job is aborted next */
  PetscFunctionReturn(0);
}
