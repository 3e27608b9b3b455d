/* granchain contact law kernel: power law (pair_style chain/power). See pair_chain.h for what a law
 * header provides; the numpy twin is granchain.physics.laws.power (tests/test_kernels.py compares
 * them through LAMMPS).
 *
 *   F = k alpha^n,  stored E = k alpha^(n+1) / (n+1),  no history, nothing dissipated.
 *   pair_coeff I J k d0 n      k in N/m^n, 1 <= n <= 3
 */

#ifndef GRANCHAIN_LAW_POWER_H
#define GRANCHAIN_LAW_POWER_H

#include <cmath>

namespace LAMMPS_NS {

struct LawPower {
  static constexpr const char *style = "chain/power";
  static constexpr const char *info = "granchain power-law contacts F = k alpha^n for 1D sphere chains";
  static constexpr int ncoeff = 2;
  static constexpr const char *coeff_names[ncoeff] = {"k", "n"};
  static constexpr bool history = false;
  static constexpr const char *vectors = "";    // per-atom vectors of the law's history

  // the first coefficient out of range (its index, *requirement says what it must be), or -1
  static int check(const double *c, const char **requirement)
  {
    if (!(c[0] > 0.0)) {
      *requirement = "must be > 0";
      return 0;
    }
    if (!(c[1] >= 1.0 && c[1] <= 3.0)) {
      *requirement = "must be in [1, 3]";
      return 1;
    }
    return -1;
  }

  // the constants force() takes, derived once per type pair from the coefficients (init_one):
  // k, n, n + 1, k / (n + 1)
  static constexpr int nconst = 4;
  static void derive(const double *c, double *d)
  {
    d[0] = c[0];
    d[1] = c[1];
    d[2] = c[1] + 1.0;
    d[3] = c[0] / (c[1] + 1.0);
  }

  // alpha >= 0 the overlap, am (unused) the largest overlap including this one, d from derive()
  static inline double force(double alpha, double /*am*/, const double *d, double *energy, double *dissipated)
  {
    if (energy) *energy = d[3] * pow(alpha, d[2]);    // k alpha^(n+1) / (n+1)
    if (dissipated) *dissipated = 0.0;
    return d[0] * pow(alpha, d[1]);
  }
};

}    // namespace LAMMPS_NS

#endif
