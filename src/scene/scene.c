/* Reads the metadata of a scene file (layout: docs/scene-h5.md) with the HDF5 C API.
   Every rank reads it: it is small, and the bodies' meshes are read by PETSc itself. */
#include <mbc/private/sceneimpl.h>
#include <mbc/private/h5util.h>
#include <hdf5.h>

const char *const MBCAnalysisTypes[] = {"static", "dynamic", "modal", "MBCAnalysisType", "MBC_ANALYSIS_", NULL};
const char *const MBCMassTypes[]     = {"consistent", "lumped", "MBCMassType", "MBC_MASS_", NULL};
const char *const MBCTimeKinds[]     = {"constant", "sudden", "table", "MBCTimeKind", "MBC_TIME_", NULL};
const char *const MBCAbsorbingInputs[] = {"none", "outcrop", "incident", "MBCAbsorbingInput", "MBC_INPUT_", NULL};
const char *const MBCLoadKinds[]     = {"gravity", "body_force", "pressure", "traction", "hydrostatic", "ground_acceleration", "nodal_force", "line_force", "uplift", "MBCLoadKind", "MBC_LOAD_", NULL};

typedef struct {
  const char *file;
  hid_t       obj;
  char        path[MBC_NAME_LEN];
} H5Node;

static PetscErrorCode H5NodeOpen(const char *file, hid_t parent, const char *parentpath, const char *name, H5Node *node)
{
  PetscFunctionBegin;
  node->file = file;
  PetscCall(PetscSNPrintf(node->path, sizeof(node->path), "%s/%s", parentpath, name));
  PetscCheck(H5Lexists(parent, name, H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: group %s is missing (write scene files with mbcontact-prep)", file, node->path);
  node->obj = H5Gopen2(parent, name, H5P_DEFAULT);
  PetscCheck(node->obj >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot open group %s", file, node->path);
  PetscFunctionReturn(0);
}

static PetscErrorCode H5NodeClose(H5Node *node)
{
  PetscFunctionBegin;
  if (node->obj >= 0) H5Gclose(node->obj);
  node->obj = -1;
  PetscFunctionReturn(0);
}

static PetscErrorCode H5AttrOpen(H5Node *node, const char *name, hid_t *attr)
{
  PetscFunctionBegin;
  PetscCheck(H5Aexists(node->obj, name) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is missing", node->file, name, node->path);
  *attr = H5Aopen(node->obj, name, H5P_DEFAULT);
  PetscCheck(*attr >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot open attribute %s of %s", node->file, name, node->path);
  PetscFunctionReturn(0);
}

/* Reads nvalues reals; a missing optional attribute leaves them unchanged. */
static PetscErrorCode H5ReadReals(H5Node *node, const char *name, PetscInt nvalues, PetscReal *values, PetscBool optional)
{
  hid_t    attr, space;
  hssize_t n;
  double  *buf;

  PetscFunctionBegin;
  if (optional && H5Aexists(node->obj, name) <= 0) PetscFunctionReturn(0);
  PetscCall(H5AttrOpen(node, name, &attr));
  space = H5Aget_space(attr);
  n     = H5Sget_simple_extent_npoints(space);
  H5Sclose(space);
  PetscCheck(n == nvalues, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s has %lld values, expected %" PetscInt_FMT, node->file, name, node->path, (long long)n, nvalues);
  {
    hid_t       type = H5Aget_type(attr);
    H5T_class_t cls  = H5Tget_class(type);
    H5Tclose(type);
    PetscCheck(cls == H5T_FLOAT || cls == H5T_INTEGER, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is not a number", node->file, name, node->path);
  }
  PetscCall(PetscMalloc1(nvalues + 1, &buf));
  PetscCheck(H5Aread(attr, H5T_NATIVE_DOUBLE, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: attribute %s of %s is not a number", node->file, name, node->path);
  H5Aclose(attr);
  for (PetscInt i = 0; i < nvalues; i++) {
    PetscCheck(!PetscIsInfOrNanReal(buf[i]), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is not finite (%g)", node->file, name, node->path, buf[i]);
    values[i] = (PetscReal)buf[i];
  }
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

static PetscErrorCode H5ReadReal(H5Node *node, const char *name, PetscReal *value, PetscBool optional)
{
  PetscFunctionBegin;
  PetscCall(H5ReadReals(node, name, 1, value, optional));
  PetscFunctionReturn(0);
}

static PetscErrorCode H5ReadInt(H5Node *node, const char *name, PetscInt *value, PetscBool optional)
{
  hid_t     attr;
  long long v;

  PetscFunctionBegin;
  if (optional && H5Aexists(node->obj, name) <= 0) PetscFunctionReturn(0);
  PetscCall(H5AttrOpen(node, name, &attr));
  {
    hid_t    type  = H5Aget_type(attr), space = H5Aget_space(attr);
    hssize_t n     = H5Sget_simple_extent_npoints(space);
    PetscBool isint = (PetscBool)(H5Tget_class(type) == H5T_INTEGER);
    H5Tclose(type);
    H5Sclose(space);
    PetscCheck(isint && n == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s must be one integer", node->file, name, node->path);
  }
  PetscCheck(H5Aread(attr, H5T_NATIVE_LLONG, &v) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: attribute %s of %s is not an integer", node->file, name, node->path);
  H5Aclose(attr);
  /* PetscInt is 32-bit here: a larger value would wrap into a wrong one */
  PetscCheck(v >= PETSC_MIN_INT && v <= PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is %lld, outside the range of a 32-bit integer", node->file, name, node->path, v);
  *value = (PetscInt)v;
  PetscFunctionReturn(0);
}

/* Reads a fixed- or variable-length string; *str is allocated when str != NULL, else copied to buf. */
static PetscErrorCode H5ReadString(H5Node *node, const char *name, char *buf, size_t len, char **str, PetscBool optional)
{
  hid_t  attr, ftype, mtype;
  char  *s = NULL;
  size_t size;

  PetscFunctionBegin;
  if (optional && H5Aexists(node->obj, name) <= 0) {
    if (str) PetscCall(PetscStrallocpy("", str));
    else buf[0] = 0;
    PetscFunctionReturn(0);
  }
  PetscCall(H5AttrOpen(node, name, &attr));
  ftype = H5Aget_type(attr);
  PetscCheck(H5Tget_class(ftype) == H5T_STRING, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: attribute %s of %s is not a string", node->file, name, node->path);
  if (H5Tis_variable_str(ftype) > 0) {
    char *vs = NULL;
    mtype    = H5Tcopy(H5T_C_S1);
    H5Tset_size(mtype, H5T_VARIABLE);
    PetscCheck(H5Aread(attr, mtype, &vs) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read string %s of %s", node->file, name, node->path);
    PetscCall(PetscStrallocpy(vs ? vs : "", &s));
    H5free_memory(vs);
  } else {
    size  = H5Tget_size(ftype);
    mtype = H5Tcopy(H5T_C_S1);
    H5Tset_size(mtype, size + 1);
    PetscCall(PetscCalloc1(size + 2, &s));
    PetscCheck(H5Aread(attr, mtype, s) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read string %s of %s", node->file, name, node->path);
  }
  H5Tclose(mtype);
  H5Tclose(ftype);
  H5Aclose(attr);
  if (str) *str = s;
  else {
    size_t slen;
    PetscCall(PetscStrlen(s, &slen));
    PetscCheck(slen < len, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: string %s of %s is longer than %zu characters", node->file, name, node->path, len - 1);
    PetscCall(PetscStrncpy(buf, s, len));
    PetscCall(PetscFree(s));
  }
  PetscFunctionReturn(0);
}

/* Maps a string attribute onto an enum; an unknown value is an error naming it and the choices. */
static PetscErrorCode H5ReadEnum(H5Node *node, const char *name, const char *const *list, PetscInt *value, PetscBool optional)
{
  char      s[MBC_NAME_LEN];
  PetscBool found = PETSC_FALSE;
  PetscInt  n;

  PetscFunctionBegin;
  if (optional && H5Aexists(node->obj, name) <= 0) PetscFunctionReturn(0);
  PetscCall(H5ReadString(node, name, s, sizeof(s), NULL, PETSC_FALSE));
  for (n = 0; list[n + 2]; n++) { /* PETSc enum lists end with type name, prefix, NULL */ }
  for (PetscInt i = 0; i < n; i++) {
    PetscCall(PetscStrcmp(s, list[i], &found));
    if (found) {
      *value = i;
      break;
    }
  }
  if (!found) {
    char choices[MBC_NAME_LEN] = "";
    for (PetscInt i = 0; i < n; i++) {
      if (i) PetscCall(PetscStrlcat(choices, ", ", sizeof(choices)));
      PetscCall(PetscStrlcat(choices, list[i], sizeof(choices)));
    }
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s of %s is '%s', not one of %s", node->file, name, node->path, s, choices);
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode H5ReadCount(H5Node *node, PetscInt *count)
{
  H5G_info_t info;

  PetscFunctionBegin;
  PetscCall(H5ReadInt(node, "count", count, PETSC_FALSE));
  PetscCheck(*count >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: negative count in %s", node->file, node->path);
  /* a count beyond the entries present would allocate for nothing, then miss an entry; entries
     beyond count are ignored (a list is cut by lowering its count) */
  PetscCheck(H5Gget_info(node->obj, &info) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot list %s", node->file, node->path);
  PetscCheck((hsize_t)*count <= info.nlinks, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s has count = %" PetscInt_FMT " but holds only %llu entries", node->file, node->path, *count, (unsigned long long)info.nlinks);
  PetscFunctionReturn(0);
}

static PetscErrorCode H5EntryOpen(H5Node *list, PetscInt i, H5Node *entry)
{
  char name[32];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(name, sizeof(name), "%" PetscInt_FMT, i));
  PetscCall(H5NodeOpen(list->file, list->obj, list->path, name, entry));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadTimeTable(H5Node *entry, MBCTimeTable *table)
{
  hid_t   dset, space;
  hsize_t dims[2];
  double *buf;

  PetscFunctionBegin;
  PetscCheck(H5Lexists(entry->obj, "table", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/table is missing", entry->file, entry->path);
  dset  = H5Dopen2(entry->obj, "table", H5P_DEFAULT);
  space = H5Dget_space(dset);
  PetscCheck(H5Sget_simple_extent_ndims(space) == 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/table must have shape (n, 2)", entry->file, entry->path);
  H5Sget_simple_extent_dims(space, dims, NULL);
  PetscCheck(dims[1] == 2 && dims[0] >= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/table must have shape (n, 2), n >= 1", entry->file, entry->path);
  PetscCall(PetscMalloc1(2 * dims[0], &buf));
  PetscCheck(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read %s/table", entry->file, entry->path);
  H5Sclose(space);
  H5Dclose(dset);
  table->n = (PetscInt)dims[0];
  PetscCall(PetscMalloc2(table->n, &table->t, table->n, &table->f));
  for (PetscInt i = 0; i < table->n; i++) {
    table->t[i] = buf[2 * i];
    table->f[i] = buf[2 * i + 1];
    PetscCheck(!PetscIsInfOrNanReal(table->t[i]) && !PetscIsInfOrNanReal(table->f[i]), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/table row %" PetscInt_FMT " is not finite", entry->file, entry->path, i);
    PetscCheck(i == 0 || table->t[i] > table->t[i - 1], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/table times must increase strictly (row %" PetscInt_FMT ")", entry->file, entry->path, i);
  }
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* The optional dataset `name` of rows (body, node in scene order), (n, 2) integers: *n rows in *rows
   (left as they are when absent). Every row must name a body and one of its nodes. */
static PetscErrorCode ReadNodePairs(H5Node *entry, MBCScene scene, const char *name, PetscInt *n, PetscInt **rows)
{
  hid_t      dset, space, type;
  hsize_t    dims[2] = {0, 0};
  long long *buf;
  PetscBool  isint;

  PetscFunctionBegin;
  if (H5Lexists(entry->obj, name, H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  dset = H5Dopen2(entry->obj, name, H5P_DEFAULT);
  PetscCheck(dset >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot open dataset %s/%s", entry->file, entry->path, name);
  space = H5Dget_space(dset);
  type  = H5Dget_type(dset);
  isint = (PetscBool)(H5Tget_class(type) == H5T_INTEGER);
  H5Tclose(type);
  PetscCheck(isint && H5Sget_simple_extent_ndims(space) == 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s must be integers of shape (n, 2)", entry->file, entry->path, name);
  H5Sget_simple_extent_dims(space, dims, NULL);
  PetscCheck(dims[1] == 2 && dims[0] >= 1 && dims[0] <= (hsize_t)PETSC_MAX_INT / 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s must have shape (n, 2), n >= 1", entry->file, entry->path, name);
  PetscCall(PetscMalloc1(2 * dims[0], &buf));
  PetscCheck(H5Dread(dset, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read %s/%s", entry->file, entry->path, name);
  H5Sclose(space);
  H5Dclose(dset);
  *n = (PetscInt)dims[0];
  PetscCall(PetscMalloc1(2 * *n, rows));
  for (PetscInt i = 0; i < *n; i++) {
    const long long b = buf[2 * i], v = buf[2 * i + 1];
    PetscCheck(b >= 0 && b < scene->nbodies && v >= 0 && v < scene->bodies[b].num_nodes, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s row %" PetscInt_FMT " names body %lld, node %lld, which do not exist", entry->file, entry->path, name, i, b, v);
    (*rows)[2 * i] = (PetscInt)b, (*rows)[2 * i + 1] = (PetscInt)v;
  }
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

/* The dataset `name` of exactly rows x cols finite reals (cols 1: shape (rows,) or (rows, 1)). */
static PetscErrorCode ReadRealDataset(H5Node *entry, const char *name, PetscInt rows, PetscInt cols, PetscReal **values)
{
  hid_t    dset, space, type;
  hssize_t npts;
  PetscBool isfloat;

  PetscFunctionBegin;
  PetscCheck(H5Lexists(entry->obj, name, H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dataset %s/%s is missing", entry->file, entry->path, name);
  dset = H5Dopen2(entry->obj, name, H5P_DEFAULT);
  PetscCheck(dset >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot open dataset %s/%s", entry->file, entry->path, name);
  space   = H5Dget_space(dset);
  type    = H5Dget_type(dset);
  isfloat = (PetscBool)(H5Tget_class(type) == H5T_FLOAT);
  npts    = H5Sget_simple_extent_npoints(space);
  H5Tclose(type);
  H5Sclose(space);
  PetscCheck(isfloat && npts == (hssize_t)rows * cols, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s must hold %" PetscInt_FMT " x %" PetscInt_FMT " reals", entry->file, entry->path, name, rows, cols);
  PetscCall(PetscMalloc1(rows * cols + 1, values));
  PetscCheck(rows * cols == 0 || H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, *values) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read %s/%s", entry->file, entry->path, name);
  H5Dclose(dset);
  for (PetscInt i = 0; i < rows * cols; i++) PetscCheck(!PetscIsInfOrNanReal((*values)[i]) && PetscAbsReal((*values)[i]) <= 1e100, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/%s[%" PetscInt_FMT "] is %g (not finite, or beyond 1e100)", entry->file, entry->path, name, i, (double)(*values)[i]);
  PetscFunctionReturn(0);
}

/* The optional uplift of a couple (attributes uplift_*, dataset uplift_table; docs/scene-h5.md):
   the prep validated it, the checks here catch a file made otherwise. */
static PetscErrorCode ReadCoupleUplift(H5Node *e, MBCScene s, MBCCoupleDesc *c)
{
  MBCUpliftDesc *u = &c->uplift;
  PetscInt       on = 0, pen = 0;
  PetscReal      dn;

  PetscFunctionBegin;
  PetscCall(H5ReadInt(e, "uplift", &on, PETSC_TRUE));
  if (!on) PetscFunctionReturn(0);
  u->on = PETSC_TRUE;
  PetscCall(H5ReadReals(e, "uplift_origin", 3, u->origin, PETSC_FALSE));
  PetscCall(H5ReadReals(e, "uplift_direction", 3, u->direction, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_length", &u->length, PETSC_FALSE));
  PetscCall(H5ReadReals(e, "uplift_lateral", 5, u->lateral, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_unit_weight", &u->unit_weight, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_heel_head", &u->heel_head, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_tail_head", &u->tail_head, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_drain", &u->drain, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_efficiency", &u->efficiency, PETSC_FALSE));
  PetscCall(H5ReadInt(e, "uplift_penetration", &pen, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_level", &u->level, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "uplift_threshold", &u->threshold, PETSC_FALSE));
  PetscCall(H5ReadInt(e, "uplift_axis", &u->axis, PETSC_FALSE));
  PetscCall(H5ReadInt(e, "uplift_table_rows", &u->ntable, PETSC_FALSE));
  u->penetration = (PetscBool)(pen != 0);
  if (u->ntable > 0) PetscCall(ReadRealDataset(e, "uplift_table", u->ntable, 2, &u->table));
  u->nzones = 1;
  PetscCall(H5ReadInt(e, "uplift_zones", &u->nzones, PETSC_TRUE));
  PetscCheck(u->nzones >= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": uplift needs at least one zone", s->filename, c->k);
  if (H5Lexists(e->obj, "uplift_zone_range", H5P_DEFAULT) > 0) PetscCall(ReadRealDataset(e, "uplift_zone_range", u->nzones, 2, &u->zones));
  else { /* a file of an earlier prep: one zone, the lateral range */
    PetscCheck(u->nzones == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": uplift_zone_range is missing", s->filename, c->k);
    PetscCall(PetscMalloc1(2, &u->zones));
    u->zones[0] = u->lateral[3], u->zones[1] = u->lateral[4];
  }
  PetscCall(PetscMalloc1(s->nbodies + 1, &u->zone_of_body));
  for (PetscInt b = 0; b < s->nbodies; b++) u->zone_of_body[b] = 0;
  if (H5Lexists(e->obj, "uplift_zone_body", H5P_DEFAULT) > 0) {
    PetscReal *zb;
    PetscCall(ReadRealDataset(e, "uplift_zone_body", s->nbodies, 1, &zb)); /* float64: the prep writes numbers */
    for (PetscInt b = 0; b < s->nbodies; b++) u->zone_of_body[b] = (PetscInt)zb[b];
    PetscCall(PetscFree(zb));
  }
  for (PetscInt b = 0; b < s->nbodies; b++) PetscCheck(u->zone_of_body[b] >= -1 && u->zone_of_body[b] < u->nzones, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": uplift_zone_body names zone %" PetscInt_FMT " of %" PetscInt_FMT, s->filename, c->k, u->zone_of_body[b], u->nzones);
  for (PetscInt z = 0; z < u->nzones; z++) PetscCheck(u->zones[2 * z] <= u->zones[2 * z + 1] && (z == 0 || u->zones[2 * z] >= u->zones[2 * z - 1] - 1e-9 * (PetscAbsReal(u->zones[2 * z - 1]) + u->length)), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": the uplift's zones must be disjoint and ascending", s->filename, c->k);
  dn = PetscSqrtReal(PetscSqr(u->direction[0]) + PetscSqr(u->direction[1]) + PetscSqr(u->direction[2]));
  PetscCheck(dn > 0 && u->length > 0 && u->unit_weight >= 0 && u->axis >= 0 && u->axis < 3 && u->efficiency >= 0 && u->efficiency <= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": uplift needs a direction, a length > 0, a unit weight >= 0, an axis 0..2 and a drain efficiency in [0, 1]", s->filename, c->k);
  for (PetscInt d = 0; d < 3; d++) u->direction[d] /= dn;
  for (PetscInt r = 1; r < u->ntable; r++) PetscCheck(u->table[2 * r] > u->table[2 * r - 2], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT ": the uplift table's positions must increase", s->filename, c->k);
  PetscFunctionReturn(0);
}

/* The joint law of a bonded couple (docs/dam.md): optional, cohesion 0 (absent) is today's
   unbonded contact; the prep resolves the defaults, a hand-made file gets them here. */
static PetscErrorCode ReadCoupleJoint(H5Node *e, MBCScene s, MBCCoupleDesc *c)
{
  PetscFunctionBegin;
  c->cohesion = 0, c->tensile = -1, c->mu_residual = -1, c->softening = 0;
  PetscCall(H5ReadReal(e, "cohesion", &c->cohesion, PETSC_TRUE));
  PetscCall(H5ReadReal(e, "softening_displacement", &c->softening, PETSC_TRUE));
  PetscCheck(c->softening >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": softening_displacement %g < 0", s->filename, c->k, (double)c->softening);
  PetscCall(H5ReadReal(e, "tensile_strength", &c->tensile, PETSC_TRUE));
  PetscCall(H5ReadReal(e, "mu_residual", &c->mu_residual, PETSC_TRUE));
  PetscCheck(c->cohesion >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": cohesion %g < 0", s->filename, c->k, (double)c->cohesion);
  if (c->cohesion == 0) {
    PetscCheck(c->tensile <= 0 && c->mu_residual < 0 && c->softening == 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": tensile_strength and mu_residual belong to a bonded joint (cohesion > 0)", s->filename, c->k);
    c->tensile = 0, c->mu_residual = c->mu;
    PetscFunctionReturn(0);
  }
  PetscCheck(c->mu > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": cohesion %g needs friction mu > 0 (the bonded cone's apex lies at -cohesion/mu)", s->filename, c->k, (double)c->cohesion);
  if (c->tensile < 0) c->tensile = c->cohesion / c->mu;
  if (c->mu_residual < 0) c->mu_residual = c->mu;
  PetscCheck(c->tensile <= c->cohesion / c->mu * (1 + 1e-12), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": tensile_strength %g exceeds cohesion / mu = %g", s->filename, c->k, (double)c->tensile, (double)(c->cohesion / c->mu));
  c->tensile = PetscMin(c->tensile, c->cohesion / c->mu);
  PetscCheck(c->mu_residual <= MBC_MAX_MU, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT ": mu_residual %g above %g", s->filename, c->k, (double)c->mu_residual, (double)MBC_MAX_MU);
  PetscFunctionReturn(0);
}

/* The optional dataset `exclude` of a couple: (n, 2) integers, body and vertex (scene order) of
   each node taken out of contact (docs/scene-h5.md). */
static PetscErrorCode ReadCoupleExclude(H5Node *entry, MBCScene scene, MBCCoupleDesc *c)
{
  PetscFunctionBegin;
  PetscCall(ReadNodePairs(entry, scene, "exclude", &c->nexclude, &c->exclude));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadTimeKind(H5Node *entry, MBCScene scene, MBCTimeKind *time, PetscInt *tf)
{
  PetscInt kind = MBC_TIME_CONSTANT;

  PetscFunctionBegin;
  PetscCall(H5ReadEnum(entry, "time", MBCTimeKinds, &kind, PETSC_FALSE));
  *time = (MBCTimeKind)kind;
  *tf   = -1;
  PetscCall(H5ReadInt(entry, "time_function", tf, PETSC_TRUE));
  if (*time == MBC_TIME_TABLE) PetscCheck(*tf >= 0 && *tf < scene->ntables, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s names time function %" PetscInt_FMT ", but the scene has %" PetscInt_FMT, entry->file, entry->path, *tf, scene->ntables);
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadBody(H5Node *e, MBCBodyDesc *b)
{
  PetscFunctionBegin;
  PetscCall(H5ReadString(e, "name", b->name, sizeof(b->name), NULL, PETSC_FALSE));
  PetscCall(H5ReadString(e, "cell_type", b->cell_type, sizeof(b->cell_type), NULL, PETSC_FALSE));
  PetscCall(H5ReadString(e, "element", b->element, sizeof(b->element), NULL, PETSC_TRUE));
  PetscCall(H5ReadInt(e, "num_cells", &b->num_cells, PETSC_FALSE));
  PetscCall(H5ReadInt(e, "num_vertices", &b->num_vertices, PETSC_FALSE));
  b->num_nodes = b->num_vertices;
  PetscCall(H5ReadInt(e, "num_nodes", &b->num_nodes, PETSC_TRUE));
  PetscCheck(b->num_vertices >= 3 && b->num_nodes >= b->num_vertices && b->num_nodes < PETSC_MAX_INT / 8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has %" PetscInt_FMT " vertices and %" PetscInt_FMT " nodes", e->file, b->name, b->num_vertices, b->num_nodes);
  if (b->num_nodes > b->num_vertices) { /* tet10: each midside node's edge and position */
    const PetscInt nm = b->num_nodes - b->num_vertices;
    PetscInt      *rows = NULL;
    PetscCheck(H5Lexists(e->obj, "midside", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has %" PetscInt_FMT " midside nodes but no dataset %s/midside", e->file, b->name, nm, e->path);
    {
      hid_t      dset = H5Dopen2(e->obj, "midside", H5P_DEFAULT), space = H5Dget_space(dset);
      hsize_t    dims[2] = {0, 0};
      long long *buf;
      PetscCheck(H5Sget_simple_extent_ndims(space) == 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/midside must have shape (%" PetscInt_FMT ", 2)", e->file, e->path, nm);
      H5Sget_simple_extent_dims(space, dims, NULL);
      H5Sclose(space);
      PetscCheck(dims[0] == (hsize_t)nm && dims[1] == 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/midside must have shape (%" PetscInt_FMT ", 2)", e->file, e->path, nm);
      PetscCall(PetscMalloc1(2 * nm, &buf));
      PetscCheck(H5Dread(dset, H5T_NATIVE_LLONG, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Scene file %s: cannot read %s/midside", e->file, e->path);
      H5Dclose(dset);
      PetscCall(PetscMalloc1(2 * nm, &rows));
      for (PetscInt i = 0; i < 2 * nm; i++) {
        PetscCheck(buf[i] >= 0 && buf[i] < b->num_vertices, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s/midside[%" PetscInt_FMT "] = %lld is not a vertex of the body", e->file, e->path, i / 2, buf[i]);
        rows[i] = (PetscInt)buf[i];
      }
      PetscCall(PetscFree(buf));
    }
    b->midside = rows;
    PetscCall(ReadRealDataset(e, "midside_coords", nm, 3, &b->midside_x));
  }
  {
    PetscInt rigid = 0;
    PetscCall(H5ReadInt(e, "rigid", &rigid, PETSC_TRUE));
    b->rigid = rigid ? PETSC_TRUE : PETSC_FALSE;
    if (b->rigid) {
      PetscCall(H5ReadReals(e, "reference", 3, b->reference, PETSC_FALSE));
      PetscCall(H5ReadReal(e, "rigid_mass", &b->rigid_mass, PETSC_TRUE));
      PetscCall(H5ReadReals(e, "rigid_inertia", 9, b->rigid_inertia, PETSC_TRUE));
      PetscCheck(b->rigid_mass >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: rigid body '%s' has mass %g < 0", e->file, b->name, (double)b->rigid_mass);
    }
  }
  if (H5Lexists(e->obj, "initial_displacement", H5P_DEFAULT) > 0) PetscCall(ReadRealDataset(e, "initial_displacement", b->num_nodes, 3, &b->initial_u));
  if (H5Lexists(e->obj, "initial_velocity", H5P_DEFAULT) > 0) PetscCall(ReadRealDataset(e, "initial_velocity", b->num_nodes, 3, &b->initial_v));
  PetscCall(H5ReadReal(e, "E", &b->E, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "nu", &b->nu, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "density", &b->density, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "damping", &b->damping, PETSC_TRUE));
  PetscCall(H5ReadReal(e, "rayleigh_alpha", &b->rayleigh_alpha, PETSC_TRUE));
  PetscCall(H5ReadReal(e, "rayleigh_beta", &b->rayleigh_beta, PETSC_TRUE));
  {
    PetscInt massless = 0;
    PetscCall(H5ReadInt(e, "massless", &massless, PETSC_TRUE));
    b->massless = massless ? PETSC_TRUE : PETSC_FALSE;
  }
  /* The prep checks these too; a hand-edited file must not reach the assembly. */
  PetscCheck(b->E > 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s': Young's modulus E = %g must be positive", e->file, b->name, (double)b->E);
  PetscCheck(b->nu > -1.0 && b->nu < 0.5, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s': Poisson's ratio nu = %g must lie in (-1, 0.5)", e->file, b->name, (double)b->nu);
  PetscCheck(b->density >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s': density %g must not be negative", e->file, b->name, (double)b->density);
  PetscCheck(b->damping >= 0 && b->rayleigh_alpha >= 0 && b->rayleigh_beta >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s': damping coefficients must not be negative", e->file, b->name);
  {
    const char     *key[5] = {"E", "density", "damping", "rayleigh_alpha", "rayleigh_beta"};
    const PetscReal val[5] = {b->E, b->density, b->damping, b->rayleigh_alpha, b->rayleigh_beta};
    for (PetscInt i = 0; i < 5; i++) PetscCheck(val[i] == 0 || (val[i] >= MBC_MATERIAL_MIN && val[i] <= MBC_MATERIAL_MAX), PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s': material %s = %g lies outside [%g, %g]: no material in any unit system, and the stiffness, mass and energies made from it leave double precision", e->file, b->name, key[i], (double)val[i], (double)MBC_MATERIAL_MIN, (double)MBC_MATERIAL_MAX);
  }
  PetscFunctionReturn(0);
}

/* A dynamic analysis' integrator: Newmark (absent), or generalized-alpha's weights alpha_m, alpha_f
   (HHT: alpha_m = 0), checked for unconditional stability and second order (Chung and Hulbert:
   alpha_m <= alpha_f <= 1/2; the prep derives beta and gamma from them). */
static PetscErrorCode ReadScheme(H5Node *e, char scheme[32], PetscReal *am, PetscReal *af)
{
  PetscFunctionBegin;
  PetscCall(PetscStrncpy(scheme, "newmark", 32));
  *am = *af = 0;
  if (H5Aexists(e->obj, "scheme") <= 0) PetscFunctionReturn(0);
  PetscCall(H5ReadString(e, "scheme", scheme, 32, NULL, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "alpha_m", am, PETSC_FALSE));
  PetscCall(H5ReadReal(e, "alpha_f", af, PETSC_FALSE));
  PetscCheck(*am <= *af + 1e-12 && *af <= 0.5 + 1e-12 && *am >= -1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s: generalized-alpha weights alpha_m %g, alpha_f %g are not unconditionally stable (need -1 <= alpha_m <= alpha_f <= 1/2)", e->file, e->path, (double)*am, (double)*af);
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadAnalysis(H5Node *root, MBCScene s)
{
  H5Node   e;
  PetscInt v;

  PetscFunctionBegin;
  PetscCall(H5NodeOpen(s->filename, root->obj, root->path, "analysis", &e));
  v = MBC_ANALYSIS_STATIC;
  PetscCall(H5ReadEnum(&e, "type", MBCAnalysisTypes, &v, PETSC_FALSE));
  s->analysis = (MBCAnalysisType)v;
  v = MBC_MASS_CONSISTENT;
  PetscCall(H5ReadEnum(&e, "mass", MBCMassTypes, &v, PETSC_TRUE));
  s->mass          = (MBCMassType)v;
  s->dt            = 1.0;
  s->final_time    = 1.0;
  s->newmark_beta  = 0.25;
  s->newmark_gamma = 0.5;
  PetscCall(H5ReadReal(&e, "dt", &s->dt, PETSC_TRUE));
  PetscCall(H5ReadReal(&e, "final_time", &s->final_time, PETSC_TRUE));
  PetscCall(H5ReadReal(&e, "newmark_beta", &s->newmark_beta, PETSC_TRUE));
  PetscCall(H5ReadReal(&e, "newmark_gamma", &s->newmark_gamma, PETSC_TRUE));
  PetscCall(ReadScheme(&e, s->scheme, &s->alpha_m, &s->alpha_f));
  s->modal_modes = 6;
  s->modal_tie   = PETSC_TRUE;
  if (s->analysis == MBC_ANALYSIS_MODAL) {
    PetscInt tie = 1;
    PetscCall(H5ReadInt(&e, "modes", &s->modal_modes, PETSC_TRUE));
    PetscCall(H5ReadInt(&e, "tie", &tie, PETSC_TRUE));
    s->modal_tie = tie ? PETSC_TRUE : PETSC_FALSE;
    PetscCheck(s->modal_modes >= 1 && s->modal_modes <= 10000, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: analysis/modes = %" PetscInt_FMT " must lie in [1, 10000]", s->filename, s->modal_modes);
  }
  PetscCall(H5NodeClose(&e));
  PetscFunctionReturn(0);
}

/* The stages (optional list; absent or empty: one analysis). Each runs from where the one
   before ends; the first one's settings become the scene's analysis. */
static PetscErrorCode ReadStages(H5Node *root, MBCScene s)
{
  H5Node list, e;

  PetscFunctionBegin;
  s->nstages = 0;
  if (H5Lexists(root->obj, "stages", H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  PetscCall(H5NodeOpen(s->filename, root->obj, root->path, "stages", &list));
  PetscCall(H5ReadCount(&list, &s->nstages));
  PetscCheck(s->nstages >= 0 && s->nstages <= MBC_MAX_STEPS, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s has count %" PetscInt_FMT, s->filename, list.path, s->nstages);
  PetscCall(PetscCalloc1(s->nstages, &s->stages));
  for (PetscInt i = 0; i < s->nstages; i++) {
    MBCStageDesc *st = &s->stages[i];
    PetscInt      v;
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadString(&e, "name", st->name, sizeof(st->name), NULL, PETSC_FALSE));
    v = MBC_ANALYSIS_STATIC;
    PetscCall(H5ReadEnum(&e, "type", MBCAnalysisTypes, &v, PETSC_FALSE));
    st->analysis = (MBCAnalysisType)v;
    v = MBC_MASS_CONSISTENT;
    PetscCall(H5ReadEnum(&e, "mass", MBCMassTypes, &v, PETSC_TRUE));
    st->mass          = (MBCMassType)v;
    st->newmark_beta  = 0.25;
    st->newmark_gamma = 0.5;
    PetscCall(H5ReadReal(&e, "start_time", &st->start_time, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "dt", &st->dt, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "final_time", &st->final_time, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "newmark_beta", &st->newmark_beta, PETSC_TRUE));
    PetscCall(H5ReadReal(&e, "newmark_gamma", &st->newmark_gamma, PETSC_TRUE));
    PetscCall(ReadScheme(&e, st->scheme, &st->alpha_m, &st->alpha_f));
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));
  PetscCall(MBCSceneCheckStages(s));
  if (s->nstages) {
    s->analysis      = s->stages[0].analysis;
    s->mass          = s->stages[0].mass;
    s->dt            = s->stages[0].dt;
    s->final_time    = s->stages[s->nstages - 1].final_time;
    s->newmark_beta  = s->stages[0].newmark_beta;
    s->newmark_gamma = s->stages[0].newmark_gamma;
    s->alpha_m       = s->stages[0].alpha_m;
    s->alpha_f       = s->stages[0].alpha_f;
    PetscCall(PetscStrncpy(s->scheme, s->stages[0].scheme, sizeof(s->scheme)));
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadOutput(H5Node *root, MBCScene s)
{
  H5Node   e, pts, p;
  char    *fields;
  PetscInt energy = 0;

  PetscFunctionBegin;
  s->output_every        = 1;
  s->output_displacement = PETSC_TRUE;
  s->output_stress       = PETSC_TRUE;
  if (H5Lexists(root->obj, "output", H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  PetscCall(H5NodeOpen(s->filename, root->obj, root->path, "output", &e));
  PetscCall(H5ReadInt(&e, "every", &s->output_every, PETSC_TRUE));
  PetscCheck(s->output_every >= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: output/every = %" PetscInt_FMT " must be at least 1", s->filename, s->output_every);
  if (H5Aexists(e.obj, "fields") > 0) {
    PetscCall(H5ReadString(&e, "fields", NULL, 0, &fields, PETSC_FALSE));
    s->output_displacement = (PetscBool)(strstr(fields, "displacement") != NULL);
    s->output_stress       = (PetscBool)(strstr(fields, "stress") != NULL);
    s->output_envelope     = (PetscBool)(strstr(fields, "envelope") != NULL);
    PetscCall(PetscFree(fields));
  }
  PetscCall(H5ReadInt(&e, "energy", &energy, PETSC_TRUE));
  s->output_energy = energy ? PETSC_TRUE : PETSC_FALSE;
  PetscCall(H5ReadInt(&e, "points_count", &s->npoints, PETSC_TRUE));
  PetscCheck(s->npoints >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: output/points_count = %" PetscInt_FMT " is negative", s->filename, s->npoints);
  if (s->npoints > 0) {
    PetscInt count;
    PetscCall(H5NodeOpen(s->filename, e.obj, e.path, "points", &pts));
    PetscCall(H5ReadCount(&pts, &count));
    PetscCheck(count == s->npoints, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: output/points_count = %" PetscInt_FMT " but output/points has count = %" PetscInt_FMT, s->filename, s->npoints, count);
    PetscCall(PetscCalloc1(s->npoints, &s->points));
    for (PetscInt i = 0; i < s->npoints; i++) {
      PetscCall(H5EntryOpen(&pts, i, &p));
      PetscCall(H5ReadString(&p, "name", s->points[i].name, MBC_NAME_LEN, NULL, PETSC_FALSE));
      PetscCall(H5ReadString(&p, "body", s->points[i].body, MBC_NAME_LEN, NULL, PETSC_TRUE));
      PetscCall(H5ReadReals(&p, "x", 3, s->points[i].x, PETSC_FALSE));
      PetscCall(H5NodeClose(&p));
    }
    PetscCall(H5NodeClose(&pts));
  }
  PetscCall(H5NodeClose(&e));
  PetscFunctionReturn(0);
}

/* Opens list group `name` under root (if present) and reads its count (0 when absent). */
static PetscErrorCode ReadList(H5Node *root, const char *name, H5Node *list, PetscInt *count)
{
  PetscFunctionBegin;
  *count   = 0;
  list->obj = -1;
  if (H5Lexists(root->obj, name, H5P_DEFAULT) <= 0) PetscFunctionReturn(0);
  PetscCall(H5NodeOpen(root->file, root->obj, root->path, name, list));
  PetscCall(H5ReadCount(list, count));
  PetscFunctionReturn(0);
}

static PetscErrorCode FindName(const char *name, PetscInt n, const char *(*get)(MBCScene, PetscInt), MBCScene s, PetscInt *index)
{
  PetscBool same = PETSC_FALSE;

  PetscFunctionBegin;
  *index = -1;
  for (PetscInt i = 0; i < n && !same; i++) {
    PetscCall(PetscStrcmp(name, get(s, i), &same));
    if (same) *index = i;
  }
  PetscFunctionReturn(0);
}
static const char *BodyName(MBCScene s, PetscInt i) { return s->bodies[i].name; }
static const char *SurfaceName(MBCScene s, PetscInt i) { return s->surfaces[i].name; }

/* Each name of a ","-joined list must be one of n names. */
static PetscErrorCode CheckNameList(MBCScene s, const char *list, PetscInt n, const char *(*get)(MBCScene, PetscInt), const char *what, const char *where)
{
  char    *copy, *tok, *save = NULL;
  PetscInt idx;

  PetscFunctionBegin;
  PetscCall(PetscStrallocpy(list, &copy));
  for (tok = strtok_r(copy, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
    PetscCall(FindName(tok, n, get, s, &idx));
    PetscCheck(idx >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s names %s '%s', which the scene does not have", s->filename, where, what, tok);
  }
  PetscCall(PetscFree(copy));
  PetscFunctionReturn(0);
}

/* References between the lists (the prep writes them consistent; a hand-edited file must not
   drop a condition or a load silently). */
static PetscErrorCode SceneCheckReferences(MBCScene s)
{
  char where[64];

  PetscFunctionBegin;
  for (PetscInt i = 0; i < s->nbodies; i++) {
    MBCBodyDesc *b = &s->bodies[i];
    PetscBool    tet, hex;
    PetscInt     j;
    PetscCheck(b->name[0] && !strchr(b->name, ',') && !strchr(b->name, '/'), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: bodies/%" PetscInt_FMT " has the name '%s' (empty, or with ',' or '/')", s->filename, i, b->name);
    PetscCall(FindName(b->name, i, BodyName, s, &j));
    PetscCheck(j < 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: bodies/%" PetscInt_FMT " and bodies/%" PetscInt_FMT " are both called '%s'", s->filename, j, i, b->name);
    {
      const char *types[] = {"tet4", "hex8", "wedge6", "pyr5", "mixed", "tet10", "surface"};
      PetscBool   known   = PETSC_FALSE, same;
      for (PetscInt t = 0; t < 7; t++) {
        PetscCall(PetscStrcmp(b->cell_type, types[t], &same));
        known = (PetscBool)(known || same);
      }
      PetscCheck(known, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has cell_type '%s', not tet4, hex8, wedge6, pyr5, mixed, tet10 or surface", s->filename, b->name, b->cell_type);
    }
    PetscCall(PetscStrcmp(b->cell_type, "tet4", &tet));
    PetscCall(PetscStrcmp(b->cell_type, "surface", &hex));
    PetscCheck(!hex || b->rigid, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' is a surface but not rigid", s->filename, b->name);
    PetscCheck((b->num_nodes > b->num_vertices) == (PetscBool)!strcmp(b->cell_type, "tet10"), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' of %s cells has %" PetscInt_FMT " nodes beyond its vertices (only tet10 bodies have midside nodes)", s->filename, b->name, b->cell_type, b->num_nodes - b->num_vertices);
    hex = (PetscBool)(!strcmp(b->cell_type, "hex8") || !strcmp(b->cell_type, "mixed"));
    if (b->element[0]) {
      PetscBool h8, h8i, h8b;
      PetscCall(PetscStrcmp(b->element, "hex8", &h8));
      PetscCall(PetscStrcmp(b->element, "hex8i", &h8i));
      PetscCall(PetscStrcmp(b->element, "hex8b", &h8b));
      PetscCheck(hex && (h8 || h8i || h8b), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' of %s cells has element '%s' (bodies with hex cells: hex8, hex8i or hex8b; others: none)", s->filename, b->name, b->cell_type, b->element);
    }
    (void)tet;
    PetscCheck(b->num_cells >= 1 && b->num_vertices >= 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s' has %" PetscInt_FMT " cells and %" PetscInt_FMT " vertices", s->filename, b->name, b->num_cells, b->num_vertices);
  }
  for (PetscInt i = 0; i < s->nsurfaces; i++) {
    PetscInt j;
    PetscCheck(s->surfaces[i].id == i + 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: surfaces/%" PetscInt_FMT " has id %" PetscInt_FMT ", expected %" PetscInt_FMT, s->filename, i, s->surfaces[i].id, i + 1);
    PetscCall(FindName(s->surfaces[i].name, i, SurfaceName, s, &j));
    PetscCheck(j < 0 && s->surfaces[i].name[0], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: surfaces/%" PetscInt_FMT " has the name '%s' (empty or already used)", s->filename, i, s->surfaces[i].name);
  }
  for (PetscInt i = 0; i < s->ncouples; i++) {
    MBCCoupleDesc *c = &s->couples[i];
    PetscCall(PetscSNPrintf(where, sizeof(where), "couples/%" PetscInt_FMT " (master)", i));
    PetscCall(CheckNameList(s, c->master, s->nsurfaces, SurfaceName, "surface", where));
    PetscCall(PetscSNPrintf(where, sizeof(where), "couples/%" PetscInt_FMT " (slave)", i));
    PetscCall(CheckNameList(s, c->slave, s->nsurfaces, SurfaceName, "surface", where));
    PetscCheck(c->master[0] && c->slave[0], PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couples/%" PetscInt_FMT " needs master and slave surfaces", s->filename, i);
    for (PetscInt j = 0; j < i; j++) PetscCheck(s->couples[j].k != c->k, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couples/%" PetscInt_FMT " and couples/%" PetscInt_FMT " have the same k = %" PetscInt_FMT, s->filename, j, i, c->k);
    /* mu tan(phi): above 1e3 (a friction angle within 0.06 degrees of 90) the cone is numerically a cylinder */
    PetscCheck(c->mu <= MBC_MAX_MU, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT " has friction coefficient mu = %g; values above %g are not physical (use a bonded couple instead)", s->filename, c->k, (double)c->mu, (double)MBC_MAX_MU);
    for (PetscInt j = 0; j < s->nbodies; j++) PetscCheck(c->master_faces[j] >= 0 && c->slave_faces[j] >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couples/%" PetscInt_FMT " has a negative face count for body '%s'", s->filename, i, s->bodies[j].name);
  }
  for (PetscInt i = 0; i < s->ndirichlet; i++) {
    MBCDirichletDesc *d = &s->dirichlet[i];
    PetscBool         same;
    if (d->surface_id < 1) continue; /* on nodes or a rigid body (checked as read) */
    PetscCheck(d->surface_id >= 1 && d->surface_id <= s->nsurfaces, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dirichlet/%" PetscInt_FMT " has surface_id %" PetscInt_FMT ", but the scene has surfaces 1 to %" PetscInt_FMT, s->filename, i, d->surface_id, s->nsurfaces);
    PetscCall(PetscStrcmp(d->surface, s->surfaces[d->surface_id - 1].name, &same));
    PetscCheck(same, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: dirichlet/%" PetscInt_FMT " names surface '%s' but its surface_id %" PetscInt_FMT " is '%s'", s->filename, i, d->surface, d->surface_id, s->surfaces[d->surface_id - 1].name);
  }
  for (PetscInt i = 0; i < s->nloads; i++) {
    MBCLoadDesc *l = &s->loads[i];
    PetscCall(PetscSNPrintf(where, sizeof(where), "loads/%" PetscInt_FMT, i));
    PetscCall(CheckNameList(s, l->bodies, s->nbodies, BodyName, "body", where));
    if (l->kind == MBC_LOAD_GRAVITY) { /* the force per volume, density times acceleration, must be a number */
      const PetscReal g = PetscMax(PetscMax(PetscAbsReal(l->vector[0]), PetscAbsReal(l->vector[1])), PetscAbsReal(l->vector[2]));
      for (PetscInt b = 0; b < s->nbodies; b++) {
        PetscBool applies;
        PetscCall(MBCLoadAppliesToBody(l, s->bodies[b].name, &applies));
        PetscCheck(!applies || !PetscIsInfOrNanReal(s->bodies[b].density * g), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: body '%s': density %g times the gravity of loads/%" PetscInt_FMT " (%g) overflows", s->filename, s->bodies[b].name, (double)s->bodies[b].density, i, (double)g);
      }
    }
    if (l->kind == MBC_LOAD_GRAVITY || l->kind == MBC_LOAD_BODY_FORCE || l->kind == MBC_LOAD_GROUND_ACCELERATION || l->kind == MBC_LOAD_NODAL_FORCE || l->kind == MBC_LOAD_LINE_FORCE) continue;
    PetscBool same;
    PetscCheck(l->surface_id >= 1 && l->surface_id <= s->nsurfaces, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: loads/%" PetscInt_FMT " has surface_id %" PetscInt_FMT ", but the scene has surfaces 1 to %" PetscInt_FMT, s->filename, i, l->surface_id, s->nsurfaces);
    PetscCall(PetscStrcmp(l->surface, s->surfaces[l->surface_id - 1].name, &same));
    PetscCheck(same, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: loads/%" PetscInt_FMT " names surface '%s' but its surface_id %" PetscInt_FMT " is '%s'", s->filename, i, l->surface, l->surface_id, s->surfaces[l->surface_id - 1].name);
  }
  for (PetscInt i = 0; i < s->npoints; i++) {
    PetscInt j = 0;
    if (s->points[i].body[0]) PetscCall(FindName(s->points[i].body, s->nbodies, BodyName, s, &j));
    PetscCheck(j >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: output point '%s' names body '%s', which the scene does not have", s->filename, s->points[i].name, s->points[i].body);
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneRead(MBCScene s, hid_t file)
{
  H5Node   root, list, e;
  PetscInt version = 0, v;

  PetscFunctionBegin;
  root.file = s->filename;
  root.obj  = file;
  root.path[0] = 0;
  PetscCheck(H5Lexists(file, "mbcontact", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "File %s is not an mbcontact scene file (no /mbcontact group); make one with mbcontact-prep", s->filename);
  PetscCall(H5NodeOpen(s->filename, file, "", "mbcontact", &root));
  PetscCall(H5ReadInt(&root, "format_version", &version, PETSC_FALSE));
  PetscCheck(version == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s has format version %" PetscInt_FMT "; this mbcontact reads version 1", s->filename, version);
  PetscCall(H5ReadString(&root, "title", s->title, sizeof(s->title), NULL, PETSC_TRUE));
  PetscCall(ReadAnalysis(&root, s));
  PetscCall(ReadStages(&root, s));
  PetscCheck(s->analysis != MBC_ANALYSIS_MODAL || !s->nstages, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: a modal analysis has no stages", s->filename);
  s->has_dynamic = (PetscBool)(s->analysis == MBC_ANALYSIS_DYNAMIC || s->analysis == MBC_ANALYSIS_MODAL); /* the bodies need M */
  for (PetscInt i = 0; i < s->nstages; i++)
    if (s->stages[i].analysis == MBC_ANALYSIS_DYNAMIC) s->has_dynamic = PETSC_TRUE;

  PetscCall(ReadList(&root, "bodies", &list, &s->nbodies));
  PetscCheck(s->nbodies > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s has no bodies", s->filename);
  PetscCall(PetscCalloc1(s->nbodies, &s->bodies));
  for (PetscInt i = 0; i < s->nbodies; i++) {
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(ReadBody(&e, &s->bodies[i]));
    if (s->has_dynamic) PetscCheck(s->bodies[i].density > 0 || s->bodies[i].massless || s->bodies[i].rigid, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s' needs a positive density for a %s analysis (or massless)", s->filename, s->bodies[i].name, MBCAnalysisTypes[s->analysis]);
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "surfaces", &list, &s->nsurfaces));
  PetscCall(PetscCalloc1(s->nsurfaces, &s->surfaces));
  for (PetscInt i = 0; i < s->nsurfaces; i++) {
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadString(&e, "name", s->surfaces[i].name, MBC_NAME_LEN, NULL, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "id", &s->surfaces[i].id, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "num_faces", &s->surfaces[i].num_faces, PETSC_TRUE));
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "couples", &list, &s->ncouples));
  PetscCall(PetscCalloc1(s->ncouples, &s->couples));
  for (PetscInt i = 0; i < s->ncouples; i++) {
    MBCCoupleDesc *c = &s->couples[i];
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadInt(&e, "k", &c->k, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "mu", &c->mu, PETSC_TRUE));
    PetscCall(H5ReadString(&e, "master", NULL, 0, &c->master, PETSC_FALSE));
    PetscCall(H5ReadString(&e, "slave", NULL, 0, &c->slave, PETSC_FALSE));
    PetscCall(PetscCalloc2(s->nbodies, &c->master_faces, s->nbodies, &c->slave_faces)); /* optional: 0 in files of older preps */
    PetscCall(H5ReadReals(&e, "master_faces", s->nbodies, c->master_faces, PETSC_TRUE));
    PetscCall(H5ReadReals(&e, "slave_faces", s->nbodies, c->slave_faces, PETSC_TRUE));
    PetscCheck(c->k >= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple %s has real constant k = %" PetscInt_FMT "; k must be at least 1", s->filename, e.path, c->k);
    PetscCheck(c->mu >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: couple k = %" PetscInt_FMT " has friction coefficient mu = %g < 0", s->filename, c->k, (double)c->mu);
    PetscCall(ReadCoupleJoint(&e, s, c));
    PetscCall(ReadCoupleExclude(&e, s, c));
    {
      char sliding[16];
      PetscCall(H5ReadString(&e, "sliding", sliding, sizeof(sliding), NULL, PETSC_TRUE));
      c->sliding = !sliding[0] ? -1 : !strcmp(sliding, "small") ? 1 : !strcmp(sliding, "finite") ? 0 : -2;
      PetscCheck(c->sliding >= -1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: couple k = %" PetscInt_FMT " has sliding '%s'; it must be finite or small", s->filename, c->k, sliding);
    }
    PetscCall(ReadCoupleUplift(&e, s, c));
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "time_functions", &list, &s->ntables));
  PetscCall(PetscCalloc1(s->ntables, &s->tables));
  for (PetscInt i = 0; i < s->ntables; i++) {
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(ReadTimeTable(&e, &s->tables[i]));
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "dirichlet", &list, &s->ndirichlet));
  PetscCall(PetscCalloc1(s->ndirichlet, &s->dirichlet));
  for (PetscInt i = 0; i < s->ndirichlet; i++) {
    MBCDirichletDesc *d = &s->dirichlet[i];
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadString(&e, "surface", d->surface, MBC_NAME_LEN, NULL, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "surface_id", &d->surface_id, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "component", &d->component, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "value", &d->value, PETSC_FALSE));
    PetscCall(ReadTimeKind(&e, s, &d->time, &d->time_function));
    d->body = -1;
    PetscCall(H5ReadInt(&e, "body", &d->body, PETSC_TRUE));
    PetscCall(ReadNodePairs(&e, s, "nodes", &d->nnodes, &d->nodes));
    PetscCheck(d->body < s->nbodies && (d->body < 0 || s->bodies[d->body].rigid), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s names body %" PetscInt_FMT ", which is no rigid body of the scene", s->filename, e.path, d->body);
    PetscCheck((d->surface_id >= 1) + (d->body >= 0) + (d->nnodes > 0) == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s needs one of a surface_id, a rigid body or nodes", s->filename, e.path);
    PetscCheck(d->component >= 0 && d->component < (d->body >= 0 ? 6 : 3), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s has component %" PetscInt_FMT ", not 0, 1 or 2 (3, 4, 5: a rigid body's rotations)", s->filename, e.path, d->component);
    for (PetscInt k = 0; k < d->nnodes; k++) PetscCheck(!s->bodies[d->nodes[2 * k]].rigid, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s prescribes nodes of rigid body '%s' (a rigid body's motion is prescribed by its body index)", s->filename, e.path, s->bodies[d->nodes[2 * k]].name);
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "loads", &list, &s->nloads));
  PetscCall(PetscCalloc1(s->nloads, &s->loads));
  for (PetscInt i = 0; i < s->nloads; i++) {
    MBCLoadDesc *l = &s->loads[i];
    PetscCall(H5EntryOpen(&list, i, &e));
    v = 0;
    PetscCall(H5ReadEnum(&e, "kind", MBCLoadKinds, &v, PETSC_FALSE));
    l->kind       = (MBCLoadKind)v;
    l->surface_id = -1;
    PetscCall(H5ReadReals(&e, "vector", 3, l->vector, PETSC_TRUE));
    PetscCall(H5ReadReal(&e, "value", &l->value, PETSC_TRUE));
    PetscCall(H5ReadString(&e, "surface", l->surface, MBC_NAME_LEN, NULL, PETSC_TRUE));
    PetscCall(H5ReadInt(&e, "surface_id", &l->surface_id, PETSC_TRUE));
    PetscCall(H5ReadString(&e, "bodies", NULL, 0, &l->bodies, PETSC_TRUE));
    PetscCall(ReadTimeKind(&e, s, &l->time, &l->time_function));
    PetscCall(H5ReadInt(&e, "stage", &l->stage, PETSC_TRUE));
    PetscCheck(l->stage >= 0 && (l->stage == 0 || l->stage < s->nstages), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: load %s acts from stage %" PetscInt_FMT ", but the scene has %" PetscInt_FMT " stages", s->filename, e.path, l->stage, s->nstages);
    if (l->kind == MBC_LOAD_PRESSURE || l->kind == MBC_LOAD_TRACTION || l->kind == MBC_LOAD_HYDROSTATIC) PetscCheck(l->surface_id >= 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s load %s needs a surface", s->filename, MBCLoadKinds[l->kind], e.path);
    if (l->kind == MBC_LOAD_HYDROSTATIC) {
      PetscCall(H5ReadReal(&e, "level", &l->level, PETSC_FALSE));
      PetscCall(H5ReadReal(&e, "unit_weight", &l->unit_weight, PETSC_FALSE));
      PetscCall(H5ReadInt(&e, "axis", &l->axis, PETSC_FALSE));
      PetscCheck(l->axis >= 0 && l->axis < 3, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: hydrostatic load %s has axis %" PetscInt_FMT ", not 0, 1 or 2", s->filename, e.path, l->axis);
      PetscCheck(l->unit_weight >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: hydrostatic load %s has unit weight %g < 0", s->filename, e.path, (double)l->unit_weight);
    }
    if (l->kind == MBC_LOAD_UPLIFT) {
      PetscCall(H5ReadInt(&e, "couple", &l->couple, PETSC_FALSE));
      PetscCall(H5ReadInt(&e, "side", &l->side, PETSC_FALSE));
      PetscCheck(l->surface_id >= 1 && l->couple >= 0 && l->couple < s->ncouples && s->couples[l->couple].uplift.on, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: uplift load %s needs a surface and a couple with an uplift", s->filename, e.path);
    }
    if (l->kind == MBC_LOAD_NODAL_FORCE || l->kind == MBC_LOAD_LINE_FORCE) {
      PetscCall(ReadNodePairs(&e, s, "nodes", &l->nnodes, &l->nodes));
      PetscCheck(l->nnodes > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: %s load %s needs its dataset nodes", s->filename, MBCLoadKinds[l->kind], e.path);
      PetscCall(ReadRealDataset(&e, "weights", l->nnodes, 1, &l->weights));
    }
    l->velocity_function = l->displacement_function = -1;
    if (l->kind == MBC_LOAD_GROUND_ACCELERATION) {
      PetscCall(H5ReadInt(&e, "velocity_function", &l->velocity_function, PETSC_FALSE));
      PetscCall(H5ReadInt(&e, "displacement_function", &l->displacement_function, PETSC_FALSE));
      PetscCheck(l->time == MBC_TIME_TABLE && l->velocity_function >= 0 && l->velocity_function < s->ntables && l->displacement_function >= 0 && l->displacement_function < s->ntables, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: ground acceleration %s needs a table and its velocity and displacement tables (time functions %" PetscInt_FMT ", %" PetscInt_FMT " of %" PetscInt_FMT ")", s->filename, e.path, l->velocity_function, l->displacement_function, s->ntables);
      PetscCheck(s->has_dynamic, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: ground acceleration %s needs a dynamic analysis", s->filename, e.path);
      { /* the integrals' tables at the acceleration's rows (MBCSceneRecord interpolates within them) */
        const MBCTimeTable *A = &s->tables[l->time_function], *V = &s->tables[l->velocity_function], *D = &s->tables[l->displacement_function];
        PetscBool same = (PetscBool)(V->n == A->n && D->n == A->n && A->n >= 2);
        for (PetscInt r = 0; same && r < A->n; r++) same = (PetscBool)(V->t[r] == A->t[r] && D->t[r] == A->t[r]);
        PetscCheck(same, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: ground acceleration %s: its velocity and displacement tables must have the acceleration's rows (at least 2)", s->filename, e.path);
      }
    }
    PetscCall(H5NodeClose(&e));
  }
  PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "added_mass", &list, &s->naddedmass));
  PetscCall(PetscCalloc1(s->naddedmass, &s->addedmass));
  for (PetscInt i = 0; i < s->naddedmass; i++) {
    MBCAddedMassDesc *m = &s->addedmass[i];
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadString(&e, "surface", m->surface, MBC_NAME_LEN, NULL, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "surface_id", &m->surface_id, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "density", &m->density, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "level", &m->level, PETSC_FALSE));
    PetscCall(H5ReadReal(&e, "bottom", &m->bottom, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "axis", &m->axis, PETSC_FALSE));
    PetscCheck(m->axis >= 0 && m->axis < 3 && m->density > 0 && m->level > m->bottom, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: added mass %s: axis %" PetscInt_FMT " (0, 1, 2), density %g (> 0), level %g above bottom %g needed", s->filename, e.path, m->axis, (double)m->density, (double)m->level, (double)m->bottom);
    PetscCheck(m->surface_id >= 1 && m->surface_id <= s->nsurfaces, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: added mass %s has surface_id %" PetscInt_FMT ", but the scene has surfaces 1 to %" PetscInt_FMT, s->filename, e.path, m->surface_id, s->nsurfaces);
    PetscCheck(s->has_dynamic, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: added mass %s needs a dynamic or modal analysis", s->filename, e.path);
    PetscCall(H5NodeClose(&e));
  }
  if (list.obj >= 0) PetscCall(H5NodeClose(&list));
  PetscCall(ReadList(&root, "absorbing", &list, &s->nabsorbing));
  PetscCall(PetscCalloc1(s->nabsorbing, &s->absorbing));
  for (PetscInt i = 0; i < s->nabsorbing; i++) {
    MBCAbsorbingDesc *a = &s->absorbing[i];
    PetscInt          v = MBC_INPUT_NONE;
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadString(&e, "surface", a->surface, MBC_NAME_LEN, NULL, PETSC_FALSE));
    PetscCall(H5ReadInt(&e, "surface_id", &a->surface_id, PETSC_FALSE));
    PetscCall(H5ReadEnum(&e, "input", MBCAbsorbingInputs, &v, PETSC_TRUE));
    a->input = (MBCAbsorbingInput)v;
    if (a->input != MBC_INPUT_NONE) s->absolute = PETSC_TRUE;
    PetscCheck(a->surface_id >= 1 && a->surface_id <= s->nsurfaces, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: absorbing boundary %s has surface_id %" PetscInt_FMT ", but the scene has surfaces 1 to %" PetscInt_FMT, s->filename, e.path, a->surface_id, s->nsurfaces);
    PetscCall(H5NodeClose(&e));
  }
  if (list.obj >= 0) PetscCall(H5NodeClose(&list));

  PetscCall(ReadList(&root, "springs", &list, &s->nsprings));
  PetscCall(PetscCalloc1(s->nsprings, &s->springs));
  for (PetscInt i = 0; i < s->nsprings; i++) {
    MBCSpringDesc *sp = &s->springs[i];
    PetscInt       nto = 0;
    PetscCall(H5EntryOpen(&list, i, &e));
    PetscCall(H5ReadReals(&e, "stiffness", 3, sp->k, PETSC_FALSE));
    PetscCall(H5ReadReals(&e, "damping", 3, sp->c, PETSC_FALSE));
    PetscCall(ReadNodePairs(&e, s, "nodes", &sp->n, &sp->nodes));
    PetscCall(ReadNodePairs(&e, s, "to", &nto, &sp->to));
    PetscCheck(sp->n > 0 && (!sp->to || nto == sp->n), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: spring %s needs nodes (and as many partners `to`, if any)", s->filename, e.path);
    for (PetscInt d = 0; d < 3; d++) PetscCheck(sp->k[d] >= 0 && sp->c[d] >= 0 && sp->k[d] <= MBC_MATERIAL_MAX && sp->c[d] <= MBC_MATERIAL_MAX, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: spring %s: stiffness and damping must lie in [0, %g]", s->filename, e.path, (double)MBC_MATERIAL_MAX);
    for (PetscInt k = 0; k < sp->n; k++) {
      PetscCheck(!s->bodies[sp->nodes[2 * k]].rigid, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: spring %s acts on rigid body '%s'", s->filename, e.path, s->bodies[sp->nodes[2 * k]].name);
      PetscCheck(!sp->to || (sp->to[2 * k] == sp->nodes[2 * k] && sp->to[2 * k + 1] != sp->nodes[2 * k + 1]), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: spring %s row %" PetscInt_FMT " joins a node to itself or to another body", s->filename, e.path, k);
    }
    PetscCall(H5NodeClose(&e));
  }
  if (list.obj >= 0) PetscCall(H5NodeClose(&list));

  PetscCall(ReadOutput(&root, s));
  PetscCall(H5NodeClose(&root));
  PetscCall(SceneCheckReferences(s));
  PetscFunctionReturn(0);
}

static PetscErrorCode SceneCreate(MPI_Comm comm, MBCScene *scene)
{
  PetscFunctionBegin;
  PetscCall(MBCInitializePackage());
  PetscCall(PetscHeaderCreate(*scene, MBC_SCENE_CLASSID, "MBCScene", "mbcontact scene", "MBCScene", comm, MBCSceneDestroy, MBCSceneView));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneLoad(MPI_Comm comm, const char filename[], MBCScene *scene)
{
  MBCScene       s;
  PetscBool      exists;
  hid_t          file;
  PetscErrorCode ierr;

  PetscFunctionBegin;
  PetscCall(MBCInitializePackage());
  PetscCall(PetscLogEventBegin(MBC_SceneLoad, 0, 0, 0, 0));
  PetscCall(PetscTestFile(filename, 'r', &exists));
  PetscCheck(exists, comm, PETSC_ERR_FILE_OPEN, "Scene file %s does not exist or cannot be read", filename);
  PetscCall(MBCH5CheckPathLength(filename, "scene file")); /* the meshes are read through MPI-IO */
  PetscCall(SceneCreate(comm, &s));
  PetscCall(PetscStrncpy(s->filename, filename, sizeof(s->filename)));
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* our messages replace HDF5's error stack dump */
  PetscCheck(H5Fis_hdf5(filename) > 0, comm, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s is not an HDF5 file; make scene files with mbcontact-prep", filename);
  file = H5Fopen(filename, H5F_ACC_RDONLY, H5P_DEFAULT);
  PetscCheck(file >= 0, comm, PETSC_ERR_FILE_OPEN, "Cannot open scene file %s", filename);
  /* the file is closed on the error paths too */
  ierr = SceneRead(s, file);
  if (!ierr) ierr = MBCSceneCheckMeshes(s, file);
  H5Fclose(file);
  PetscCall(ierr);
  PetscCall(PetscLogEventEnd(MBC_SceneLoad, 0, 0, 0, 0));
  *scene = s;
  PetscCall(PetscObjectViewFromOptions((PetscObject)s, NULL, "-mbc_scene_view"));
  PetscFunctionReturn(0);
}

/* A scene with no bodies and the default analysis settings (for -help). */
PetscErrorCode MBCSceneCreateEmpty(MPI_Comm comm, MBCScene *scene)
{
  PetscFunctionBegin;
  PetscValidPointer(scene, 2);
  PetscCall(SceneCreate(comm, scene));
  (*scene)->dt            = 1.0;
  (*scene)->final_time    = 1.0;
  (*scene)->newmark_beta  = 0.25;
  (*scene)->newmark_gamma = 0.5;
  PetscCall(PetscStrncpy((*scene)->scheme, "newmark", sizeof((*scene)->scheme)));
  (*scene)->output_every  = 1;
  (*scene)->modal_modes   = 6;
  (*scene)->modal_tie     = PETSC_TRUE;
  PetscCall(PetscStrncpy((*scene)->filename, "scene.h5", sizeof((*scene)->filename)));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneDestroy(MBCScene *scene)
{
  MBCScene s = *scene;

  PetscFunctionBegin;
  if (!s) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(s, MBC_SCENE_CLASSID, 1);
  if (--((PetscObject)s)->refct > 0) {
    *scene = NULL;
    PetscFunctionReturn(0);
  }
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].master));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].slave));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree2(s->couples[i].master_faces, s->couples[i].slave_faces));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].exclude));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].uplift.table));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].uplift.zones));
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscFree(s->couples[i].uplift.zone_of_body));
  for (PetscInt i = 0; i < s->ntables; i++) PetscCall(PetscFree2(s->tables[i].t, s->tables[i].f));
  for (PetscInt i = 0; i < s->nloads; i++) PetscCall(PetscFree(s->loads[i].bodies));
  for (PetscInt i = 0; i < s->nloads; i++) PetscCall(PetscFree(s->loads[i].nodes));
  for (PetscInt i = 0; i < s->nloads; i++) PetscCall(PetscFree(s->loads[i].weights));
  for (PetscInt i = 0; i < s->ndirichlet; i++) PetscCall(PetscFree(s->dirichlet[i].nodes));
  for (PetscInt i = 0; i < s->nsprings; i++) PetscCall(PetscFree(s->springs[i].nodes));
  for (PetscInt i = 0; i < s->nsprings; i++) PetscCall(PetscFree(s->springs[i].to));
  for (PetscInt i = 0; i < s->nbodies; i++) {
    PetscCall(PetscFree(s->bodies[i].midside));
    PetscCall(PetscFree(s->bodies[i].midside_x));
    PetscCall(PetscFree(s->bodies[i].initial_u));
    PetscCall(PetscFree(s->bodies[i].initial_v));
  }
  PetscCall(PetscFree(s->springs));
  PetscCall(PetscFree(s->bodies));
  PetscCall(PetscFree(s->surfaces));
  PetscCall(PetscFree(s->couples));
  PetscCall(PetscFree(s->tables));
  PetscCall(PetscFree(s->dirichlet));
  PetscCall(PetscFree(s->loads));
  PetscCall(PetscFree(s->points));
  PetscCall(PetscFree(s->stages));
  PetscCall(PetscFree(s->addedmass));
  PetscCall(PetscFree(s->absorbing));
  PetscCall(PetscHeaderDestroy(scene));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneGetFilename(MBCScene s, const char **filename)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SCENE_CLASSID, 1);
  PetscValidPointer(filename, 2);
  *filename = s->filename;
  PetscFunctionReturn(0);
}

/* The factor multiplying a load or prescribed value at time t. */
PetscErrorCode MBCTimeFactor(MBCScene s, MBCTimeKind kind, PetscInt tf, PetscReal t, PetscReal *factor)
{
  MBCTimeTable *tab;
  PetscInt      i;

  PetscFunctionBegin;
  if (kind != MBC_TIME_TABLE) {
    *factor = 1.0;
    PetscFunctionReturn(0);
  }
  tab = &s->tables[tf];
  if (t <= tab->t[0]) *factor = tab->f[0];
  else if (t >= tab->t[tab->n - 1]) *factor = tab->f[tab->n - 1];
  else {
    for (i = 1; tab->t[i] < t; i++) { }
    *factor = tab->f[i - 1] + (tab->f[i] - tab->f[i - 1]) * (t - tab->t[i - 1]) / (tab->t[i] - tab->t[i - 1]);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCLoadAppliesToBody(MBCLoadDesc *load, const char body[], PetscBool *applies)
{
  char  *list, *tok, *save = NULL;

  PetscFunctionBegin;
  *applies = PETSC_TRUE;
  if (!load->bodies || !load->bodies[0]) PetscFunctionReturn(0);
  *applies = PETSC_FALSE;
  PetscCall(PetscStrallocpy(load->bodies, &list));
  for (tok = strtok_r(list, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
    PetscBool same;
    PetscCall(PetscStrcmp(tok, body, &same));
    if (same) *applies = PETSC_TRUE;
  }
  PetscCall(PetscFree(list));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneView(MBCScene s, PetscViewer viewer)
{
  PetscBool ascii;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SCENE_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(PetscObjectComm((PetscObject)s), &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCall(PetscViewerASCIIPrintf(viewer, "Scene %s%s%s: %s analysis, dt %g, final time %g, %s beta %g gamma %g alpha_m %g alpha_f %g, %s mass\n", s->filename, s->title[0] ? " - " : "", s->title, MBCAnalysisTypes[s->analysis], (double)s->dt, (double)s->final_time, s->scheme, (double)s->newmark_beta, (double)s->newmark_gamma, (double)s->alpha_m, (double)s->alpha_f, MBCMassTypes[s->mass]));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  for (PetscInt i = 0; i < s->nstages; i++) {
    MBCStageDesc *st = &s->stages[i];
    PetscCall(PetscViewerASCIIPrintf(viewer, "stage %" PetscInt_FMT " %s: %s, t %g to %g, dt %g, Newmark beta %g gamma %g\n", i, st->name, MBCAnalysisTypes[st->analysis], (double)st->start_time, (double)st->final_time, (double)st->dt, (double)st->newmark_beta, (double)st->newmark_gamma));
  }
  for (PetscInt i = 0; i < s->nbodies; i++) {
    MBCBodyDesc *b = &s->bodies[i];
    PetscCall(PetscViewerASCIIPrintf(viewer, "body %s: %" PetscInt_FMT " %s cells, %" PetscInt_FMT " vertices, E %g nu %g density %g damping %g rayleigh %g %g\n", b->name, b->num_cells, b->cell_type, b->num_vertices, (double)b->E, (double)b->nu, (double)b->density, (double)b->damping, (double)b->rayleigh_alpha, (double)b->rayleigh_beta));
  }
  for (PetscInt i = 0; i < s->ncouples; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "couple %" PetscInt_FMT ": master %s (+k), slave %s (-k), mu %g, %" PetscInt_FMT " master nodes taken out of contact%s\n", s->couples[i].k, s->couples[i].master, s->couples[i].slave, (double)s->couples[i].mu, s->couples[i].nexclude, s->couples[i].cohesion > 0 ? ", bonded" : ""));
  for (PetscInt i = 0; i < s->ndirichlet; i++) {
    const MBCDirichletDesc *d = &s->dirichlet[i];
    const char *const       comp[] = {"ux", "uy", "uz", "rx", "ry", "rz"};
    if (d->body >= 0) PetscCall(PetscViewerASCIIPrintf(viewer, "prescribed %s = %g of rigid body %s (%s)\n", comp[d->component], (double)d->value, s->bodies[d->body].name, MBCTimeKinds[d->time]));
    else if (d->nnodes) PetscCall(PetscViewerASCIIPrintf(viewer, "prescribed %s = %g on %" PetscInt_FMT " nodes (%s)\n", comp[d->component], (double)d->value, d->nnodes, MBCTimeKinds[d->time]));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "prescribed %s = %g on %s (%s)\n", comp[d->component], (double)d->value, d->surface, MBCTimeKinds[d->time]));
  }
  for (PetscInt i = 0; i < s->nsprings; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "springs %" PetscInt_FMT ": %" PetscInt_FMT " %s, stiffness (%g, %g, %g), damping (%g, %g, %g)\n", i, s->springs[i].n, s->springs[i].to ? "node to node" : "node to ground", (double)s->springs[i].k[0], (double)s->springs[i].k[1], (double)s->springs[i].k[2], (double)s->springs[i].c[0], (double)s->springs[i].c[1], (double)s->springs[i].c[2]));
  for (PetscInt i = 0; i < s->nloads; i++) {
    MBCLoadDesc *l = &s->loads[i];
    if (l->kind == MBC_LOAD_UPLIFT) PetscCall(PetscViewerASCIIPrintf(viewer, "load uplift of couple k = %" PetscInt_FMT " on %s (%s)\n", s->couples[l->couple].k, l->surface, MBCTimeKinds[l->time]));
    else if (l->kind == MBC_LOAD_HYDROSTATIC) PetscCall(PetscViewerASCIIPrintf(viewer, "load hydrostatic on %s: unit weight %g, level %c = %g (%s)\n", l->surface, (double)l->unit_weight, "xyz"[l->axis], (double)l->level, MBCTimeKinds[l->time]));
    else PetscCall(PetscViewerASCIIPrintf(viewer, "load %s (%g, %g, %g) value %g%s%s bodies [%s] (%s)\n", MBCLoadKinds[l->kind], (double)l->vector[0], (double)l->vector[1], (double)l->vector[2], (double)l->value, l->surface[0] ? " on " : "", l->surface, l->bodies, MBCTimeKinds[l->time]));
    if (l->kind == MBC_LOAD_GROUND_ACCELERATION) PetscCall(PetscViewerASCIIPrintf(viewer, "  ground acceleration along (%g, %g, %g): %" PetscInt_FMT " rows from t = %g to %g\n", (double)l->vector[0], (double)l->vector[1], (double)l->vector[2], s->tables[l->time_function].n, (double)s->tables[l->time_function].t[0], (double)s->tables[l->time_function].t[s->tables[l->time_function].n - 1]));
    if (l->stage) PetscCall(PetscViewerASCIIPrintf(viewer, "  from stage %" PetscInt_FMT " (%s)\n", l->stage, s->stages[l->stage].name));
  }
  for (PetscInt i = 0; i < s->naddedmass; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "added mass (Westergaard) on %s: water density %g, level %c = %g, floor %g\n", s->addedmass[i].surface, (double)s->addedmass[i].density, "xyz"[s->addedmass[i].axis], (double)s->addedmass[i].level, (double)s->addedmass[i].bottom));
  for (PetscInt i = 0; i < s->nabsorbing; i++) PetscCall(PetscViewerASCIIPrintf(viewer, "absorbing boundary (Lysmer-Kuhlemeyer dashpots) on %s, input %s\n", s->absorbing[i].surface, MBCAbsorbingInputs[s->absorbing[i].input]));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* A ground acceleration's record at time t: the acceleration linear between its rows, the
   velocity and displacement its exact integrals (quadratic and cubic between the rows, from the
   prep's tables of their values at the rows); before the first row at rest, after the last one
   the acceleration held (0: the prep pads a record with zeros) and integrated on. */
PetscErrorCode MBCSceneRecord(MBCScene s, MBCLoadDesc *l, PetscReal t, PetscReal *d, PetscReal *v, PetscReal *a)
{
  const MBCTimeTable *A = &s->tables[l->time_function], *V = &s->tables[l->velocity_function], *D = &s->tables[l->displacement_function];
  PetscInt            i;
  PetscReal           tau, h, slope;

  PetscFunctionBegin;
  PetscCheck(V->n == A->n && D->n == A->n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Scene file %s: a ground acceleration's velocity and displacement tables must have its %" PetscInt_FMT " rows", s->filename, A->n);
  if (t <= A->t[0]) {
    *d = D->f[0], *v = V->f[0], *a = t < A->t[0] ? 0.0 : A->f[0];
    PetscFunctionReturn(0);
  }
  if (t >= A->t[A->n - 1]) {
    tau = t - A->t[A->n - 1];
    *a  = A->f[A->n - 1];
    *v  = V->f[A->n - 1] + *a * tau;
    *d  = D->f[A->n - 1] + V->f[A->n - 1] * tau + 0.5 * *a * tau * tau;
    PetscFunctionReturn(0);
  }
  { /* the row before t, by bisection (records have thousands of rows) */
    PetscInt lo = 0, hi = A->n - 1;
    while (hi - lo > 1) {
      const PetscInt mid = (lo + hi) / 2;
      if (A->t[mid] <= t) lo = mid;
      else hi = mid;
    }
    i = lo;
  }
  tau   = t - A->t[i];
  h     = A->t[i + 1] - A->t[i];
  slope = (A->f[i + 1] - A->f[i]) / h;
  *a    = A->f[i] + slope * tau;
  *v    = V->f[i] + A->f[i] * tau + 0.5 * slope * tau * tau;
  *d    = D->f[i] + V->f[i] * tau + 0.5 * A->f[i] * tau * tau + slope * tau * tau * tau / 6;
  PetscFunctionReturn(0);
}

/* The base's displacement, velocity and acceleration at time t in stage `stage`: the sum of the
   ground accelerations acting by then, each along its vector (0 in a scene in absolute motion,
   whose bodies' own motion is absolute). */
PetscErrorCode MBCSceneGroundMotion(MBCScene s, PetscInt stage, PetscReal t, PetscReal d[3], PetscReal v[3], PetscReal a[3])
{
  PetscFunctionBegin;
  for (PetscInt c = 0; c < 3; c++) d[c] = v[c] = a[c] = 0;
  if (s->absolute) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < s->nloads; i++) {
    MBCLoadDesc *l = &s->loads[i];
    PetscReal    f[3];
    if (l->kind != MBC_LOAD_GROUND_ACCELERATION || l->stage > stage) continue;
    PetscCall(MBCSceneRecord(s, l, t, &f[0], &f[1], &f[2]));
    for (PetscInt c = 0; c < 3; c++) {
      d[c] += l->vector[c] * f[0];
      v[c] += l->vector[c] * f[1];
      a[c] += l->vector[c] * f[2];
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneGetNumBodies(MBCScene s, PetscInt *n)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SCENE_CLASSID, 1);
  *n = s->nbodies;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSceneGetBodyName(MBCScene s, PetscInt b, const char **name)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SCENE_CLASSID, 1);
  PetscCheck(b >= 0 && b < s->nbodies, PetscObjectComm((PetscObject)s), PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body %" PetscInt_FMT " out of range [0, %" PetscInt_FMT ")", s->filename, b, s->nbodies);
  *name = s->bodies[b].name;
  PetscFunctionReturn(0);
}
