/* The monitor's timing of a long run: wall-clock time of the last step, elapsed since the
   stepping started (set-up excluded, the first factorizations included), and the time left if
   the remaining steps take the mean time so far; the contact solve iterations of the step (the
   sum over its solves: equilibrium iterations, cut steps); the steps cut so far, if any. The
   contact line of each multiplier solve. */
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

/* The monitor's line of a contact solve: with mult, the solve just done; its line waits, and is
   printed (mult NULL, or the next solve) with the points' states as they are then: the step's
   last one at the step's end, after the contact search, with the states the result file and the
   CSV write (MBCInterfaceStates; the search may have found other points). */
PetscErrorCode MBCSolverMonitorContact(MBCSolver s, MBCMultiplier mult)
{
  PetscFunctionBegin;
  if (s->contact_line[0]) {
    PetscInt count[3] = {0, 0, 0};
    PetscCall(MBCInterfaceStates(s->iface, count, NULL, NULL));
    if (MBCInterfaceHasJoints(s->iface)) PetscCall(PetscPrintf(s->comm, "%s; separated %" PetscInt_FMT ", stick %" PetscInt_FMT ", slip %" PetscInt_FMT ", bonded %" PetscInt_FMT "\n", s->contact_line, count[MBC_CONTACT_SEPARATED], count[MBC_CONTACT_STICK], count[MBC_CONTACT_SLIP], MBCInterfaceJointBonded(s->iface)));
    else PetscCall(PetscPrintf(s->comm, "%s; separated %" PetscInt_FMT ", stick %" PetscInt_FMT ", slip %" PetscInt_FMT "\n", s->contact_line, count[MBC_CONTACT_SEPARATED], count[MBC_CONTACT_STICK], count[MBC_CONTACT_SLIP]));
    s->contact_line[0] = 0;
  }
  if (mult) {
    MBCMultiplierType type;
    PetscCall(MBCMultiplierGetType(mult, &type));
    PetscCall(PetscSNPrintf(s->contact_line, sizeof(s->contact_line), "step %5" PetscInt_FMT " t %-12.6g contact: %s %s in %" PetscInt_FMT " iterations (merit %.2e)", s->step, (double)s->time, type, MBCMultiplierConvergedReasonName(mult->reason), mult->its, (double)mult->merit));
    if (s->iface->jbroke) { /* bonded couples: the cascade of this solve */
      size_t len;
      PetscCall(PetscStrlen(s->contact_line, &len));
      PetscCall(PetscSNPrintf(s->contact_line + len, sizeof(s->contact_line) - len, ", %" PetscInt_FMT " bonds broke (%" PetscInt_FMT " solves)", s->iface->jbroke, s->iface->jsolves));
    }
  }
  PetscFunctionReturn(0);
}
