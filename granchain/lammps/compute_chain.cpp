/* granchain: the run watch's computes, chain/fmax and chain/momentum. See compute_chain.h. */

#include "compute_chain.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "update.h"

#include <cfloat>
#include <mpi.h>

using namespace LAMMPS_NS;

ComputeChainFmax::ComputeChainFmax(LAMMPS *lmp, int narg, char **arg) : Compute(lmp, narg, arg), index(-1)
{
  if (narg != 3) error->all(FLERR, "Illegal compute chain/fmax command: compute ID group chain/fmax");
  vector_flag = 1;
  size_vector = 2;
  extvector = 0;
  vector = new double[2];
}

ComputeChainFmax::~ComputeChainFmax()
{
  delete[] vector;
}

void ComputeChainFmax::init()
{
  int flag, cols;
  index = atom->find_custom("fc", flag, cols);
  if (index < 0 || flag != 1 || cols != 0)
    error->all(FLERR, "compute chain/fmax needs the per-atom vector d_fc (fix property/atom d_fc ...)");
}

void ComputeChainFmax::compute_vector()
{
  invoked_vector = update->ntimestep;
  const double *fc = atom->dvector[index];
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  // as compute reduce max with replace: the first largest value on this rank, then the rank holding
  // the largest (MPI_MAXLOC: the lowest rank among equals) gives its atom's ID
  struct {
    double value;
    int proc;
  } in{-DBL_MAX, comm->me}, out;
  int imax = -1;
  for (int i = 0; i < nlocal; i++)
    if ((mask[i] & groupbit) && fc[i] > in.value) {
      in.value = fc[i];
      imax = i;
    }
  MPI_Allreduce(&in, &out, 1, MPI_DOUBLE_INT, MPI_MAXLOC, world);
  double id = (comm->me == out.proc && imax >= 0) ? (double) atom->tag[imax] : 0.0;
  MPI_Bcast(&id, 1, MPI_DOUBLE, out.proc, world);
  vector[0] = out.value;
  vector[1] = id;
}

ComputeChainMomentum::ComputeChainMomentum(LAMMPS *lmp, int narg, char **arg) : Compute(lmp, narg, arg)
{
  if (narg != 3) error->all(FLERR, "Illegal compute chain/momentum command: compute ID group chain/momentum");
  scalar_flag = 1;
  extscalar = 0;
}

void ComputeChainMomentum::init() {}

double ComputeChainMomentum::compute_scalar()
{
  invoked_scalar = update->ntimestep;
  const double *const *v = atom->v;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  double p = 0.0;
  if (atom->rmass) {
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit) p += atom->rmass[i] * v[i][0];
  } else {
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit) p += atom->mass[atom->type[i]] * v[i][0];
  }
  MPI_Allreduce(&p, &scalar, 1, MPI_DOUBLE, MPI_SUM, world);
  return scalar;
}
