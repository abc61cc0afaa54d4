/* Contact-face couples: gathered from the bodies (whatever ranks own them), searched, viewed. */
#include <mbc/private/contactimpl.h>
#include <petscbt.h>
#include <petscsf.h>
#include <stdlib.h>

PetscLogEvent MBC_RankWait, MBC_ContactGather, MBC_GlobalSearch, MBC_LocalSearch, MBC_ContactIntegrate;

PetscErrorCode MBCContactCreate(MPI_Comm comm, MBCScene scene, MBCContact *contact)
{
  MBCContact c;

  PetscFunctionBegin;
  PetscCall(PetscNew(&c));
  c->comm        = comm;
  c->scene       = scene;
  c->cell_factor = 1.0;
  c->extension   = 0.1;
  c->hysteresis  = 0.05;
  c->integrate   = PETSC_TRUE;
  c->nquad       = 3; /* a piece of parallelogram or triangle faces: degree 4, exact from 3 on (contactintegrate.c) */
  c->ncouples    = scene->ncouples;
  c->penetration_tol   = -0.05;
  c->check_penetration = PETSC_TRUE;
  c->interference_tol  = -1e-4;
  c->slide_limit       = 0.2;
  PetscCall(PetscCalloc1(c->ncouples, &c->couples));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    c->couples[i].k  = scene->couples[i].k;
    c->couples[i].mu = scene->couples[i].mu;
  }
  PetscCall(PetscCalloc1(scene->nbodies, &c->usearch));
  *contact = c;
  PetscFunctionReturn(0);
}

/* The search's options, -<prefix>mbc_contact_* (prefix: the solver's, or NULL). */
PetscErrorCode MBCContactSetFromOptions(MBCContact c, const char prefix[])
{
  PetscFunctionBegin;
  PetscOptionsBegin(c->comm, prefix, "mbcontact contact search options", "MBCContact");
  PetscCall(PetscOptionsReal("-mbc_contact_cell_factor", "Search cell edge / mean face edge", "MBCContactSetFromOptions", c->cell_factor, &c->cell_factor, NULL));
  PetscCall(PetscOptionsReal("-mbc_contact_margin", "Box enlargement and re-search distance (0: one cell edge)", "MBCContactSetFromOptions", c->margin, &c->margin, NULL));
  PetscCall(PetscOptionsReal("-mbc_contact_extension", "Fraction of its edge by which a slave face reaches beyond the slave surface's free boundary", "MBCContactSetFromOptions", c->extension, &c->extension, NULL));
  PetscCall(PetscOptionsReal("-mbc_contact_hysteresis", "A master node keeps the slave face of the pairs H was built for while its projection lies on that face or within this fraction of an edge beyond it, the two faces on one smooth surface (0: the best face at every search)", "MBCContactSetFromOptions", c->hysteresis, &c->hysteresis, NULL));
  { /* given, it sets every couple (a run against the other kind without editing the scene);
       else each couple's `sliding` key decides, finite where it has none */
    const char *const slidings[] = {"finite", "small", "MBCContactSliding", "", NULL};
    PetscInt          sliding    = 0;
    PetscBool         set;
    PetscCall(PetscOptionsEList("-mbc_contact_sliding", "Every couple's sliding, over the scene's `sliding` keys. finite: a search at every step; small: the pairs, weights and frames of a search kept, the gaps moved by the motion since (until a new stage, step size or -mbc_contact_slide_repair)", "MBCContactSetFromOptions", slidings, 2, slidings[sliding], &sliding, &set));
    c->small_sliding = PETSC_FALSE;
    for (PetscInt i = 0; i < c->ncouples; i++) {
      const PetscInt key = c->scene->couples[i].sliding;
      c->couples[i].small_sliding = (PetscBool)(set ? sliding == 1 : key == 1);
      c->small_sliding            = (PetscBool)(c->small_sliding || c->couples[i].small_sliding);
    }
  }
  PetscCall(PetscOptionsReal("-mbc_contact_slide_limit", "Small sliding: a point that slid more than this fraction of its slave face's shortest edge since its pairs were fixed is reported", "MBCContactSetFromOptions", c->slide_limit, &c->slide_limit, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_slide_repair", "Small sliding: search again when a point slid beyond -mbc_contact_slide_limit, instead of reporting it", "MBCContactSetFromOptions", c->slide_repair, &c->slide_repair, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_check_search", "After every search, pair every master node with every slave face by brute force and stop at a pair the search missed (debug)", "MBCContactSetFromOptions", c->check, &c->check, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_integrate", "Average each point's gap over its master node's share of the surface (else collocate at the node, as the paper)", "MBCContactSetFromOptions", c->integrate, &c->integrate, NULL));
  PetscCall(PetscOptionsInt("-mbc_contact_quadrature", "Gauss points per direction on a master face for -mbc_contact_integrate", "MBCContactSetFromOptions", c->nquad, &c->nquad, NULL));
  PetscCall(PetscOptionsReal("-mbc_contact_penetration_tol", "Largest initial penetration accepted (< 0: that fraction of the mean face edge)", "MBCContactSetFromOptions", c->penetration_tol, &c->penetration_tol, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_accept_penetration", "Warn about a larger initial penetration or interference instead of stopping", "MBCContactSetFromOptions", c->accept_penetration, &c->accept_penetration, NULL));
  PetscCall(PetscOptionsReal("-mbc_contact_interference_tol", "Largest initial interference of the faceted contact surfaces accepted (< 0: that fraction of the mean face edge)", "MBCContactSetFromOptions", c->interference_tol, &c->interference_tol, NULL));
  { /* read as a string: PETSc's "Input string abc has no numeric value" would not name the option */
    char      str[64] = "";
    PetscBool set;
    PetscCall(PetscOptionsString("-mbc_contact_adjust", "Strain-free adjustment: initial gaps and interferences within this distance are treated as zero for the whole run (0: off)", "MBCContactSetFromOptions", str, str, sizeof(str), &set));
    if (set) {
      char *end = NULL;
      c->adjust = (PetscReal)strtod(str, &end);
      PetscCheck(str[0] && end && !*end, c->comm, PETSC_ERR_ARG_WRONG, "-mbc_contact_adjust '%s' is not a number (a distance: initial gaps within it are treated as zero)", str);
    }
  }
  PetscCall(PetscOptionsBool("-mbc_contact_keep_penetration", "Dynamic: a step starts from max(gap, 0), so a penetration it finds may only not grow (the contact forces never do work on the bodies) instead of being closed within the step", "MBCContactSetFromOptions", c->keep_penetration, &c->keep_penetration, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_view", "Print the search results per couple", "MBCContactSetFromOptions", c->view, &c->view, NULL));
  PetscCall(PetscOptionsString("-mbc_contact_dump", "Write PREFIX_pairs.csv and PREFIX_points.csv", "MBCContactSetFromOptions", c->dump, c->dump, sizeof(c->dump), NULL));
  PetscOptionsEnd();
  PetscCheck(c->nquad >= 1 && c->nquad <= 16, c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_quadrature %" PetscInt_FMT " must lie in [1, 16]", c->nquad);
  /* below 1 a master node over a large slave face may find no partner (contactsearch.c): the
     contact points go silently (1e-9: 9 points -> 0); above 1e3 every node shares one cell */
  PetscCheck(c->cell_factor >= 1 && c->cell_factor <= 1e3, c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_cell_factor %g must lie in [1, 1000] (smaller cells miss contacts)", (double)c->cell_factor);
  PetscCheck(c->margin >= 0 && !PetscIsInfOrNanReal(c->margin), c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_margin %g must be finite and not negative", (double)c->margin);
  PetscCheck(c->adjust >= 0 && !PetscIsInfOrNanReal(c->adjust), c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_adjust %g must be finite and not negative (a distance; 0: off)", (double)c->adjust);
  PetscCheck(!PetscIsInfOrNanReal(c->interference_tol), c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_interference_tol %g must be finite", (double)c->interference_tol);
  PetscCheck(c->hysteresis >= 0 && c->hysteresis <= 0.5, c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_hysteresis %g must lie in [0, 0.5] (a fraction of an edge's length)", (double)c->hysteresis);
  PetscCheck(c->slide_limit > 0 && c->slide_limit < PETSC_MAX_REAL, c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_slide_limit %g must be positive and finite (a fraction of an edge's length)", (double)c->slide_limit);
  PetscCheck(c->extension >= 0 && c->extension <= 0.5, c->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_extension %g must lie in [0, 0.5]", (double)c->extension);
  PetscFunctionReturn(0);
}

/* Record of one face, packed in reals for one Allgatherv: couple index, side (0 master,
   1 slave), body, nv (3, 4, or 6: a tet10's tri6), then per node: x0[3], x[3], row (unused
   slots zero: the canonical order compares whole records). */
#define FACE_REC (4 + 7 * MBC_MAX_WEIGHT_NODES)

/* Faces of this rank's part of a body carrying a contact label, oriented outward. */
static PetscErrorCode BodyContactFaces(MBCContact c, MBCBody body, Vec u, PetscReal **buf, PetscInt *n, PetscInt *cap)
{
  DM                 dm, cdm;
  PetscSection       csec, gsec, lsec;
  Vec                coords, uloc = NULL;
  const PetscScalar *x, *ul = NULL;
  PetscSF            sf;
  PetscInt           nleaves, vStart, vEnd, cStart, cEnd;
  const PetscInt    *leaves;
  PetscBT            notmine;
  const char        *labels[2] = {"contact_master", "contact_slave"};
  PetscInt           bindex;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetDM(body, &dm));
  PetscCall(MBCBodyGetIndex(body, &bindex));
  PetscCall(DMGetCoordinateDM(dm, &cdm));
  PetscCall(DMGetLocalSection(cdm, &csec));
  PetscCall(DMGetGlobalSection(dm, &gsec));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(VecGetArrayRead(coords, &x));
  if (u) {
    PetscCall(DMGetLocalVector(dm, &uloc));
    PetscCall(DMGlobalToLocal(dm, u, INSERT_VALUES, uloc));
    PetscCall(VecGetArrayRead(uloc, &ul));
  }
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetHeightStratum(dm, 0, &cStart, &cEnd));
  { /* points this rank does not own are leaves of the point SF */
    PetscInt pStart, pEnd;
    PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
    PetscCall(PetscBTCreate(pEnd, &notmine));
    PetscCall(DMGetPointSF(dm, &sf));
    PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &leaves, NULL));
    for (PetscInt i = 0; i < nleaves && nleaves > 0; i++) PetscCall(PetscBTSet(notmine, leaves ? leaves[i] : i));
  }
  for (PetscInt side = 0; side < 2; side++) {
    DMLabel label;
    PetscCall(DMGetLabel(dm, labels[side], &label));
    if (!label) continue;
    for (PetscInt ci = 0; ci < c->ncouples; ci++) {
      IS              faceIS;
      const PetscInt *faces;
      PetscInt        nfaces;
      PetscCall(DMLabelGetStratumIS(label, c->couples[ci].k, &faceIS));
      if (!faceIS) continue;
      PetscCall(ISGetLocalSize(faceIS, &nfaces));
      PetscCall(ISGetIndices(faceIS, &faces));
      for (PetscInt fi = 0; fi < nfaces; fi++) {
        const PetscInt f = faces[fi];
        PetscInt       pts[6], nv, ncorner;
        PetscReal     *r, X[6][3];

        if (PetscBTLookup(notmine, f)) continue;
        /* its nodes wound outward (a rigid surface's: towards the couple's other side, from the prep) */
        PetscCall(MBCBodyFaceNodes(body, f, x, pts, X, &nv, &ncorner));
        if (*n == *cap) {
          *cap = 2 * (*cap) + 64;
          PetscCall(PetscRealloc((size_t)(*cap) * FACE_REC * sizeof(PetscReal), buf));
        }
        r = &(*buf)[(*n)++ * FACE_REC];
        PetscCall(PetscArrayzero(r, FACE_REC));
        r[0] = ci;
        r[1] = side;
        r[2] = bindex;
        r[3] = nv;
        for (PetscInt i = 0; i < nv; i++) {
          PetscInt off, loff;
          PetscCall(PetscSectionGetOffset(gsec, pts[i], &off));
          PetscCall(PetscSectionGetOffset(lsec, pts[i], &loff));
          for (PetscInt d = 0; d < 3; d++) {
            r[4 + 7 * i + d]     = X[i][d];
            r[4 + 7 * i + 3 + d] = X[i][d] + (ul ? PetscRealPart(ul[loff + d]) : 0);
          }
          r[4 + 7 * i + 6] = off < 0 ? -(off + 1) : off;
        }
      }
      PetscCall(ISRestoreIndices(faceIS, &faces));
      PetscCall(ISDestroy(&faceIS));
    }
  }
  PetscCall(PetscBTDestroy(&notmine));
  if (u) {
    PetscCall(VecRestoreArrayRead(uloc, &ul));
    PetscCall(DMRestoreLocalVector(dm, &uloc));
  }
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt         body;
  const PetscReal *x0;
  PetscInt         rec, slot;
} NodeRef;

static int CompareNodeRef(const void *a, const void *b)
{
  const NodeRef *p = (const NodeRef *)a, *q = (const NodeRef *)b;
  if (p->body != q->body) return p->body < q->body ? -1 : 1;
  for (int d = 0; d < 3; d++)
    if (p->x0[d] != q->x0[d]) return p->x0[d] < q->x0[d] ? -1 : 1;
  return 0;
}

/* The 4 sub-triangles of a tri6 (corners c0 c1 c2, midside nodes m01 m12 m20 at 3 4 5), wound as
   the tri6: its three corners' triangles, then the middle one. */
static const PetscInt Tri6Sub[4][3] = {
  {0, 3, 5},
  {3, 1, 4},
  {5, 4, 2},
  {3, 4, 5}
};

/* Builds one side of a couple from the gathered records: nodes in canonical order (body, then
   reference coordinates), faces in record order after sorting the records canonically, a tri6
   as its 4 sub-triangles (MBCSurface's fqnode). */
static PetscErrorCode SurfaceFromRecords(MBCSurface *s, const PetscReal *rec, PetscInt nrec, PetscInt ci, PetscInt side)
{
  NodeRef  *refs;
  PetscInt  nrefs = 0, nfaces = 0, *map, f = 0;
  PetscBool quad = PETSC_FALSE;

  PetscFunctionBegin;
  PetscCall(MBCSurfaceReset(s));
  for (PetscInt i = 0; i < nrec; i++)
    if ((PetscInt)rec[i * FACE_REC] == ci && (PetscInt)rec[i * FACE_REC + 1] == side) {
      const PetscInt nv = (PetscInt)rec[i * FACE_REC + 3];
      nfaces += nv == 6 ? 4 : 1;
      nrefs += nv;
      quad = (PetscBool)(quad || nv == 6);
    }
  PetscCall(PetscMalloc1(nrefs, &refs));
  nrefs = 0;
  for (PetscInt i = 0; i < nrec; i++) {
    const PetscReal *r = &rec[i * FACE_REC];
    if ((PetscInt)r[0] != ci || (PetscInt)r[1] != side) continue;
    for (PetscInt j = 0; j < (PetscInt)r[3]; j++) refs[nrefs++] = (NodeRef){(PetscInt)r[2], &r[4 + 7 * j], i, j};
  }
  qsort(refs, (size_t)nrefs, sizeof(NodeRef), CompareNodeRef);
  PetscCall(PetscMalloc1(nrec * MBC_MAX_WEIGHT_NODES, &map)); /* (record, slot) -> node */
  for (PetscInt i = 0; i < nrefs; i++) {
    if (i == 0 || CompareNodeRef(&refs[i - 1], &refs[i])) s->nnodes++;
  }
  PetscCall(PetscMalloc4(s->nnodes, &s->nbody, s->nnodes, &s->nrow, 3 * s->nnodes, &s->x0, 3 * s->nnodes, &s->x));
  for (PetscInt i = 0, v = -1; i < nrefs; i++) {
    if (i == 0 || CompareNodeRef(&refs[i - 1], &refs[i])) {
      const PetscReal *r = &rec[refs[i].rec * FACE_REC + 4 + 7 * refs[i].slot];
      v++;
      s->nbody[v] = refs[i].body;
      s->nrow[v]  = (PetscInt)r[6];
      for (PetscInt d = 0; d < 3; d++) {
        s->x0[3 * v + d] = r[d];
        s->x[3 * v + d]  = r[3 + d];
      }
    }
    map[refs[i].rec * MBC_MAX_WEIGHT_NODES + refs[i].slot] = v;
  }
  s->nfaces = nfaces;
  PetscCall(PetscMalloc3(nfaces, &s->fnv, MBC_MAX_FACE_NODES * nfaces, &s->fnode, nfaces, &s->fbody));
  if (quad) PetscCall(PetscMalloc2(6 * nfaces, &s->fqnode, 3 * nfaces, &s->fqslot));
  for (PetscInt i = 0; i < nrec; i++) {
    const PetscReal *r  = &rec[i * FACE_REC];
    const PetscInt  *mp = &map[i * MBC_MAX_WEIGHT_NODES], nv = (PetscInt)r[3];
    if ((PetscInt)r[0] != ci || (PetscInt)r[1] != side) continue;
    for (PetscInt t = 0; t < (nv == 6 ? 4 : 1); t++, f++) {
      s->fnv[f]   = nv == 6 ? 3 : nv;
      s->fbody[f] = (PetscInt)r[2];
      for (PetscInt j = 0; j < MBC_MAX_FACE_NODES; j++) s->fnode[MBC_MAX_FACE_NODES * f + j] = j >= s->fnv[f] ? -1 : nv == 6 ? mp[Tri6Sub[t][j]] : mp[j];
      if (!quad) continue;
      for (PetscInt j = 0; j < 6; j++) s->fqnode[6 * f + j] = nv == 6 ? mp[j] : -1;
      for (PetscInt j = 0; j < 3; j++) s->fqslot[3 * f + j] = nv == 6 ? Tri6Sub[t][j] : -1;
    }
  }
  PetscCall(PetscFree(map));
  PetscCall(PetscFree(refs));
  PetscCall(MBCSurfaceSetUp(s));
  PetscFunctionReturn(0);
}

typedef struct {
  const PetscReal *r;
  PetscReal        key[4]; /* body, then the smallest reference vertex (x, y, z) */
} FaceKey;

static int CompareFaceKey(const void *a, const void *b)
{
  const FaceKey *p = (const FaceKey *)a, *q = (const FaceKey *)b;
  for (int i = 0; i < 2; i++)
    if (p->r[i] != q->r[i]) return p->r[i] < q->r[i] ? -1 : 1;
  for (int i = 0; i < 4; i++)
    if (p->key[i] != q->key[i]) return p->key[i] < q->key[i] ? -1 : 1;
  for (int i = 4; i < FACE_REC; i++) /* faces sharing that vertex: by their whole record */
    if (p->r[i] != q->r[i]) return p->r[i] < q->r[i] ? -1 : 1;
  return 0;
}

/* Gathers every couple's faces from all bodies to every rank, in canonical order. */
static PetscErrorCode ContactGather(MBCContact c, PetscInt nbodies, MBCBody bodies[], PetscBool reference, PetscReal **all, PetscInt *nall)
{
  PetscReal  *mine = NULL, *sorted;
  PetscInt    nmine = 0, cap = 0;
  PetscMPIInt size, *counts, *displs, count;
  FaceKey    *keys;

  PetscFunctionBegin;
  /* the ranks meet here first: the time a rank waits for the slowest (its bodies' factorizations,
     D) is load imbalance, not the gather's (on 2 ranks at 200k DOFs it was 8.7 s of a 0.08 s gather) */
  PetscCall(PetscLogEventBegin(MBC_RankWait, 0, 0, 0, 0));
  PetscCallMPI(MPI_Barrier(c->comm));
  PetscCall(PetscLogEventEnd(MBC_RankWait, 0, 0, 0, 0));
  PetscCall(PetscLogEventBegin(MBC_ContactGather, 0, 0, 0, 0));
  for (PetscInt b = 0; b < nbodies; b++) {
    Vec u;
    if (!bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(bodies[b], &u));
    PetscCall(BodyContactFaces(c, bodies[b], reference ? NULL : u, &mine, &nmine, &cap));
  }
  PetscCallMPI(MPI_Comm_size(c->comm, &size));
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCall(PetscMPIIntCast(nmine * FACE_REC, &count));
  PetscCallMPI(MPI_Allgather(&count, 1, MPI_INT, counts, 1, MPI_INT, c->comm));
  displs[0] = 0;
  for (PetscMPIInt r = 0; r < size; r++) displs[r + 1] = displs[r] + counts[r];
  *nall = displs[size] / FACE_REC;
  PetscCall(PetscMalloc1(displs[size] + 1, all));
  PetscCallMPI(MPI_Allgatherv(mine, count, MPIU_REAL, *all, counts, displs, MPIU_REAL, c->comm));
  PetscCall(PetscFree(mine));
  PetscCall(PetscFree2(counts, displs));
  /* canonical face order: couple, side, body, smallest reference vertex, record */
  PetscCall(PetscMalloc1(*nall, &keys));
  for (PetscInt i = 0; i < *nall; i++) {
    const PetscReal *r = &(*all)[i * FACE_REC];
    keys[i].r          = r;
    keys[i].key[0]     = r[2];
    for (PetscInt d = 0; d < 3; d++) keys[i].key[1 + d] = r[4 + d];
    for (PetscInt j = 1; j < (PetscInt)r[3]; j++) {
      const PetscReal *v = &r[4 + 7 * j], *k = &keys[i].key[1];
      if (v[0] < k[0] || (v[0] == k[0] && (v[1] < k[1] || (v[1] == k[1] && v[2] < k[2]))))
        for (PetscInt d = 0; d < 3; d++) keys[i].key[1 + d] = v[d];
    }
  }
  qsort(keys, (size_t)*nall, sizeof(FaceKey), CompareFaceKey);
  PetscCall(PetscMalloc1(*nall * FACE_REC + 1, &sorted));
  for (PetscInt i = 0; i < *nall; i++) PetscCall(PetscArraycpy(&sorted[i * FACE_REC], keys[i].r, FACE_REC));
  PetscCall(PetscFree(keys));
  PetscCall(PetscFree(*all));
  *all = sorted;
  PetscCall(PetscLogEventEnd(MBC_ContactGather, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* -mbc_contact_check_search: the search's pairs and the integration's slave faces against brute force. */
static PetscErrorCode ContactCheck(MBCContact c, MBCCouple *cp)
{
  PetscInt  v, f, k;
  PetscReal gap, a, b;

  PetscFunctionBegin;
  PetscCall(MBCCoupleCheckSearch(cp, &v, &f, &gap));
  if (v >= 0) {
    const PetscReal *x = &cp->master.x[3 * v];
    PetscInt         at = -1;
    for (PetscInt j = 0; j < cp->npoints; j++)
      if (cp->points[j].master == v) at = cp->points[j].face;
    SETERRQ(c->comm, PETSC_ERR_PLIB, "-mbc_contact_check_search, couple k = %" PetscInt_FMT ": master node (%g, %g, %g) of body '%s' projects onto slave face %" PetscInt_FMT " of body '%s' (centre (%g, %g, %g), gap %g) by brute force, but the search paired it with %s%s", cp->k, (double)x[0], (double)x[1], (double)x[2], c->scene->bodies[cp->master.nbody[v]].name, f, c->scene->bodies[cp->slave.fbody[f]].name, (double)cp->slave.fcenter[3 * f], (double)cp->slave.fcenter[3 * f + 1], (double)cp->slave.fcenter[3 * f + 2], (double)gap, at < 0 ? "no face" : "a worse face", "");
  }
  if (!c->integrate) PetscFunctionReturn(0);
  PetscCall(MBCCoupleCheckIntegrate(cp, c->nquad, &k, &a, &b));
  if (k >= 0) {
    const PetscReal *x = &cp->master.x[3 * cp->points[k].master];
    SETERRQ(c->comm, PETSC_ERR_PLIB, "-mbc_contact_check_search, couple k = %" PetscInt_FMT ": the integrated constraint of master node (%g, %g, %g) of body '%s' covers %.12g of its share, %.12g with every slave face: the integration missed slave faces", cp->k, (double)x[0], (double)x[1], (double)x[2], c->scene->bodies[cp->master.nbody[cp->points[k].master]].name, (double)a, (double)b);
  }
  PetscFunctionReturn(0);
}

/* Bodies overlapping at the start: the first step pushes them apart with an impulse that is no
   physics (an overlap of 0.2 threw a block 0.5 m in 5 ms). Every rank holds the same points. */
static PetscErrorCode ContactCheckInitialPenetration(MBCContact c)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp  = &c->couples[i];
    PetscReal  tol = c->penetration_tol, worst = 0;
    PetscInt   jw  = -1;

    if (tol < 0) tol = -tol * cp->h / c->cell_factor; /* h: the cell factor times at least the mean face edge */
    for (PetscInt j = 0; j < cp->npoints; j++)
      if (cp->points[j].gap < worst) {
        worst = cp->points[j].gap;
        jw    = j;
      }
    if (jw >= 0 && -worst > tol) {
      const MBCContactPoint *p  = &cp->points[jw];
      const PetscInt         mb = cp->master.nbody[p->master], sb = cp->slave.nbody[cp->slave.fnode[MBC_MAX_FACE_NODES * p->face]];
      const PetscReal       *x  = &cp->master.x[3 * p->master];
      char                   msg[4 * MBC_NAME_LEN];
      PetscCall(PetscSNPrintf(msg, sizeof(msg), "Scene file %s: couple k = %" PetscInt_FMT ": body '%s' (master) penetrates body '%s' (slave) by %g at (%g, %g, %g) at the start, beyond the tolerance %g (-mbc_contact_penetration_tol)", c->scene->filename, cp->k, c->scene->bodies[mb].name, c->scene->bodies[sb].name, (double)-worst, (double)x[0], (double)x[1], (double)x[2], (double)tol));
      PetscCheck(c->accept_penetration, c->comm, PETSC_ERR_USER_INPUT, "%s; move the bodies apart, or accept it with -mbc_contact_accept_penetration", msg);
      PetscCall(PetscPrintf(c->comm, "mbcontact: warning: %s (accepted by -mbc_contact_accept_penetration)\n", msg));
    }
  }
  PetscFunctionReturn(0);
}

/* The reference-geometry pass, once per run before the first update (the solver's first update
   is on the undeformed state, a restart's too: a restart without the first run's adjustment is
   refused as the first run would have been): the couples searched and integrated on the
   reference coordinates; then
   * -mbc_contact_adjust d: every point whose node-to-face gap, mortar gap and interference
     (MBCCoupleInterference) are all within d keeps its two initial gaps in g0n / g0i, subtracted
     from its gaps for the whole run: the geometry as the contact sees it is moved to touch, free
     of strain (Abaqus' ADJUST, ANSYS' ICONT);
   * the interference check (not for -mbc_contact_search_only): points
     whose faceted surfaces interpenetrate by more than -mbc_contact_interference_tol and that the
     adjustment did not take stop the run. Two independently meshed faceted versions of one
     curved surface interpenetrate and gape by their facets' sagitta: the lame scene's 12 against
     16 cells per quarter (3.2e-3, 30 times the load's displacement) ran to exit 0 with u_r(1)
     +44 % (the concave side as slave: every mortar gap open while the nodes penetrate) or
     +5 % / -380 ... -660 % (docs/stability.md). */
static PetscErrorCode ContactReference(MBCContact c, PetscInt nbodies, MBCBody bodies[])
{
  PetscReal *rec = NULL;
  PetscInt   nrec = 0;

  PetscFunctionBegin;
  c->reference_done = PETSC_TRUE;
  if (!c->adjust && !c->check_penetration) PetscFunctionReturn(0);
  PetscCall(ContactGather(c, nbodies, bodies, PETSC_TRUE, &rec, &nrec));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp   = &c->couples[i];
    PetscReal *qmin, tol = c->interference_tol, worst = 0, need = 0;
    PetscInt   jw = -1, nbad = 0;
    PetscBool  deep = PETSC_FALSE;

    PetscCall(SurfaceFromRecords(&cp->master, rec, nrec, i, 0));
    PetscCall(SurfaceFromRecords(&cp->slave, rec, nrec, i, 1));
    if (!(cp->master.nfaces > 0 && cp->slave.nfaces > 0)) continue; /* MBCContactUpdate says so */
    cp->extension = c->extension;
    PetscCall(MBCCoupleGlobalSearch(cp, c->cell_factor, c->margin));
    PetscCall(MBCCoupleLocalSearch(cp));
    PetscCall(MBCCoupleIntegrate(cp, c->integrate, c->nquad));
    PetscCall(PetscMalloc1(cp->npoints + 1, &qmin));
    PetscCall(MBCCoupleInterference(cp, c->nquad, qmin));
    if (c->adjust > 0) {
      PetscCall(PetscFree2(cp->g0n, cp->g0i));
      PetscCall(PetscCalloc2(cp->master.nnodes, &cp->g0n, cp->master.nnodes, &cp->g0i));
    }
    if (tol < 0) tol = -tol * cp->h / c->cell_factor; /* h: the cell factor times at least the mean face edge */
    { /* a penetration beyond -mbc_contact_penetration_tol is bodies overlapping: that check's
         message (after the first update) speaks for the couple */
      PetscReal ptol = c->penetration_tol < 0 ? -c->penetration_tol * cp->h / c->cell_factor : c->penetration_tol;
      for (PetscInt k = 0; k < cp->npoints; k++)
        if (-cp->points[k].gap > ptol && !(c->adjust > 0 && -cp->points[k].gap <= c->adjust)) deep = PETSC_TRUE;
    }
    for (PetscInt k = 0; k < cp->npoints; k++) {
      const MBCContactPoint *p    = &cp->points[k];
      const PetscReal        size = PetscMax(PetscMax(PetscAbsReal(p->gap), PetscAbsReal(cp->igap[k])), -qmin[k]);
      if (c->adjust > 0 && size <= c->adjust) {
        cp->g0n[p->master] = p->gap;
        cp->g0i[p->master] = cp->igap[k];
        continue;
      }
      if (-qmin[k] > tol) {
        nbad++;
        need = PetscMax(need, size);
        if (qmin[k] < worst) {
          worst = qmin[k];
          jw    = k;
        }
      }
    }
    if (jw >= 0 && c->check_penetration && !deep) {
      const MBCContactPoint *p  = &cp->points[jw];
      const PetscInt         mb = cp->master.nbody[p->master], sb = cp->slave.nbody[cp->slave.fnode[MBC_MAX_FACE_NODES * p->face]];
      const PetscReal       *x  = &cp->master.x0[3 * p->master];
      char                   msg[8 * MBC_NAME_LEN];
      PetscCall(PetscSNPrintf(msg, sizeof(msg), "Scene file %s: couple k = %" PetscInt_FMT ": the contact surfaces of body '%s' (master) and body '%s' (slave) interpenetrate at the start at %" PetscInt_FMT " of its %" PetscInt_FMT " contact points, by up to %g around the master node at (%g, %g, %g) (its node-to-face gap %g, mortar gap %g), beyond the tolerance %g (-mbc_contact_interference_tol). Two faceted surfaces meshed independently on one curved surface interpenetrate and gape by their facets' sagitta, and the contact would carry that as geometry (an interference fit, or no contact at all): the answer would be wrong without a message", c->scene->filename, cp->k, c->scene->bodies[mb].name, c->scene->bodies[sb].name, nbad, cp->npoints, (double)-worst, (double)x[0], (double)x[1], (double)x[2], (double)p->gap, (double)cp->igap[jw], (double)tol));
      PetscCheck(c->accept_penetration, c->comm, PETSC_ERR_USER_INPUT, "%s; treat the initial gaps as zero, free of strain, with -mbc_contact_adjust %.2g (a distance: at least %.2g here), or, for an intended interference fit, accept it with -mbc_contact_accept_penetration", msg, (double)(2 * need), (double)need);
      PetscCall(PetscPrintf(c->comm, "mbcontact: warning: %s (accepted by -mbc_contact_accept_penetration)\n", msg));
    }
    PetscCall(PetscFree(qmin));
  }
  PetscCall(PetscFree(rec));
  PetscFunctionReturn(0);
}

/* Gathers the couples' surfaces at the current displacements; a global search runs when asked,
   the first time, or when a body moved more than half the margin since the last one; the local
   search runs every time. */
PetscErrorCode MBCContactUpdate(MBCContact c, PetscInt nbodies, MBCBody bodies[], PetscBool force, PetscBool *researched)
{
  PetscReal *rec = NULL, moved = 0;
  PetscInt   nrec = 0;
  PetscBool  global, keep = PETSC_FALSE; /* keep: the small-sliding couples' references hold */

  PetscFunctionBegin;
  if (!c->reference_done) PetscCall(ContactReference(c, nbodies, bodies));
  if (c->small_sliding && c->frozen && !force) { /* the small-sliding couples' gaps moved; the others searched below */
    PetscBool repair, finite = PETSC_FALSE, done = PETSC_FALSE;
    for (PetscInt i = 0; i < c->ncouples; i++) finite = (PetscBool)(finite || !c->couples[i].small_sliding);
    if (!finite) PetscCall(MBCContactSlidingGather(c, nbodies, bodies, &done));
    if (!done) {
      PetscCall(ContactGather(c, nbodies, bodies, PETSC_FALSE, &rec, &nrec));
      for (PetscInt i = 0; i < c->ncouples; i++) {
        if (!c->couples[i].small_sliding) continue;
        PetscCall(SurfaceFromRecords(&c->couples[i].master, rec, nrec, i, 0));
        PetscCall(SurfaceFromRecords(&c->couples[i].slave, rec, nrec, i, 1));
      }
    }
    PetscCall(MBCContactSlidingUpdate(c, &repair));
    if (!repair && !finite) {
      PetscCall(PetscFree(rec));
      if (researched) *researched = PETSC_FALSE;
      if (c->dump[0]) PetscCall(MBCContactDump(c));
      PetscFunctionReturn(0);
    }
    keep = (PetscBool)!repair;
  }
  if (!rec) PetscCall(ContactGather(c, nbodies, bodies, PETSC_FALSE, &rec, &nrec));
  /* a search of small-sliding couples is global (a restart's replay of the last global search
     restores their reference); a global search takes them along (so the last one is their reference) */
  global = (PetscBool)(force || c->nsearches == 0 || (c->small_sliding && !keep));
  for (PetscInt b = 0; b < nbodies && !global; b++) { /* largest displacement since the last search */
    PetscReal d = 0;
    Vec       u = NULL, du;
    PetscCall(MBCBodyGetDisplacement(bodies[b], &u));
    if (!u || !c->usearch[b]) continue;
    PetscCall(VecDuplicate(u, &du));
    PetscCall(VecWAXPY(du, -1.0, c->usearch[b], u));
    PetscCall(VecNorm(du, NORM_INFINITY, &d));
    PetscCall(VecDestroy(&du));
    moved = PetscMax(moved, PetscSqrtReal(3.0) * d);
  }
  if (!global) {
    PetscReal margin = PETSC_MAX_REAL;
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPIU_REAL, MPI_MAX, c->comm));
    for (PetscInt i = 0; i < c->ncouples; i++) margin = PetscMin(margin, c->couples[i].margin);
    global = (PetscBool)(moved > 0.5 * margin);
    if (global) keep = PETSC_FALSE;
  }
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    if (keep && cp->small_sliding) continue;
    PetscCall(SurfaceFromRecords(&cp->master, rec, nrec, i, 0));
    PetscCall(SurfaceFromRecords(&cp->slave, rec, nrec, i, 1));
    PetscCheck(cp->master.nfaces > 0 && cp->slave.nfaces > 0, c->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: couple k = %" PetscInt_FMT " has no %s faces (surfaces %s); every couple needs master (+k) and slave (-k) faces", c->scene->filename, cp->k, cp->master.nfaces ? "slave" : "master", cp->master.nfaces ? c->scene->couples[i].slave : c->scene->couples[i].master);
    cp->extension = c->extension;
    cp->hysteresis = c->hysteresis;
    if (global) PetscCall(MBCCoupleGlobalSearch(cp, c->cell_factor, c->margin));
    PetscCall(MBCCoupleLocalSearch(cp));
    PetscCall(MBCCoupleIntegrate(cp, c->integrate, c->nquad));
    if (cp->g0n)
      for (PetscInt k = 0; k < cp->npoints; k++) { /* -mbc_contact_adjust: the initial gaps subtracted */
        cp->points[k].gap -= cp->g0n[cp->points[k].master];
        cp->igap[k] -= cp->g0i[cp->points[k].master];
      }
    if (c->check) PetscCall(ContactCheck(c, cp));
  }
  PetscCall(PetscFree(rec));
  if (c->nsearches == 0 && c->check_penetration) PetscCall(ContactCheckInitialPenetration(c));
  if (global) {
    c->nsearches++;
    for (PetscInt b = 0; b < nbodies; b++) {
      Vec u = NULL;
      PetscCall(MBCBodyGetDisplacement(bodies[b], &u));
      if (!u) continue;
      if (!c->usearch[b]) PetscCall(VecDuplicate(u, &c->usearch[b]));
      PetscCall(VecCopy(u, c->usearch[b]));
    }
  }
  if (c->small_sliding && !keep) PetscCall(MBCContactSlidingFreeze(c));
  if (researched) *researched = global;
  if (c->dump[0]) PetscCall(MBCContactDump(c));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCContactView(MBCContact c, PetscViewer viewer)
{
  PetscFunctionBegin;
  PetscCall(PetscViewerASCIIPrintf(viewer, "Contact search (%" PetscInt_FMT " global searches so far)\n", c->nsearches));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    PetscReal  gmin = PETSC_MAX_REAL, gmax = PETSC_MIN_REAL;
    for (PetscInt j = 0; j < cp->npoints; j++) {
      gmin = PetscMin(gmin, cp->points[j].gap);
      gmax = PetscMax(gmax, cp->points[j].gap);
    }
    PetscCall(PetscViewerASCIIPrintf(viewer, "  couple %" PetscInt_FMT ": %" PetscInt_FMT " master nodes, %" PetscInt_FMT " slave nodes, master/slave faces %" PetscInt_FMT "/%" PetscInt_FMT ", cell %g, margin %g\n", cp->k, cp->master.nnodes, cp->slave.nnodes, cp->master.nfaces, cp->slave.nfaces, (double)cp->h, (double)cp->margin));
    PetscCall(PetscViewerASCIIPrintf(viewer, "    test pairs %" PetscInt_FMT " (point-face tests %" PetscInt_FMT "), contact points %" PetscInt_FMT ", gap range [%g, %g]\n", cp->npairs, cp->ntests, cp->npoints, cp->npoints ? (double)gmin : 0.0, cp->npoints ? (double)gmax : 0.0));
  }
  PetscFunctionReturn(0);
}

/* The slave faces the local search prefers (-mbc_contact_hysteresis): per couple and master node
   the face of pairs (n points of `size` entries: couple, master node, slave face, ...; the pairs
   H and D were built for), -1 for the others. A master node whose projection sits on an edge
   between two faces keeps its face while that face still takes the projection within the
   hysteresis (MBCCoupleKeepsFace), so a pairing does not flip with motions far below the mesh
   size. The preference is a function of the pairs built alone: a
   restart that builds the same pairs searches with the same preference. */
PetscErrorCode MBCContactSetPreferredFaces(MBCContact c, PetscInt n, const PetscInt pairs[], PetscInt size)
{
  PetscFunctionBegin;
  PetscCall(MBCContactSlidingReset(c)); /* small sliding: the reference is the search that finds these pairs again */
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    if (cp->nprefer < cp->master.nnodes) {
      PetscCall(PetscFree(cp->prefer));
      PetscCall(PetscMalloc1(cp->master.nnodes + 1, &cp->prefer));
      cp->nprefer = cp->master.nnodes;
    }
    for (PetscInt v = 0; v < cp->nprefer; v++) cp->prefer[v] = -1;
  }
  for (PetscInt k = 0; k < n; k++) {
    const PetscInt *p = &pairs[size * k];
    if (p[0] >= 0 && p[0] < c->ncouples && p[1] >= 0 && p[1] < c->couples[p[0]].nprefer) c->couples[p[0]].prefer[p[1]] = p[2];
  }
  PetscFunctionReturn(0);
}

/* Rank 0 writes the pairs and points of every couple (every rank holds the same results). */
PetscErrorCode MBCContactDump(MBCContact c)
{
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN + 16];
  FILE       *fp, *fq;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(c->comm, &rank));
  if (rank) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_pairs.csv", c->dump));
  PetscCall(MBCFileOpenWrite(file, &fp));
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_points.csv", c->dump));
  PetscCall(MBCFileOpenWrite(file, &fq));
  fprintf(fp, "k,master_body,mx,my,mz,slave_body,sx,sy,sz,distance\n");
  fprintf(fq, "k,master_body,mx,my,mz,slave_body,nv,v0x,v0y,v0z,v1x,v1y,v1z,v2x,v2y,v2z,v3x,v3y,v3z,w0,w1,w2,w3,px,py,pz,nx,ny,nz,t1x,t1y,t1z,t2x,t2y,t2z,gap\n");
  for (PetscInt i = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    MBCSurface *m = &cp->master, *s = &cp->slave;
    for (PetscInt j = 0; j < cp->npairs; j++) {
      const PetscInt a = cp->pairs[j].master, b = cp->pairs[j].cand[0];
      fprintf(fp, "%d,%d,%.17g,%.17g,%.17g,%d,%.17g,%.17g,%.17g,%.17g\n", (int)cp->k, (int)m->nbody[a], (double)m->x[3 * a], (double)m->x[3 * a + 1], (double)m->x[3 * a + 2], (int)s->nbody[b], (double)s->x[3 * b], (double)s->x[3 * b + 1], (double)s->x[3 * b + 2], (double)cp->pairs[j].distance);
    }
    for (PetscInt j = 0; j < cp->npoints; j++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscInt         a = p->master, *fv = &s->fnode[MBC_MAX_FACE_NODES * p->face];
      fprintf(fq, "%d,%d,%.17g,%.17g,%.17g,%d,%d", (int)cp->k, (int)m->nbody[a], (double)m->x[3 * a], (double)m->x[3 * a + 1], (double)m->x[3 * a + 2], (int)s->fbody[p->face], (int)p->nv);
      for (PetscInt v = 0; v < MBC_MAX_FACE_NODES; v++)
        for (PetscInt d = 0; d < 3; d++) fprintf(fq, ",%.17g", v < p->nv ? (double)s->x[3 * fv[v] + d] : 0.0);
      for (PetscInt v = 0; v < MBC_MAX_FACE_NODES; v++) fprintf(fq, ",%.17g", (double)p->w[v]);
      for (PetscInt d = 0; d < 3; d++) fprintf(fq, ",%.17g", (double)p->p[d]);
      for (PetscInt d = 0; d < 3; d++) fprintf(fq, ",%.17g", (double)p->n[d]);
      for (PetscInt d = 0; d < 3; d++) fprintf(fq, ",%.17g", (double)p->t1[d]);
      for (PetscInt d = 0; d < 3; d++) fprintf(fq, ",%.17g", (double)p->t2[d]);
      fprintf(fq, ",%.17g\n", (double)p->gap);
    }
  }
  fclose(fp);
  fclose(fq);
  PetscFunctionReturn(0);
}

PetscErrorCode MBCContactDestroy(MBCContact *contact)
{
  MBCContact c = *contact;

  PetscFunctionBegin;
  if (!c) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < c->ncouples; i++) {
    PetscCall(MBCSurfaceReset(&c->couples[i].master));
    PetscCall(MBCSurfaceReset(&c->couples[i].slave));
    PetscCall(PetscFree(c->couples[i].pairs));
    PetscCall(PetscFree(c->couples[i].points));
    PetscCall(PetscFree(c->couples[i].prefer));
    PetscCall(MBCCoupleIntegrateReset(&c->couples[i]));
    PetscCall(PetscFree2(c->couples[i].g0n, c->couples[i].g0i));
    PetscCall(PetscFree(c->couples[i].exclude));
    PetscCall(MBCCoupleSlidingDestroy(&c->couples[i]));
  }
  for (PetscInt b = 0; b < c->scene->nbodies; b++) PetscCall(VecDestroy(&c->usearch[b]));
  PetscCall(PetscFree(c->usearch));
  PetscCall(PetscFree(c->couples));
  PetscCall(PetscFree(*contact));
  PetscFunctionReturn(0);
}

static int ComparePair(const void *a, const void *b)
{
  const PetscInt *p = (const PetscInt *)a, *q = (const PetscInt *)b;
  return p[0] != q[0] ? (p[0] < q[0] ? -1 : 1) : (p[1] != q[1] ? (p[1] < q[1] ? -1 : 1) : 0);
}

/* Couple i's master nodes taken out of contact: n of them, (body, first global row) each. */
PetscErrorCode MBCContactSetExcluded(MBCContact c, PetscInt i, PetscInt n, const PetscInt pairs[])
{
  MBCCouple *cp = &c->couples[i];

  PetscFunctionBegin;
  PetscCall(PetscFree(cp->exclude));
  PetscCall(PetscMalloc1(2 * n + 1, &cp->exclude));
  PetscCall(PetscArraycpy(cp->exclude, pairs, 2 * n));
  qsort(cp->exclude, (size_t)n, 2 * sizeof(PetscInt), ComparePair);
  cp->nexclude = n;
  PetscFunctionReturn(0);
}
