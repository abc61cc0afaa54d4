/* The analysis stages of a run (docs/scene.md, stages): a scene's list of stages, or its one
   analysis with the command line's overrides. Time runs on across stages: stage i runs from
   where stage i - 1 ended. */
#include <mbc/private/solverimpl.h>

/* The stage table. overridden: -mbc_analysis, -mbc_dt or -mbc_newmark_* was given, which a
   scene with stages refuses (each stage has its own); -mbc_final_time ends such a run early
   (the stages after it dropped, the one it falls in cut short). */
PetscErrorCode MBCSolverStagesSetUp(MBCSolver s, PetscBool overridden)
{
  MBCScene scene = s->scene;
  PetscInt step0 = 0;

  PetscFunctionBegin;
  PetscCall(PetscFree(s->stages));
  if (!scene->nstages) {
    s->nstages = 1;
    PetscCall(PetscCalloc1(1, &s->stages));
    s->stages[0].analysis = s->analysis;
    s->stages[0].t0       = 0;
    s->stages[0].t1       = s->final_time;
    s->stages[0].dt       = s->dt;
    s->stages[0].beta     = s->beta;
    s->stages[0].gamma    = s->gamma;
    s->stages[0].am       = s->am;
    s->stages[0].af       = s->af;
    s->stages[0].scheme   = s->scheme;
    s->stages[0].nsteps   = s->analysis == MBC_ANALYSIS_MODAL ? s->modal_nev : (PetscInt)PetscCeilReal(s->final_time / s->dt - 1e-9); /* modal: an output per mode */
  } else {
    PetscCheck(!overridden, s->comm, PETSC_ERR_ARG_INCOMP, "Scene file %s has %" PetscInt_FMT " analysis stages, each with its analysis settings: -mbc_analysis, -mbc_dt, -mbc_newmark_* and -mbc_scheme do not apply (change the stages in the scene; -mbc_final_time ends the run early)", scene->filename, scene->nstages);
    PetscCall(PetscCalloc1(scene->nstages, &s->stages));
    s->nstages = 0;
    for (PetscInt i = 0; i < scene->nstages; i++) {
      const MBCStageDesc *d  = &scene->stages[i];
      MBCSolverStage     *st = &s->stages[s->nstages];
      if (d->start_time >= s->final_time * (1 - 1e-12)) break; /* -mbc_final_time: not reached */
      st->analysis = d->analysis;
      st->t0       = d->start_time;
      st->t1       = PetscMin(d->final_time, s->final_time);
      st->dt       = d->dt;
      st->beta     = d->newmark_beta;
      st->gamma    = d->newmark_gamma;
      st->am       = d->alpha_m;
      st->af       = d->alpha_f;
      st->scheme   = MBCSchemeFromName(d->scheme);
      st->nsteps   = PetscMax(1, (PetscInt)PetscCeilReal((st->t1 - st->t0) / st->dt - 1e-9));
      s->nstages++;
    }
  }
  for (PetscInt i = 0; i < s->nstages; i++) {
    s->stages[i].step0 = step0;
    step0 += s->stages[i].nsteps;
  }
  s->nsteps = step0;
  s->istage = 0;
  s->dt     = s->stages[0].dt; /* the step control's and the monitor's, of the current stage */
  s->beta   = s->stages[0].beta;
  s->gamma  = s->stages[0].gamma;
  s->am     = s->stages[0].am;
  s->af     = s->stages[0].af;
  s->scheme = s->stages[0].scheme;
  PetscFunctionReturn(0);
}

/* Time at the end of step k (0: the start) of the current stage: a static stage ends at its
   final time, a dynamic one after a whole number of steps. */
PetscReal MBCSolverStageTime(MBCSolver s, PetscInt k)
{
  const MBCSolverStage *st = &s->stages[s->istage];
  const PetscReal       t  = st->t0 + k * st->dt;

  return st->analysis == MBC_ANALYSIS_STATIC ? PetscMin(t, st->t1) : t;
}

/* -log_view: stage i of the run becomes the current PETSc log stage (registered once, named
   after the scene's stage); i < 0 pops the last one. */
PetscErrorCode MBCSolverStageLog(MBCSolver s, PetscInt i)
{
  PetscFunctionBegin;
  if (s->log_pushed) PetscCall(PetscLogStagePop());
  s->log_pushed = PETSC_FALSE;
  if (i < 0) PetscFunctionReturn(0);
  if (s->stages[i].log <= 0) {
    char name[MBC_NAME_LEN + 32];
    if (s->scene->nstages) PetscCall(PetscSNPrintf(name, sizeof(name), "MBC stage %" PetscInt_FMT " %s", i, s->scene->stages[i].name));
    else PetscCall(PetscSNPrintf(name, sizeof(name), "MBC %s analysis", MBCAnalysisTypes[s->stages[i].analysis]));
    PetscCall(PetscLogStageGetId(name, &s->stages[i].log)); /* another solver of this process may have it */
    if (s->stages[i].log < 0) PetscCall(PetscLogStageRegister(name, &s->stages[i].log));
  }
  PetscCall(PetscLogStagePush(s->stages[i].log));
  s->log_pushed = PETSC_TRUE;
  PetscFunctionReturn(0);
}
