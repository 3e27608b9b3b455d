/* granchain: fix chain/nve, velocity Verlet along x only, for a chain along x (LAMMPS plugin).
 *
 *   fix ID group chain/nve       the same updates as fix nve on the x components (the same expressions,
 *                                so the same numbers), none on y and z; at setup it refuses a group atom
 *                                with a y or z velocity or force (then fix nve is the one to use)
 * Run ahead: when nothing looks at the atoms between a step's end and the next step's first half-kick
 * (not the run's last step, no output and no end-of-step fix due, no timer timeout, no other fix that
 * integrates), final_integrate also does the next step's half-kick and drift in the same pass and the
 * next initial_integrate does nothing: the same expressions on the same forces, so the same doubles.
 */

#ifndef GRANCHAIN_FIX_CHAIN_NVE_H
#define GRANCHAIN_FIX_CHAIN_NVE_H

#include "fix.h"

#include <vector>

namespace LAMMPS_NS {

class FixChainNVE : public Fix {
 public:
  FixChainNVE(class LAMMPS *, int, char **);
  int setmask() override;
  void init() override;
  void setup(int) override;
  void initial_integrate(int) override;
  void final_integrate() override;
  void reset_dt() override;

 private:
  double dtv, dtf;
  std::vector<double> dtfm;    // dtf / m per owned atom, as of the neighbour build cached_ncalls
  bigint cached_ncalls;
  int cached_nlocal;
  double cached_dtf;
  bool ahead;                              // the next step's initial_integrate was done by this step's final_integrate
  std::vector<const Fix *> end_of_step;    // the fixes with end_of_step, as of setup
  bool can_run_ahead() const;
  void refresh();
  void refresh_if_stale();
};

}    // namespace LAMMPS_NS

#endif
