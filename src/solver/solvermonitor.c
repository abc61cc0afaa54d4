/* The monitor's timing of a long run: wall-clock time of the last step, elapsed since the
   stepping started (set-up excluded, the first factorizations included), and the time left if
   the remaining steps take the mean time so far; the steps cut so far, if any. */
#include <mbc/private/solverimpl.h>

PetscErrorCode MBCSolverMonitorTiming(MBCSolver s, char buf[], size_t len)
{
  PetscLogDouble now, elapsed, eta;

  PetscFunctionBegin;
  PetscCall(PetscTime(&now));
  elapsed = now - s->t_start;
  eta     = s->step > 0 ? elapsed / s->step * (s->nsteps - s->step) : 0;
  if (s->ncuts) PetscCall(PetscSNPrintf(buf, len, "time: step %.3g s elapsed %.4g s ETA %.4g s, steps cut %" PetscInt_FMT, (double)(now - s->t_last), (double)elapsed, (double)eta, s->ncuts));
  else PetscCall(PetscSNPrintf(buf, len, "time: step %.3g s elapsed %.4g s ETA %.4g s", (double)(now - s->t_last), (double)elapsed, (double)eta));
  s->t_last = now;
  PetscFunctionReturn(0);
}
