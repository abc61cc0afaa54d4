/* The monitor's timing of a long run: wall-clock time of the last step, elapsed since the
   stepping started (set-up excluded, the first factorizations included), and the time left if
   the remaining steps take the mean time so far; the contact solve iterations of the step (the
   sum over its solves: equilibrium iterations, cut steps); the steps cut so far, if any. */
#include <mbc/private/solverimpl.h>

PetscErrorCode MBCSolverMonitorTiming(MBCSolver s, char buf[], size_t len)
{
  PetscLogDouble now, elapsed, eta;
  char           its[48] = "";

  PetscFunctionBegin;
  PetscCall(PetscTime(&now));
  elapsed = now - s->t_start;
  eta     = s->step > s->step_begin ? elapsed / (s->step - s->step_begin) * (s->nsteps - s->step) : 0; /* a restart's steps only */
  if (s->iface) PetscCall(PetscSNPrintf(its, sizeof(its), "contact its %" PetscInt_FMT " ", s->step_its));
  if (s->ncuts) PetscCall(PetscSNPrintf(buf, len, "%stime: step %.3g s elapsed %.4g s ETA %.4g s, steps cut %" PetscInt_FMT, its, (double)(now - s->t_last), (double)elapsed, (double)eta, s->ncuts));
  else PetscCall(PetscSNPrintf(buf, len, "%stime: step %.3g s elapsed %.4g s ETA %.4g s", its, (double)(now - s->t_last), (double)elapsed, (double)eta));
  s->t_last = now;
  PetscFunctionReturn(0);
}
