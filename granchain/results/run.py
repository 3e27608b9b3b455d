"""A finished run (RunResult): its summary, tables, display, plot, price and provenance."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from granchain.physics.event import EVENT_FIELDS, maxima_summary
from granchain.postprocess.domains import beyond_yield
from granchain.postprocess.observables import end_summary, measure
from granchain.postprocess.sensors import sensor_summary
from granchain.results.provenance import _PROVENANCE_EXTRA, provenance
from granchain.results.solution import ChainSolution
from granchain.results.tables import PEAK_UNITS, _key_observables, _num, peak_columns
from granchain.scene.display import html_table, printable


def _now_utc() -> datetime:
    return datetime.now(UTC)


@dataclass
class RunResult:
    """A finished run: the scene, which backend produced it, and its solution.

    plan: the planner's Plan the scene was run with (granchain.workflows.plan), None if nothing was
    planned. started_utc: when the run started, if the caller knows (otherwise the provenance
    estimates it as finished_utc minus the run's elapsed time, and says so). finished_utc: when the
    result was made, i.e. the end of the run. command: the command line that made the run (default:
    this Python process's sys.argv when the summary is written). errors: the run's measured error
    estimates (granchain.workflows.error_estimates.ErrorReport), None when none were made.
    method_reason: why the run's integrator was chosen for its scene when none was asked for
    (workflows.run.method_choice: the reference's Verlet on a scene with velocity-dependent damping), else None;
    summary.json's "method_reason".
    """

    scene: object  # granchain.scene.Scene
    backend: str
    solution: ChainSolution
    extra: dict = field(default_factory=dict)  # backend-specific facts (e.g. LAMMPS version)
    plan: object | None = None  # granchain.workflows.plan.Plan
    started_utc: datetime | None = None
    finished_utc: datetime = field(default_factory=_now_utc)
    command: list[str] | None = None
    errors: object | None = None  # granchain.workflows.error_estimates.ErrorReport
    method_reason: str | None = None
    # a result read back from a run directory (granchain.load_run): the directory, and what it keeps
    # that a solution cannot give again (summary.json; peaks.csv's error columns)
    path: Path | None = None
    stored: StoredRun | None = field(default=None, repr=False)

    def __init_subclass__(cls, **kw):
        """Give a subclass the short display too."""
        # a subclass made a dataclass keeps the short display (the decorator adds __repr__ only
        # where the class body has none)
        super().__init_subclass__(**kw)
        cls.__repr__ = RunResult.__repr__

    def observables(self) -> dict:
        """The observables (leading peak, wave speed, ...; docs/observables.md); a loaded run's as written."""
        if self.stored is not None:
            return copy.deepcopy(self.stored.summary.get("observables") or {})
        return measure(self.scene, self.solution).values

    @property
    def peak_table(self) -> np.ndarray:
        """The peak-force table of peaks.csv as a numpy structured array: contact (1-based), peak_force
        (N), time_of_peak (s, nan if not reached) and complete (see peaks.complete_peaks)."""
        idx = np.asarray(self.scene.peak_contacts, dtype=int) - 1
        s = self.solution
        table = np.empty(
            idx.size, dtype=[("contact", int), ("peak_force", float), ("time_of_peak", float), ("complete", bool)]
        )
        table["contact"] = idx + 1
        table["peak_force"] = s.peak_force[idx]
        table["time_of_peak"] = s.time_of_peak[idx]
        table["complete"] = s.complete[idx]
        return table

    def observables_missing(self) -> dict[str, str]:
        """Why each observable that is None could not be measured (name -> reason)."""
        if self.stored is not None:
            return dict(self.stored.summary.get("observables_missing") or {})
        return measure(self.scene, self.solution).missing

    def observables_notes(self) -> dict[str, str]:
        """What each measured observable that is not what its name says is (name -> note): a wave
        speed averaged over a window whose contacts differ."""
        if self.stored is not None:
            return dict(self.stored.summary.get("observables_notes") or {})
        return measure(self.scene, self.solution).notes

    def peak_status(self) -> dict:
        """How many of the measured contacts (those of peaks.csv) have a complete peak, one that is not
        complete yet (the wave is still there at the end of the run) and one never reached."""
        if self.stored is not None and "peaks" in self.stored.summary:
            return dict(self.stored.summary["peaks"])
        idx = np.asarray(self.scene.peak_contacts, dtype=int) - 1
        reached = np.isfinite(self.solution.time_of_peak[idx])
        complete = self.solution.complete[idx]
        return {
            "complete": int(np.sum(complete)),
            "incomplete": int(np.sum(reached & ~complete)),
            "unreached": int(np.sum(~reached)),
        }

    @property
    def summary(self) -> Summary:
        """summary.json as a dict (``result.summary["observables"]``; ``result.summary()`` gives the
        same): backend, method, time step, observables and why any is missing, peak status counts,
        conservation checks, error estimates, price and provenance. A loaded run's is its file's."""
        if self.stored is not None:
            return Summary(self.stored.summary)
        return Summary(self._summary())

    def _summary(self) -> dict:
        s, sc = self.solution, self.scene
        eb = s.energy_balance_error
        work_scale = float(np.max(np.abs(s.work))) if s.work.size else 0.0
        observables, missing, notes, inapplicable = measure(sc, s)  # every registered observable, in one pass
        extra = {k: v for k, v in self.extra.items() if k not in _PROVENANCE_EXTRA}  # the rest: provenance
        outside = beyond_yield(sc, s)
        return {
            "title": sc.title,
            "scene_source": sc.source,
            "backend": self.backend,
            "method": s.method,
            **({"method_reason": self.method_reason} if self.method_reason is not None else {}),
            "timestep": s.timestep,
            "steps": s.steps,
            "end_time": s.end_time,
            "beads": sc.chain.beads,
            "contact_law": sc.contact.law,
            "loading": sc.loading.kind,
            "wall_time": s.wall_time,
            "observables": observables,
            "observables_missing": missing,
            # those of observables_missing the scene never measures, whatever the run (a wall's on a
            # free chain): a campaign's `unmeasured` column leaves them out
            "observables_inapplicable": list(inapplicable),
            # what a measured value is where it is not what its name says (a wave speed averaged over
            # a window whose contacts differ); only where there is one
            **({"observables_notes": notes} if notes else {}),
            "peaks": self.peak_status(),
            # an elastic law's peaks beyond the force at which the beads yield (postprocess.domains)
            **({"outside_domain": outside} if outside else {}),
            # the state at the end of the run: both backends' energy series end with it
            "conservation": {
                "time": float(s.energy_time[-1]) if s.energy_time.size else 0.0,
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
            **end_summary(s),  # the end contacts' peaks (postprocess.observables.ends)
            # the far-end wall's event as the run tracked it (physics.event; [outputs] event)
            **({"event": {k: getattr(s, k) for k in EVENT_FIELDS}} if s.wall_impulse is not None else {}),
            # the chosen contacts' and sensors' largest total force over it ([outputs] event_max_contacts, ...)
            **({"event_maxima": m} if (m := maxima_summary(s)) else {}),
            # the sensor beads' peaks and times, bead by bead (granchain.postprocess.sensors)
            **({"sensors": sensor_summary(sc, s)} if sc.outputs.sensors else {}),
            **({"extra": extra} if extra else {}),
            # the largest relative error of a measured peak, and every number's error and how it
            # was obtained (granchain.workflows.error_estimates); none without companion runs
            "error_estimate": None if self.errors is None else self.errors.error_estimate,
            "errors": None if self.errors is None else self.errors.summary(s.wall_time),
            # what the run cost, split by where the time went (RunResult.price)
            "price": self.price(),
            "provenance": self.provenance(),
        }

    # ---- tables and labelled arrays (pandas and xarray, imported when first asked for)

    @property
    def peaks(self):
        """peaks.csv as a pandas DataFrame indexed by contact (contact i joins beads i and i+1).

        Columns (units in ``df.attrs["units"]``; :data:`PEAK_UNITS`): peak_force (N), time_of_peak
        (s; nan where the wave never reached the contact), peak_force_nondim (F / (E* R*^2) of the contact's own pair),
        complete (bool: the peak is over, granchain.peaks.complete_peaks), leading_pulse_force (N)
        and arrival_time (s) of the leading pulse (nan until it completed), and with error
        estimates peak_force_error (N), time_of_peak_error (s) and error_status (text; why an
        error is missing). The rows are the scene's measured contacts ([outputs] peak_force).
        """
        import pandas as pd

        if self.stored is not None:
            cols = dict(self.stored.peaks)
        else:
            cols = peak_columns(self)
        contact = np.asarray(cols.pop("contact"), dtype=np.int64)
        for k, v in cols.items():
            if k == "complete":
                cols[k] = np.asarray(v, dtype=bool)
            elif k == "error_status":
                cols[k] = np.asarray([str(x) for x in v], dtype=object)
            else:
                cols[k] = np.asarray(v, dtype=np.float64)
        df = pd.DataFrame(cols, index=pd.Index(contact, name="contact"))
        df.attrs["units"] = {k: PEAK_UNITS[k] for k in df.columns if k in PEAK_UNITS}
        df.attrs["description"] = "peak contact force per contact (granchain peaks.csv; docs/observables.md)"
        return df

    @property
    def histories(self):
        """The recorded contact force and bead velocity histories ([outputs] histories) as an
        xarray Dataset with dimensions time (s) x contact, or None when the scene asked for none.

        Variables: force (N), the force of contact i; velocity (m/s), the velocity of bead i (the
        left bead of contact i). Units in each variable's and coordinate's ``attrs["units"]``.
        """
        import xarray as xr

        s = self.solution
        if not s.history_contacts:
            return None
        contacts = np.asarray(s.history_contacts, dtype=np.int64) + 1
        time = xr.Variable("time", np.asarray(s.history_time, dtype=np.float64), {"units": "s", "long_name": "time"})
        contact = xr.Variable(
            "contact", contacts, {"units": "1", "long_name": "contact i (between bead i and bead i+1)"}
        )
        return xr.Dataset(
            {
                "force": (
                    ("time", "contact"),
                    np.asarray(s.history_force, dtype=np.float64).reshape(time.size, contacts.size),
                    {"units": "N", "long_name": "contact force F_{i,i+1}"},
                ),
                "velocity": (
                    ("time", "contact"),
                    np.asarray(s.history_velocity, dtype=np.float64).reshape(time.size, contacts.size),
                    {"units": "m/s", "long_name": "velocity v_i of bead i (the left bead of contact i)"},
                ),
            },
            coords={"time": time, "contact": contact},
            attrs=self._array_attrs("contact force and bead velocity histories"),
        )

    @property
    def snapshots(self):
        """The profiles along the chain at the snapshot times ([outputs] snapshots) as an xarray
        Dataset, or None when the scene asked for none.

        Variables: contact_force (N) over contact x time (contact i between bead i and i+1);
        displacement (m) and velocity (m/s) over bead x time. Units in ``attrs["units"]``.
        """
        import xarray as xr

        s = self.solution
        if not np.size(s.snapshot_time):
            return None
        n = int(self.scene.chain.beads)
        time = xr.Variable("time", np.asarray(s.snapshot_time, dtype=np.float64), {"units": "s", "long_name": "time"})
        bead = xr.Variable("bead", np.arange(1, n + 1, dtype=np.int64), {"units": "1", "long_name": "bead i"})
        contact = xr.Variable(
            "contact",
            np.arange(1, n, dtype=np.int64),
            {"units": "1", "long_name": "contact i (between bead i and bead i+1)"},
        )
        t = time.size

        def arr(a, width):
            return np.asarray(a, dtype=np.float64).reshape(t, width).T

        return xr.Dataset(
            {
                "contact_force": (
                    ("contact", "time"),
                    arr(s.snapshot_force, n - 1),
                    {"units": "N", "long_name": "contact force F_{i,i+1}"},
                ),
                "displacement": (
                    ("bead", "time"),
                    arr(s.snapshot_displacement, n),
                    {"units": "m", "long_name": "bead displacement u_i"},
                ),
                "velocity": (
                    ("bead", "time"),
                    arr(s.snapshot_velocity, n),
                    {"units": "m/s", "long_name": "bead velocity v_i"},
                ),
            },
            coords={"contact": contact, "bead": bead, "time": time},
            attrs=self._array_attrs("force, displacement and velocity along the chain at the snapshot times"),
        )

    @property
    def dump(self):
        """The whole-chain dump (chain.dump: a LAMMPS run with ``[outputs] dump_interval`` and ``out``)
        as an xarray Dataset over time (s) x bead, or None when the run directory has none.

        Variables: position (the bead's centre x) and displacement (m), velocity (m/s) over time x
        bead; contact_force (N) over time x contact. Units in ``attrs["units"]``; a symbolic link in
        place of the file is refused (granchain.postprocess.chain_dump).
        """
        from granchain.postprocess.chain_dump import CHAIN_DUMP, chain_dump_dataset
        from granchain.safe_files import check_not_link

        if self.path is None:
            return None
        path = Path(self.path) / CHAIN_DUMP
        check_not_link(path)
        if not path.is_file():
            return None
        return chain_dump_dataset(path, self.scene, self._array_attrs(f"the whole-chain dump {CHAIN_DUMP}"))

    @property
    def energy(self):
        """energy.csv as a pandas DataFrame indexed by time (s): kinetic, potential (stored in the
        contacts), dissipated and work (done on the chain by the load), all in J
        (``df.attrs["units"]``)."""
        import pandas as pd

        s = self.solution
        df = pd.DataFrame(
            {
                "kinetic": np.asarray(s.kinetic, dtype=np.float64),
                "potential": np.asarray(s.potential, dtype=np.float64),
                "dissipated": np.asarray(s.dissipated, dtype=np.float64),
                "work": np.asarray(s.work, dtype=np.float64),
            },
            index=pd.Index(np.asarray(s.energy_time, dtype=np.float64), name="time"),
        )
        df.attrs["units"] = {"time": "s", "kinetic": "J", "potential": "J", "dissipated": "J", "work": "J"}
        return df

    def _array_attrs(self, what: str) -> dict:
        sm = self.summary
        return {
            "description": what,
            "title": self.scene.title or "",
            "backend": sm["backend"],
            "method": sm["method"],
            "timestep": sm["timestep"],
            "timestep_units": "s",
        }

    # ---- display

    def __repr__(self) -> str:
        """A few lines: scene, backend, step, key observables with their errors (< 2000 characters)."""
        try:
            sm = self.summary
        except Exception as e:  # a display never raises: say what is missing
            return f"<{type(self).__name__} {self.backend}: summary unavailable ({type(e).__name__}: {e})>"
        t = lambda x: printable(x, 80)  # noqa: E731 - the summary's text as a terminal shows it
        lines = [f"<{type(self).__name__}: {printable(self.scene.title or self.scene.source or 'untitled scene', 120)}"]
        lines.append(
            f"  {t(sm['backend'])} ({t(sm['method'])}), dt = {sm['timestep']:.4g} s, {sm['steps']} steps to "
            f"t = {sm['end_time']:.4g} s, {sm['wall_time']:.3g} s wall; {t(sm.get('beads', '?'))} beads, "
            f"{t(sm.get('contact_law', '?'))} contacts, {t(sm.get('loading', '?'))} load"
        )
        missing = sm.get("observables_missing") or {}
        notes = sm.get("observables_notes") or {}
        for name, value, unit, err in _key_observables(sm):
            if value is None:
                why = printable(missing.get(name, "not measured"), 100)
                lines.append(f"  {name:28s} -   ({why})")
                continue
            bar = f" +- {err:.2g}" if err is not None else ""
            note = f"   (note: {printable(notes[name], 100)})" if name in notes else ""
            lines.append(f"  {name:28s} {t(_num(value))}{bar} {unit}{note}")
        pk = sm.get("peaks") or {}
        if pk:
            lines.append(
                f"  peaks: {t(pk.get('complete', 0))} complete, {t(pk.get('incomplete', 0))} incomplete, "
                f"{t(pk.get('unreached', 0))} unreached"
            )
        if self.path is not None:
            lines.append(f"  run directory: {printable(str(self.path), 200)}")
        return "\n".join(lines) + ">"

    def _repr_html_(self) -> str:
        """A small HTML table for notebooks: the run, then each key observable with its error and unit."""
        sm = self.summary
        rows = [
            ("scene", self.scene.title or self.scene.source or "untitled scene", ""),
            ("backend", f"{sm['backend']} ({sm['method']})", ""),
            ("time step", f"{sm['timestep']:.4g}", "s"),
            ("steps", sm["steps"], ""),
            ("end time", f"{sm['end_time']:.4g}", "s"),
            ("wall time", f"{sm['wall_time']:.3g}", "s"),
            ("beads", sm.get("beads", "?"), ""),
            ("contact law, load", f"{sm.get('contact_law', '?')}, {sm.get('loading', '?')}", ""),
        ]
        for name, value, unit, err in _key_observables(sm):
            rows.append((name, _num(value) + (f" \u00b1 {err:.2g}" if err is not None else ""), unit))
        pk = sm.get("peaks") or {}
        if pk:
            rows.append(("peaks", ", ".join(f"{v} {k}" for k, v in pk.items()), ""))
        if self.path is not None:
            rows.append(("run directory", self.path, ""))
        return html_table(rows, f"granchain {type(self).__name__}")

    def plot(self, kind: str = "peaks", **kw):
        """A figure of this run: ``kind`` one of "peaks", "histories", "snapshots", "heatmap".

        Returns a matplotlib Figure (not shown, not saved, pyplot's state untouched: a notebook shows
        it as a cell's value; ``fig.savefig(path)`` writes it). Keywords go to the figure function of
        granchain.workflows.plots (e.g. ``log=False`` for linear peak axes).
        """
        if _PLOTTER is None:
            raise RuntimeError(
                "no figure functions are loaded: import granchain (granchain.run and granchain.load_run "
                "load them) or granchain.workflows.plots"
            )
        return _PLOTTER(self, kind, **kw)

    def price(self) -> dict:
        """What the run cost (summary.json's "price"), in s unless named otherwise:

        start_up      LAMMPS: starting its process, Python, the LAMMPS instance and loading the plugin
                      (the parent's clock around the process minus the deck's own time; 0 in process)
        plugin_build  compiling the plugin (0 when it was cached)
        setup         LAMMPS: the deck outside its run loops (data file, each run's setup, snapshot and
                      results dumps)
        integration   the time-stepping loops without their output (LAMMPS: "Loop time" minus the
                      "Output" rows of its timing breakdown; reference: the solver, whose histories
                      and energy samples are recorded inside its loop and counted here)
        output        LAMMPS: dumps and thermo during the runs plus reading the results back
        error_estimate  the companion runs at 2 dt and 4 dt (granchain.workflows.error_estimates), when made
        steps, bead_steps (steps x moving beads, striker included), ns_per_bead_step (integration)
        A part the backend does not time is None, with the reason in "not_timed". A loaded run's is
        its summary's.
        """
        if self.stored is not None and "price" in self.stored.summary:
            return copy.deepcopy(self.stored.summary["price"])
        s, sc, ex = self.solution, self.scene, self.extra
        steps = int(s.steps) + int(s.extra_steps or 0)
        beads = int(sc.chain.beads) + (1 if sc.loading.kind == "striker" else 0)
        not_timed: dict[str, str] = {}
        if self.backend == "lammps":
            loop, out_t = ex.get("loop_time"), ex.get("output_time")
            # the process from its start to the deck's first command (the worker times only the part
            # after Python started): what a user waits before LAMMPS integrates anything
            proc = ex.get("process_time")
            start = ex.get("startup_time") if proc is None else max(float(proc) - float(s.wall_time), 0.0)
            integration = None if loop is None else loop - (out_t or 0.0)
            setup = None if loop is None else max(float(s.wall_time) - loop, 0.0)
            output = None if out_t is None else out_t + float(ex.get("read_time") or 0.0)
            if loop is None:
                not_timed["integration"] = not_timed["setup"] = "no timing breakdown in log.lammps"
            if start is None:
                not_timed["start_up"] = "not run through granchain's worker (a plain-LAMMPS run collected)"
            plugin = float(ex.get("plugin_build_time") or 0.0)
        else:
            start, plugin, setup, integration, output = 0.0, 0.0, 0.0, float(s.wall_time), None
            not_timed["output"] = "recorded inside the integration loop (histories, energy samples): counted there"
        parts = [start, plugin, setup, integration, output]
        companions = None if self.errors is None else float(sum(self.errors.wall_times))
        return {
            "wall_time": float(sum(p for p in parts if p is not None)),
            "start_up": start,
            "plugin_build": plugin,
            "setup": setup,
            "integration": integration,
            "output": output,
            "error_estimate": companions,
            "steps": steps,
            "bead_steps": steps * beads,
            "ns_per_bead_step": None if integration is None or steps == 0 else 1e9 * integration / (steps * beads),
            **({"not_timed": not_timed} if not_timed else {}),
        }

    def provenance(self) -> dict:
        """Where the run came from: the summary's "provenance" (see :func:`provenance`); a loaded run's
        as written."""
        if self.stored is not None and "provenance" in self.stored.summary:
            return copy.deepcopy(self.stored.summary["provenance"])
        return provenance(self)

    def lammps_provenance(self) -> dict | None:
        """The provenance record's "lammps": None here; a LAMMPS run's result says which LAMMPS and
        plugin ran it (granchain.lammps.runner.LammpsRunResult)."""
        return None


class Summary(dict):
    """summary.json as a dict; calling it returns itself (``result.summary()`` as well as
    ``result.summary[...]``)."""

    def __call__(self) -> Summary:
        """The summary itself (``result.summary()`` as well as ``result.summary[...]``)."""
        return self


@dataclass
class StoredRun:
    """What a run directory keeps that a ChainSolution cannot give again: summary.json as read, and
    peaks.csv's columns (name -> array, contact 1-based), error columns included."""

    summary: dict
    peaks: dict


#: the figure function RunResult.plot calls (result, kind, **kw) -> Figure; granchain.workflows.plots
#: registers it (the package root, granchain.run and granchain.load_run see that it is)
_PLOTTER = None


def register_plotter(fn) -> None:
    """Set the function RunResult.plot draws with (granchain.workflows.plots.plot_result)."""
    global _PLOTTER
    _PLOTTER = fn
