/* Output: one HDF5 result file <output>.h5, written collectively by all ranks (the bodies'
   geometry and fields in the scene's order, solveroutputbody.c; the contact points,
   solveroutputcontact.c), its XDMF index for ParaView, time histories of named points and
   energies to CSV. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>

/* Nearest owned vertex of each output point, over the bodies it may belong to. */
static PetscErrorCode SolverLocatePoints(MBCSolver s)
{
  MBCScene    scene = s->scene;
  PetscMPIInt rank;
  struct {
    double d;
    int    rank;
  } *best;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc1(scene->npoints, &s->points));
  PetscCall(PetscMalloc1(scene->npoints, &best));
  for (PetscInt p = 0; p < scene->npoints; p++) {
    s->points[p].distance = PETSC_MAX_REAL;
    s->points[p].body     = -1;
    s->points[p].row      = -1;
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody            body = s->bodies[b];
    PetscSection       gsec, csec;
    Vec                coords;
    const PetscScalar *x;
    PetscInt           vStart, vEnd;
    if (!body) continue;
    PetscCall(DMGetGlobalSection(body->dm, &gsec));
    PetscCall(DMGetCoordinateSection(body->dm, &csec));
    PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
    PetscCall(VecGetArrayRead(coords, &x));
    PetscCall(DMPlexGetDepthStratum(body->dm, 0, &vStart, &vEnd));
    for (PetscInt v = vStart; v < vEnd; v++) {
      PetscInt off, coff;
      PetscCall(PetscSectionGetOffset(gsec, v, &off));
      if (off < 0) continue;
      PetscCall(PetscSectionGetOffset(csec, v, &coff));
      for (PetscInt p = 0; p < scene->npoints; p++) {
        PetscReal d = 0;
        PetscBool same = PETSC_TRUE;
        if (scene->points[p].body[0]) PetscCall(PetscStrcmp(scene->points[p].body, body->name, &same));
        if (!same) continue;
        for (PetscInt c = 0; c < 3; c++) d += PetscSqr(PetscRealPart(x[coff + c]) - scene->points[p].x[c]);
        d = PetscSqrtReal(d);
        if (d < s->points[p].distance) {
          s->points[p].distance = d;
          s->points[p].body     = b;
          s->points[p].row      = off;
          for (PetscInt c = 0; c < 3; c++) s->points[p].xv[c] = PetscRealPart(x[coff + c]);
        }
      }
    }
    PetscCall(VecRestoreArrayRead(coords, &x));
  }
  for (PetscInt p = 0; p < scene->npoints; p++) {
    best[p].d    = (double)s->points[p].distance;
    best[p].rank = rank;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, best, (PetscMPIInt)scene->npoints, MPI_DOUBLE_INT, MPI_MINLOC, s->comm));
  for (PetscInt p = 0; p < scene->npoints; p++) {
    PetscCheck(best[p].d < 0.5 * PETSC_MAX_REAL, s->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: output point '%s' names body '%s', which does not exist", scene->filename, scene->points[p].name, scene->points[p].body);
    s->points[p].rank = best[p].rank;
    if (best[p].rank != rank) s->points[p].row = -1;
    PetscCallMPI(MPI_Bcast(s->points[p].xv, 3, MPIU_REAL, best[p].rank, s->comm));
    PetscCallMPI(MPI_Bcast(&s->points[p].body, 1, MPIU_INT, best[p].rank, s->comm));
    s->points[p].distance = best[p].d;
    if (s->view) PetscCall(PetscPrintf(s->comm, "  output point %s at (%g, %g, %g): vertex (%g, %g, %g) of body %s, distance %g\n", scene->points[p].name, (double)scene->points[p].x[0], (double)scene->points[p].x[1], (double)scene->points[p].x[2], (double)s->points[p].xv[0], (double)s->points[p].xv[1], (double)s->points[p].xv[2], scene->bodies[s->points[p].body].name, (double)s->points[p].distance));
  }
  PetscCall(PetscFree(best));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputOpen(MBCSolver s)
{
  MBCScene    scene  = s->scene;
  PetscBool   fields = (PetscBool)(scene->output_displacement || scene->output_stress);
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscMalloc2(s->nsteps + 2, &s->output_times, s->nsteps + 2, &s->output_npoints));
  s->noutputs = 0;
  if (fields || s->contact) {
    hid_t file_id;
    int   version = 2; /* 2: stress in XDMF's Tensor6 order (1: xx yy zz xy yz xz) */
    PetscCall(PetscSNPrintf(s->h5file, sizeof(s->h5file), "%s.h5", s->output));
    PetscCall(MBCH5FileCreate(s->comm, s->h5file, &file_id));
    s->h5 = file_id;
    PetscCall(MBCH5WriteAttributeString(file_id, "format", "mbcontact result"));
    PetscCall(MBCH5WriteAttribute(file_id, "format_version", H5T_NATIVE_INT, 1, &version));
    PetscCall(MBCH5WriteAttributeString(file_id, "title", scene->title));
    if (fields) PetscCall(MBCSolverOutputBodiesOpen(s));
  }
  if (scene->npoints) {
    PetscCall(SolverLocatePoints(s));
    if (!rank) {
      PetscCall(PetscSNPrintf(file, sizeof(file), "%s_points.csv", s->output));
      PetscCall(MBCFileOpenWrite(file, &s->points_csv));
      fprintf(s->points_csv, "t");
      for (PetscInt p = 0; p < scene->npoints; p++) fprintf(s->points_csv, ",%s_ux,%s_uy,%s_uz", scene->points[p].name, scene->points[p].name, scene->points[p].name);
      fprintf(s->points_csv, "\n");
    }
  }
  PetscCall(MBCSolverOutputContactOpen(s));
  if (scene->output_energy && s->analysis == MBC_ANALYSIS_DYNAMIC && !rank) {
    PetscCall(PetscSNPrintf(file, sizeof(file), "%s_energy.csv", s->output));
    PetscCall(MBCFileOpenWrite(file, &s->energy_csv));
    fprintf(s->energy_csv, "t,kinetic,strain,external_work,damping_dissipation,friction_dissipation,contact_dissipation,total\n");
  }
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverOutputPoints(MBCSolver s)
{
  MBCScene   scene = s->scene;
  PetscReal *val;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(3 * scene->npoints, &val));
  for (PetscInt p = 0; p < scene->npoints; p++) {
    const PetscScalar *u;
    PetscInt           rstart;
    MBCBody            body;
    if (s->points[p].row < 0) continue;
    body = s->bodies[s->points[p].body];
    PetscCall(VecGetOwnershipRange(body->u, &rstart, NULL));
    PetscCall(VecGetArrayRead(body->u, &u));
    for (PetscInt c = 0; c < 3; c++) val[3 * p + c] = PetscRealPart(u[s->points[p].row - rstart + c]);
    PetscCall(VecRestoreArrayRead(body->u, &u));
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, val, 3 * (PetscMPIInt)scene->npoints, MPIU_REAL, MPI_SUM, s->comm));
  if (s->points_csv) {
    fprintf(s->points_csv, "%.17g", (double)s->time);
    for (PetscInt i = 0; i < 3 * scene->npoints; i++) fprintf(s->points_csv, ",%.17g", (double)val[i]);
    fprintf(s->points_csv, "\n");
  }
  PetscCall(PetscFree(val));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputStep(MBCSolver s)
{
  MBCScene  scene = s->scene;
  PetscBool fields = (PetscBool)(scene->output_displacement || scene->output_stress);
  PetscBool fieldstep = (PetscBool)((fields || s->contact) && (s->step % s->output_every == 0 || s->step == s->nsteps));

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  if (scene->npoints) PetscCall(SolverOutputPoints(s));
  if (scene->output_energy && s->analysis == MBC_ANALYSIS_DYNAMIC) {
    PetscReal e[MBC_NENERGY];
    PetscCall(MBCSolverEnergy(s, e));
    if (s->energy_csv) fprintf(s->energy_csv, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (double)s->time, (double)e[0], (double)e[1], (double)e[2], (double)e[3], (double)e[4], (double)e[5], (double)(e[0] + e[1] - e[2] + e[3] + e[4] + e[5]));
  }
  PetscCall(MBCSolverOutputContactStep(s, fieldstep));
  if (fieldstep) {
    if (fields) PetscCall(MBCSolverOutputBodiesStep(s));
    if (!s->contact) s->output_npoints[s->noutputs] = 0;
    s->output_times[s->noutputs++] = s->time;
  }
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* The XDMF index: a temporal collection of spatial collections (a grid per body, one for the
   contact points), every dataset in the one result file. */
static PetscErrorCode SolverWriteXdmf(MBCSolver s)
{
  char  file[PETSC_MAX_PATH_LEN];
  FILE *fp;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s.xmf", s->output));
  PetscCall(MBCFileOpenWrite(file, &fp));
  fprintf(fp, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n  <Domain>\n");
  fprintf(fp, "  <Grid Name=\"mbcontact\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  for (PetscInt k = 0; k < s->noutputs; k++) {
    fprintf(fp, "    <Grid Name=\"step%" PetscInt_FMT "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n      <Time Value=\"%.17g\"/>\n", k, (double)s->output_times[k]);
    PetscCall(MBCSolverOutputBodiesXdmf(s, fp, k));
    PetscCall(MBCSolverOutputContactXdmf(s, fp, k));
    fprintf(fp, "    </Grid>\n");
  }
  fprintf(fp, "  </Grid>\n  </Domain>\n</Xdmf>\n");
  PetscCheck(!ferror(fp) && !fclose(fp), PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write %s (is the disk full?)", file);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputClose(MBCSolver s)
{
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(MBCSolverOutputContactClose(s));
  if (s->points_csv) fclose(s->points_csv);
  if (s->energy_csv) fclose(s->energy_csv);
  s->points_csv = s->energy_csv = NULL;
  if (s->h5 >= 0) {
    hid_t file = (hid_t)s->h5;
    int   n    = (int)s->noutputs;
    PetscCall(MBCH5WriteRows(file, "time", H5T_NATIVE_DOUBLE, s->noutputs, 1, 0, rank ? 0 : s->noutputs, s->output_times));
    PetscCall(MBCH5WriteAttribute(file, "num_outputs", H5T_NATIVE_INT, 1, &n));
    PetscCall(MBCH5FileClose(&file));
    s->h5 = -1;
    if (!rank) PetscCall(SolverWriteXdmf(s));
  }
  PetscCall(MBCSolverOutputBodiesClose(s));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
