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
  // k, n, n + 1, k / (n + 1), and m, h where n = m + h/2 is a whole or half-whole exponent (the
  // common ones: 1, 3/2, 2, 5/2, 3), m = -1 otherwise: alpha^n is then m products and one sqrt,
  // not a pow, which is what a contact in force costs (benchmarks/RESULTS.md, issue 41)
  static constexpr int nconst = 6;
  static void derive(const double *c, double *d)
  {
    d[0] = c[0];
    d[1] = c[1];
    d[2] = c[1] + 1.0;
    d[3] = c[0] / (c[1] + 1.0);
    const double twice = 2.0 * c[1];
    const bool halves = twice == std::floor(twice);
    d[4] = halves ? std::floor(c[1]) : -1.0;
    d[5] = halves ? twice - 2.0 * std::floor(c[1]) : 0.0;
  }

  // alpha^n: where n = m + h/2 is whole or half-whole (d[4] = m >= 0, m <= 3), (sqrt(alpha) or 1) times
  // (1, alpha, alpha^2 or alpha^2 alpha), each picked by index, not by a branch (g++ -O2 makes a loop or
  // conditional products into jumps, which an n changing from contact to contact can mispredict: the
  // indexed form took 0.95 of their loop time on the disorder list, benchmarks/RESULTS.md, 2026-12-03);
  // else pow. The numpy twin (PowerLaw.power) takes the same products in the same order
  static inline double power(double alpha, const double *d)
  {
    if (d[4] < 0.0) return pow(alpha, d[1]);
    const double a2 = alpha * alpha;
    const double whole[4] = {1.0, alpha, a2, a2 * alpha};
    const double half[2] = {1.0, sqrt(alpha)};
    return half[static_cast<int>(d[5])] * whole[static_cast<int>(d[4])];
  }

  // alpha >= 0 the overlap, am (unused) the largest overlap including this one, d from derive()
  static inline double force(double alpha, double /*am*/, const double *d, double *energy, double *dissipated)
  {
    if (energy) *energy = d[3] * pow(alpha, d[2]);    // k alpha^(n+1) / (n+1)
    if (dissipated) *dissipated = 0.0;
    return d[0] * power(alpha, d);
  }

  // dF/dalpha = n k alpha^(n-1) = n F / alpha at overlap alpha > 0 from the force F there (felastic,
  // force()'s), 0 apart: a division instead of a second pow (the numpy twin's damping_tangent)
  static inline double tangent(double alpha, double /*am*/, const double *d, double felastic)
  {
    return alpha > 0.0 ? d[1] * felastic / alpha : 0.0;
  }
};

}    // namespace LAMMPS_NS

#endif
