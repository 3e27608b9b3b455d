/* granchain contact law kernel: bilinear elastoplastic, Walton-Braun (pair_style chain/bilinear).
 * See pair_chain.h for what a law header provides; the numpy twin is granchain.physics.laws.bilinear
 * (tests/test_kernels.py compares them through LAMMPS).
 *
 *   history am = alpha_max, the largest overlap so far (including this step)
 *   loading F = k alpha (alpha = am), un/reloading F = k_u (alpha - beta am) >= 0, k_u = k / (1 - beta);
 *   stored E = k_u/2 (alpha - beta am)^2, dissipated beta k am^2 / 2 (paper Eq. 20).
 *   pair_coeff I J k d0 beta      k in N/m, 0 <= beta < 1
 */

#ifndef GRANCHAIN_LAW_BILINEAR_H
#define GRANCHAIN_LAW_BILINEAR_H

namespace LAMMPS_NS {

struct LawBilinear {
  static constexpr const char *style = "chain/bilinear";
  static constexpr const char *info = "granchain bilinear (Walton-Braun) elastoplastic contacts for 1D sphere chains";
  static constexpr int ncoeff = 2;
  static constexpr const char *coeff_names[ncoeff] = {"k", "beta"};
  static constexpr bool history = true;
  static constexpr const char *vectors = "d_amax d_edis";

  static int check(const double *c, const char **requirement)
  {
    if (!(c[0] > 0.0)) {
      *requirement = "must be > 0";
      return 0;
    }
    if (!(c[1] >= 0.0 && c[1] < 1.0)) {
      *requirement = "must be in [0, 1)";
      return 1;
    }
    return -1;
  }

  // the constants force() takes, derived once per type pair (init_one): beta, k_u = k / (1 - beta),
  // k_u / 2, beta k / 2 (the same expressions as before, so the same doubles), k (the loading tangent)
  static constexpr int nconst = 5;
  static void derive(const double *c, double *d)
  {
    const double k = c[0], b = c[1];
    d[0] = b;
    d[1] = k / (1.0 - b);
    d[2] = 0.5 * d[1];
    d[3] = 0.5 * b * k;
    d[4] = k;
  }

  static inline double force(double alpha, double am, const double *c, double *energy, double *dissipated)
  {
    const double b = c[0], ku = c[1];
    const double d = alpha - b * am;
    if (energy) *energy = d > 0.0 ? c[2] * d * d : 0.0;
    if (dissipated) *dissipated = c[3] * am * am;
    return d > 0.0 ? ku * d : 0.0;
  }

  // dF/dalpha of the branch in force (the numpy twin's overlap_tangent): k on the loading line
  // (alpha = am), k_u while un/reloading with a force, 0 apart
  static inline double tangent(double alpha, double am, const double *c, double /*felastic*/)
  {
    if (!(alpha > 0.0)) return 0.0;
    if (alpha >= am) return c[4];
    return alpha - c[0] * am > 0.0 ? c[1] : 0.0;
  }
};

}    // namespace LAMMPS_NS

#endif
