/* granchain: fix chain/nve. See fix_chain_nve.h. */

#include "fix_chain_nve.h"

#include "atom.h"
#include "error.h"
#include "force.h"
#include "group.h"
#include "modify.h"
#include "neighbor.h"
#include "output.h"
#include "timer.h"
#include "update.h"

#include <mpi.h>

using namespace LAMMPS_NS;
using namespace FixConst;

FixChainNVE::FixChainNVE(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), dtv(0.0), dtf(0.0), cached_ncalls(-1), cached_nlocal(-1), cached_dtf(0.0), ahead(false)
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
  ahead = false;
  // the fixes Modify calls at the end of a step (its own list is not public); fixed during a run
  end_of_step.clear();
  for (int k = 0; k < modify->nfix; k++)
    if (modify->fix[k]->setmask() & END_OF_STEP) end_of_step.push_back(modify->fix[k]);
  double **v = atom->v;
  double **f = atom->f;
  const int *mask = atom->mask;
  int bad = 0;
  for (int i = 0; i < atom->nlocal; i++)
    if ((mask[i] & groupbit) && (v[i][1] != 0.0 || v[i][2] != 0.0 || f[i][1] != 0.0 || f[i][2] != 0.0)) bad = 1;
  int any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, world);
  if (any)
    error->all(FLERR,
               "fix chain/nve integrates along x only, but an atom of group {} has a y or z velocity or "
               "force: use fix nve",
               group->names[igroup]);
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

// x, v, f as the contiguous n x 3 blocks LAMMPS allocates them in (no row pointer loaded per atom), and no
// group test for group all: one tight loop over the x components (the same expressions as fix nve, so the
// same doubles). With the pair style's rotated samples (3fe6675) the loop time went 0.83 / 0.81x at 1e3 /
// 1e4 beads (bench_pair.py plugins); perf at 1e4 beads: the two passes 20% -> 13% of the samples
#define CHAIN_NVE_BLOCKS                                                   \
  double(*const __restrict xx)[3] = (double(*)[3]) atom->x[0];             \
  double(*const __restrict vv)[3] = (double(*)[3]) atom->v[0];             \
  const double(*const __restrict ff)[3] = (const double(*)[3]) atom->f[0]; \
  const int *const __restrict mask = atom->mask;                           \
  const int nlocal = atom->nlocal;                                         \
  const double *const __restrict m = dtfm.data();

void FixChainNVE::initial_integrate(int)
{
  if (ahead) {    // done by the previous step's final_integrate
    ahead = false;
    return;
  }
  refresh_if_stale();
  if (atom->nlocal == 0) return;
  CHAIN_NVE_BLOCKS
  const double dt = dtv;
  if (igroup == 0) {    // group all
    for (int i = 0; i < nlocal; i++) {
      vv[i][0] += m[i] * ff[i][0];
      xx[i][0] += dt * vv[i][0];
    }
  } else {
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit) {
        vv[i][0] += m[i] * ff[i][0];
        xx[i][0] += dt * vv[i][0];
      }
  }
}

// whether nothing can look at the atoms between this step's final half-kick and the next step's first
// half-kick and drift: not the run's last step, no output (thermo, dump) and no end-of-step fix due this
// step (Modify calls a fix's end_of_step when the step is a multiple of its nevery), no time limit
// (timer timeout), and this fix the only one that integrates. Then the next step's x and v (the same
// expressions on the same f, so the same doubles) are computed now, in the same pass
bool FixChainNVE::can_run_ahead() const
{
  const bigint n = update->ntimestep;
  if (n >= update->laststep || n == output->next || timer->has_timeout()) return false;
  if (modify->n_initial_integrate != 1 || modify->n_final_integrate != 1) return false;
  for (const Fix *fix : end_of_step) {
    const int every = fix->nevery;
    if (every <= 1 || n % every == 0) return false;
  }
  return true;
}

void FixChainNVE::final_integrate()
{
  refresh_if_stale();
  ahead = can_run_ahead();
  if (atom->nlocal == 0) return;
  CHAIN_NVE_BLOCKS
  // with run ahead: v = (v + dtf/m f) + dtf/m f, then x += dt v, as final_integrate and the next
  // initial_integrate would (f does not change between them); the step's end state is never seen.
  // Measured: one pass over x, v, f instead of two over v, f and one over x, v, f
  const double dt = dtv;
  if (ahead) {
    if (igroup == 0) {
      for (int i = 0; i < nlocal; i++) {
        const double kick = m[i] * ff[i][0];
        vv[i][0] = (vv[i][0] + kick) + kick;
        xx[i][0] += dt * vv[i][0];
      }
    } else {
      for (int i = 0; i < nlocal; i++)
        if (mask[i] & groupbit) {
          const double kick = m[i] * ff[i][0];
          vv[i][0] = (vv[i][0] + kick) + kick;
          xx[i][0] += dt * vv[i][0];
        }
    }
  } else if (igroup == 0) {
    for (int i = 0; i < nlocal; i++) vv[i][0] += m[i] * ff[i][0];
  } else {
    for (int i = 0; i < nlocal; i++)
      if (mask[i] & groupbit) vv[i][0] += m[i] * ff[i][0];
  }
}

void FixChainNVE::reset_dt()
{
  dtv = update->dt;
  dtf = 0.5 * update->dt * force->ftm2v;
}
