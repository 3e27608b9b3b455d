/* granchain: fix chain/history. See fix_chain_history.h. */

#include "fix_chain_history.h"

#include "atom.h"
#include "comm.h"
#include "error.h"
#include "group.h"
#include "update.h"
#include "utils.h"

#include <algorithm>
#include <cstdio>
#include <mpi.h>
#include <unistd.h>

using namespace LAMMPS_NS;
using namespace FixConst;

FixChainHistory::FixChainHistory(LAMMPS *lmp, int narg, char **arg) :
    Fix(lmp, narg, arg), index(-1), last_step(-1), written_frames(-1)
{
  if (narg != 5) error->all(FLERR, "Illegal fix chain/history command: fix ID group chain/history N file");
  nevery = utils::inumeric(FLERR, arg[3], false, lmp);
  if (nevery <= 0) error->all(FLERR, "fix chain/history N must be > 0, got {}", nevery);
  // the file's absolute path, fixed now: the fix may write it when deleted (a LAMMPS instance closed after
  // an error), by when the caller may have changed directory
  file = arg[4];
  if (!file.empty() && file[0] != '/') {
    char cwd[4096];
    if (getcwd(cwd, sizeof(cwd))) file = std::string(cwd) + "/" + file;
  }
  if (atom->map_style == Atom::MAP_NONE)
    error->all(FLERR, "fix chain/history needs an atom map (atom_modify map array or hash)");
}

FixChainHistory::~FixChainHistory()
{
  // a run that stopped with an error: what was sampled, if more than the file holds (one rank only: on
  // several, the others may not be here to gather with)
  try {
    if (comm->nprocs == 1 && (bigint) steps.size() != written_frames) write();
  } catch (...) {
  }
}

int FixChainHistory::setmask()
{
  return END_OF_STEP | POST_RUN;
}

void FixChainHistory::init()
{
  int flag, cols;
  index = atom->find_custom("fc", flag, cols);
  if (index < 0 || flag != 1 || cols != 0)
    error->all(FLERR, "fix chain/history needs the per-atom vector d_fc (fix property/atom d_fc ...)");
  // the group's IDs from every rank, sorted (the slots); fixed for the fix's life
  std::vector<tagint> mine;
  for (int i = 0; i < atom->nlocal; i++)
    if (atom->mask[i] & groupbit) mine.push_back(atom->tag[i]);
  int n = (int) mine.size(), nprocs = comm->nprocs;
  std::vector<int> counts(nprocs), displs(nprocs, 0);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, world);
  for (int p = 1; p < nprocs; p++) displs[p] = displs[p - 1] + counts[p - 1];
  std::vector<tagint> all(displs[nprocs - 1] + counts[nprocs - 1]);
  MPI_Allgatherv(mine.data(), n, MPI_LMP_TAGINT, all.data(), counts.data(), displs.data(), MPI_LMP_TAGINT, world);
  std::sort(all.begin(), all.end());
  if (all.empty()) error->all(FLERR, "fix chain/history: group {} has no atoms", group->names[igroup]);
  if (!ids.empty() && ids != all)
    error->all(FLERR, "fix chain/history: the atoms of group {} changed between runs", group->names[igroup]);
  ids = all;
}

void FixChainHistory::setup(int)
{
  if (update->ntimestep % nevery == 0) sample();
}

void FixChainHistory::end_of_step()
{
  sample();
}

void FixChainHistory::sample()
{
  const bigint step = update->ntimestep;
  if (step == last_step) return;    // a run's setup on the step the previous run ended (and sampled) on
  last_step = step;
  const double frame = (double) steps.size();
  steps.push_back((double) step);
  const double *fc = atom->dvector[index];
  double **v = atom->v;
  const int nlocal = atom->nlocal;
  for (size_t s = 0; s < ids.size(); s++) {
    const int i = atom->map(ids[s]);    // owned atoms take precedence over ghosts in the map
    if (i >= 0 && i < nlocal) {
      records.push_back(frame);
      records.push_back((double) s);
      records.push_back(fc[i]);
      records.push_back(v[i][0]);
    }
  }
}

void FixChainHistory::post_run()
{
  write();
}

// every sample so far, gathered on rank 0, as file.npy (through file.npy.part)
void FixChainHistory::write()
{
  const int nprocs = comm->nprocs, me = comm->me;
  int n = (int) records.size();
  std::vector<int> counts(nprocs), displs(nprocs, 0);
  MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, world);
  std::vector<double> all;
  if (me == 0) {
    for (int p = 1; p < nprocs; p++) displs[p] = displs[p - 1] + counts[p - 1];
    all.resize(displs[nprocs - 1] + counts[nprocs - 1]);
  }
  MPI_Gatherv(records.data(), n, MPI_DOUBLE, all.data(), counts.data(), displs.data(), MPI_DOUBLE, 0, world);
  written_frames = (bigint) steps.size();
  if (me != 0) return;

  const size_t ng = ids.size(), cols = 1 + 2 * ng, rows = 1 + steps.size();
  std::vector<double> table(rows * cols, 0.0);
  table[0] = (double) ng;
  for (size_t s = 0; s < ng; s++) table[1 + s] = table[1 + ng + s] = (double) ids[s];
  for (size_t k = 0; k < steps.size(); k++) table[(1 + k) * cols] = steps[k];
  size_t filled = 0;
  for (size_t r = 0; r + 4 <= all.size(); r += 4) {
    const size_t k = (size_t) all[r], s = (size_t) all[r + 1];
    table[(1 + k) * cols + 1 + s] = all[r + 2];
    table[(1 + k) * cols + 1 + ng + s] = all[r + 3];
    filled++;
  }
  if (filled != steps.size() * ng)
    error->one(FLERR, "fix chain/history: {} of {} samples found their owner", filled, steps.size() * ng);

  // .npy version 1.0: magic, header length, a Python dict literal padded to a multiple of 64 bytes
  std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
      std::to_string(cols) + "), }";
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  const std::string part = file + ".part";
  FILE *fp = fopen(part.c_str(), "wb");
  if (!fp) error->one(FLERR, "fix chain/history cannot open {}", part);
  const unsigned char magic[8] = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  const unsigned short hlen = (unsigned short) header.size();
  const unsigned char len[2] = {(unsigned char) (hlen & 0xff), (unsigned char) (hlen >> 8)};
  bool ok = fwrite(magic, 1, 8, fp) == 8 && fwrite(len, 1, 2, fp) == 2 &&
      fwrite(header.data(), 1, header.size(), fp) == header.size() &&
      fwrite(table.data(), sizeof(double), table.size(), fp) == table.size();
  ok = (fclose(fp) == 0) && ok;
  if (!ok || rename(part.c_str(), file.c_str()) != 0) error->one(FLERR, "fix chain/history cannot write {}", file);
}
