/* granchain damping part: none (no [damping]). See pair_chain.h for what a damping header provides;
 * the Python twin is granchain.physics.damping.none. */

#ifndef GRANCHAIN_DAMPING_NONE_H
#define GRANCHAIN_DAMPING_NONE_H

namespace LAMMPS_NS {

struct DampingNone {
  static constexpr const char *word = "none";    // (never on a pair_style line)
  static constexpr bool velocity = false;        // the force needs no velocities

  template <class Law>
  static inline double force(double felastic, double /*alpha*/, double /*am*/, const double * /*d*/, double /*rate*/,
                             double /*coeff*/)
  {
    return felastic;
  }
};

}    // namespace LAMMPS_NS

#endif
