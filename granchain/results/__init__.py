"""The one result format every backend produces, and the run directory it is written to.

A backend (reference solver or LAMMPS) fills a :class:`ChainSolution`, wrapped in a
:class:`RunResult`: the tables researchers use (``peaks`` and ``energy`` as pandas DataFrames,
``histories`` and ``snapshots`` as xarray Datasets, units in their attrs), ``summary`` (a dict), a
short display (``repr``, ``_repr_html_``) and ``plot``. granchain.rundir.write_run_dir turns it into
a run directory; granchain.workflows.load.load_run reads one back into the same RunResult:

    scene.toml      the scene as given
    summary.json    backend, method, timestep, steps, wall_time, price (RunResult.price: start-up,
                    plugin build, setup, integration, output, bead-steps, ns per bead-step),
                    observables (and why any is missing),
                    peak status counts, conservation checks (the state at the end of the run), and
                    provenance (see :func:`provenance`: versions, command, times, host, scene hash, plan)
    peaks.csv       contact,peak_force,time_of_peak,peak_force_nondim,complete,leading_pulse_force,
                    arrival_time (contacts numbered from 1; peak_force: the largest of the run;
                    complete: 1 if that peak is complete, see peaks.complete_peaks; leading_pulse_force
                    and arrival_time: the first maximum and its time, see peaks.leading_pulse; nan
                    until then; a precompressed chain: dynamic_peak_force, dynamic_leading_pulse_force
                    and front_time, the half-amplitude arrival, see postprocess.fronts)
    histories.csv   time, force_<i>, velocity_<i> for each requested contact i (if requested)
    snapshots.csv   time, bead, displacement, velocity, contact_force (if requested)
    energy.csv      time, kinetic, potential, dissipated, work

The directory is written under a hidden temporary name and renamed into place at the end, so an
interrupted run never leaves a directory that looks complete.

The package's modules: solution (ChainSolution), run (RunResult, its summary, tables, display, plot
and price), tables (peaks.csv's columns and units), provenance (where a run came from); printable
text is granchain.scene.display's. Every name is importable from granchain.results itself.
"""

from __future__ import annotations

from granchain.results import run as _run
from granchain.results.provenance import (
    CAMPAIGN_PACKAGES,
    PROVENANCE_SCHEMA,
    RUN_PACKAGES,
    default_command,
    distribution_version,
    package_versions,
    provenance,
    scene_hash,
)
from granchain.results.run import RunResult, StoredRun, Summary, register_plotter
from granchain.results.solution import ChainSolution
from granchain.results.tables import OBSERVABLE_UNITS, PEAK_UNITS, peak_columns
from granchain.scene.display import printable

__all__ = [
    "CAMPAIGN_PACKAGES",
    "OBSERVABLE_UNITS",
    "PEAK_UNITS",
    "PROVENANCE_SCHEMA",
    "RUN_PACKAGES",
    "ChainSolution",
    "RunResult",
    "StoredRun",
    "Summary",
    "default_command",
    "distribution_version",
    "package_versions",
    "peak_columns",
    "printable",
    "provenance",
    "register_plotter",
    "scene_hash",
]


def __getattr__(name: str):
    # the figure function RunResult.plot calls lives in results.run, where register_plotter sets it
    if name == "_PLOTTER":
        return _run._PLOTTER
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
