/* Output: fields per body to HDF5 (PETSc's viz layout) with one XDMF index for ParaView,
   time histories of named points and energies to CSV. */
#include <mbc/private/solverimpl.h>
#include <hdf5.h>

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

static PetscErrorCode SolverBodyFile(MBCSolver s, PetscInt b, char *name, size_t len, PetscBool basename)
{
  const char *base = s->output, *slash;

  PetscFunctionBegin;
  if (basename && (slash = strrchr(s->output, '/'))) base = slash + 1;
  PetscCall(PetscSNPrintf(name, len, "%s_%s.h5", base, s->scene->bodies[b].name));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputOpen(MBCSolver s)
{
  MBCScene    scene = s->scene;
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc1(s->nbodies, &s->h5));
  PetscCall(PetscMalloc1(s->nsteps + 2, &s->output_times));
  s->noutputs = 0;
  if (scene->output_displacement || scene->output_stress) {
    for (PetscInt b = 0; b < s->nbodies; b++) {
      if (!s->bodies[b]) continue;
      PetscCall(SolverBodyFile(s, b, file, sizeof(file), PETSC_FALSE));
      PetscCall(PetscViewerHDF5Open(s->bodies[b]->comm, file, FILE_MODE_WRITE, &s->h5[b]));
      PetscCall(PetscViewerPushFormat(s->h5[b], PETSC_VIEWER_HDF5_VIZ));
      PetscCall(DMView(s->bodies[b]->dm, s->h5[b]));
      PetscCall(PetscViewerHDF5PushTimestepping(s->h5[b]));
    }
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
    fprintf(s->energy_csv, "t,kinetic,strain,external_work,damping_dissipation,total\n");
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
    PetscReal e[4];
    PetscCall(MBCSolverEnergy(s, e));
    if (s->energy_csv) fprintf(s->energy_csv, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (double)s->time, (double)e[0], (double)e[1], (double)e[2], (double)e[3], (double)(e[0] + e[1] - e[2] + e[3]));
  }
  PetscCall(MBCSolverOutputContactStep(s, fieldstep));
  if (fieldstep) {
    for (PetscInt b = 0; fields && b < s->nbodies; b++) {
      MBCBody body = s->bodies[b];
      if (!body) continue;
      PetscCall(PetscViewerHDF5SetTimestep(s->h5[b], s->noutputs));
      if (scene->output_displacement) PetscCall(VecView(body->u, s->h5[b]));
      if (scene->output_stress) {
        Vec stress;
        PetscCall(DMGetGlobalVector(body->dmStress, &stress));
        PetscCall(PetscObjectSetName((PetscObject)stress, "stress"));
        PetscCall(MBCBodyComputeStress(body, body->u, stress));
        PetscCall(VecView(stress, s->h5[b]));
        PetscCall(DMRestoreGlobalVector(body->dmStress, &stress));
      }
    }
    s->output_times[s->noutputs++] = s->time;
  }
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* Shape of a dataset, or ndims = 0 if absent. */
static void H5Shape(hid_t file, const char *path, int *ndims, hsize_t dims[3])
{
  hid_t d, sp;

  *ndims = 0;
  if (H5Lexists(file, path, H5P_DEFAULT) <= 0) return;
  d      = H5Dopen2(file, path, H5P_DEFAULT);
  sp     = H5Dget_space(d);
  *ndims = H5Sget_simple_extent_ndims(sp);
  H5Sget_simple_extent_dims(sp, dims, NULL);
  H5Sclose(sp);
  H5Dclose(d);
}

/* One XDMF attribute per dataset of a field group, a hyperslab at output k. */
static PetscErrorCode XdmfAttributes(FILE *fp, hid_t file, const char *h5name, const char *group, const char *center, PetscInt k)
{
  H5G_info_t info;
  hid_t      g;

  PetscFunctionBegin;
  if (H5Lexists(file, group, H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  g = H5Gopen2(file, group, H5P_DEFAULT);
  H5Gget_info(g, &info);
  for (hsize_t i = 0; i < info.nlinks; i++) {
    char    name[256], label[256], path[512];
    int     nd;
    hsize_t dims[3];
    H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof(name), H5P_DEFAULT);
    PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s", group, name));
    PetscCall(PetscStrncpy(label, name, sizeof(label)));
    H5Shape(file, path, &nd, dims);
    if (nd != 3) continue;
    { /* PETSc names the dataset <vec>_<field>; both are the same word here: show it once */
      size_t len = strlen(name);
      if (len % 2 && name[len / 2] == '_' && !strncmp(name, name + len / 2 + 1, len / 2)) label[len / 2] = 0;
    }
    fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"%s\">\n", label, dims[2] == 3 ? "Vector" : (dims[2] == 6 ? "Tensor6" : "Scalar"), center);
    fprintf(fp, "          <DataItem ItemType=\"HyperSlab\" Dimensions=\"1 %llu %llu\" Type=\"HyperSlab\">\n", (unsigned long long)dims[1], (unsigned long long)dims[2]);
    fprintf(fp, "            <DataItem Dimensions=\"3 3\" Format=\"XML\">%" PetscInt_FMT " 0 0 1 1 1 1 %llu %llu</DataItem>\n", k, (unsigned long long)dims[1], (unsigned long long)dims[2]);
    fprintf(fp, "            <DataItem Dimensions=\"%llu %llu %llu\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:%s</DataItem>\n", (unsigned long long)dims[0], (unsigned long long)dims[1], (unsigned long long)dims[2], h5name, path);
    fprintf(fp, "          </DataItem>\n        </Attribute>\n");
  }
  H5Gclose(g);
  PetscFunctionReturn(0);
}

/* The XDMF index: a temporal collection of spatial collections (one grid per body). */
static PetscErrorCode SolverWriteXdmf(MBCSolver s)
{
  char  file[PETSC_MAX_PATH_LEN], h5name[PETSC_MAX_PATH_LEN], h5path[PETSC_MAX_PATH_LEN];
  FILE *fp;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s.xmf", s->output));
  PetscCall(MBCFileOpenWrite(file, &fp));
  fprintf(fp, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n  <Domain>\n");
  fprintf(fp, "  <Grid Name=\"mbcontact\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  for (PetscInt k = 0; k < s->noutputs; k++) {
    fprintf(fp, "    <Grid Name=\"step%" PetscInt_FMT "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n      <Time Value=\"%.17g\"/>\n", k, (double)s->output_times[k]);
    for (PetscInt b = 0; s->h5 && (s->scene->output_displacement || s->scene->output_stress) && b < s->nbodies; b++) {
      hid_t   h5;
      int     nd;
      hsize_t cdims[3], vdims[3];
      PetscCall(SolverBodyFile(s, b, h5name, sizeof(h5name), PETSC_TRUE));
      PetscCall(SolverBodyFile(s, b, h5path, sizeof(h5path), PETSC_FALSE));
      h5 = H5Fopen(h5path, H5F_ACC_RDONLY, H5P_DEFAULT);
      PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot reopen %s", h5path);
      H5Shape(h5, "/viz/topology/cells", &nd, cdims);
      H5Shape(h5, "/geometry/vertices", &nd, vdims);
      fprintf(fp, "      <Grid Name=\"%s\" GridType=\"Uniform\">\n", s->scene->bodies[b].name);
      fprintf(fp, "        <Topology TopologyType=\"%s\" NumberOfElements=\"%llu\">\n", cdims[1] == 8 ? "Hexahedron" : "Tetrahedron", (unsigned long long)cdims[0]);
      fprintf(fp, "          <DataItem Dimensions=\"%llu %llu\" NumberType=\"Int\" Precision=\"%d\" Format=\"HDF\">%s:/viz/topology/cells</DataItem>\n        </Topology>\n", (unsigned long long)cdims[0], (unsigned long long)cdims[1], (int)sizeof(PetscInt), h5name);
      fprintf(fp, "        <Geometry GeometryType=\"XYZ\">\n          <DataItem Dimensions=\"%llu 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/geometry/vertices</DataItem>\n        </Geometry>\n", (unsigned long long)vdims[0], h5name);
      PetscCall(XdmfAttributes(fp, h5, h5name, "/vertex_fields", "Node", k));
      PetscCall(XdmfAttributes(fp, h5, h5name, "/cell_fields", "Cell", k));
      fprintf(fp, "      </Grid>\n");
      H5Fclose(h5);
    }
    PetscCall(MBCSolverOutputContactXdmf(s, fp, k));
    fprintf(fp, "    </Grid>\n");
  }
  fprintf(fp, "  </Grid>\n  </Domain>\n</Xdmf>\n");
  fclose(fp);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputClose(MBCSolver s)
{
  PetscMPIInt rank;
  PetscBool   fields = (PetscBool)(s->scene->output_displacement || s->scene->output_stress);

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    if (!s->h5[b]) continue;
    PetscCall(PetscViewerHDF5PopTimestepping(s->h5[b]));
    PetscCall(PetscViewerPopFormat(s->h5[b]));
    PetscCall(PetscViewerDestroy(&s->h5[b]));
  }
  PetscCall(MBCSolverOutputContactClose(s));
  if (s->points_csv) fclose(s->points_csv);
  if (s->energy_csv) fclose(s->energy_csv);
  s->points_csv = s->energy_csv = NULL;
  PetscCallMPI(MPI_Barrier(s->comm));
  if ((fields || s->contact) && !rank) PetscCall(SolverWriteXdmf(s));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
