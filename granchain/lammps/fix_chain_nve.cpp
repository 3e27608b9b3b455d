/* granchain: fix chain/nve. See fix_chain_nve.h. */

#include "fix_chain_nve.h"

#include "atom.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "neighbor.h"
#include "update.h"

#include <mpi.h>

using namespace LAMMPS_NS;
using namespace FixConst;

FixChainNVE::FixChainNVE(LAMMPS *lmp, int narg, char **arg) : Fix(lmp, narg, arg), dtv(0.0), dtf(0.0), cached_ncalls(-1), cached_nlocal(-1), cached_dtf(0.0)
{
  if (narg != 3) error->all(FLERR, "Illegal fix chain/nve command: fix ID group chain/nve");
  dynamic_group_allow = 1;
  time_integrate = 1;
}

int FixChainNVE::setmask()
{
  return INITIAL_INTEGRATE | FINAL_INTEGRATE;
}

void FixChainNVE::init()
{
  dtv = update->dt;
  dtf = 0.5 * update->dt * force->ftm2v;
}

void FixChainNVE::setup(int)
{
  double **v = atom->v;
  double **f = atom->f;
  const int *mask = atom->mask;
  int bad = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && (v[i][1] != 0.0 || v[i][2] != 0.0 || f[i][1] != 0.0 || f[i][2] != 0.0)) bad = 1;
  int any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR, "fix chain/nve integrates along x only, but an atom of group {} has a y or z velocity or "
               "force: use fix nve", group->names[igroup]);
}

// dtf / m of every owned atom, kept between neighbour builds (atoms are exchanged and sorted only at
// a build): the same numbers fix nve divides out twice per step
void FixChainNVE::refresh()
{
  const int nlocal = atom->nlocal;
  dtfm.resize(nlocal);
  if (atom->rmass)
    for (int i = 0; i < nlocal; i++) dtfm[i] = dtf / atom->rmass[i];
  else
    for (int i = 0; i < nlocal; i++) dtfm[i] = dtf / atom->mass[atom->type[i]];
  cached_ncalls = neighbor->ncalls;
  cached_nlocal = nlocal;
  cached_dtf = dtf;
}

// dt/m per atom holds until atoms migrate (a neighbour build), their number changes, or dt does
void FixChainNVE::refresh_if_stale()
{
  if (neighbor->ncalls != cached_ncalls || atom->nlocal != cached_nlocal || dtf != cached_dtf) refresh();
}

void FixChainNVE::initial_integrate(int)
{
  refresh_if_stale();
  double **x = atom->x;
  double **v = atom->v;
  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double *m = dtfm.data();
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit) {
      v[i][0] += m[i] * f[i][0];
      x[i][0] += dtv * v[i][0];
    }
}

void FixChainNVE::final_integrate()
{
  refresh_if_stale();
  double **v = atom->v;
  double **f = atom->f;
  const int *mask = atom->mask;
  const int nlocal = atom->nlocal;
  const double *m = dtfm.data();
  for (int i = 0; i < nlocal; i++)
    if (mask[i] & groupbit) v[i][0] += m[i] * f[i][0];
}

void FixChainNVE::reset_dt()
{
  dtv = update->dt;
  dtf = 0.5 * update->dt * force->ftm2v;
}
