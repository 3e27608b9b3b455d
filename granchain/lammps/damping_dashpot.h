/* granchain damping part: a linear dashpot (pair_style chain/<law> dashpot gamma). See pair_chain.h
 * for what a damping header provides; the Python twin is granchain.physics.damping.dashpot.
 *
 *   F = max(F_law + gamma d(alpha)/dt, 0) while beads overlap, gamma in N s/m
 */

#ifndef GRANCHAIN_DAMPING_DASHPOT_H
#define GRANCHAIN_DAMPING_DASHPOT_H

namespace LAMMPS_NS {

struct DampingDashpot {
  static constexpr const char *word = "dashpot";
  static constexpr bool velocity = true;

  template <class Law>
  static inline double force(double felastic, double /*alpha*/, double /*am*/, const double * /*d*/, double rate,
                             double gamma)
  {
    const double f = felastic + gamma * rate;    // the total never pulls
    return f > 0.0 ? f : 0.0;
  }
};

}    // namespace LAMMPS_NS

#endif
