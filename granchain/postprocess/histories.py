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

import math
import os
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.postprocess.dumps import read_dump

HISTORY_NPY = "histories.npy"
HISTORY_DUMP = "histories.dump"


class HistoryFileError(ValueError):
    """histories.npy is not what fix chain/history writes."""


def _load_checked(path: str | Path) -> np.ndarray:
    """histories.npy's array, its header's shape checked against the file's size before anything is
    allocated (a header claiming (1e12, 3) would ask for 21.8 TiB); never read through a link."""
    with safe_files.open_for_read(path, "rb") as fh:
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
        else:
            shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
        need = math.prod(shape) * dtype.itemsize
        have = os.fstat(fh.fileno()).st_size - fh.tell()
        if dtype.hasobject or need != have:
            raise HistoryFileError(
                f"{path}: its header says shape {shape} of {dtype} ({need} bytes), the file holds {have} bytes of "
                "data: not what fix chain/history writes (damaged or cut off)"
            )
        fh.seek(0)
        return np.load(fh, allow_pickle=False)


def read_history_table(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """histories.npy -> (steps (frames,), ids (n,), force (frames, n), velocity (frames, n))."""
    a = _load_checked(path)
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
