/* MBCMultiplier: the contact multiplier solve as an object with types (PETSc's KSP pattern).
   Options (prefix p, "mbc_" in the solver): -p_multiplier_type pgs|newton, -p_multiplier_rtol,
   -p_multiplier_max_it, -p_multiplier_monitor, -p_multiplier_converged_reason,
   -p_multiplier_view; each type adds its own (-p_pgs_*, -p_newton_*). */
#include <mbc/private/multiplierimpl.h>

PetscClassId      MBC_MULTIPLIER_CLASSID;
PetscFunctionList MBCMultiplierList;
PetscLogEvent     MBC_MultiplierSolve, MBC_MultiplierSetUp, MBC_NewtonInverse, MBC_NewtonLowRank, MBC_NewtonLowRankFactor;
static PetscBool  MBCMultiplierPackageInitialized = PETSC_FALSE;

const char *const MBCMultiplierConvergedReasons[] = {"DIVERGED_INFEASIBLE", "DIVERGED_LINE_SEARCH", "", "DIVERGED_NANORINF", "DIVERGED_ITS", "", "", "ITERATING", "", "CONVERGED_RTOL", "MBCMultiplierConvergedReason", "MBC_MULTIPLIER_", NULL};

const char *MBCMultiplierConvergedReasonName(MBCMultiplierConvergedReason r)
{
  return MBCMultiplierConvergedReasons[(int)r + 7];
}

static PetscErrorCode MBCMultiplierFinalizePackage(void)
{
  PetscFunctionBegin;
  PetscCall(PetscFunctionListDestroy(&MBCMultiplierList));
  MBCMultiplierPackageInitialized = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierInitializePackage(void)
{
  PetscFunctionBegin;
  if (MBCMultiplierPackageInitialized) PetscFunctionReturn(0);
  MBCMultiplierPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("MBCMultiplier", &MBC_MULTIPLIER_CLASSID));
  PetscCall(PetscLogEventRegister("MBCMultiplierSetUp", MBC_MULTIPLIER_CLASSID, &MBC_MultiplierSetUp));
  PetscCall(PetscLogEventRegister("MBCMultiplierSolve", MBC_MULTIPLIER_CLASSID, &MBC_MultiplierSolve));
  PetscCall(PetscLogEventRegister("MBCNewtonInverse", MBC_MULTIPLIER_CLASSID, &MBC_NewtonInverse));
  PetscCall(PetscLogEventRegister("MBCNewtonLRFactor", MBC_MULTIPLIER_CLASSID, &MBC_NewtonLowRankFactor));
  PetscCall(PetscLogEventRegister("MBCNewtonLowRank", MBC_MULTIPLIER_CLASSID, &MBC_NewtonLowRank));
  PetscCall(PetscLogEventRegister("MBCMixedLUFactor", MBC_MULTIPLIER_CLASSID, &MBC_MixedLUFactor));
  PetscCall(PCRegister(PCMBCMIXEDLU, PCCreate_MBCMixedLU));
  PetscCall(MBCMultiplierRegister(MBCMULTIPLIERPGS, MBCMultiplierCreate_PGS));
  PetscCall(MBCMultiplierRegister(MBCMULTIPLIERNEWTON, MBCMultiplierCreate_Newton));
  PetscCall(PetscRegisterFinalize(MBCMultiplierFinalizePackage));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierRegister(const char name[], PetscErrorCode (*create)(MBCMultiplier))
{
  PetscFunctionBegin;
  PetscCall(PetscFunctionListAdd(&MBCMultiplierList, name, create));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierCreate(MPI_Comm comm, MBCMultiplier *mult)
{
  MBCMultiplier m;

  PetscFunctionBegin;
  PetscValidPointer(mult, 2);
  PetscCall(MBCMultiplierInitializePackage());
  PetscCall(PetscHeaderCreate(m, MBC_MULTIPLIER_CLASSID, "MBCMultiplier", "Contact multiplier solve", "MBCMultiplier", comm, MBCMultiplierDestroy, MBCMultiplierView));
  m->rtol   = 1e-8;
  m->max_it = -1; /* the type's default */
  m->reason = MBC_MULTIPLIER_ITERATING;
  *mult     = m;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierSetType(MBCMultiplier m, MBCMultiplierType type)
{
  PetscErrorCode (*create)(MBCMultiplier);
  PetscBool same;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  PetscCall(PetscObjectTypeCompare((PetscObject)m, type, &same));
  if (same) PetscFunctionReturn(0);
  PetscCall(PetscFunctionListFind(MBCMultiplierList, type, &create));
  PetscCheck(create, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_UNKNOWN_TYPE, "Unknown multiplier solve type '%s' (-mbc_multiplier_type): pgs or newton", type);
  if (m->ops->destroy) PetscCall((*m->ops->destroy)(m));
  PetscCall(PetscMemzero(m->ops, sizeof(struct _MBCMultiplierOps)));
  PetscCall(MatDestroy(&m->Wsetup));
  m->data        = NULL;
  m->setupcalled = PETSC_FALSE;
  m->max_it      = -1; /* the new type's default; -mbc_multiplier_max_it is read after the type */
  PetscCall(PetscObjectChangeTypeName((PetscObject)m, type));
  PetscCall((*create)(m));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetType(MBCMultiplier m, MBCMultiplierType *type)
{
  PetscFunctionBegin;
  *type = ((PetscObject)m)->type_name;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierSetOptionsPrefix(MBCMultiplier m, const char prefix[])
{
  PetscFunctionBegin;
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)m, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierAppendOptionsPrefix(MBCMultiplier m, const char prefix[])
{
  PetscFunctionBegin;
  PetscCall(PetscObjectAppendOptionsPrefix((PetscObject)m, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierSetFromOptions(MBCMultiplier m)
{
  char      type[256];
  PetscBool set;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  PetscObjectOptionsBegin((PetscObject)m);
  PetscCall(PetscOptionsFList("-multiplier_type", "Contact multiplier solve", "MBCMultiplierSetType", MBCMultiplierList, ((PetscObject)m)->type_name ? ((PetscObject)m)->type_name : MBCMULTIPLIERNEWTON, type, sizeof(type), &set));
  if (set || !((PetscObject)m)->type_name) PetscCall(MBCMultiplierSetType(m, set ? type : MBCMULTIPLIERNEWTON));
  PetscCall(PetscOptionsDeprecated("-pgs_rtol", "-multiplier_rtol", "0.3", NULL));
  PetscCall(PetscOptionsDeprecated("-pgs_max_it", "-multiplier_max_it", "0.3", NULL));
  PetscCall(PetscOptionsDeprecated("-pgs_monitor", "-multiplier_monitor", "0.3", NULL));
  PetscCall(PetscOptionsReal("-multiplier_rtol", "Tolerance on the FCLIB merit (in a simulation of the step problem scaled to |q| = 1, so relative)", "MBCMultiplierSetTolerances", m->rtol, &m->rtol, NULL));
  PetscCall(PetscOptionsInt("-multiplier_max_it", "Maximum iterations (sweeps for pgs, Newton steps for newton)", "MBCMultiplierSetTolerances", m->max_it, &m->max_it, NULL));
  PetscCall(PetscOptionsBool("-multiplier_monitor", "Print the merit every iteration", "MBCMultiplierSolve", m->monitor, &m->monitor, NULL));
  PetscCall(PetscOptionsBool("-multiplier_converged_reason", "Print why each solve stopped", "MBCMultiplierSolve", m->converged_reason, &m->converged_reason, NULL));
  if (m->ops->setfromoptions) PetscCall((*m->ops->setfromoptions)(m, PetscOptionsObject));
  PetscOptionsEnd();
  PetscCheck(m->rtol > 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_multiplier_rtol %g must be positive", (double)m->rtol);
  PetscCheck(m->max_it > 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "-mbc_multiplier_max_it %" PetscInt_FMT " must be positive", m->max_it);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierSetTolerances(MBCMultiplier m, PetscReal rtol, PetscInt max_it)
{
  PetscFunctionBegin;
  if (rtol != (PetscReal)PETSC_DEFAULT) m->rtol = rtol;
  if (max_it != PETSC_DEFAULT) m->max_it = max_it;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetTolerances(MBCMultiplier m, PetscReal *rtol, PetscInt *max_it)
{
  PetscFunctionBegin;
  if (rtol) *rtol = m->rtol;
  if (max_it) *max_it = m->max_it;
  PetscFunctionReturn(0);
}

/* The problem is borrowed: it must live while the solve does. A new W (another Mat, or the same
   one changed) makes the next solve set up again. */
PetscErrorCode MBCMultiplierSetProblem(MBCMultiplier m, MBCFrictionProblem *fp)
{
  PetscFunctionBegin;
  m->fp = fp;
  PetscFunctionReturn(0);
}

/* The state of the type's solve that a restart needs to repeat the run bit for bit: one value per
   row of W in r's layout and a count (the Newton type: the reference of its kept inverse, the
   direct steps since); *has false where the type keeps none. Collective. */
PetscErrorCode MBCMultiplierGetRestartState(MBCMultiplier m, Vec s, PetscInt *count, PetscBool *has)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  *has   = PETSC_FALSE;
  *count = 0;
  PetscTryMethod(m, "MBCMultiplierGetRestartState_C", (MBCMultiplier, Vec, PetscInt *, PetscBool *), (m, s, count, has));
  PetscFunctionReturn(0);
}

/* ... given back after the restart's MBCMultiplierSetProblem, before its first solve */
PetscErrorCode MBCMultiplierSetRestartState(MBCMultiplier m, Vec s, PetscInt count)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  PetscTryMethod(m, "MBCMultiplierSetRestartState_C", (MBCMultiplier, Vec, PetscInt), (m, s, count));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierSetUp(MBCMultiplier m)
{
  PetscObjectState state;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  PetscCheck(m->fp && m->fp->W, PetscObjectComm((PetscObject)m), PETSC_ERR_ORDER, "MBCMultiplierSetProblem() first");
  if (!((PetscObject)m)->type_name) PetscCall(MBCMultiplierSetType(m, MBCMULTIPLIERNEWTON));
  PetscCall(PetscObjectStateGet((PetscObject)m->fp->W, &state));
  if (m->setupcalled && m->Wsetup == m->fp->W && m->Wstate == state) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(MBC_MultiplierSetUp, m, 0, 0, 0));
  if (m->setupcalled && m->ops->reset) PetscCall((*m->ops->reset)(m));
  PetscCall(PetscObjectReference((PetscObject)m->fp->W));
  PetscCall(MatDestroy(&m->Wsetup));
  m->Wsetup = m->fp->W;
  m->Wstate = state;
  if (m->ops->setup) PetscCall((*m->ops->setup)(m));
  m->setupcalled = PETSC_TRUE;
  PetscCall(PetscLogEventEnd(MBC_MultiplierSetUp, m, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* r holds the warm start on entry, the solution on exit; u = W r + q (+ G^T alpha). */
PetscErrorCode MBCMultiplierSolve(MBCMultiplier m, Vec r, Vec u)
{
  PetscLogDouble t0, t1;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  PetscCall(MBCMultiplierSetUp(m));
  PetscCall(PetscLogEventBegin(MBC_MultiplierSolve, m, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  m->its    = 0;
  m->reason = MBC_MULTIPLIER_ITERATING;
  PetscCall((*m->ops->solve)(m, r, u));
  PetscCall(PetscTime(&t1));
  m->time = t1 - t0;
  PetscCall(PetscLogEventEnd(MBC_MultiplierSolve, m, 0, 0, 0));
  if (m->converged_reason) PetscCall(PetscPrintf(PetscObjectComm((PetscObject)m), "  multiplier solve (%s) %s in %" PetscInt_FMT " iterations, FCLIB merit %.3e\n", ((PetscObject)m)->type_name, MBCMultiplierConvergedReasonName(m->reason), m->its, (double)m->merit));
  PetscCall(PetscObjectViewFromOptions((PetscObject)m, NULL, "-multiplier_view"));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierMonitorMerit(MBCMultiplier m, PetscInt it, PetscReal merit, const char extra[])
{
  PetscFunctionBegin;
  if (m->monitor) PetscCall(PetscPrintf(PetscObjectComm((PetscObject)m), "  %s %4" PetscInt_FMT " FCLIB merit %.6e%s\n", ((PetscObject)m)->type_name, it, (double)merit, extra ? extra : ""));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetConvergedReason(MBCMultiplier m, MBCMultiplierConvergedReason *reason)
{
  PetscFunctionBegin;
  *reason = m->reason;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetIterationNumber(MBCMultiplier m, PetscInt *its)
{
  PetscFunctionBegin;
  *its = m->its;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetMerit(MBCMultiplier m, PetscReal *merit)
{
  PetscFunctionBegin;
  *merit = m->merit;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierGetSolveTime(MBCMultiplier m, PetscLogDouble *t)
{
  PetscFunctionBegin;
  *t = m->time;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierView(MBCMultiplier m, PetscViewer viewer)
{
  PetscBool ascii;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, MBC_MULTIPLIER_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)m), &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)m, viewer));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "tolerance on the FCLIB merit %g, at most %" PetscInt_FMT " iterations\n", (double)m->rtol, m->max_it));
  if (m->reason != MBC_MULTIPLIER_ITERATING) PetscCall(PetscViewerASCIIPrintf(viewer, "last solve: %s in %" PetscInt_FMT " iterations, merit %g, %g s\n", MBCMultiplierConvergedReasonName(m->reason), m->its, (double)m->merit, (double)m->time));
  if (m->ops->view) PetscCall((*m->ops->view)(m, viewer));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* Frees what belongs to the last W (factors, ghost scatters); keeps type and options. */
PetscErrorCode MBCMultiplierReset(MBCMultiplier m)
{
  PetscFunctionBegin;
  if (!m) PetscFunctionReturn(0);
  if (m->ops->reset) PetscCall((*m->ops->reset)(m));
  PetscCall(MatDestroy(&m->Wsetup));
  m->setupcalled = PETSC_FALSE;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCMultiplierDestroy(MBCMultiplier *m)
{
  PetscFunctionBegin;
  if (!*m) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(*m, MBC_MULTIPLIER_CLASSID, 1);
  if (--((PetscObject)(*m))->refct > 0) {
    *m = NULL;
    PetscFunctionReturn(0);
  }
  PetscCall(MBCMultiplierReset(*m));
  if ((*m)->ops->destroy) PetscCall((*(*m)->ops->destroy)(*m));
  PetscCall(PetscHeaderDestroy(m));
  PetscFunctionReturn(0);
}
