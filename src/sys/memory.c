/* What memory a rank may still take: its share of its node's available memory. */
#include <mbcontact.h>
#include <stdio.h>

/* *mb: MemAvailable of /proc/meminfo over the ranks on this rank's node, read at once by all of
   them; 0 where the kernel does not say. Collective. */
PetscErrorCode MBCMemoryAvailable(MPI_Comm comm, PetscReal *mb)
{
  MPI_Comm    node;
  PetscMPIInt nlocal;
  double      kb = 0;
  char        line[256];
  FILE       *fp = fopen("/proc/meminfo", "r");

  PetscFunctionBegin;
  while (fp && fgets(line, sizeof(line), fp))
    if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1) break;
  if (fp) fclose(fp);
  PetscCallMPI(MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
  PetscCallMPI(MPI_Comm_size(node, &nlocal));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &kb, 1, MPI_DOUBLE, MPI_MIN, node)); /* one figure for the node */
  PetscCallMPI(MPI_Comm_free(&node));
  *mb = kb > 0 ? kb / 1024.0 / nlocal : 0;
  PetscFunctionReturn(0);
}
