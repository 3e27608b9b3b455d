/* granchain: the run watch's computes, chain/fmax and chain/momentum. See compute_chain.h. */

#include "compute_chain.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "update.h"

#include <cfloat>
#include <mpi.h>

using namespace LAMMPS_NS;

ComputeChainFmax::ComputeChainFmax(LAMMPS *lmp, int narg, char **arg) :
    Compute(lmp, narg, arg), index(-1), bound_index(-1)
{
  if (narg != 3 && narg != 4)
    error->all(FLERR, "Illegal compute chain/fmax command: compute ID group chain/fmax [bound-vector]");
  if (narg == 4) bound_name = arg[3];
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
  if (!bound_name.empty()) {
    bound_index = atom->find_custom(bound_name.c_str(), flag, cols);
    if (bound_index < 0 || flag != 1 || cols != 0)
      error->all(FLERR, "compute chain/fmax {} needs the per-atom vector d_{} (fix property/atom d_{})", bound_name,
                 bound_name, bound_name);
  }
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
  if (bound_index < 0) {
    for (int i = 0; i < nlocal; i++)
      if ((mask[i] & groupbit) && fc[i] > in.value) {
        in.value = fc[i];
        imax = i;
      }
  } else {
    // each contact against its own bound: the same division as the atom-style variable d_fc/d_bound
    const double *bound = atom->dvector[bound_index];
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit) {
        const double ratio = fc[i] / bound[i];
        if (ratio > in.value) {
          in.value = ratio;
          imax = i;
        }
      }
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
