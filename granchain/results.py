"""The one result format every backend produces, and the run directory it is written to.

A backend (reference solver or LAMMPS) fills a :class:`ChainSolution`; :func:`write_run_dir`
turns it into a run directory:

    scene.toml      the scene as given
    summary.json    backend, method, timestep, steps, wall_time, observables, conservation checks
    peaks.csv       contact,peak_force,time_of_peak,peak_force_nondim (contacts numbered from 1)
    histories.csv   time, force_<i>, velocity_<i> for each requested contact i (if requested)
    snapshots.csv   time, bead, displacement, velocity, contact_force (if requested)
    energy.csv      time, kinetic, potential, dissipated, work

The directory is written under a hidden temporary name and renamed into place at the end, so an
interrupted run never leaves a directory that looks complete.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from granchain.postprocess.observables import measure_observables

#: A contact counts as reached by the wave when its peak force exceeds this fraction of the largest
#: peak in the chain. Below it a "peak" is round-off: LAMMPS places bead i at x = (i-1) D, and the
#: difference of two such positions misses D by an ulp, a spurious overlap of ~1e-18 m.
REACHED_FRACTION = 1e-9


def unreached_as_nan(peak_force: np.ndarray, time_of_peak: np.ndarray, static_force: float = 0.0) -> np.ndarray:
    """time_of_peak with nan where the contact was not reached (see REACHED_FRACTION).

    static_force: a precompression F0 every contact starts at; reached means rising above it.
    """
    rise = np.asarray(peak_force) - static_force
    floor = REACHED_FRACTION * float(np.max(rise, initial=0.0))
    return np.where(rise > floor, time_of_peak, np.nan)


@dataclass
class ChainSolution:
    """What a solver run returns. Contacts are 0-based here (contact i joins beads i and i+1)."""

    method: str
    timestep: float
    steps: int
    wall_time: float
    end_time: float
    peak_overlap: np.ndarray  # (N-1,) m, 0 for contacts never compressed
    peak_force: np.ndarray  # (N-1,) N
    time_of_peak: np.ndarray  # (N-1,) s, nan for contacts never compressed
    history_contacts: tuple[int, ...] = ()
    history_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    history_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (samples, contacts)
    history_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # bead i of contact i
    snapshot_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    snapshot_displacement: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (snaps, N)
    snapshot_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    snapshot_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (snaps, N-1)
    energy_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kinetic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    potential: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work: np.ndarray = field(default_factory=lambda: np.zeros(0))
    displacement: np.ndarray = field(default_factory=lambda: np.zeros(0))  # final state
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))
    alpha_max: np.ndarray = field(default_factory=lambda: np.zeros(0))  # final bilinear history
    impulse_delivered: float = 0.0  # A * min(T, end_time)
    momentum: float = 0.0  # total momentum sum(m v) at the end
    extra_steps: int = 0  # steps beyond the grid's (RK4 event location: rejected and split steps)
    wall_peak_force: float | None = None  # far-end wall contact (only with a wall)
    wall_time_of_peak: float | None = None
    striker_peak_force: float | None = None  # striker-bead 1 contact (only with a striker)
    striker_time_of_peak: float | None = None
    striker_velocity: float | None = None  # at the end

    @property
    def energy_balance_error(self) -> np.ndarray:
        """kinetic + stored + dissipated - work, at every energy sample."""
        return self.kinetic + self.potential + self.dissipated - self.work


@dataclass
class RunResult:
    """A finished run: the scene, which backend produced it, and its solution."""

    scene: object  # granchain.scene.Scene
    backend: str
    solution: ChainSolution
    extra: dict = field(default_factory=dict)  # backend-specific facts (e.g. LAMMPS version)

    def observables(self) -> dict:
        return measure_observables(self.scene, self.solution)

    def summary(self) -> dict:
        s, sc = self.solution, self.scene
        eb = s.energy_balance_error
        work_scale = float(np.max(np.abs(s.work))) if s.work.size else 0.0
        return {
            "title": sc.title,
            "scene_source": sc.source,
            "backend": self.backend,
            "method": s.method,
            "timestep": s.timestep,
            "steps": s.steps,
            "end_time": s.end_time,
            "beads": sc.chain.beads,
            "contact_law": sc.contact.law,
            "loading": sc.loading.kind,
            "wall_time": s.wall_time,
            "observables": self.observables(),
            "conservation": {
                "impulse_delivered": s.impulse_delivered,
                "momentum": s.momentum,
                "work": float(s.work[-1]) if s.work.size else 0.0,
                "kinetic": float(s.kinetic[-1]) if s.kinetic.size else 0.0,
                "potential": float(s.potential[-1]) if s.potential.size else 0.0,
                "dissipated": float(s.dissipated[-1]) if s.dissipated.size else 0.0,
                "energy_balance_error_max": float(np.max(np.abs(eb))) if eb.size else 0.0,
                "energy_balance_error_relative": (float(np.max(np.abs(eb))) / work_scale) if work_scale else 0.0,
            },
            "scales": {"force_scale": sc.force_scale, "impulse_scale": sc.impulse_scale, "tau": sc.tau},
            **({"wall_peak_force": s.wall_peak_force} if s.wall_peak_force is not None else {}),
            **(
                {"striker_peak_force": s.striker_peak_force, "striker_velocity": s.striker_velocity}
                if s.striker_peak_force is not None
                else {}
            ),
            **({"extra": self.extra} if self.extra else {}),
        }


class RunDirError(RuntimeError):
    """The run directory cannot be written (exists, not writable, disk full, ...)."""


def check_output_dir(out: str | Path, overwrite: bool = False) -> Path:
    """Fail early (before a run starts) if the run directory cannot be created."""
    out = Path(out)
    if out.exists() and not overwrite:
        raise RunDirError(f"{out}: already exists; choose another --out or pass --overwrite to replace it")
    if out.exists() and not out.is_dir():
        raise RunDirError(f"{out}: exists and is not a directory; choose another --out")
    parent = out.resolve().parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise RunDirError(
            f"{parent}: cannot create the parent directory of the run ({e.strerror}); choose another --out"
        ) from None
    if not os.access(parent, os.W_OK):
        raise RunDirError(f"{parent}: is not writable; choose another --out")
    return out


def _write_csv(path: Path, header: list[str], rows) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for row in rows:
            w.writerow([_fmt(x) for x in row])


def _fmt(x) -> str:
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    x = float(x)
    return repr(x) if np.isfinite(x) else "nan"


def write_run_dir(result: RunResult, out: str | Path, overwrite: bool = False, extra_files: dict | None = None) -> Path:
    """Write the run directory atomically; returns its path.

    extra_files: name -> text or source Path, copied in as well (e.g. a LAMMPS deck and log).
    """
    out = check_output_dir(out, overwrite)
    parent = out.resolve().parent
    tmp = parent / f".{out.name}.partial-{os.getpid()}"
    for stale in parent.glob(f".{out.name}.partial-*"):  # left by a killed writer (or this pid's past)
        pid = stale.name.rsplit("-", 1)[-1]
        if stale == tmp or (pid.isdigit() and not pid_alive(int(pid))):
            shutil.rmtree(stale, ignore_errors=True)
    try:
        tmp.mkdir()
        _write_contents(result, tmp, extra_files or {})
        if out.exists():
            old = parent / f".{out.name}.old-{os.getpid()}"
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except OSError as e:
        shutil.rmtree(tmp, ignore_errors=True)
        raise RunDirError(f"{out}: could not write the run directory ({e}); nothing was left behind") from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def pid_alive(pid: int) -> bool:
    """Whether a process exists (stale partial run and LAMMPS work directories name their writer)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _write_contents(result: RunResult, d: Path, extra_files: dict) -> None:
    sc, s = result.scene, result.solution
    (d / "scene.toml").write_text(sc.source_text if sc.source_text else sc.to_toml())
    contacts = np.asarray(sc.peak_contacts, dtype=int)
    idx = contacts - 1
    _write_csv(
        d / "peaks.csv",
        ["contact", "peak_force", "time_of_peak", "peak_force_nondim"],
        zip(contacts, s.peak_force[idx], s.time_of_peak[idx], s.peak_force[idx] / sc.force_scale, strict=True),
    )
    if s.history_contacts:
        cols = [f"force_{i + 1}" for i in s.history_contacts] + [f"velocity_{i + 1}" for i in s.history_contacts]
        _write_csv(
            d / "histories.csv",
            ["time", *cols],
            (
                np.concatenate(([t], f, v))
                for t, f, v in zip(s.history_time, s.history_force, s.history_velocity, strict=True)
            ),
        )
    if s.snapshot_time.size:
        n = sc.chain.beads

        def rows():
            for k, t in enumerate(s.snapshot_time):
                f = np.append(s.snapshot_force[k], 0.0)  # bead N has no right-hand contact
                for b in range(n):
                    yield (t, b + 1, s.snapshot_displacement[k, b], s.snapshot_velocity[k, b], f[b])

        _write_csv(d / "snapshots.csv", ["time", "bead", "displacement", "velocity", "contact_force"], rows())
    _write_csv(
        d / "energy.csv",
        ["time", "kinetic", "potential", "dissipated", "work"],
        zip(s.energy_time, s.kinetic, s.potential, s.dissipated, s.work, strict=True),
    )
    for name, content in extra_files.items():
        if isinstance(content, Path):
            shutil.copyfile(content, d / name)
        else:
            (d / name).write_text(content)
    # summary last: its presence marks a complete directory even before the rename
    (d / "summary.json").write_text(json.dumps(result.summary(), indent=2, default=_json_default) + "\n")


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(repr(o))


def read_peaks(run_dir: str | Path) -> dict[str, np.ndarray]:
    """peaks.csv of a run directory as arrays (contact is 1-based)."""
    data = np.genfromtxt(Path(run_dir) / "peaks.csv", delimiter=",", names=True, ndmin=1)
    return {name: np.asarray(data[name]) for name in data.dtype.names}


def read_summary(run_dir: str | Path) -> dict:
    return json.loads((Path(run_dir) / "summary.json").read_text())
