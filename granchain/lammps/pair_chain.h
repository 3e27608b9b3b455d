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
 *                                the dashpot energy of each contact so far
 *   pair_style chain/<law> lead floor F0   tracks the leading pulse (d_flead, d_tlead)
 *   pair_coeff I J k d0 [extras] k in N/m^1.5 (hertz, thornton) or N/m (bilinear), d0 = contact distance
 *                                (R_I + R_J), then the law's extras: beta the unloading coefficient
 *                                (bilinear), d_y the yield overlap in m (thornton).
 *
 * Each law is a header (law_<name>.h) with a struct of static inline functions:
 *   style, info                  the pair style's name and the plugin's description of it
 *   ncoeff, coeff_names          its pair_coeff numbers without d0: k first, then the extras
 *   check(c, &requirement)       the index of the first coefficient out of range (requirement: what it
 *                                must be), or -1
 *   history, vectors             whether the force depends on alpha_max (then the contact keeps d_amax
 *                                and d_edis), and those per-atom vectors' names for the error messages
 *   force(alpha, am, c, energy, dissipated)   the force at overlap alpha >= 0 with am = max(alpha_max
 *                                before this step, alpha), the history after it; writes the stored
 *                                energy and the energy dissipated so far where the pointers are not null
 * PairChain<Law> does the rest (neighbour loop, history, dashpot, peaks, communication); the kernel is
 * inlined into its loop. pair_chain.cpp instantiates it for every law and plugin.cpp registers them.
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
 *   d_flead, d_tlead   (with 'lead floor F0') the leading pulse: the first maximum of the contact's
 *            force (a sample above both neighbours, refined like the peak) that rises more than
 *            floor above F0, and its time, frozen from then on; 0 until then
 * Requires newton_pair off: a pair that straddles two ranks is computed on both, so the rank that
 * owns bead i always writes bead i's data itself; alpha_max reaches ghost copies by forward comm.
 *
 * single() (compute pair/local, pair_write) returns the pair's stored energy and F / r for the pair's
 * current overlap and the history of its left bead (lower ID), am = max(d_amax, alpha) (d_amax as it
 * is on this rank: the owner's value, or a ghost copy from the last forward comm, which lags by at most
 * the step whose alpha the max restores). It has no velocities, so it leaves out the dashpot, and it
 * changes no per-atom data.
 */

#ifndef GRANCHAIN_PAIR_CHAIN_H
#define GRANCHAIN_PAIR_CHAIN_H

#include "pair.h"

namespace LAMMPS_NS {

// what every law shares: settings, per-atom data, peak tracking, forward comm of alpha_max
class PairChainBase : public Pair {
 public:
  PairChainBase(class LAMMPS *, bool history, const char *vectors);
  ~PairChainBase() override;
  void settings(int, char **) override;
  void init_style() override;
  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;

 protected:
  const bool history;       // the law keeps alpha_max (d_amax, d_edis)
  const char *vectors;      // the law's per-atom vectors, for the error messages
  double gamma;    // dashpot coefficient, 0: none
  bool lead;       // track the leading pulse (d_flead, d_tlead): pair_style ... lead floor F0
  double lead_floor = 0.0, lead_f0 = 0.0;
  double **d0;
  double t_fc, t_fprev, t_fprev2;    // times of the current and the two previous samples
  double *amax_comm;         // the d_amax vector during forward comm
  void allocate_base();
  double *custom(const char *name);
  bool begin_sample(double t, double *fc, double *fprev, double *fprev2);
  void track_peaks(double t, bool new_sample, const double *fc, const double *fprev, const double *fprev2);
};

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
  void allocate();
};

}    // namespace LAMMPS_NS

#endif
