/* granchain contact law kernel: Hertz (pair_style chain/hertz). See pair_chain.h for what a law
 * header provides; the numpy twin is granchain.physics.laws.hertz (tests/test_kernels.py compares
 * them through LAMMPS).
 *
 *   F = k alpha^(3/2),  stored E = 2/5 k alpha^(5/2),  no history, nothing dissipated.
 *   pair_coeff I J k d0      k = 4/3 E* sqrt(R*) in N/m^1.5
 */

#ifndef GRANCHAIN_LAW_HERTZ_H
#define GRANCHAIN_LAW_HERTZ_H

#include <cmath>

namespace LAMMPS_NS {

struct LawHertz {
  static constexpr const char *style = "chain/hertz";
  static constexpr const char *info = "granchain Hertz contacts for 1D sphere chains";
  static constexpr int ncoeff = 1;
  static constexpr const char *coeff_names[ncoeff] = {"k"};
  static constexpr bool history = false;
  static constexpr const char *vectors = "";    // per-atom vectors of the law's history

  // the first coefficient out of range (its index, *requirement says what it must be), or -1
  static int check(const double *c, const char **requirement)
  {
    if (!(c[0] > 0.0)) {
      *requirement = "must be > 0";
      return 0;
    }
    return -1;
  }

  // the constants force() takes, derived once per type pair from the coefficients (init_one): k, 0.4 k
  static constexpr int nconst = 2;
  static void derive(const double *c, double *d)
  {
    d[0] = c[0];
    d[1] = 0.4 * c[0];
  }

  // alpha >= 0 the overlap, am (unused) the largest overlap including this one, d from derive()
  static inline double force(double alpha, double /*am*/, const double *d, double *energy, double *dissipated)
  {
    const double k = d[0];
    const double sa = sqrt(alpha);
    if (energy) *energy = d[1] * alpha * alpha * sa;    // 0.4 k alpha^2 sqrt(alpha)
    if (dissipated) *dissipated = 0.0;
    return k * alpha * sa;
  }

  // dF/dalpha at overlap alpha >= 0 (the damping parts' tangent; the numpy twin's overlap_tangent)
  static inline double tangent(double alpha, double /*am*/, const double *d, double /*felastic*/)
  {
    return 1.5 * d[0] * sqrt(alpha);
  }
};

}    // namespace LAMMPS_NS

#endif
