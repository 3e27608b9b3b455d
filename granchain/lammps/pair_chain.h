/* granchain: normal contact pair styles for 1D chains of spheres (LAMMPS plugin).
 *
 *   pair_style chain/hertz       F = k alpha^(3/2),            E = 2/5 k alpha^(5/2)
 *   pair_style chain/bilinear    Walton-Braun elastoplastic law with history alpha_max:
 *                                loading F = k alpha, un/reloading F = k_u (alpha - beta alpha_max) >= 0,
 *                                k_u = k / (1 - beta); stored E = k_u/2 (alpha - beta alpha_max)^2,
 *                                dissipated beta k alpha_max^2 / 2 (paper Eq. 20).
 *   pair_style chain/<law> dashpot gamma   adds gamma * d(alpha)/dt while beads overlap (the total
 *                                never pulls); needs 'comm_modify vel yes' and the vector d_edash,
 *                                the dashpot energy of each contact so far
 *   pair_style chain/<law> lead floor F0   tracks the leading pulse (d_flead, d_tlead)
 *   pair_coeff I J k d0 [beta]   k in N/m^1.5 (hertz) or N/m (bilinear), d0 = contact distance
 *                                (R_I + R_J), beta the unloading coefficient (bilinear only).
 *
 * Contact i joins the beads with IDs i and i+1; its per-contact data live on bead i in per-atom
 * custom vectors created by  fix ID all property/atom d_fc d_fprev d_fprev2 d_fpeak d_tpeak
 * [d_amax d_edis] d_fmin ghost yes:
 *   d_fc     force of the contact at the current step (readable by dump custom / computes)
 *   d_fprev, d_fprev2   the two previous samples (for the peak refinement)
 *   d_fpeak, d_tpeak    running peak force and its time, refined by a parabola through three samples
 *   d_fmin   smallest force sample since the peak (restarted by every new peak): the peak is complete
 *            once it has fallen far enough (granchain.results.complete_peaks)
 *   d_amax   largest overlap so far (bilinear history), d_edis  energy dissipated so far (bilinear)
 *   d_flead, d_tlead   (with 'lead floor F0') the leading pulse: the first maximum of the contact's
 *            force (a sample above both neighbours, refined like the peak) that rises more than
 *            floor above F0, and its time, frozen from then on; 0 until then
 * Requires newton_pair off: a pair that straddles two ranks is computed on both, so the rank that
 * owns bead i always writes bead i's data itself; alpha_max reaches ghost copies by forward comm.
 */

#ifndef GRANCHAIN_PAIR_CHAIN_H
#define GRANCHAIN_PAIR_CHAIN_H

#include "pair.h"

namespace LAMMPS_NS {

class PairChain : public Pair {
 public:
  PairChain(class LAMMPS *, bool bilinear);
  ~PairChain() override;
  void compute(int, int) override;
  void settings(int, char **) override;
  void coeff(int, char **) override;
  void init_style() override;
  double init_one(int, int) override;
  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  void *extract(const char *, int &) override;

 protected:
  bool bilinear;
  double gamma;    // dashpot coefficient, 0: none
  bool lead;       // track the leading pulse (d_flead, d_tlead): pair_style ... lead floor F0
  double lead_floor = 0.0, lead_f0 = 0.0;
  double **kcoeff, **d0, **beta;
  double t_fc, t_fprev, t_fprev2;    // times of the current and the two previous samples
  double *amax_comm;         // the d_amax vector during forward comm
  void allocate();
  double *custom(const char *name);
};

}    // namespace LAMMPS_NS

#endif
