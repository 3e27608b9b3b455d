"""LAMMPS dumps -> arrays, through MDAnalysis, and dump-derived peak-force tables.

MDAnalysis's LAMMPSDUMP reader has quirks; how each is handled here:
- It needs an ``id`` column and a full ``x y z`` triplet, so granchain's dumps carry x y z even
  though they are not used; ``vx vy vz`` are read only as a triplet.
- Positions and velocities come back as float32 and positions are shifted by the box's lower bound
  (which moves: the x boundary is shrink-wrapped). So granchain dumps the quantities it needs as
  extra full-precision columns and reads them with ``additional_columns`` (float64 in ``ts.data``):
  ``d_fc`` (contact force), ``v_vel`` (x velocity) and ``v_ux`` (displacement from
  ``compute displace/atom``). The float32 x/vx are ignored.
- Time is step x the dt passed in; a granchain run shortens the step before each breakpoint (load
  end, snapshot), so time is not step x dt. We pass dt = 1 and map ``ts.data['step']`` to time with
  the run's step plan (``granchain.schedule.step_times``).
- Masses default to 1.0: never used (masses come from the scene).
- The whole-chain dump (chain.dump) also carries ``type radius`` after ``id`` and ``v_radius`` at the
  end, for other tools: MDAnalysis takes the atom types from ``type`` (and reads the radius with
  ``additional_columns=["radius"]``), OVITO maps ``radius`` to its particle radius, ASE's reader
  needs ``type`` and keeps only prefixed columns, hence ``v_radius``. read_dump reads columns by
  name, so the extra ones change nothing here (tests/test_dump_readers.py).
- ``dump_modify format float %.17g`` makes the text exact; ``sort id`` orders atoms by ID.
- MDAnalysis cannot parse the optional ``ITEM: TIME`` header (2.11 counts n_atoms + 9 lines a frame
  and reads the step from the second), so decks do not write it: chain.dump carries each frame's
  time as a column, ``v_time``, and ``element`` X. Dumps written before those columns read as before
  (columns by name); granchain.postprocess.chain_dump takes ``v_time`` where it is there.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from granchain.peaks import complete_peaks

DUMP_COLUMNS = ("d_fc", "v_vel", "v_ux")


@dataclass
class DumpData:
    """A LAMMPS dump read back: its frames' steps and times, the bead IDs, and each column by name."""

    step: np.ndarray  # (frames,)
    time: np.ndarray  # (frames,) s
    ids: np.ndarray  # (atoms,) bead IDs, sorted
    columns: dict[str, np.ndarray]  # name -> (frames, atoms), float64


def _mdanalysis():
    """MDAnalysis, imported without the TqdmWarning "IProgress not found" it gives in a notebook
    without ipywidgets (its progress bars import tqdm.auto; granchain shows none of them): that one
    warning, only while MDAnalysis is imported; every other warning, and tqdm's elsewhere, stays."""
    from tqdm import TqdmWarning

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="IProgress not found", category=TqdmWarning)
        import MDAnalysis
    return MDAnalysis


def read_dump(path: str | Path, times: np.ndarray | None = None, columns=DUMP_COLUMNS) -> DumpData:
    """Read a LAMMPS text dump with MDAnalysis; times[step] gives each frame's time."""
    mda = _mdanalysis()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Guessed all Masses to 1.0" and friends: see module doc
        u = mda.Universe(str(path), format="LAMMPSDUMP", additional_columns=list(columns), dt=1.0)
    order = np.argsort(u.atoms.ids)
    steps, data = [], {c: [] for c in columns}
    for ts in u.trajectory:
        steps.append(int(ts.data["step"]))
        for c in columns:
            data[c].append(np.asarray(ts.data[c], dtype=np.float64)[order])
    step = np.asarray(steps)
    time = times[step] if times is not None else step.astype(float)
    return DumpData(
        step=step, time=time, ids=np.asarray(u.atoms.ids)[order], columns={c: np.asarray(v) for c, v in data.items()}
    )


def peaks_from_samples(time: np.ndarray, force: np.ndarray, refine: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Peak force per column of force (frames, contacts) and its time.

    refine: the vertex of the parabola through the largest sample and its two neighbours (the same
    three-point rule as the pair styles' in-run tracking). Contacts never loaded: 0 and nan.
    """
    k = np.argmax(force, axis=0)
    cols = np.arange(force.shape[1])
    peak = force[k, cols].copy()
    tpk = time[k].astype(float)
    if refine:
        inner = (k > 0) & (k < len(time) - 1) & (peak > 0)
        ki, ci = k[inner], cols[inner]
        t0, t1, t2 = time[ki - 1], time[ki], time[ki + 1]
        f0, f1, f2 = force[ki - 1, ci], force[ki, ci], force[ki + 1, ci]
        a, b = t0 - t1, t2 - t1
        fa, fb = f0 - f1, f2 - f1
        det = a * b * (b - a)
        c1 = (fa * b * b - fb * a * a) / det
        c2 = (a * fb - b * fa) / det
        ok = c2 < 0
        s = np.clip(-c1[ok] / (2 * c2[ok]), a[ok], b[ok])
        val = f1[ok] + (c1[ok] + c2[ok] * s) * s
        idx = ci[ok]
        better = val > peak[idx]
        peak[idx[better]] = val[better]
        tpk[idx[better]] = t1[ok][better] + s[better]
    tpk[peak <= 0] = np.nan
    return peak, tpk


def complete_from_samples(
    time: np.ndarray, force: np.ndarray, peak_force: np.ndarray, time_of_peak: np.ndarray, static_force: float = 0.0
) -> np.ndarray:
    """Which contacts' peaks are complete, from force samples (frames, contacts), e.g. a dump or histories.

    The smallest sample at or after each contact's time of peak, judged by granchain.peaks.complete_peaks
    (the definition the backends apply to their in-run minimum). Sampled every step, this is the in-run answer.
    """
    tp = np.asarray(time_of_peak, dtype=float)
    after = np.asarray(time, dtype=float)[:, None] >= np.where(np.isfinite(tp), tp, np.inf)[None, :]
    fmin = np.where(after, force, np.inf).min(axis=0, initial=np.inf)
    return complete_peaks(peak_force, fmin, tp, static_force)


def arrival_times(time: np.ndarray, force: np.ndarray, fraction: float = 0.5) -> np.ndarray:
    """First time each contact's force reaches fraction x its peak (linear interpolation)."""
    peak = force.max(axis=0)
    out = np.full(force.shape[1], np.nan)
    for c in np.flatnonzero(peak > 0):
        level = fraction * peak[c]
        i = int(np.argmax(force[:, c] >= level))
        if i == 0:
            out[c] = time[0]
            continue
        f0, f1 = force[i - 1, c], force[i, c]
        out[c] = time[i - 1] + (level - f0) / (f1 - f0) * (time[i] - time[i - 1])
    return out
