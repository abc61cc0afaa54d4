/* Private: contact-face couples and their search (docs/contact-search.md). */
#pragma once

#include <mbc/private/bodyimpl.h>

#define MBC_MAX_FACE_NODES 4
#define MBC_SEARCH_CANDIDATES 8 /* slave nodes tried per master node, nearest first */
/* two faces sharing a node belong to one smooth surface there when their normals are less than
   acos(0.75) = 41.4 degrees apart (a faceted cylinder of 3 or more cells per quarter); a larger kink
   (a block's edge, 2 cells per quarter) is a feature edge and keeps each face's own normal */
#define MBC_FEATURE_COS 0.75

/* One side of a couple: nodes and faces gathered from all bodies and ranks, in canonical
   order (body, then reference coordinates), so results do not depend on the rank count. */
typedef struct {
  PetscInt   nnodes, nfaces;
  PetscInt  *nbody;         /* per node: body index */
  PetscInt  *nrow;          /* per node: first global row of its DOFs in the body's Vec */
  PetscReal *x0, *x;        /* per node: reference and current coordinates (3 each) */
  PetscReal *nnormal;       /* per node: averaged unit normal */
  PetscInt  *fnv, *fnode;   /* per face: vertex count and node indices (MBC_MAX_FACE_NODES each), counter-clockwise seen from outside */
  PetscInt  *fbody;
  PetscReal *fnormal;       /* per face: unit outward normal (Newell: area-weighted, warped quads too) */
  PetscReal *fcenter;
  PetscReal *fcnormal;      /* per face corner (MBC_MAX_FACE_NODES x 3 per face): unit mean of the normals of the faces around the
                               corner's node within the feature angle of this face (MBC_FEATURE_COS): the smoothed surface's normal there */
  PetscInt  *n2foff, *n2f;  /* node -> faces (CSR) */
  PetscBool *ffree;         /* per face edge i (vertex i to i+1): on the surface's free boundary (no other face shares it) */
  /* a tet10 body's 6-node faces enter as their 4 flat sub-triangles (corner ones, then the middle
     one; docs/design.md): per face, the tri6's nodes (corners, then the midside nodes of
     (c0 c1) (c1 c2) (c2 c0); -1 for a linear face) and its 3 vertices' places among them. NULL
     without tri6 faces. The geometry (search, projection, mortar pieces) is the sub-triangles';
     the weights that couple the bodies are the tri6's quadratic shape functions there
     (MBCSurfaceFaceWeights), so a uniform pressure gives the quadratic face's consistent loads. */
  PetscInt *fqnode, *fqslot;
} MBCSurface;

#define MBC_MAX_WEIGHT_NODES 6 /* nodes a face's weights reach: a tri6's */

/* The nodes and weights of face f of s that reproduce the point with weights w on its vertices:
   w itself on a linear face, the tri6's quadratic shape functions at that point on a
   sub-triangle. Returns their count. */
static inline PetscInt MBCSurfaceFaceWeights(const MBCSurface *s, PetscInt f, const PetscReal w[], PetscInt node[], PetscReal W[])
{
  static const PetscReal B[6][3] = {
    {1,   0,   0  },
    {0,   1,   0  },
    {0,   0,   1  },
    {0.5, 0.5, 0  },
    {0,   0.5, 0.5},
    {0.5, 0,   0.5}
  };
  PetscReal L[3] = {0, 0, 0};

  if (!s->fqnode || s->fqnode[6 * f] < 0) {
    for (PetscInt i = 0; i < s->fnv[f]; i++) node[i] = s->fnode[MBC_MAX_FACE_NODES * f + i], W[i] = w[i];
    return s->fnv[f];
  }
  for (PetscInt i = 0; i < 3; i++)
    for (PetscInt d = 0; d < 3; d++) L[d] += w[i] * B[s->fqslot[3 * f + i]][d];
  for (PetscInt i = 0; i < 3; i++) W[i] = L[i] * (2 * L[i] - 1), W[3 + i] = 4 * L[i] * L[(i + 1) % 3];
  for (PetscInt i = 0; i < 6; i++) node[i] = s->fqnode[6 * f + i];
  return 6;
}

typedef struct {
  PetscInt  master;                          /* master node */
  PetscInt  ncand, cand[MBC_SEARCH_CANDIDATES]; /* slave nodes within h, nearest first (cand[0]: partner) */
  PetscReal distance;                        /* to the partner */
} MBCTestPair;

typedef struct {
  PetscInt  master, face, nv;
  PetscReal w[MBC_MAX_FACE_NODES], p[3], n[3], t1[3], t2[3], gap;
  PetscReal area;   /* the master node's share of the contact surface on the reference (undeformed) geometry (integrated: the part that projects onto slave faces); pressure and traction are per this area */
} MBCContactPoint;

typedef struct {
  PetscInt   k;
  PetscReal  mu;
  MBCSurface master, slave;
  PetscReal  h, margin, lo[3];
  PetscReal  extension;     /* slave faces reach this fraction of their edge beyond the slave surface's free boundary */
  PetscReal  hysteresis;    /* -mbc_contact_hysteresis: a master node keeps its face prefer[] while its projection lies on that
                               face or within this fraction of an edge beyond it (0: the best face always) */
  PetscInt   nprefer, *prefer; /* per master node: the slave face of the pairs D was built for, or -1 */
  PetscInt   npairs, ntests;
  MBCTestPair *pairs;
  PetscInt   npoints;
  MBCContactPoint *points;
  /* the constraint of each point (MBCCoupleIntegrate): its gap is sum_j mw_j x_j - sum_j sw_j x_j
     along n over master nodes mnode[moff[k]..] and slave nodes snode[soff[k]..]; igap its value */
  PetscInt  *moff, *mnode, *soff, *snode;
  PetscReal *mw, *sw, *igap;
  /* -mbc_contact_adjust: per master node, its point's initial node-to-face and mortar gaps on the
     reference geometry (0 beyond the distance, or without a point), subtracted from its gaps for
     the whole run (a strain-free adjustment of the initial geometry); NULL without the option */
  PetscReal *g0n, *g0i;
  PetscInt   nexclude, *exclude; /* master nodes taken out of contact (the scene's `exclude`): (body, first global row), sorted */
  PetscBool  small_sliding; /* the scene's `sliding: small` (or -mbc_contact_sliding small for every couple) */
  /* small sliding (contactsliding.c): the nodes' coordinates and the points' gaps at
     the search the pairs were fixed at, and per point the slide beyond which it is reported */
  PetscReal *xref_m, *xref_s, *gref, *igref, *slide_max;
  PetscInt   nref_m, nref_s, nref_p;
} MBCCouple;

/* Is master node v of c taken out of contact? */
static inline PetscBool MBCCoupleExcludes(const MBCCouple *c, PetscInt v)
{
  const PetscInt b = c->master.nbody[v], r = c->master.nrow[v];
  PetscInt       lo = 0, hi = c->nexclude;
  while (lo < hi) {
    const PetscInt mid = (lo + hi) / 2, mb = c->exclude[2 * mid], mr = c->exclude[2 * mid + 1];
    if (mb == b && mr == r) return PETSC_TRUE;
    if (mb < b || (mb == b && mr < r)) lo = mid + 1;
    else hi = mid;
  }
  return PETSC_FALSE;
}

typedef struct _n_MBCContact *MBCContact;
struct _n_MBCContact {
  MPI_Comm   comm;
  MBCScene   scene;         /* borrowed */
  PetscInt   ncouples;
  MBCCouple *couples;
  PetscReal  cell_factor, margin;   /* margin <= 0: one cell edge */
  PetscReal  extension;     /* -mbc_contact_extension */
  PetscReal  hysteresis;    /* -mbc_contact_hysteresis */
  PetscBool  check;         /* -mbc_contact_check_search: brute-force cross-check of every search */
  PetscBool  integrate;     /* constraints averaged over each master node's share of the surface (else at the node) */
  PetscInt   nquad;         /* Gauss points per direction on a master face */
  PetscBool  view;
  char       dump[PETSC_MAX_PATH_LEN];
  PetscInt   nsearches;     /* global searches so far */
  PetscReal  penetration_tol;     /* initial penetration refused beyond this (< 0: this times -1 the mean face edge) */
  PetscBool  accept_penetration;  /* warn instead */
  PetscBool  check_penetration;   /* off for -mbc_contact_search_only: a report, no steps */
  PetscReal  interference_tol;    /* initial interference of the faceted surfaces refused beyond this (< 0: this times -1 the mean face edge) */
  PetscReal  adjust;              /* -mbc_contact_adjust: initial gaps within this distance treated as zero (strain-free); 0: off */
  PetscBool  reference_done;      /* the reference-geometry pass (interference check, adjustment) is done */
  PetscBool  keep_penetration; /* -mbc_contact_keep_penetration: a dynamic step starts from max(gap, 0) */
  Vec       *usearch;       /* per body: displacement at the last global search (NULL off the body) */
  PetscBool  small_sliding; /* some couple slides small: pairs, weights and frames fixed at a search, gaps linear in the motion since */
  PetscReal  slide_limit;   /* -mbc_contact_slide_limit: a point sliding more than this fraction of its slave face's shortest edge is reported */
  PetscBool  slide_repair;  /* -mbc_contact_slide_repair: and searched again instead */
  PetscBool  frozen;        /* small sliding: the references hold (else the next update searches those couples) */
};

PETSC_EXTERN PetscLogEvent MBC_RankWait, MBC_ContactGather, MBC_GlobalSearch, MBC_LocalSearch, MBC_ContactIntegrate;

PETSC_INTERN PetscErrorCode MBCContactCreate(MPI_Comm, MBCScene, MBCContact *);
PETSC_INTERN PetscErrorCode MBCContactSetFromOptions(MBCContact, const char[]);
PETSC_INTERN PetscErrorCode MBCContactUpdate(MBCContact, PetscInt, MBCBody[], PetscBool, PetscBool *);
PETSC_INTERN PetscErrorCode MBCContactView(MBCContact, PetscViewer);
PETSC_INTERN PetscErrorCode MBCContactDump(MBCContact);
PETSC_INTERN PetscErrorCode MBCContactDestroy(MBCContact *);
PETSC_INTERN PetscErrorCode MBCContactSetPreferredFaces(MBCContact, PetscInt, const PetscInt[], PetscInt);
PETSC_INTERN PetscErrorCode MBCContactSetExcluded(MBCContact, PetscInt, PetscInt, const PetscInt[]);
PETSC_INTERN PetscErrorCode MBCContactSlidingFreeze(MBCContact);
PETSC_INTERN PetscErrorCode MBCContactSlidingUpdate(MBCContact, PetscBool *);
PETSC_INTERN PetscErrorCode MBCContactSlidingGather(MBCContact, PetscInt, MBCBody[], PetscBool *);
PETSC_INTERN PetscErrorCode MBCContactSlidingReset(MBCContact);
PETSC_INTERN PetscErrorCode MBCCoupleSlidingDestroy(MBCCouple *);

/* the search on gathered surfaces (no MPI): contactsearch.c */
PETSC_EXTERN PetscErrorCode MBCSurfaceSetUp(MBCSurface *);
PETSC_EXTERN PetscErrorCode MBCSurfaceReset(MBCSurface *);
PETSC_EXTERN PetscErrorCode MBCCoupleGlobalSearch(MBCCouple *, PetscReal, PetscReal);
PETSC_EXTERN PetscErrorCode MBCCoupleLocalSearch(MBCCouple *);
PETSC_EXTERN PetscErrorCode MBCCoupleIntegrate(MBCCouple *, PetscBool, PetscInt);
PETSC_EXTERN PetscErrorCode MBCCoupleIntegrateReset(MBCCouple *);
PETSC_EXTERN PetscErrorCode MBCCoupleInterference(MBCCouple *, PetscInt, PetscReal[]);
PETSC_EXTERN PetscErrorCode MBCCoupleCheckSearch(MBCCouple *, PetscInt *, PetscInt *, PetscReal *);
PETSC_EXTERN PetscErrorCode MBCCoupleCheckIntegrate(MBCCouple *, PetscInt, PetscInt *, PetscReal *, PetscReal *);
PETSC_INTERN PetscBool      MBCCoupleKeepsFace(MBCCouple *, const PetscReal[], const PetscReal[], PetscInt, PetscInt, MBCContactPoint *);
PETSC_INTERN PetscBool      MBCCoupleProjectOnFace(MBCCouple *, const PetscReal[], const PetscReal[], PetscInt, PetscBool, MBCContactPoint *, PetscReal *);

/* A face in its own plane: centre and Newell normal n, in-plane basis e1, e2 (e1 along the first
   edge, e1 x e2 = n), the vertices' plane coordinates Y and, for a quad, its bilinear map
   Y(u, v) = B0 + B1 u + B2 v + B3 u v. Computed once per face where many points meet it (the mortar
   integration's quadrature points) instead of at every projection. */
typedef struct {
  PetscReal c[3], n[3], e1[3], e2[3];
  PetscReal Y[MBC_MAX_FACE_NODES][2], B[4][2];
} MBCFacePlane;

PETSC_INTERN void      MBCSurfaceFacePlane(const MBCSurface *, PetscInt, MBCFacePlane *);
PETSC_EXTERN PetscBool MBCBilinearInverse(const PetscReal[][2], const PetscReal[], PetscReal *, PetscReal *); /* of MBCFacePlane's B */
PETSC_INTERN PetscBool MBCCoupleProjectOnFacePlane(MBCCouple *, const PetscReal[], const PetscReal[], PetscInt, const MBCFacePlane *, PetscBool, MBCContactPoint *, PetscReal *);

static inline void MBCSub(const PetscReal a[], const PetscReal b[], PetscReal c[])
{
  c[0] = a[0] - b[0];
  c[1] = a[1] - b[1];
  c[2] = a[2] - b[2];
}
static inline void MBCCross(const PetscReal a[], const PetscReal b[], PetscReal c[])
{
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}
static inline PetscReal MBCDot(const PetscReal a[], const PetscReal b[])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline PetscReal MBCNormalize(PetscReal a[])
{
  PetscReal n = PetscSqrtReal(MBCDot(a, a));
  if (n > 0) a[0] /= n, a[1] /= n, a[2] /= n;
  return n;
}
/* x's coordinates y in the plane of P (MBCFacePlane): along e1, e2 from its centre */
static inline void MBCFacePlaneCoords(const MBCFacePlane *P, const PetscReal x[], PetscReal y[])
{
  PetscReal e[3];
  MBCSub(x, P->c, e);
  y[0] = MBCDot(e, P->e1);
  y[1] = MBCDot(e, P->e2);
}
/* signed area of triangle (a, b, c) seen along the unit normal n */
static inline PetscReal MBCArea(const PetscReal a[], const PetscReal b[], const PetscReal c[], const PetscReal n[])
{
  PetscReal u[3], v[3], w[3];
  MBCSub(b, a, u);
  MBCSub(c, a, v);
  MBCCross(u, v, w);
  return 0.5 * MBCDot(w, n);
}

