/* granchain: the chain/<law> pair styles, PairChain<Law> over the kernels of law_*.h. See pair_chain.h. */

#include "pair_chain.h"

#include "chain_laws.h"    // generated from the law registry: GRANCHAIN_LAWS(X), every law's header

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "force.h"
#include "memory.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "update.h"
#include "utils.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

using namespace LAMMPS_NS;

// the damping parts' pair_style words, in the registry's order (chain_laws.h: GRANCHAIN_DAMPING; the
// first, "none", is never on a pair_style line): PairChainBase::damping indexes them
static const char *const damping_words[] = {
#define GRANCHAIN_WORD(D) D::word,
    GRANCHAIN_DAMPING(GRANCHAIN_WORD)
#undef GRANCHAIN_WORD
};
static constexpr int ndamping = sizeof(damping_words) / sizeof(damping_words[0]);

/* ---------------------------------------------------------------------- the shared machinery */

PairChainBase::PairChainBase(LAMMPS *lmp, bool has_history, const char *law_vectors) :
    Pair(lmp), history(has_history), vectors(law_vectors), damping(0), damping_coeff(0.0), lead(false), d0(nullptr),
    t_fc(-std::numeric_limits<double>::infinity()), t_fprev(-std::numeric_limits<double>::infinity()),
    t_fprev2(-std::numeric_limits<double>::infinity()), amax_comm(nullptr)
{
  single_enable = 1;
  restartinfo = 0;
  writedata = 0;
  comm_forward = 1;    // alpha_max of owned beads to their ghost copies
}

PairChainBase::~PairChainBase()
{
  if (allocated) {
    memory->destroy(setflag);
    memory->destroy(cutsq);
    memory->destroy(d0);
  }
}

void PairChainBase::allocate_base()
{
  allocated = 1;
  int n = atom->ntypes + 1;
  memory->create(setflag, n, n, "pair:setflag");
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) setflag[i][j] = 0;
  memory->create(cutsq, n, n, "pair:cutsq");
  memory->create(d0, n, n, "pair:d0");
}

void PairChainBase::settings(int narg, char **arg)
{
  damping = 0;
  damping_coeff = 0.0;
  lead = false;
  lead_fall = 0.0;
  peaks_all = false;
  sensors.clear();
  ladder_per_octave = 0;
  int i = 0;
  while (i < narg) {
    int part = 0;    // a damping part's word: its index in damping_words
    for (int k = 1; k < ndamping; k++)
      if (strcmp(arg[i], damping_words[k]) == 0) part = k;
    if (part && i + 1 < narg) {
      if (damping && damping != part)
        error->all(FLERR, "pair_style {}: {} and {} together: give one damping part", force->pair_style,
                   damping_words[damping], damping_words[part]);
      damping = part;
      damping_coeff = utils::numeric(FLERR, arg[i + 1], false, lmp);
      if (damping_coeff < 0.0)
        error->all(FLERR, "pair_style {} {} coefficient must be >= 0, got {}", force->pair_style, arg[i],
                   damping_coeff);
      i += 2;
    } else if (strcmp(arg[i], "lead") == 0 && i + 2 < narg) {
      lead = true;
      lead_floor = utils::numeric(FLERR, arg[i + 1], false, lmp);
      lead_f0 = utils::numeric(FLERR, arg[i + 2], false, lmp);
      if (lead_floor <= 0.0) error->all(FLERR, "pair_style {} lead needs floor > 0", force->pair_style);
      i += 3;
    } else if (strcmp(arg[i], "fall") == 0 && i + 1 < narg) {
      lead_fall = utils::numeric(FLERR, arg[i + 1], false, lmp);
      if (!(lead_fall >= 0.0))
        error->all(FLERR, "pair_style {} fall needs R >= 0, got {}", force->pair_style, lead_fall);
      i += 2;
    } else if (strcmp(arg[i], "ladder") == 0 && i + 2 < narg) {
      ladder_per_octave = utils::inumeric(FLERR, arg[i + 1], false, lmp);
      ladder_slots = utils::inumeric(FLERR, arg[i + 2], false, lmp);
      if (ladder_per_octave < 1 || ladder_slots < 1)
        error->all(FLERR, "pair_style {} ladder needs rungs per octave >= 1 and slots >= 1", force->pair_style);
      i += 3;
    } else if (strcmp(arg[i], "sensors") == 0 && i + 1 < narg) {
      const int k = utils::inumeric(FLERR, arg[i + 1], false, lmp);
      if (k < 1 || i + 1 + k >= narg)
        error->all(FLERR, "pair_style {} sensors needs a count K >= 1 and K atom IDs", force->pair_style);
      for (int m = 0; m < k; m++) sensors.push_back(utils::tnumeric(FLERR, arg[i + 2 + m], false, lmp));
      i += 2 + k;
    } else if (strcmp(arg[i], "peaks") == 0 && i + 1 < narg && strcmp(arg[i + 1], "all") == 0) {
      peaks_all = true;
      i += 2;
    } else {
      error->all(FLERR,
                 "Illegal pair_style {} command: expected [dashpot gamma | kuwabara_kono A] [lead floor F0] [fall R] "
                 "[ladder per_octave slots] [sensors K id..] [peaks all]",
                 force->pair_style);
    }
  }
  if (ladder_per_octave && !lead) error->all(FLERR, "pair_style {} ladder needs lead floor F0", force->pair_style);
  if (lead_fall > 0.0 && !lead) error->all(FLERR, "pair_style {} fall needs lead floor F0", force->pair_style);
}

int PairChainBase::index_of(const char *name)
{
  int flag, cols;
  const int k = atom->find_custom(name, flag, cols);
  if (k < 0 || flag != 1 || cols != 0)
    error->all(FLERR,
               "pair {} needs the per-atom vector d_{}: add 'fix ID all property/atom d_fc d_fprev d_fprev2 "
               "d_fpeak d_tpeak{}{} d_fmin ghost yes' before the run (granchain's decks do)",
               force->pair_style, name, *vectors ? " " : "", vectors);
  return k;
}

double *PairChainBase::custom(const char *name)
{
  return atom->dvector[index_of(name)];
}

void PairChainBase::init_style()
{
  if (force->newton_pair)
    error->all(FLERR, "pair {} requires 'newton off' (contact data live on the left bead of each pair)",
               force->pair_style);
  if (!atom->tag_enable) error->all(FLERR, "pair {} requires atom IDs", force->pair_style);
  // the per-atom vectors' indices, looked up once per run (find_custom compares names: every step it
  // cost about 1 ns per bead-step at N = 1000); their arrays move as atoms grow, so vec() reads
  // atom->dvector at every use
  for (int &k : idx) k = -1;
  idx[FC] = index_of("fc");
  idx[FPREV] = index_of("fprev");
  idx[FPREV2] = index_of("fprev2");
  idx[FPEAK] = index_of("fpeak");
  idx[TPEAK] = index_of("tpeak");
  idx[FMIN] = index_of("fmin");
  if (lead) {
    idx[FLEAD] = index_of("flead");
    idx[TLEAD] = index_of("tlead");
  }
  ladder_idx = -1;
  if (ladder_per_octave) {
    int flag, cols;
    ladder_idx = atom->find_custom("ladder", flag, cols);
    if (ladder_idx < 0 || flag != 1 || cols != ladder_slots + 1)
      error->all(FLERR,
                 "pair {} ladder {} {} needs the per-atom array d2_ladder of {} columns: add 'fix ID all "
                 "property/atom d2_ladder {}' before the run (granchain's decks do)",
                 force->pair_style, ladder_per_octave, ladder_slots, ladder_slots + 1, ladder_slots + 1);
  }
  if (!sensors.empty()) {
    if (!atom->map_style)
      error->all(FLERR, "pair {} sensors needs an atom map (atom_modify map array)", force->pair_style);
    const char *names[] = {"sfc", "sprev", "sprev2", "speak", "stpeak", "sfmin"};
    for (int k = 0; k < 6; k++) idx[SFC + k] = index_of(names[k]);
  }
  if (history) {
    idx[AMAX] = index_of("amax");
    idx[EDIS] = index_of("edis");
  }
  // the deck may check the neighbour list every N > 1 steps (a chain's pairs never change while beads
  // keep their order): only with the distance check, and compute() stops at a dangerous build
  if ((neighbor->every > 1 || neighbor->delay > 0) && !neighbor->dist_check)
    error->all(FLERR, "pair {} with neigh_modify every {} delay {} needs 'check yes'", force->pair_style,
               neighbor->every, neighbor->delay);
  if (damped()) {
    idx[EDASH] = index_of("edash");
    if (!comm->ghost_velocity)
      error->all(FLERR, "pair {} {} needs 'comm_modify vel yes' (velocities of ghost beads)", force->pair_style,
                 damping_words[damping]);
  }
  neighbor->add_request(this);
}

// the start of a force evaluation at elapsed time t: a new sample shifts the owned contacts' force
// samples (fc -> fprev -> fprev2); fc restarts at 0. A run's setup recomputes the forces of the state
// the previous run ended in, which is not a new sample. advance_time moves the sample times, shift_all
// the samples. (Each contact's shift and peak inside the pair loop, one pass instead of three, measured
// 1.3-1.5x slower on 10 000 beads: the separate passes are simple enough to vectorise)
bool PairChainBase::advance_time(double t)
{
  const bool new_sample = t > t_fc;
  if (new_sample) {
    t_fprev2 = t_fprev;
    t_fprev = t_fc;
    t_fc = t;
  }
  return new_sample;
}

void PairChainBase::shift_all(bool new_sample, double *&fc, double *&fprev, double *&fprev2)
{
  // a new sample rotates the three vectors' arrays (fix property/atom reaches them through
  // atom->dvector at every use; all three have the same length): fprev2 <- fprev <- fc <- the old
  // fprev2, which becomes fc and is cleared. Copying the samples instead, a pass reading two arrays and
  // writing three, took 5-7% of a 1000-10 000-bead run's time (perf)
  if (new_sample) {
    double **dv = atom->dvector;
    double *const oldest = dv[idx[FPREV2]];
    dv[idx[FPREV2]] = dv[idx[FPREV]];
    dv[idx[FPREV]] = dv[idx[FC]];
    dv[idx[FC]] = oldest;
    fc = dv[idx[FC]];
    fprev = dv[idx[FPREV]];
    fprev2 = dv[idx[FPREV2]];
  }
  if (atom->nlocal > 0) memset(fc, 0, sizeof(double) * atom->nlocal);
}

// running peak of every owned contact (track_one in pair_chain.h)
void PairChainBase::track_peaks(const PeakStep &ps, const double *fc, const double *fprev, const double *fprev2)
{
  const int nlocal = atom->nlocal;
  for (int i = 0; i < nlocal; i++) track_one(ps, i, fc, fprev, fprev2);
}

// the crossing-time ladder of owned contact i (granchain.postprocess.fronts): while its leading pulse is
// not frozen, the time its force rose through each rung F0 + floor * 2^(k / per_octave), k = 0, 1, ...,
// on the line between the previous sample and this one (the first sample: its own time). Each rung is
// counted once, when the force first rises through it: a rung not counted lies above the running peak.
// Before the leading pulse freezes the force can fall back below a counted rung only by less than the
// fall R (a larger fall below a maximum above the floor freezes it). Row: [rungs crossed, then a ring of the last
// `slots` crossing times, rung k in column 1 + k % slots]; pow() as Python's float ** (the same libm)
void PairChainBase::climb(const PeakStep &ps, int i, const double *fc, const double *fprev) const
{
  double *row = ps.ladder[i];
  int k = (int) row[0];
  double level = lead_f0 + lead_floor * pow(2.0, (double) k / ladder_per_octave);
  while (fc[i] >= level) {
    double tc = ps.t;
    if (std::isfinite(t_fprev) && fc[i] > fprev[i] && fprev[i] < level)
      tc = t_fprev + (level - fprev[i]) / (fc[i] - fprev[i]) * (ps.t - t_fprev);
    row[1 + k % ladder_slots] = tc;
    k++;
    row[0] = k;
    level = lead_f0 + lead_floor * pow(2.0, (double) k / ladder_per_octave);
  }
}

// the sensors' samples at the start of a force evaluation: a new sample shifts each owned sensor's
// (sfc -> sprev -> sprev2, as shift_all the contacts'); sfc restarts at 0 on every owned atom, the pair
// loop adds half of each contact's force to both its beads
void PairChainBase::start_sensors(bool new_sample)
{
  double *sfc = vec(SFC), *sprev = vec(SPREV), *sprev2 = vec(SPREV2);
  const int nlocal = atom->nlocal;
  if (new_sample)
    for (const tagint id : sensors) {
      const int i = atom->map(id);
      if (i < 0 || i >= nlocal) continue;
      sprev2[i] = sprev[i];
      sprev[i] = sfc[i];
    }
  if (nlocal > 0) memset(sfc, 0, sizeof(double) * nlocal);
}

// each owned sensor's running peak, smallest force since it and refinement: track_one on the sensors'
// vectors at the contacts' sample times (no leading pulse, no ladder)
void PairChainBase::track_sensors(const PeakStep &contacts)
{
  PeakStep ps = contacts;
  ps.lead = false;
  ps.fpeak = vec(SPEAK);
  ps.tpeak = vec(STPEAK);
  ps.fmin = vec(SFMIN);
  ps.flead = ps.tlead = nullptr;
  ps.ladder = nullptr;
  const double *sfc = vec(SFC), *sprev = vec(SPREV), *sprev2 = vec(SPREV2);
  const int nlocal = atom->nlocal;
  for (const tagint id : sensors) {
    const int i = atom->map(id);
    if (i >= 0 && i < nlocal) track_one(ps, i, sfc, sprev, sprev2);
  }
}

// a new sample makes this sample's written contacts the previous one's; a force evaluation that is not
// a new sample (a run's setup recomputing the state it starts in) writes fc again, fprev stays
void PairChainBase::start_active(bool new_sample)
{
  if (new_sample) {
    act_fprev.swap(act_fc);
    nact_fprev = nact_fc;
  }
  nact_fc = 0;
}

// the running peaks of the contacts whose bookkeeping can change: those written at this sample or the
// previous one. Any other contact has fc = fprev = 0 now and track_one would change nothing: its fmin
// is <= 0 since the last sample it was tracked at with fc = 0 (the sample after its last written one,
// or a full pass); its fpeak >= 0 (0 at the start, it only grows), so no new peak; no refinement
// (fprev > 0 fails); and the leading pulse's tests see the fc and fpeak they saw then. track_one is idempotent
// (a second call on the same samples changes nothing), so a contact in both lists is tracked twice,
// harmlessly. Results are bit for bit those of track_peaks; a chain at rest ahead of the front costs
// nothing here (track_peaks over every bead: 22% of a 10 000-bead run's time, perf)
void PairChainBase::track_active(const PeakStep &ps, const double *fc, const double *fprev, const double *fprev2)
{
  for (int k = 0; k < nact_fc; k++) track_one(ps, act_fc[k], fc, fprev, fprev2);
  for (int k = 0; k < nact_fprev; k++)
    if (fc[act_fprev[k]] == 0.0) track_one(ps, act_fprev[k], fc, fprev, fprev2);    // the others are in act_fc
}

PairChainBase::PeakStep PairChainBase::peak_step(double t, bool new_sample)
{
  PeakStep ps;
  ps.t = t;
  ps.refine = new_sample && std::isfinite(t_fprev2);
  ps.lead = lead;
  ps.a = t_fprev2 - t_fprev;    // sample times relative to the middle one
  ps.b = t_fc - t_fprev;
  ps.det = ps.a * ps.b * (ps.b - ps.a);
  ps.fpeak = vec(FPEAK);
  ps.tpeak = vec(TPEAK);
  ps.fmin = vec(FMIN);
  ps.flead = lead ? vec(FLEAD) : nullptr;
  ps.tlead = lead ? vec(TLEAD) : nullptr;
  ps.ladder = ladder_idx >= 0 ? atom->darray[ladder_idx] : nullptr;
  return ps;
}

int PairChainBase::pack_forward_comm(int n, int *list_, double *buf, int, int *)
{
  for (int i = 0; i < n; i++) buf[i] = amax_comm[list_[i]];
  return n;
}

void PairChainBase::unpack_forward_comm(int n, int first, double *buf)
{
  for (int i = 0; i < n; i++) amax_comm[first + i] = buf[i];
}

/* ---------------------------------------------------------------------- one law */

template <class Law> PairChain<Law>::PairChain(LAMMPS *lmp) : PairChainBase(lmp, Law::history, Law::vectors)
{
  for (int m = 0; m < Law::ncoeff; m++) coeffs[m] = nullptr;
}

template <class Law> PairChain<Law>::~PairChain()
{
  if (allocated)
    for (int m = 0; m < Law::ncoeff; m++) memory->destroy(coeffs[m]);
}

template <class Law> void PairChain<Law>::allocate()
{
  allocate_base();
  int n = atom->ntypes + 1;
  for (int m = 0; m < Law::ncoeff; m++) memory->create(coeffs[m], n, n, "pair:coeff");
}

template <class Law> void PairChain<Law>::coeff(int narg, char **arg)
{
  constexpr int nc = Law::ncoeff;
  if (narg != 3 + nc) {
    std::string extras;
    for (int m = 1; m < nc; m++) extras += std::string(" ") + Law::coeff_names[m];
    error->all(FLERR, "pair_coeff for {} needs: I J k d0{}", force->pair_style, extras);
  }
  if (!allocated) allocate();
  int ilo, ihi, jlo, jhi;
  utils::bounds(FLERR, arg[0], 1, atom->ntypes, ilo, ihi, error);
  utils::bounds(FLERR, arg[1], 1, atom->ntypes, jlo, jhi, error);
  double c[nc];
  c[0] = utils::numeric(FLERR, arg[2], false, lmp);
  double d = utils::numeric(FLERR, arg[3], false, lmp);
  for (int m = 1; m < nc; m++) c[m] = utils::numeric(FLERR, arg[3 + m], false, lmp);
  const char *requirement = "";
  const int bad = Law::check(c, &requirement);
  if (bad == 0) error->all(FLERR, "pair_coeff k {}, got {}", requirement, c[0]);
  if (d <= 0.0) error->all(FLERR, "pair_coeff d0 must be > 0, got {}", d);
  if (bad > 0) error->all(FLERR, "pair_coeff {} {}, got {}", Law::coeff_names[bad], requirement, c[bad]);
  int count = 0;
  for (int i = ilo; i <= ihi; i++)
    for (int j = MAX(jlo, i); j <= jhi; j++) {
      for (int m = 0; m < nc; m++) coeffs[m][i][j] = c[m];
      d0[i][j] = d;
      setflag[i][j] = 1;
      count++;
    }
  if (count == 0) error->all(FLERR, "Incorrect args for pair coefficients");
}

template <class Law> double PairChain<Law>::init_one(int i, int j)
{
  if (setflag[i][j] == 0) error->all(FLERR, "All pair coeffs are not set (pair {} {})", i, j);
  for (int m = 0; m < Law::ncoeff; m++) coeffs[m][j][i] = coeffs[m][i][j];
  d0[j][i] = d0[i][j];
  // the pair's constants as one record for compute(); cutsq as Pair::init computes it from the cutoff
  const int nt = atom->ntypes + 1;
  if ((int) table.size() != nt * nt) {
    table.assign(nt * nt, Coef{});
    cutsq_max = 0.0;
  }
  Coef cf;
  cf.d0 = d0[i][j];
  cf.cutsq = cf.d0 * cf.d0;
  cutsq_max = MAX(cutsq_max, cf.cutsq);
  double c[Law::ncoeff];
  for (int m = 0; m < Law::ncoeff; m++) c[m] = coeffs[m][i][j];
  Law::derive(c, cf.c);
  table[i * nt + j] = table[j * nt + i] = cf;
  return d0[i][j];
}

// a neighbour list checked every N > 1 steps is safe while no bead moves more than half the skin between
// two checks; LAMMPS counts the builds that find one did ("Dangerous builds") and carries on. Here the run
// fails at its end (Finish calls finish() after every run, one stopped by fix halt too): a too sparse
// check never passes silently, and the run watch, which names what went wrong (a blow-up moves beads
// that fast), has its say first
void PairChainBase::finish()
{
  if (neighbor->ndanger > 0 && (neighbor->every > 1 || neighbor->delay > 0))
    error->all(FLERR,
               "pair {}: {} dangerous neighbour list build(s) (a bead moved more than half the skin within "
               "the {} steps between two checks, so contacts may have been missed): check every step "
               "(neigh_modify every 1 delay 0 check yes) or give a larger skin",
               force->pair_style, neighbor->ndanger, MAX(neighbor->every, neighbor->delay));
}

template <class Law> void PairChain<Law>::compute(int eflag, int vflag)
{
  ev_init(eflag, vflag);
  double **x = atom->x;
  double **f = atom->f;
  const int *type = atom->type;
  const tagint *tag = atom->tag;
  const int nlocal = atom->nlocal;
  const int newton_pair = force->newton_pair;

  double *fc = vec(FC);
  double *fprev = vec(FPREV);
  double *fprev2 = vec(FPREV2);
  double *amax = Law::history ? vec(AMAX) : nullptr;
  double *edis = Law::history ? vec(EDIS) : nullptr;
  double *edash = damped() ? vec(EDASH) : nullptr;
  double **v = atom->v;

  if constexpr (Law::history) {
    amax_comm = amax;
    comm->forward_comm(this);    // ghosts get the owners' alpha_max of the previous step
  }

  // elapsed time of this force evaluation
  const double t = update->atime + (update->ntimestep - update->atimestep) * update->dt;
  const bool new_sample = advance_time(t);
  shift_all(new_sample, fc, fprev, fprev2);
  const PeakStep ps = peak_step(t, new_sample);
  start_active(new_sample);
  if (!sensors.empty()) start_sensors(new_sample);
  double *const sfc = sensors.empty() ? nullptr : vec(SFC);
  // every contact is tracked where the lists may not name them all: a neighbour list built this step
  // (atoms may have been sorted or exchanged: act_fprev's local indices are stale), a recomputed sample,
  // the first evaluation
  const bool track_all = peaks_all || !new_sample || neighbor->ago == 0 || !act_ready;
  act_ready = true;

  const int inum = list->inum;
  const int *ilist = list->ilist;
  const int *numneigh = list->numneigh;
  int **firstneigh = list->firstneigh;
  if (inum == 0) {
    track_peaks(ps, fc, fprev, fprev2);
    if (sfc) track_sensors(ps);
    return;
  }
  // the list's pairs in its order as one flat array (the same force sums, in the same order), made
  // again after every build of the list: the loop below reads 8 bytes a pair instead of ilist,
  // numneigh, firstneigh and the neighbour page (a chain's half list has about one pair per bead)
  if (neighbor->ago == 0 || neighbor->ncalls != pairs_ncalls) {
    pairs.clear();
    for (int ii = 0; ii < inum; ii++) {
      const int i = ilist[ii];
      const int *jlist = firstneigh[i];
      for (int jj = 0; jj < numneigh[i]; jj++) pairs.push_back(IJ{i, jlist[jj] & NEIGHMASK});
    }
    pairs_ncalls = neighbor->ncalls;
  }
  // x, f, v are contiguous n x 3 blocks: index them as such (no row pointer to load per access)
  const double(*const xx)[3] = (const double(*)[3]) x[0];
  double(*const ff)[3] = (double(*)[3]) f[0];
  const double(*const vv)[3] = (const double(*)[3]) v[0];
  const Coef *const tab = table.data();
  const int nt = atom->ntypes + 1;

  // the pair loop (a branch skips pairs out of contact: measured faster than a branch-free loop,
  // 1.2-1.3x in Pair time, benchmarks/RESULTS.md), less a square root and a
  // division for a chain along x: y and z never change there (every force is along x), so
  // r = |delx| (sqrt(x * x) == |x| in IEEE arithmetic) and the force is +-F along x. Each type pair's
  // constants are one record (init_one); with one atom type, one record for the whole loop
  const double dt = update->dt;
  const double coef = damping_coeff;
  // the damping's energy of a step: its power at the step's end (half-step velocities) times dt, as
  // the reference books it; the evaluation at t = 0 ends no step (a precompressed contact closing
  // at t = 0 has power there, which belongs to no step)
  const bool dash_tally = new_sample && t > 0.0;
  // the loop is instantiated for (one atom type or several) x (each damping part: damping_<name>.h) x
  // (energy/virial tallied this step or not): none of the three is tested per pair, and a step without
  // tallies computes no energy (the tallies come every energy sample, 1% of the steps)
  auto loop = [&](auto one_type, auto damping_part, auto tally) {
    constexpr bool ONE = decltype(one_type)::value;
    using Damping = decltype(damping_part);
    constexpr bool EV = decltype(tally)::value;
    const double(*const __restrict xq)[3] = xx;
    double(*const __restrict fq)[3] = ff;
    double *const __restrict fcq = fc;
    double *const __restrict sfq = sfc;    // (a local: a branch on a register, not on the capture)
    const Coef &cf1 = tab[nt + 1];         // types 1 1
    const double cutsq1 = cf1.cutsq;
    // the apart pairs' test before the type pair's record is looked up: no pair's cutsq is above
    // cutsq_max, so a pair it skips is one its own cutsq skips (the same decisions); with several atom
    // types (per-contact values: one type per value and residue) the lookup cost 1.4x in loop time
    // (benchmarks/bench_pair.py parts, the disorder list)
    const double cutsq_skip = ONE ? cutsq1 : cutsq_max;
    const int npairs = (int) pairs.size();
    const IJ *const pq = pairs.data();
    // the contacts written, into a buffer with room for every pair (a push_back here made the compiler
    // keep the loop's counter in memory: 1.3x slower)
    if ((int) act_fc.size() < npairs) act_fc.resize(npairs);
    int *const __restrict actq = act_fc.data();
    int nact = 0;
    for (int p = 0; p < npairs; p++) {
      const int i = pq[p].i, j = pq[p].j;
      const double delx = xq[i][0] - xq[j][0];
      // most pairs of a chain are apart or just touching: decided on x alone, the same decision as on
      // rsq (rsq = fl(fl(delx^2 + dely^2) + delz^2) >= fl(delx^2): rounding is monotone), with a
      // third of the loads and arithmetic
      if (delx * delx >= cutsq_skip) continue;
      const Coef &cf = ONE ? cf1 : tab[type[i] * nt + type[j]];
      const double cutsq = ONE ? cutsq1 : cf.cutsq;
      const double dely = xq[i][1] - xq[j][1];
      const double delz = xq[i][2] - xq[j][2];
      const double rsq = delx * delx + dely * dely + delz * delz;
      if (rsq >= cutsq) continue;
      const bool collinear = dely == 0.0 && delz == 0.0;
      const double r = collinear ? fabs(delx) : sqrt(rsq);
      const double alpha = cf.d0 - r;
      const tagint ti = tag[i], tj = tag[j];
      if (ti - tj != 1 && tj - ti != 1)
        error->one(FLERR,
                   "beads {} and {} overlap but are not neighbours in the chain: beads passed through "
                   "each other (time step too large for this load?)",
                   ti, tj);
      const int left = ti < tj ? i : j;
      double energy = 0.0;
      double *const eptr = (EV && eflag) ? &energy : nullptr;
      double fmag;
      double am = alpha;    // the largest overlap including this one (laws with history)
      if constexpr (Law::history) {
        am = MAX(amax[left], alpha);
        if (left < nlocal) {
          fmag = Law::force(alpha, am, cf.c, eptr, &edis[left]);
          amax[left] = am;
        } else {
          fmag = Law::force(alpha, am, cf.c, eptr, nullptr);
        }
      } else {
        fmag = Law::force(alpha, alpha, cf.c, EV ? eptr : nullptr, nullptr);
      }
      if constexpr (Damping::velocity) {
        // the damping part on the overlap rate: d(alpha)/dt = -dr/dt; the total force never pulls
        const double rate =
            -(delx * (vv[i][0] - vv[j][0]) + dely * (vv[i][1] - vv[j][1]) + delz * (vv[i][2] - vv[j][2])) / r;
        const double felastic = fmag;
        fmag = Damping::template force<Law>(felastic, alpha, am, cf.c, rate, coef);
        if (dash_tally && left < nlocal) edash[left] += (fmag - felastic) * rate * dt;
      }
      if (left < nlocal) {
        fcq[left] = fmag;
        actq[nact++] = left;
      }
      if (sfq) {    // each sensor bead reads half of each of its contacts (0.5 F: exact, so the sum is 0.5 (F_l + F_r))
        if (i < nlocal) sfq[i] += 0.5 * fmag;
        if (j < nlocal) sfq[j] += 0.5 * fmag;
      }
      // repulsive: pushes i away from j (newton_pair is off: init_style)
      if (collinear) {
        const double fx = delx > 0.0 ? fmag : -fmag;
        fq[i][0] += fx;
        if (j < nlocal) fq[j][0] -= fx;
      } else {
        const double fpair = fmag / r;
        fq[i][0] += delx * fpair;
        fq[i][1] += dely * fpair;
        fq[i][2] += delz * fpair;
        if (j < nlocal) {
          fq[j][0] -= delx * fpair;
          fq[j][1] -= dely * fpair;
          fq[j][2] -= delz * fpair;
        }
      }
      if constexpr (EV) ev_tally(i, j, nlocal, newton_pair, energy, 0.0, fmag / r, delx, dely, delz);
    }
    nact_fc = nact;
  };
  auto with_tally = [&](auto one_type, auto damping_part) {
    if (evflag)
      loop(one_type, damping_part, std::true_type{});
    else
      loop(one_type, damping_part, std::false_type{});
  };
  // the damping part of the pair_style line (0, "none", where it names none or a coefficient of 0)
  const int part = damped() ? damping : 0;
  auto with_damping = [&](auto one_type) {
    int k = 0;
#define GRANCHAIN_DISPATCH(D) \
  if (k++ == part) with_tally(one_type, D{});
    GRANCHAIN_DAMPING(GRANCHAIN_DISPATCH)
#undef GRANCHAIN_DISPATCH
  };
  if (atom->ntypes == 1)
    with_damping(std::true_type{});
  else
    with_damping(std::false_type{});

  // (where most contacts carry a force, the contiguous pass over all of them is the cheaper one)
  if (track_all || 2 * (nact_fc + nact_fprev) > nlocal)
    track_peaks(ps, fc, fprev, fprev2);
  else
    track_active(ps, fc, fprev, fprev2);
  if (sfc) track_sensors(ps);
  if (vflag_fdotr) virial_fdotr_compute();
}

// the stored energy of the pair and fforce = F / r, for its current overlap and the history of its left
// bead (lower ID); no damping (no velocities here); nothing is written. compute() refuses beads that
// overlap without being neighbours; single() does not look (pair_write calls it for atoms 0 and 1)
template <class Law>
double PairChain<Law>::single(int i, int j, int itype, int jtype, double rsq, double, double, double &fforce)
{
  fforce = 0.0;
  const double r = sqrt(rsq);
  const double alpha = d0[itype][jtype] - r;
  if (!(alpha > 0.0)) return 0.0;
  double c[Law::ncoeff];
  for (int m = 0; m < Law::ncoeff; m++) c[m] = coeffs[m][itype][jtype];
  double d[Law::nconst];
  Law::derive(c, d);
  double am = alpha;
  if constexpr (Law::history) am = MAX(custom("amax")[atom->tag[i] < atom->tag[j] ? i : j], alpha);
  double energy = 0.0;
  const double fmag = Law::force(alpha, am, d, &energy, nullptr);
  fforce = fmag / r;
  return energy;
}

template <class Law> void *PairChain<Law>::extract(const char *str, int &dim)
{
  dim = 2;
  if (strcmp(str, "d0") == 0) return (void *) d0;
  for (int m = 0; m < Law::ncoeff; m++)
    if (strcmp(str, Law::coeff_names[m]) == 0) return (void *) coeffs[m];
  return nullptr;
}

namespace LAMMPS_NS {
#define GRANCHAIN_INSTANTIATE(Law) template class PairChain<Law>;
GRANCHAIN_LAWS(GRANCHAIN_INSTANTIATE)
#undef GRANCHAIN_INSTANTIATE
}    // namespace LAMMPS_NS
