/* Time tables: linear interpolation inside, held at the end values outside. */
#include <mbc/private/sceneimpl.h>

int main(int argc, char **argv)
{
  struct _n_MBCScene scene;
  MBCTimeTable       table;
  PetscReal          t[3] = {0.0, 1.0, 3.0}, f[3] = {0.0, 2.0, -2.0}, v;
  const PetscReal    at[6] = {-1.0, 0.0, 0.5, 1.0, 2.0, 9.0}, expect[6] = {0.0, 0.0, 1.0, 2.0, 0.0, -2.0};

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscMemzero(&scene, sizeof(scene)));
  table.n       = 3;
  table.t       = t;
  table.f       = f;
  scene.ntables = 1;
  scene.tables  = &table;
  for (int i = 0; i < 6; i++) {
    PetscCall(MBCTimeFactor(&scene, MBC_TIME_TABLE, 0, at[i], &v));
    PetscCheck(PetscAbsReal(v - expect[i]) < 1e-14, PETSC_COMM_SELF, PETSC_ERR_PLIB, "table at t = %g gives %g, expected %g", (double)at[i], (double)v, (double)expect[i]);
  }
  PetscCall(MBCTimeFactor(&scene, MBC_TIME_SUDDEN, -1, 5.0, &v));
  PetscCheck(v == 1.0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "sudden load factor %g, expected 1", (double)v);
  PetscCall(PetscPrintf(PETSC_COMM_SELF, "time factors ok\n"));
  PetscCall(PetscFinalize());
  return 0;
}
