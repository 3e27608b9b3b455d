/* granchain: fix chain/history, the history contacts' force and velocity in memory, one binary file per
 * run's end (LAMMPS plugin).
 *
 *   fix ID group chain/history N file.npy
 *       every N steps (on the steps a 'dump ID group custom N ...' writes: multiples of N, each step
 *       once, the first run's setup included) the d_fc and vx of the group's atoms, kept in memory; at
 *       the end of every run (and, on one rank, when the fix is deleted: after a run stopped by an error)
 *       all samples so far are written to file.npy: a NumPy .npy file of float64, shape (1 + frames,
 *       1 + 2 n) for the group's n atoms in ID order:
 *         row 0:       n, the n atom IDs, the n atom IDs again
 *         row 1 + k:   step of sample k, d_fc of the n atoms, vx of the n atoms
 *       The file is written under file.npy.part and renamed: a file.npy is always whole. The same doubles
 *       as 'dump custom ... id d_fc vx' with %.17g (granchain.postprocess.histories reads both).
 *       The group's atoms are looked up by ID (atom_modify map), not by a pass over all atoms: a sample
 *       costs O(n), whatever the chain's length.
 */

#ifndef GRANCHAIN_FIX_CHAIN_HISTORY_H
#define GRANCHAIN_FIX_CHAIN_HISTORY_H

#include "fix.h"

#include <string>
#include <vector>

namespace LAMMPS_NS {

class FixChainHistory : public Fix {
 public:
  FixChainHistory(class LAMMPS *, int, char **);
  ~FixChainHistory() override;
  int setmask() override;
  void init() override;
  void setup(int) override;
  void end_of_step() override;
  void post_run() override;

 private:
  std::string file;
  int index;                      // d_fc in atom->dvector
  std::vector<tagint> ids;        // the group's atom IDs, sorted: the slots of a sample
  std::vector<double> steps;      // the sampled steps
  std::vector<double> records;    // this rank's samples: (frame, slot, d_fc, vx) per owned slot
  bigint last_step;               // the last sampled step (-1: none)
  bigint written_frames;          // frames in the file written last (-1: none yet)
  void sample();
  void write();
};

}    // namespace LAMMPS_NS

#endif
