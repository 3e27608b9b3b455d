/* granchain: normal contact pair styles for 1D chains of spheres (LAMMPS plugin).
 *
 *   pair_style chain/hertz       F = k alpha^(3/2),            E = 2/5 k alpha^(5/2)      (law_hertz.h)
 *   pair_style chain/bilinear    Walton-Braun elastoplastic law with history alpha_max:   (law_bilinear.h)
 *                                loading F = k alpha, un/reloading F = k_u (alpha - beta alpha_max) >= 0,
 *                                k_u = k / (1 - beta); stored E = k_u/2 (alpha - beta alpha_max)^2,
 *                                dissipated beta k alpha_max^2 / 2 (paper Eq. 20).
 *   pair_style chain/thornton    Thornton (1997) elastic-perfectly-plastic spheres with   (law_thornton.h)
 *                                history alpha_max and yield overlap d_y
 *   pair_style chain/<law> dashpot gamma   adds gamma * d(alpha)/dt while beads overlap (the total
 *                                never pulls); needs 'comm_modify vel yes' and the vector d_edash,
 *                                the damping energy of each contact so far (damping_dashpot.h)
 *   pair_style chain/<law> kuwabara_kono A   adds A * dF/dalpha * d(alpha)/dt (Kuwabara-Kono), the same
 *                                way (damping_kuwabara_kono.h); one damping part at a time
 *   pair_style chain/<law> lead floor F0 [fall R]   tracks the leading pulse (d_flead, d_tlead); fall R: a
 *                                maximum counts once the force has fallen R below it (default 0)
 *   pair_style chain/<law> lead floor F0 ladder P S   also records each contact's crossing-time ladder
 *                                (d2_ladder: P rungs per octave above F0 + floor, the last S kept)
 *   pair_style chain/<law> sensors K id1 .. idK   tracks the sensor beads' (atom IDs) average force
 *                                (F_left + F_right) / 2 of their two contacts (a striker's and a wall's
 *                                count; a missing one is 0) in d_sfc and its running peak like a contact's:
 *                                d_sprev d_sprev2 d_speak d_stpeak d_sfmin (postprocess.sensors)
 *   pair_style chain/<law> peaks all   runs every contact's peak bookkeeping every step instead of only the
 *                                contacts written at this sample or the previous one (the same numbers,
 *                                slower: a check of the shortcut, tests/test_peak_tracking.py)
 *   pair_coeff I J k d0 [extras] k in N/m^1.5 (hertz, thornton) or N/m (bilinear), d0 = contact distance
 *                                (R_I + R_J), then the law's extras: beta the unloading coefficient
 *                                (bilinear), d_y the yield overlap in m (thornton).
 *
 * Each law is a header (law_<name>.h) with a struct of static inline functions:
 *   style, info                  the pair style's name and the plugin's description of it
 *   ncoeff, coeff_names          its pair_coeff numbers without d0: k first, then the extras
 *   check(c, &requirement)       the index of the first coefficient out of range (requirement: what it
 *                                must be), or -1
 *   nconst, derive(c, d)         the nconst constants force() takes, derived from the coefficients once per
 *                                type pair (init_one)
 *   history, vectors             whether the force depends on alpha_max (then the contact keeps d_amax
 *                                and d_edis), and those per-atom vectors' names for the error messages
 *   force(alpha, am, d, energy, dissipated)   the force at overlap alpha >= 0 (d from derive) with am = max(alpha_max
 *                                before this step, alpha), the history after it; writes the stored
 *                                energy and the energy dissipated so far where the pointers are not null
 *   tangent(alpha, am, d, f)     dF/dalpha of the branch in force (the damping parts read it), f the
 *                                force() there (a law may derive the tangent from it)
 * Each damping part is a header (damping_<name>.h) with a struct: word (its pair_style word), velocity
 * (its force needs the overlap rate) and force<Law>(felastic, alpha, am, d, rate, coeff), the damped
 * total, never negative. PairChain<Law> does the rest (neighbour loop, history, damping, peaks,
 * communication); the kernels are inlined into its loop, which is instantiated for each <Law, Damping>.
 * pair_chain.cpp instantiates it for every law and plugin.cpp registers them.
 *
 * Contact i joins the beads with IDs i and i+1; its per-contact data live on bead i in per-atom
 * custom vectors created by  fix ID all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak
 * [d_amax d_edis] d_fmin ghost yes:
 *   d_fc     force of the contact at the current step (readable by dump custom / computes)
 *   d_fprev, d_fprev2   the two previous samples (for the peak refinement)
 *   d_fpeak, d_tpeak    running peak force and its time, refined by a parabola through three samples
 *   d_fmin   smallest force sample since the peak (restarted by every new peak): the peak is complete
 *            once it has fallen far enough (granchain.results.complete_peaks)
 *   d_amax   largest overlap so far, d_edis  energy dissipated so far (laws with history)
 *   d_flead, d_tlead   (with 'lead floor F0 [fall R]') the leading pulse: the first maximum of the
 *            contact's force (a sample above both neighbours, refined like the peak) that rises more
 *            than floor above F0 and that the force then falls R below before it rises above it (a
 *            higher maximum takes its place), and its time, frozen from then on; 0 until then (-1
 *            while a maximum waits for the fall)
 *   d2_ladder (with 'ladder P S', fix ID all property/atom d2_ladder S+1) the crossing-time ladder:
 *            [rungs crossed, the last S rungs' crossing times], rungs F0 + floor * 2^(k/P) (climb)
 * The neighbour list may be checked every N > 1 steps (neigh_modify every N delay 0 check yes): a run
 * with a dangerous build (a bead moved more than half the skin between two checks), which LAMMPS only
 * counts, fails at its end.
 * Requires newton_pair off: a pair that straddles two ranks is computed on both, so the rank that
 * owns bead i always writes bead i's data itself; alpha_max reaches ghost copies by forward comm.
 *
 * single() (compute pair/local, pair_write) returns the pair's stored energy and F / r for the pair's
 * current overlap and the history of its left bead (lower ID), am = max(d_amax, alpha) (d_amax as it
 * is on this rank: the owner's value, or a ghost copy from the last forward comm, which lags by at most
 * the step whose alpha the max restores). It has no velocities, so it leaves out the damping, and it
 * changes no per-atom data.
 */

#ifndef GRANCHAIN_PAIR_CHAIN_H
#define GRANCHAIN_PAIR_CHAIN_H

#include "atom.h"
#include "pair.h"

#include <vector>

namespace LAMMPS_NS {

// what every law shares: settings, per-atom data, peak tracking, forward comm of alpha_max
class PairChainBase : public Pair {
 public:
  PairChainBase(class LAMMPS *, bool history, const char *vectors);
  ~PairChainBase() override;
  void settings(int, char **) override;
  void init_style() override;
  void finish() override;
  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;

 protected:
  const bool history;      // the law keeps alpha_max (d_amax, d_edis)
  const char *vectors;     // the law's per-atom vectors, for the error messages
  int damping;             // the damping part: its index in GRANCHAIN_DAMPING (0: none)
  double damping_coeff;    // its coefficient (dashpot gamma N s/m, Kuwabara-Kono A s), 0: none
  bool damped() const { return damping > 0 && damping_coeff > 0.0; }
  bool lead;                      // track the leading pulse (d_flead, d_tlead): pair_style ... lead floor F0
  bool peaks_all;                 // 'peaks all': every contact's peak bookkeeping every step (a check of track_active)
  std::vector<tagint> sensors;    // 'sensors K id..': the sensor beads' atom IDs
  double lead_floor = 0.0, lead_f0 = 0.0;
  double lead_fall = 0.0;    // the fall below a maximum that makes it the leading pulse: pair_style ... fall R
  int ladder_per_octave = 0, ladder_slots = 0;    // the crossing-time ladder: pair_style ... ladder P S
  int ladder_idx = -1;                            // d2_ladder in atom->darray
  double **d0;
  double t_fc, t_fprev, t_fprev2;    // times of the current and the two previous samples
  double *amax_comm;                 // the d_amax vector during forward comm
  // the per-atom vectors, by their indices in atom->dvector (looked up once per run in init_style)
  enum {
    FC,
    FPREV,
    FPREV2,
    FPEAK,
    TPEAK,
    FMIN,
    FLEAD,
    TLEAD,
    AMAX,
    EDIS,
    EDASH,
    SFC,
    SPREV,
    SPREV2,
    SPEAK,
    STPEAK,
    SFMIN,
    NVEC
  };
  int idx[NVEC];
  double *vec(int k) const { return atom->dvector[idx[k]]; }
  void allocate_base();
  int index_of(const char *name);
  double *custom(const char *name);
  bool advance_time(double t);
  void shift_all(bool new_sample, double *&fc, double *&fprev, double *&fprev2);

  // the peak bookkeeping of one step: sample times, whether to refine, the per-atom vectors
  struct PeakStep {
    double t, a, b, det;
    bool refine;
    bool lead;    // the leading pulse's bookkeeping (flead, tlead): contacts with 'lead', never sensors
    double *fpeak, *tpeak, *fmin, *flead, *tlead;
    double **ladder;    // d2_ladder rows, or null without 'ladder'
  };
  PeakStep peak_step(double t, bool new_sample);
  void track_peaks(const PeakStep &ps, const double *fc, const double *fprev, const double *fprev2);
  void start_sensors(bool new_sample);
  void track_sensors(const PeakStep &contacts);
  void climb(const PeakStep &ps, int i, const double *fc, const double *fprev) const;
  // the owned contacts the pair loop wrote a force for at this sample (act_fc) and at the previous one
  // (act_fprev), by local index: every other contact has fc = fprev = 0 and nothing to track
  // (track_active). act_fprev is usable while the local indices stay those of the previous sample
  // (no neighbour list build since): act_ready
  std::vector<int> act_fc, act_fprev;    // the first nact_fc, nact_fprev entries
  int nact_fc = 0, nact_fprev = 0;
  struct IJ {
    int i, j;
  };
  std::vector<IJ> pairs;       // the neighbour list's pairs (i, j), in its order
  bigint pairs_ncalls = -1;    // neighbor->ncalls when pairs was made
  bool act_ready = false;
  void start_active(bool new_sample);
  void track_active(const PeakStep &ps, const double *fc, const double *fprev, const double *fprev2);
  __attribute__((always_inline)) inline void track_one(const PeakStep &ps, int i, const double *fc, const double *fprev,
                                                       const double *fprev2);
};

// running peak of owned contact i: the largest sample, refined by the vertex of the parabola
// through the last three samples when the middle one is a local maximum; and the smallest sample
// since the peak (granchain.results.complete_peaks), restarted by every new peak
__attribute__((always_inline)) inline void PairChainBase::track_one(const PeakStep &ps, int i, const double *fc,
                                                                    const double *fprev, const double *fprev2)
{
  double *fpeak = ps.fpeak, *tpeak = ps.tpeak, *fmin = ps.fmin;
  fmin[i] = MIN(fmin[i], fc[i]);
  // a rung not crossed yet lies above every sample and every refined maximum so far (climb), so only a
  // sample at or above the running peak can cross one: the ladder costs one comparison otherwise
  if (ps.ladder && fc[i] >= fpeak[i] && ps.flead[i] <= 0.0) climb(ps, i, fc, fprev);
  if (fc[i] > fpeak[i]) {
    fpeak[i] = fc[i];
    tpeak[i] = ps.t;
    fmin[i] = fc[i];
  }
  if (ps.refine && fprev[i] > fc[i] && fprev[i] >= fprev2[i] && fprev[i] > 0.0) {
    // the middle sample is a local maximum: its value is the vertex of the parabola through the
    // three samples where that opens downwards, else the sample itself
    const double a = ps.a, b = ps.b;
    const double fa = fprev2[i] - fprev[i], fb = fc[i] - fprev[i];
    const double c1 = (fa * b * b - fb * a * a) / ps.det;
    const double c2 = (a * fb - b * fa) / ps.det;
    if (c2 < 0.0) {
      const double s = MIN(MAX(-c1 / (2.0 * c2), a), b);
      const double val = fprev[i] + (c1 + c2 * s) * s;
      if (val > fpeak[i]) {
        fpeak[i] = val;
        tpeak[i] = t_fprev + s;
        fmin[i] = fc[i];    // the refined peak lies before this sample
      }
    }
    // a maximum that rises more than lead_floor above F0 is the leading pulse's candidate
    // (flead = -1: waiting for the fall). At the first one the running peak is that maximum (before
    // it the force only rose), refined as above
    if (ps.lead && ps.flead[i] == 0.0 && fpeak[i] - lead_f0 > lead_floor) ps.flead[i] = -1.0;
  }
  // the leading pulse (granchain.peaks.leading_pulse): the candidate is the running peak (a later
  // rise above it moves it on), frozen once the force has fallen lead_fall below it (the force
  // resolution: round-off on a slow rise makes no maximum that counts); flead = 0 until a candidate,
  // -1 while it waits, then the frozen value (> F0 + floor > 0). lead_fall = 0: frozen at the maximum
  // itself (fc <= fpeak always)
  if (ps.lead && ps.flead[i] < 0.0 && fc[i] <= fpeak[i] - lead_fall) {
    ps.flead[i] = fpeak[i];
    ps.tlead[i] = tpeak[i];
  }
}

template <class Law> class PairChain : public PairChainBase {
 public:
  PairChain(class LAMMPS *);
  ~PairChain() override;
  void compute(int, int) override;
  void coeff(int, char **) override;
  double init_one(int, int) override;
  double single(int, int, int, int, double, double, double, double &) override;
  void *extract(const char *, int &) override;

 protected:
  double **coeffs[Law::ncoeff];    // the law's pair_coeff numbers per type pair, k first
  struct Coef {
    double cutsq, d0, c[Law::nconst];    // c: the law's constants (Law::derive)
  };
  std::vector<Coef> table;    // per type pair (itype * (ntypes + 1) + jtype), filled by init_one
  double cutsq_max = 0.0;     // the largest cutsq in table (init_one): no pair at or beyond it is in contact
  void allocate();
};

}    // namespace LAMMPS_NS

#endif
