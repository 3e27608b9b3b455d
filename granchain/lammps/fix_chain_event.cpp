/* granchain: fix chain/event. See fix_chain_event.h. */

#include "fix_chain_event.h"

#include "atom.h"
#include "compute.h"
#include "error.h"
#include "modify.h"
#include "update.h"
#include "utils.h"

#include <cmath>
#include <cstring>
#include <mpi.h>
#include <vector>

using namespace LAMMPS_NS;
using namespace FixConst;

FixChainEvent::FixChainEvent(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), index(-1), pe(nullptr), started(false), ended(false), g(0.0), fmax(0.0), tmax(0.0),
    impulse(0.0), dynamic(0.0), energy(0.0), end_time(0.0), sfc_index(-1)
{
  const char *usage =
      "Illegal fix chain/event command: fix ID group chain/event CHECK WALL_ATOM FS FLOOR HELD LOAD_END [track K ID1 "
      "KIND1 ..]";
  if (narg < 9) error->all(FLERR, usage);
  if (narg > 9) {
    if (narg < 11 || strcmp(arg[9], "track") != 0) error->all(FLERR, usage);
    const int k = utils::inumeric(FLERR, arg[10], false, lmp);
    if (k < 0 || narg != 11 + 2 * k) error->all(FLERR, usage);
    for (int i = 0; i < k; i++) {
      track_id.push_back(utils::tnumeric(FLERR, arg[11 + 2 * i], false, lmp));
      track_kind.push_back(utils::inumeric(FLERR, arg[12 + 2 * i], false, lmp));
      if (track_kind.back() != 0 && track_kind.back() != 1)
        error->all(FLERR, "fix chain/event track KIND must be 0 (d_fc) or 1 (d_sfc), got {}", track_kind.back());
    }
  }
  check = utils::inumeric(FLERR, arg[3], false, lmp);
  wall_atom = utils::tnumeric(FLERR, arg[4], false, lmp);
  fs = utils::numeric(FLERR, arg[5], false, lmp);
  floor = utils::numeric(FLERR, arg[6], false, lmp);
  held = utils::inumeric(FLERR, arg[7], false, lmp) != 0;
  load_end = utils::numeric(FLERR, arg[8], false, lmp);
  if (check <= 0) error->all(FLERR, "fix chain/event CHECK must be > 0, got {}", check);
  if (atom->map_style == Atom::MAP_NONE) error->all(FLERR, "fix chain/event needs an atom map (atom_modify map array)");
  nevery = 1;
  vector_flag = 1;
  size_vector = 7 + 2 * (int) track_id.size();
  global_freq = 1;
  extvector = 0;
  for (int k = 0; k < 3; k++) t[k] = f[k] = 0.0;
}

int FixChainEvent::setmask()
{
  return END_OF_STEP;
}

void FixChainEvent::init()
{
  int flag, cols;
  index = atom->find_custom("fc", flag, cols);
  if (index < 0 || flag != 1 || cols != 0)
    error->all(FLERR, "fix chain/event needs the per-atom vector d_fc (fix property/atom d_fc ...)");
  pe = modify->get_compute_by_id("thermo_pe");
  if (!pe) error->all(FLERR, "fix chain/event needs the compute thermo_pe");
  for (const int kind : track_kind) {
    if (kind != 1) continue;
    sfc_index = atom->find_custom("sfc", flag, cols);
    if (sfc_index < 0 || flag != 1 || cols != 0)
      error->all(FLERR,
                 "fix chain/event track KIND 1 needs the per-atom vector d_sfc (pair_style chain/<law> sensors)");
  }
}

// the tracked forces now, by the ranks that own their atoms
void FixChainEvent::track_sample(std::vector<double> &out) const
{
  const int k = (int) track_id.size();
  std::vector<double> mine(k, 0.0);
  out.assign(k, 0.0);
  for (int j = 0; j < k; j++) {
    const int i = atom->map(track_id[j]);
    if (i >= 0 && i < atom->nlocal) mine[j] = atom->dvector[track_kind[j] ? sfc_index : index][i];
  }
  if (k) MPI_Allreduce(mine.data(), out.data(), k, MPI_DOUBLE, MPI_SUM, world);
}

// a new sample of the tracked forces at t[2] (add has shifted the times): the running maximum, refined
// by the vertex of the parabola through three samples around a local maximum (EventMaxima.add)
void FixChainEvent::track_add(const std::vector<double> &fk)
{
  tf[0].swap(tf[1]);
  tf[1].swap(tf[2]);
  tf[2] = fk;
  const double a = t[0] - t[1], b = t[2] - t[1], det = a * b * (b - a);
  for (size_t j = 0; j < fk.size(); j++) {
    if (fk[j] > tfmax[j]) {
      tfmax[j] = fk[j];
      ttmax[j] = t[2];
    }
    const double f0 = tf[0][j], f1 = tf[1][j], f2 = fk[j];
    if (!(std::isfinite(t[0]) && f1 > f2 && f1 >= f0 && f1 > 0.0)) continue;
    const double fa = f0 - f1, fb = f2 - f1;
    const double c1 = (fa * b * b - fb * a * a) / det;
    const double c2 = (a * fb - b * fa) / det;
    if (c2 < 0.0) {
      const double s = std::fmin(std::fmax(-c1 / (2.0 * c2), a), b);
      const double val = f1 + (c1 + c2 * s) * s;
      if (val > tfmax[j]) {
        tfmax[j] = val;
        ttmax[j] = t[1] + s;
      }
    }
  }
}

bigint FixChainEvent::next_check() const
{
  return (update->ntimestep / check + 1) * check;
}

double FixChainEvent::now() const
{
  return update->atime + (update->ntimestep - update->atimestep) * update->dt;
}

// the wall's contact force and bead N's vx, from the rank that owns bead N's atom
void FixChainEvent::wall_sample(double &fw, double &vw) const
{
  double mine[2] = {0.0, 0.0}, all[2];
  const int i = atom->map(wall_atom);
  if (i >= 0 && i < atom->nlocal) {
    mine[0] = atom->dvector[index][i];
    mine[1] = atom->v[i][0];
  }
  MPI_Allreduce(mine, all, 2, MPI_DOUBLE, MPI_SUM, world);
  fw = all[0];
  vw = all[1];
}

void FixChainEvent::setup(int)
{
  if (!held && !ended) modify->addstep_compute_all(next_check());    // pe tallied on the next check
  if (started) return;    // a later run's setup recomputes the same state: no new sample
  started = true;
  double fw, vw;
  wall_sample(fw, vw);
  t[0] = t[1] = -INFINITY;
  t[2] = now();
  f[0] = f[1] = 0.0;
  f[2] = fw;
  g = (fw - fs) * std::fmax(vw, 0.0);
  fmax = fw;
  tmax = t[2];
  std::vector<double> fk;
  track_sample(fk);
  tf[0].assign(fk.size(), 0.0);
  tf[1].assign(fk.size(), 0.0);
  tf[2] = fk;
  tfmax = fk;
  ttmax.assign(fk.size(), t[2]);
}

void FixChainEvent::add(double time, double fw, double vw)
{
  const double h = time - t[2], fp = f[2];
  impulse += 0.5 * h * (fp + fw);
  dynamic += 0.5 * h * ((fp - fs) + (fw - fs));
  const double gn = (fw - fs) * std::fmax(vw, 0.0);
  energy += 0.5 * h * (g + gn);
  g = gn;
  t[0] = t[1];
  t[1] = t[2];
  t[2] = time;
  f[0] = f[1];
  f[1] = fp;
  f[2] = fw;
  if (fw > fmax) {
    fmax = fw;
    tmax = time;
  }
  if (std::isfinite(t[0]) && f[1] > fw && f[1] >= f[0] && f[1] > 0.0) {
    // the middle sample is a local maximum: the vertex of the parabola through the three
    const double a = t[0] - t[1], b = t[2] - t[1], det = a * b * (b - a);
    const double fa = f[0] - f[1], fb = f[2] - f[1];
    const double c1 = (fa * b * b - fb * a * a) / det;
    const double c2 = (a * fb - b * fa) / det;
    if (c2 < 0.0) {
      const double s = std::fmin(std::fmax(-c1 / (2.0 * c2), a), b);
      const double val = f[1] + (c1 + c2 * s) * s;
      if (val > fmax) {
        fmax = val;
        tmax = t[1] + s;
      }
    }
  }
}

// whether the chain has left the wall for good at this check (granchain.physics.event.left_for_good)
bool FixChainEvent::left()
{
  const int nlocal = atom->nlocal;
  double **v = atom->v;
  if (t[2] < load_end || f[2] > 0.0) return false;
  // every moving atom's vx, mass and d_fc by ID (slots 0 .. n - 1: the atoms up to bead N's; the wall after)
  const int n = (int) wall_atom;
  std::vector<double> mine(3 * n, 0.0), all(3 * n);
  const double *fc = atom->dvector[index];
  for (int i = 0; i < nlocal; i++) {
    const tagint k = atom->tag[i] - 1;
    if (k >= n) continue;
    mine[k] = v[i][0];
    mine[n + k] = atom->rmass[i];
    mine[2 * n + k] = fc[i];
  }
  MPI_Allreduce(mine.data(), all.data(), 3 * n, MPI_DOUBLE, MPI_SUM, world);
  if (!(pe->invoked_flag & Compute::INVOKED_SCALAR)) {
    pe->compute_scalar();
    pe->invoked_flag |= Compute::INVOKED_SCALAR;
  }
  return left_for_good(all.data(), all.data() + n, all.data() + 2 * n, n, pe->scalar);
}

// the same test as granchain.physics.event.left_for_good (a group k .. j-1 holding every closed contact,
// the bodies before and after it in free flight it can never catch)
bool FixChainEvent::left_for_good(const double *vel, const double *m, const double *fcon, int n, double stored)
{
  if (fcon[n - 1] > 0.0) return false;
  std::vector<char> free(n), tail(n + 1), left(n + 1);
  bool all = true;
  for (int i = 0; i < n; i++) {
    const double ahead = i + 1 < n ? vel[i + 1] : 0.0;
    free[i] = fcon[i] <= 0.0 && vel[i] <= ahead;
    all = all && free[i];
  }
  if (all) return true;
  tail[n] = 1;
  for (int i = n - 1; i >= 0; i--) tail[i] = tail[i + 1] && free[i];
  left[0] = 1;
  for (int i = 0; i < n; i++) left[i + 1] = left[i] && free[i];
  std::vector<double> cp(n + 1, 0.0), cm(n + 1, 0.0), ck(n + 1, 0.0);
  for (int i = 0; i < n; i++) {
    cp[i + 1] = cp[i] + m[i] * vel[i];
    cm[i + 1] = cm[i] + m[i];
    ck[i + 1] = ck[i] + 0.5 * m[i] * vel[i] * vel[i];
  }
  int last_left = 0;    // the largest k < j with left[k]
  for (int j = 1; j <= n; j++) {
    if (left[j - 1]) last_left = j - 1;
    if (!tail[j] || fcon[j - 1] > 0.0) continue;
    const double vend = j < n ? vel[j] : 0.0;
    const int ks[2] = {0, last_left};
    for (int c = 0; c < (last_left ? 2 : 1); c++) {
      const int k = ks[c];
      const double pg = cp[j] - cp[k], mg = cm[j] - cm[k], vg = pg / mg;
      const double e = std::fmax(ck[j] - ck[k] + stored - 0.5 * pg * vg, 0.0);
      if (vg + std::sqrt(2.0 * e / m[j - 1]) <= vend && (k == 0 || vel[k - 1] <= vg - std::sqrt(2.0 * e / m[k])))
        return true;
    }
  }
  return false;
}

// a held chain's end after every step (granchain.physics.event.EventSums.cross): the wall's dynamic force
// crossed its static value in this step, bead N and the chain moving away; the end the crossing,
// interpolated, and the step's trapezoids cut there
void FixChainEvent::cross(double vw)
{
  const double t0 = t[1], t1 = t[2], f0 = f[1], f1 = f[2];
  if (!(fmax - fs > floor && f0 - fs > 0.0 && f1 - fs <= 0.0 && vw <= 0.0)) return;
  double p = 0.0, pall;
  for (int i = 0; i < atom->nlocal; i++) p += atom->rmass[i] * atom->v[i][0];
  MPI_Allreduce(&p, &pall, 1, MPI_DOUBLE, MPI_SUM, world);
  if (pall > 0.0) return;
  const double tc = t0 + (t1 - t0) * ((f0 - fs) / (f0 - f1));
  const double after = t1 - tc;
  impulse -= 0.5 * after * (fs + f1);
  dynamic -= 0.5 * after * (f1 - fs);
  energy -= 0.5 * after * g;
  ended = true;
  end_time = tc;
}

void FixChainEvent::end_of_step()
{
  if (ended) return;
  double fw, vw;
  wall_sample(fw, vw);
  const double time = now();
  add(time, fw, vw);
  if (!track_id.empty()) {
    std::vector<double> fk;
    track_sample(fk);
    track_add(fk);
  }
  if (held) {
    cross(vw);
    return;
  }
  if (update->ntimestep % check) return;
  if (fmax - fs > floor && left()) {
    ended = true;
    end_time = time;
  } else {
    modify->addstep_compute(next_check());
  }
}

double FixChainEvent::compute_vector(int k)
{
  switch (k) {
    case 0:
      return ended ? 1.0 : 0.0;
    case 1:
      return end_time;
    case 2:
      return fmax - fs;
    case 3:
      return tmax;
    case 4:
      return impulse;
    case 5:
      return dynamic;
    case 6:
      return energy;
    default: {
      const int j = (k - 7) / 2;
      return (k - 7) % 2 ? ttmax[j] : tfmax[j];
    }
  }
}
