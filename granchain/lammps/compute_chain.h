/* granchain: computes for the run watch of a chain deck (LAMMPS plugin).
 *
 *   compute ID group chain/fmax       global vector of 2: the largest d_fc of the group's atoms and the
 *                                     ID of the atom holding it; the same numbers as
 *                                       variable fc atom d_fc
 *                                       variable id atom id
 *                                       compute ID group reduce max v_fc v_id replace 2 1
 *                                     in one pass over the atoms, without the atom-style variables'
 *                                     per-atom expression evaluation
 *   compute ID group chain/fmax name  the same with d_fc / d_name, each contact's force over its own
 *                                     bound (a per-atom vector of fix property/atom): the numbers of
 *                                       variable fc atom d_fc/d_name
 *                                     and the rest as above
 *   compute ID group chain/momentum   global scalar: sum of mass * vx over the group (as compute reduce
 *                                     sum of 'variable mv atom mass*vx')
 */

#ifndef GRANCHAIN_COMPUTE_CHAIN_H
#define GRANCHAIN_COMPUTE_CHAIN_H

#include "compute.h"

#include <string>

namespace LAMMPS_NS {

class ComputeChainFmax : public Compute {
 public:
  ComputeChainFmax(class LAMMPS *, int, char **);
  ~ComputeChainFmax() override;
  void init() override;
  void compute_vector() override;

 private:
  int index;                 // d_fc in atom->dvector
  int bound_index;           // the bounds' vector in atom->dvector, -1: none
  std::string bound_name;    // its name (d_<name>), empty: none
};

class ComputeChainMomentum : public Compute {
 public:
  ComputeChainMomentum(class LAMMPS *, int, char **);
  void init() override;
  double compute_scalar() override;
};

}    // namespace LAMMPS_NS

#endif
