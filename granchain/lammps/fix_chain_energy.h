/* granchain: fix chain/energy, the deck's energy samples written through a buffer, and the run watch's
 * energy balance on the same numbers (LAMMPS plugin).
 *
 *   fix ID group chain/energy N FILE title TITLE first ATOM [dissipated CID] [extra COL ...]
 *   fix_modify ID watch BOUND WORK FMAX
 *
 * Every N steps (multiples of N, and at each run's setup on such a step, as fix print) one line of
 * %.17g numbers: time ke pe [c_CID] x[ATOM] [the extra columns], the same doubles as
 *   fix ID all print N "$(time:%.17g) $(ke:%.17g) $(pe:%.17g) [$(c_CID:%.17g)] $(x[ATOM]:%.17g) ..."
 * (ke and pe as the thermo keywords compute them: the computes thermo_temp and thermo_pe). An extra
 * column is x[ID] or v_NAME (an equal-style variable). FILE "none": no samples written (the watch
 * alone; a benchmark's deck without outputs). FILE is written with TITLE as its first line
 * when the fix is made; the lines are kept in memory and written at the end of every run, when the fix
 * is deleted (unfix, clear, an error), and before the watch stops a run: fix print flushed every line.
 *
 * watch: at every sample but a run's setup, the relative energy balance
 *   e = ke + pe [+ c_CID],  w = v_WORK,  scale = 0.5 (|w| + ke + pe + ||w| - ke - pe|)
 *   rel = (e - w) / (scale + 1e-300)
 * in the order of operations of the LAMMPS variables it replaces (templates/energy_watch.lmp.j2); when
 * |rel| > BOUND the run stops with an error "Fix chain/energy condition watch_energy met on step S with
 * value V", V = sign(rel) (the ID of the atom with the largest d_fc, compute FMAX's second value, +
 * min(|rel|, 0.999)), the value the deck's fix halt gave.
 */

#ifndef GRANCHAIN_FIX_CHAIN_ENERGY_H
#define GRANCHAIN_FIX_CHAIN_ENERGY_H

#include "fix.h"

#include <cstdio>
#include <string>
#include <vector>

namespace LAMMPS_NS {

class FixChainEnergy : public Fix {
 public:
  FixChainEnergy(class LAMMPS *, int, char **);
  ~FixChainEnergy() override;
  int setmask() override;
  int modify_param(int, char **) override;
  void init() override;
  void setup(int) override;
  void end_of_step() override;
  void post_run() override;

 private:
  enum Kind { ATOM_X, VARIABLE };
  struct Extra {
    Kind kind;
    tagint atom;         // ATOM_X
    std::string name;    // VARIABLE
    int ivar;
  };
  FILE *fp;                     // rank 0 (none with FILE none)
  std::string buffer;           // rank 0: lines not yet written
  tagint first;                 // bead 1's atom ID
  std::string dissipated_id;    // "" none
  std::vector<Extra> extras;
  bool watch;
  double bound;
  std::string work_name, fmax_id;
  int work_var;
  class Compute *temperature, *pe, *dissipated, *fmax;
  bigint next_sample;
  void sample(bool check);
  double scalar(class Compute *);
  double atom_x(tagint);
  void flush();
};

}    // namespace LAMMPS_NS

#endif
