"""A LAMMPS run's histories (the force of the contacts in [outputs] histories and the x velocity of their
left beads, every history stride steps) -> arrays, from either file a deck writes:

- histories.npy, fix chain/history's (granchain.templates.DeckOptions(history_file="npy")): float64,
  shape (1 + frames, 1 + 2 n) for n atoms in ID order; row 0 holds n and the atom IDs (twice), row
  1 + k the step of sample k, then d_fc of the n atoms, then their vx. Written whole under a temporary
  name and renamed at the end of each run, so a histories.npy is never half a file.
- histories.npy absent: the text dump histories.dump (dump custom ... d_fc v_vel, %.17g, sort id),
  read with MDAnalysis (granchain.postprocess.dumps.read_dump).

Both give the same doubles (tests/test_history_output.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from granchain.postprocess.dumps import read_dump

HISTORY_NPY = "histories.npy"
HISTORY_DUMP = "histories.dump"


class HistoryFileError(ValueError):
    """histories.npy is not what fix chain/history writes."""


def read_history_table(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """histories.npy -> (steps (frames,), ids (n,), force (frames, n), velocity (frames, n))."""
    a = np.load(path, allow_pickle=False)
    if a.ndim != 2 or a.dtype != np.float64 or a.shape[0] < 1 or a.shape[1] < 3 or (a.shape[1] - 1) % 2:
        raise HistoryFileError(f"{path}: not a fix chain/history table (shape {a.shape}, {a.dtype})")
    n = (a.shape[1] - 1) // 2
    ids = a[0, 1 : 1 + n]
    if a[0, 0] != n or not np.array_equal(ids, a[0, 1 + n :]):
        raise HistoryFileError(f"{path}: its first row is not n and the atom IDs twice")
    steps = a[1:, 0]
    return steps.astype(np.int64), ids.astype(np.int64), a[1:, 1 : 1 + n], a[1:, 1 + n :]


def read_histories(work_dir: str | Path, times: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(time (frames,), force (frames, n), velocity (frames, n)) of a run directory's histories, the n
    history atoms in ID order; times[step] is each sample's time (granchain.schedule.step_times), the
    step itself without it. histories.npy when the deck wrote one, else histories.dump."""
    work = Path(work_dir)
    if (work / HISTORY_NPY).exists():
        steps, _, force, velocity = read_history_table(work / HISTORY_NPY)
        time = times[steps] if times is not None else steps.astype(float)
        return time, force, velocity
    dd = read_dump(work / HISTORY_DUMP, times)
    return dd.time, dd.columns["d_fc"], dd.columns["v_vel"]
