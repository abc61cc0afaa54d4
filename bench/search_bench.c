/* Contact search time against the number of surface nodes.
   Two non-matching wavy quad surfaces z = A sin(2 pi x) sin(2 pi y) on [0,1]^2, the master one
   a gap g above the slave one, with jittered nodes; times the global (cell grid) and local
   (projection) search of mbcontact and writes the node sets as NumPy .npy files
   (PREFIX_master_N.npy, PREFIX_slave_N.npy: float64, shape (nodes, 3)) for the KD-tree and
   brute-force timings of bench/search_python.py.
     bench_search [-sizes 1000,10000,...] [-prefix DIR/search] */
#include <mbc/private/contactimpl.h>
#include <petsctime.h>

static PetscReal Jitter(PetscInt i, PetscInt j, PetscInt s)
{
  unsigned long long h = (unsigned long long)(i * 73856093LL) ^ (unsigned long long)(j * 19349663LL) ^ (unsigned long long)(s * 83492791LL);
  h = (h ^ (h >> 33)) * 0xff51afd7ed558ccdULL;
  h = (h ^ (h >> 33)) * 0xc4ceb9fe1a85ec53ULL;
  return (PetscReal)((h ^ (h >> 33)) % 1000000ULL) / 1e6 - 0.5;
}

/* n x n quads; outward normal +z (slave, below) or -z (master, above). */
static PetscErrorCode WavySurface(MBCSurface *s, PetscInt n, PetscReal z0, PetscBool up, PetscInt body)
{
  const PetscReal h = 1.0 / n, A = 0.01;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(s, sizeof(*s)));
  s->nnodes = (n + 1) * (n + 1);
  s->nfaces = n * n;
  PetscCall(PetscMalloc4(s->nnodes, &s->nbody, s->nnodes, &s->nrow, 3 * s->nnodes, &s->x0, 3 * s->nnodes, &s->x));
  PetscCall(PetscMalloc3(s->nfaces, &s->fnv, MBC_MAX_FACE_NODES * s->nfaces, &s->fnode, s->nfaces, &s->fbody));
  for (PetscInt j = 0; j <= n; j++)
    for (PetscInt i = 0; i <= n; i++) {
      const PetscInt v = j * (n + 1) + i;
      PetscReal      x = i * h, y = j * h;
      if (i > 0 && i < n) x += 0.3 * h * Jitter(i, j, body);
      if (j > 0 && j < n) y += 0.3 * h * Jitter(j, i, body + 7);
      s->x[3 * v]     = x;
      s->x[3 * v + 1] = y;
      s->x[3 * v + 2] = z0 + A * PetscSinReal(2 * PETSC_PI * x) * PetscSinReal(2 * PETSC_PI * y);
      s->nbody[v]     = body;
      s->nrow[v]      = 3 * v;
    }
  PetscCall(PetscArraycpy(s->x0, s->x, 3 * s->nnodes));
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < n; i++) {
      const PetscInt f = j * n + i, v0 = j * (n + 1) + i, q[4] = {v0, v0 + 1, v0 + n + 2, v0 + n + 1};
      s->fnv[f]   = 4;
      s->fbody[f] = body;
      for (PetscInt k = 0; k < 4; k++) s->fnode[4 * f + k] = up ? q[k] : q[3 - k];
    }
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteNpy(const char *file, const MBCSurface *s)
{
  FILE *fp = fopen(file, "wb");
  char  header[128];
  int   len;

  PetscFunctionBegin;
  PetscCheck(fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot write %s", file);
  len = snprintf(header, sizeof(header), "{'descr': '<f8', 'fortran_order': False, 'shape': (%d, 3), }", (int)s->nnodes);
  while ((10 + len + 1) % 64) header[len++] = ' ';
  header[len++] = '\n';
  fwrite("\x93NUMPY\x01\x00", 1, 8, fp);
  fputc(len & 0xff, fp);
  fputc(len >> 8, fp);
  fwrite(header, 1, (size_t)len, fp);
  fwrite(s->x, sizeof(double), 3 * (size_t)s->nnodes, fp);
  fclose(fp);
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscInt  sizes[16] = {1000, 10000, 100000, 1000000, 4000000}, nsizes = 5;
  char      prefix[PETSC_MAX_PATH_LEN] = "";
  PetscBool set;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(MBCInitializePackage());
  PetscCall(PetscOptionsGetIntArray(NULL, NULL, "-sizes", sizes, (nsizes = 16, &nsizes), &set));
  if (!set) nsizes = 5;
  PetscCall(PetscOptionsGetString(NULL, NULL, "-prefix", prefix, sizeof(prefix), NULL));
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "%10s %10s %10s %12s %12s %12s %14s %10s\n", "nodes", "master", "slave", "global [s]", "local [s]", "total [s]", "nodes/s", "points"));
  for (PetscInt i = 0; i < nsizes; i++) {
    /* master and slave grids of about equal size, non-matching (ratio 1.1) */
    const PetscInt ns = PetscMax(2, (PetscInt)PetscSqrtReal(sizes[i] / 2.21)), nm = (PetscInt)(1.1 * ns);
    MBCCouple      c;
    PetscLogDouble t0, t1, t2;
    PetscInt       nodes;

    PetscCall(PetscMemzero(&c, sizeof(c)));
    PetscCall(WavySurface(&c.slave, ns, 0.0, PETSC_TRUE, 0));
    PetscCall(WavySurface(&c.master, nm, 1e-4, PETSC_FALSE, 1));
    PetscCall(MBCSurfaceSetUp(&c.slave));
    PetscCall(MBCSurfaceSetUp(&c.master));
    nodes = c.master.nnodes + c.slave.nnodes;
    PetscCall(PetscTime(&t0));
    PetscCall(MBCCoupleGlobalSearch(&c, 1.0, 0.0));
    PetscCall(PetscTime(&t1));
    PetscCall(MBCCoupleLocalSearch(&c));
    PetscCall(PetscTime(&t2));
    PetscCall(PetscPrintf(PETSC_COMM_SELF, "%10" PetscInt_FMT " %10" PetscInt_FMT " %10" PetscInt_FMT " %12.4f %12.4f %12.4f %14.3e %10" PetscInt_FMT "\n", nodes, c.master.nnodes, c.slave.nnodes, t1 - t0, t2 - t1, t2 - t0, nodes / (t2 - t0), c.npoints));
    if (prefix[0]) {
      char file[PETSC_MAX_PATH_LEN + 64];
      PetscCall(PetscSNPrintf(file, sizeof(file), "%s_master_%" PetscInt_FMT ".npy", prefix, nodes));
      PetscCall(WriteNpy(file, &c.master));
      PetscCall(PetscSNPrintf(file, sizeof(file), "%s_slave_%" PetscInt_FMT ".npy", prefix, nodes));
      PetscCall(WriteNpy(file, &c.slave));
    }
    PetscCall(MBCSurfaceReset(&c.master));
    PetscCall(MBCSurfaceReset(&c.slave));
    PetscCall(PetscFree(c.pairs));
    PetscCall(PetscFree(c.points));
  }
  PetscCall(PetscFinalize());
  return 0;
}
