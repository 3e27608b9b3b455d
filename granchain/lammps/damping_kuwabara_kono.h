/* granchain damping part: viscoelastic Kuwabara-Kono damping (pair_style chain/<law> kuwabara_kono A).
 * See pair_chain.h for what a damping header provides; the Python twin is
 * granchain.physics.damping.kuwabara_kono.
 *
 *   F = max(F_law + A dF_law/dalpha d(alpha)/dt, 0) while beads overlap, A in s; dF/dalpha is the
 *   law's tangent of the branch in force (Law::tangent), for Hertz 3/2 k sqrt(alpha)
 */

#ifndef GRANCHAIN_DAMPING_KUWABARA_KONO_H
#define GRANCHAIN_DAMPING_KUWABARA_KONO_H

namespace LAMMPS_NS {

struct DampingKuwabara_kono {
  static constexpr const char *word = "kuwabara_kono";
  static constexpr bool velocity = true;

  template <class Law>
  static inline double force(double felastic, double alpha, double am, const double *d, double rate, double a)
  {
    const double f = felastic + a * Law::tangent(alpha, am, d, felastic) * rate;    // the total never pulls
    return f > 0.0 ? f : 0.0;
  }
};

}    // namespace LAMMPS_NS

#endif
