/* granchain: fix chain/event, the far-end wall's event quantities at every step (LAMMPS plugin).
 *
 *   fix ID all chain/event CHECK WALL_ATOM FS FLOOR HELD LOAD_END [track K ID1 KIND1 .. IDK KINDK]
 *
 * After every step (end_of_step) the wall's contact force F (d_fc of WALL_ATOM, bead N's atom: the
 * wall's contact lives on it) and bead N's vx v, summed as granchain.physics.event.EventSums does, in
 * the same order: trapezoids of F (the impulse), of F - FS (the dynamic impulse) and of
 * (F - FS) max(v, 0) (the energy into the wall's contact), and the running maximum of F refined by
 * the vertex of the parabola through three samples around a local maximum. Every CHECK steps (on
 * multiples of CHECK) the event's end: the maximum rose above FS by FLOOR, and then, HELD = 0 (an
 * unloaded chain), after LOAD_END, with the wall's contact open (F <= 0): a group holding every closed
 * contact whose energy keeps it from ever catching the free bodies around it or the wall
 * (granchain.physics.event.left_for_good, the same arithmetic:
 * the atoms up to WALL_ATOM by ID, the wall left out; the stored energy the compute thermo_pe's,
 * tallied on every check step); HELD = 1 (a chain pressed on the wall), after every step: F - FS crossed 0
 * in the step, v <= 0 and the total momentum sum m vx <= 0, the end the interpolated crossing and the
 * step's trapezoids cut there. From then on nothing changes. The first run's setup takes the t = 0 sample;
 * a later run's setup (the same state) takes none.
 *
 * track: K more forces whose running maximum over the event is kept as the wall's is (the same samples,
 * the same parabola; granchain.physics.event.EventMaxima, [outputs] event_max_contacts and
 * event_max_sensors): atom IDk's d_fc (KINDk = 0, the contact it carries) or d_sfc (KINDk = 1, a sensor
 * bead's average force, pair_style chain/<law> sensors).
 *
 * Global vector (every step): [1] 1 once the event has ended, else 0; [2] its end time (0 before);
 * [3] the largest F - FS; [4] its time; [5] the impulse; [6] the dynamic impulse; [7] the energy;
 * [8 + 2k], [9 + 2k] the k-th tracked force's largest value (total, not less a static force) and its time.
 */

#ifndef GRANCHAIN_FIX_CHAIN_EVENT_H
#define GRANCHAIN_FIX_CHAIN_EVENT_H

#include "fix.h"

#include <vector>

namespace LAMMPS_NS {

class FixChainEvent : public Fix {
 public:
  FixChainEvent(class LAMMPS *, int, char **);
  int setmask() override;
  void init() override;
  void setup(int) override;
  void end_of_step() override;
  double compute_vector(int) override;

 private:
  int check;
  tagint wall_atom;
  double fs, floor, load_end;
  bool held;
  int index;    // d_fc in atom->dvector
  bool started, ended;
  double t[3], f[3], g;
  double fmax, tmax, impulse, dynamic, energy, end_time;
  class Compute *pe;
  // the tracked forces (track): atom IDs, 0 d_fc / 1 d_sfc, the last three samples, the running maxima
  std::vector<tagint> track_id;
  std::vector<int> track_kind;
  std::vector<double> tf[3], tfmax, ttmax;
  int sfc_index;
  void track_sample(std::vector<double> &out) const;
  void track_add(const std::vector<double> &fk);
  bigint next_check() const;
  static bool left_for_good(const double *vel, const double *m, const double *fcon, int n, double stored);
  double now() const;
  void wall_sample(double &fw, double &vw) const;
  void add(double time, double fw, double vw);
  bool left();
  void cross(double vw);
};

}    // namespace LAMMPS_NS

#endif
