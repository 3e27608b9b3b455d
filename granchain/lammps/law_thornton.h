/* granchain contact law kernel: Thornton (1997) elastic-perfectly-plastic spheres
 * (pair_style chain/thornton). See pair_chain.h for what a law header provides; the numpy twin is
 * granchain.physics.laws.thornton (tests/test_kernels.py compares them through LAMMPS).
 *
 *   pair_coeff I J k d0 d_y      k = 4/3 E* sqrt(R*) in N/m^1.5, d_y > 0 the yield overlap in m
 *   history am = alpha_max, the largest overlap so far (including this step)
 *   Fy = k d_y^(3/2) the yield force, S = 3/2 k d_y^(1/2) = pi p_y R* the plastic slope (the Hertz
 *   slope at d_y, so the virgin curve has a continuous slope).
 *   am <= d_y (elastic): F = k alpha^(3/2), stored E = 2/5 k alpha^(5/2), nothing dissipated.
 *   am >  d_y: the virgin curve at am is Fmax = Fy + S (am - d_y); un/reloading is Hertz with the
 *     enlarged radius R_p = R* (Fy/Fmax) ((2 Fmax + Fy) / (3 Fy))^(3/2), kp = k sqrt(R_p/R*), from the
 *     residual overlap dp = am - (Fmax/kp)^(2/3):  s = alpha - dp,  F = kp s^(3/2) (0 for s <= 0),
 *     stored E = 2/5 F s, dissipated W(am) - 2/5 Fmax (am - dp) with W(am) = 2/5 k d_y^(5/2)
 *     + Fy (am - d_y) + S/2 (am - d_y)^2 the work along the virgin curve.
 *   At alpha = am the un/reloading curve gives Fmax, so one expression serves loading and unloading.
 */

#ifndef GRANCHAIN_LAW_THORNTON_H
#define GRANCHAIN_LAW_THORNTON_H

#include <cmath>

namespace LAMMPS_NS {

struct LawThornton {
  static constexpr const char *style = "chain/thornton";
  static constexpr const char *info = "granchain Thornton elastic-perfectly-plastic contacts for 1D sphere chains";
  static constexpr int ncoeff = 2;
  static constexpr const char *coeff_names[ncoeff] = {"k", "d_y"};
  static constexpr bool history = true;
  static constexpr const char *vectors = "d_amax d_edis";

  static int check(const double *c, const char **requirement)
  {
    if (!(c[0] > 0.0)) {
      *requirement = "must be > 0";
      return 0;
    }
    if (!(c[1] > 0.0)) {
      *requirement = "must be > 0";
      return 1;
    }
    return -1;
  }

  // the constants force() takes, derived once per type pair (init_one; the same expressions as before,
  // so the same doubles): k, d_y, 0.4 k, sqrt(d_y), Fy = k d_y sqrt(d_y), S = 1.5 k sqrt(d_y), 3 Fy, S / 2,
  // 0.4 k d_y^2 sqrt(d_y) (the virgin curve's elastic work)
  static constexpr int nconst = 9;
  enum { K, DY, K04, SY, FY, SLOPE, FY3, HSLOPE, W0 };
  static void derive(const double *c, double *d)
  {
    const double k = c[0], dy = c[1];
    d[K] = k;
    d[DY] = dy;
    d[K04] = 0.4 * k;
    d[SY] = sqrt(dy);
    d[FY] = k * dy * d[SY];
    d[SLOPE] = 1.5 * k * d[SY];
    d[FY3] = 3.0 * d[FY];
    d[HSLOPE] = 0.5 * d[SLOPE];
    d[W0] = 0.4 * k * dy * dy * d[SY];
  }

  static inline double force(double alpha, double am, const double *c, double *energy, double *dissipated)
  {
    const double k = c[K], dy = c[DY];
    if (am <= dy) {
      const double sa = sqrt(alpha);
      if (energy) *energy = c[K04] * alpha * alpha * sa;
      if (dissipated) *dissipated = 0.0;
      return k * alpha * sa;
    }
    const double fy = c[FY];
    const double slope = c[SLOPE];
    const double da = am - dy;
    const double fmax = fy + slope * da;
    // pow(x, 1.5) as x sqrt(x) and pow(y, 2/3) as cbrt(y^2): the same values to an ulp, and a chain of
    // plastic contacts 86 -> 68 ns per bead-step (Hertz: 23)
    const double x = (2.0 * fmax + fy) / c[FY3];
    const double kp = k * sqrt((fy / fmax) * (x * sqrt(x)));
    const double y = fmax / kp;
    // d_p >= 0: just above d_y round-off can put am - (Fmax/kp)^(2/3) a few ulps below 0, which would
    // leave a force at zero overlap (the numpy twin clips the same way)
    const double dp0 = am - cbrt(y * y);
    const double dp = dp0 > 0.0 ? dp0 : 0.0;
    const double s = alpha - dp;
    const double f = s > 0.0 ? kp * s * sqrt(s) : 0.0;
    if (energy) *energy = s > 0.0 ? 0.4 * f * s : 0.0;
    if (dissipated) *dissipated = c[W0] + fy * da + c[HSLOPE] * da * da - 0.4 * fmax * (am - dp);
    return f;
  }

  // dF/dalpha of the branch in force (the numpy twin's overlap_tangent): the plastic slope S on the
  // virgin plastic line (alpha = am > d_y), else the un/reloading Hertz curve's 3/2 k_p sqrt(alpha - d_p)
  static inline double tangent(double alpha, double am, const double *c, double /*felastic*/)
  {
    const double k = c[K], dy = c[DY];
    if (am <= dy) return 1.5 * k * sqrt(alpha);
    if (alpha >= am && alpha > 0.0) return c[SLOPE];
    const double fy = c[FY];
    const double fmax = fy + c[SLOPE] * (am - dy);
    const double x = (2.0 * fmax + fy) / c[FY3];
    const double kp = k * sqrt((fy / fmax) * (x * sqrt(x)));
    const double y = fmax / kp;
    const double dp0 = am - cbrt(y * y);
    const double s = alpha - (dp0 > 0.0 ? dp0 : 0.0);
    return s > 0.0 ? 1.5 * kp * sqrt(s) : 0.0;
  }
};

}    // namespace LAMMPS_NS

#endif
