/* granchain: fix chain/energy. See fix_chain_energy.h. */

#include "fix_chain_energy.h"

#include "atom.h"
#include "comm.h"
#include "compute.h"
#include "error.h"
#include "force.h"
#include "input.h"
#include "modify.h"
#include "update.h"
#include "utils.h"
#include "variable.h"

#include <cmath>
#include <cstring>
#include <mpi.h>

using namespace LAMMPS_NS;
using namespace FixConst;

// the buffer is written out once it holds this much (a long run's samples never pile up in memory)
static constexpr size_t FLUSH_BYTES = 1 << 20;

FixChainEnergy::FixChainEnergy(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), fp(nullptr), first(-1), watch(false), bound(0.0), work_var(-1), temperature(nullptr),
    pe(nullptr), dissipated(nullptr), fmax(nullptr), next_sample(0)
{
  const char *usage =
      "fix ID group chain/energy N file title TEXT first ATOM [dissipated COMPUTE] [extra x[ID]|v_NAME ...]";
  if (narg < 5) error->all(FLERR, "Illegal fix chain/energy command: {}", usage);
  nevery = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nevery <= 0) error->all(FLERR, "fix chain/energy N must be > 0, got {}", nevery);
  const std::string file = arg[4];
  std::string title;
  bool have_title = false;
  int iarg = 5;
  while (iarg < narg) {
    const std::string key = arg[iarg];
    if (key == "extra") {
      for (iarg++; iarg < narg; iarg++) {
        const std::string col = arg[iarg];
        Extra e{ATOM_X, 0, "", -1};
        if (utils::strmatch(col, "^x\\[\\d+\\]$")) {
          e.atom = utils::tnumeric(FLERR, col.substr(2, col.size() - 3), false, lmp);
        } else if (utils::strmatch(col, "^v_")) {
          e.kind = VARIABLE;
          e.name = col.substr(2);
        } else {
          error->all(FLERR, "fix chain/energy extra column {}: x[ID] or v_NAME", col);
        }
        extras.push_back(e);
      }
      break;
    }
    if (iarg + 2 > narg) error->all(FLERR, "fix chain/energy {} needs a value: {}", key, usage);
    if (key == "title") {
      title = arg[iarg + 1];
      have_title = true;
    } else if (key == "first") {
      first = utils::tnumeric(FLERR, arg[iarg + 1], false, lmp);
    } else if (key == "dissipated") {
      dissipated_id = arg[iarg + 1];
    } else {
      error->all(FLERR, "fix chain/energy: unknown keyword {}: {}", key, usage);
    }
    iarg += 2;
  }
  if (!have_title || first <= 0) error->all(FLERR, "fix chain/energy needs title and first: {}", usage);
  if (atom->map_style == Atom::MAP_NONE)
    error->all(FLERR, "fix chain/energy needs an atom map (atom_modify map array or hash)");
  if (comm->me == 0 && file != "none") {    // none: the watch without the samples (benchmarks/bench_pair.py)
    fp = fopen(file.c_str(), "w");
    if (!fp) error->one(FLERR, "Cannot open fix chain/energy file {}: {}", file, utils::getsyserror());
    buffer = title + "\n";
  }
}

FixChainEnergy::~FixChainEnergy()
{
  // unfix, clear, or a run stopped by an error: what was sampled is written (rank 0 holds it all)
  try {
    flush();
  } catch (...) {
  }
  if (fp) fclose(fp);
}

int FixChainEnergy::setmask()
{
  return END_OF_STEP | POST_RUN;
}

// fix_modify ID watch BOUND WORK FMAX: the run watch's energy balance (see the header)
int FixChainEnergy::modify_param(int narg, char **arg)
{
  if (strcmp(arg[0], "watch") != 0) return 0;
  if (narg < 4) error->all(FLERR, "fix_modify {} watch BOUND v_WORK FMAX: three values", id);
  bound = utils::numeric(FLERR, arg[1], false, lmp);
  if (!(bound > 0.0)) error->all(FLERR, "fix_modify {} watch: BOUND must be > 0, got {}", id, arg[1]);
  if (!utils::strmatch(arg[2], "^v_")) error->all(FLERR, "fix_modify {} watch: WORK must be v_NAME", id);
  work_name = arg[2] + 2;
  fmax_id = arg[3];
  watch = true;
  return 4;
}

void FixChainEnergy::init()
{
  // the computes the thermo keywords ke and pe use (thermo_style makes them afresh: looked up every run)
  temperature = modify->get_compute_by_id("thermo_temp");
  pe = modify->get_compute_by_id("thermo_pe");
  if (!temperature || !pe) error->all(FLERR, "fix chain/energy needs the computes thermo_temp and thermo_pe");
  dissipated = nullptr;
  if (!dissipated_id.empty()) {
    dissipated = modify->get_compute_by_id(dissipated_id);
    if (!dissipated || !dissipated->scalar_flag)
      error->all(FLERR, "fix chain/energy: no compute {} with a global scalar", dissipated_id);
  }
  for (auto &e : extras) {
    if (e.kind != VARIABLE) continue;
    e.ivar = input->variable->find(e.name.c_str());
    if (e.ivar < 0 || !input->variable->equalstyle(e.ivar))
      error->all(FLERR, "fix chain/energy: no equal-style variable {}", e.name);
  }
  if (watch) {
    work_var = input->variable->find(work_name.c_str());
    if (work_var < 0 || !input->variable->equalstyle(work_var))
      error->all(FLERR, "fix chain/energy watch: no equal-style variable {}", work_name);
    fmax = modify->get_compute_by_id(fmax_id);
    if (!fmax || !fmax->vector_flag || fmax->size_vector < 2)
      error->all(FLERR, "fix chain/energy watch: no compute {} with a global vector of 2", fmax_id);
  }
  // as fix print: the next sample's step, told to every compute (pe must be tallied on it)
  if (update->ntimestep % nevery)
    next_sample = (update->ntimestep / nevery) * nevery + nevery;
  else
    next_sample = update->ntimestep;
  modify->addstep_compute_all(next_sample);
}

void FixChainEnergy::setup(int)
{
  sample(false);    // a run's setup on a sample step: the line, not the watch (fix halt has no setup)
}

void FixChainEnergy::end_of_step()
{
  sample(watch);
}

void FixChainEnergy::post_run()
{
  flush();
}

// a compute's global scalar as a variable's c_ID reads it: computed once a step
double FixChainEnergy::scalar(Compute *c)
{
  if (!(c->invoked_flag & Compute::INVOKED_SCALAR)) {
    c->compute_scalar();
    c->invoked_flag |= Compute::INVOKED_SCALAR;
  }
  return c->scalar;
}

// x[ID] as a variable reads it: the owner's x, summed over ranks (the others give 0)
double FixChainEnergy::atom_x(tagint tag)
{
  const int i = atom->map(tag);
  const double mine = (i >= 0 && i < atom->nlocal) ? atom->x[i][0] : 0.0;
  double value;
  MPI_Allreduce(&mine, &value, 1, MPI_DOUBLE, MPI_SUM, world);
  return value;
}

void FixChainEnergy::sample(bool check)
{
  if (update->ntimestep != next_sample) return;
  modify->clearstep_compute();
  // the thermo keywords' arithmetic (Thermo::compute_time, compute_ke, compute_pe; units si: no norm)
  const double time = update->atime + (update->ntimestep - update->atimestep) * update->dt;
  double ke = scalar(temperature);
  ke *= 0.5 * temperature->dof * force->boltz;
  const double pot = scalar(pe);
  const double dis = dissipated ? scalar(dissipated) : 0.0;
  const double x1 = atom_x(first);
  std::vector<double> extra(extras.size());
  for (size_t k = 0; k < extras.size(); k++)
    extra[k] = extras[k].kind == ATOM_X ? atom_x(extras[k].atom) : input->variable->compute_equal(extras[k].ivar);
  double work = 0.0;
  if (check) work = input->variable->compute_equal(work_var);
  next_sample = (update->ntimestep / nevery) * nevery + nevery;
  modify->addstep_compute(next_sample);

  if (fp) {
    char num[32];
    auto put = [&](double x, bool space) {
      snprintf(num, sizeof(num), space ? " %.17g" : "%.17g", x);
      buffer += num;
    };
    put(time, false);
    put(ke, true);
    put(pot, true);
    if (dissipated) put(dis, true);
    put(x1, true);
    for (double x : extra) put(x, true);
    buffer += '\n';
    if (buffer.size() >= FLUSH_BYTES) flush();
  }
  if (!check) return;
  // the energy balance, in the order of operations of the LAMMPS formulas it replaces
  // (watch_e = ke + pe [+ c_dissipated]; watch_scale = 0.5*(abs(w) + ke + pe + abs(abs(w) - ke - pe)))
  double e = ke + pot;
  if (dissipated) e = e + dis;
  const double scale = 0.5 * (std::fabs(work) + ke + pot + std::fabs(std::fabs(work) - ke - pot));
  const double rel = (e - work) / (scale + 1e-300);
  if (!(std::fabs(rel) > bound)) return;    // (a NaN passes: a non-finite state stops LAMMPS by itself)
  if (!(fmax->invoked_flag & Compute::INVOKED_VECTOR)) {
    fmax->compute_vector();
    fmax->invoked_flag |= Compute::INVOKED_VECTOR;
  }
  const double a = std::fabs(rel);
  const double value = (rel / (a + 1e-300)) * (fmax->vector[1] + 0.5 * (a + 0.999 - std::fabs(a - 0.999)));
  flush();
  error->all(FLERR, "Fix chain/energy condition watch_energy met on step {} with value {}", update->ntimestep, value);
}

void FixChainEnergy::flush()
{
  if (!fp || buffer.empty()) return;
  const bool ok = fwrite(buffer.data(), 1, buffer.size(), fp) == buffer.size() && fflush(fp) == 0;
  buffer.clear();
  if (!ok) error->one(FLERR, "fix chain/energy cannot write its file: {}", utils::getsyserror());
}
