"""The whole-chain LAMMPS dump (chain.dump, [outputs] dump_interval) as an xarray Dataset.

Time and bead are its coordinates, SI units in every variable's and coordinate's ``attrs["units"]``:
position (the bead's centre x), displacement (from the unloaded chain, as in the snapshots) and
velocity over time x bead, contact_force over time x contact. It reads the columns at full precision
(granchain.postprocess.dumps.read_dump: MDAnalysis's ``additional_columns``, float64, not its float32
positions measured from the box's corner). A frame's time is its ``v_time`` column (LAMMPS's own
time); a dump written before decks wrote that column gets the time of its step from the run's step
plan instead, as granchain's other readers do.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from granchain.physics.effects import active_effects
from granchain.postprocess.dumps import read_dump
from granchain.problem import precompressed_displacements, scene_static_load
from granchain.safe_files import read_head
from granchain.schedule import scene_step_plan, step_times

#: the whole-chain dump's file name in a run directory (granchain/templates/chain_dump.lmp.j2)
CHAIN_DUMP = "chain.dump"

#: each column the view reads: (variable, column, dimension, units, long name)
_BEAD_COLUMNS = (
    (
        "position",
        "x",
        "m",
        "bead centre x (the deck's frame: bead i starts at (i-1) D, or displaced by a precompression)",
    ),
    (
        "displacement",
        "v_ux",
        "m",
        "bead displacement u_i from the unloaded chain (a precompression's static one included)",
    ),
    ("velocity", "vx", "m/s", "bead velocity v_i"),
)


def dump_columns(path: str | Path) -> list[str]:
    """The column names of a LAMMPS text dump's first frame (its ``ITEM: ATOMS`` line)."""
    head = read_head(path, 1 << 16).decode("utf-8", errors="replace")
    for line in head.splitlines():
        if line.startswith("ITEM: ATOMS"):
            return line.split()[2:]
    raise ValueError(f"{path}: no ITEM: ATOMS line in its first 64 KiB: not a LAMMPS text dump")


def chain_dump_dataset(path: str | Path, scene, attrs: dict | None = None):
    """A whole-chain dump as an xarray Dataset over time and bead (and contact).

    Parameters
    ----------
    path : str or pathlib.Path
        The dump (a run directory's chain.dump).
    scene : granchain.scene.Scene
        The scene as run: which atoms are the beads (a striker's atom comes first), and, for a dump
        without the ``v_time`` column, the step plan that gives each frame's time.
    attrs : dict, optional
        The Dataset's attributes (the run's title, backend, ...); a description is added.

    Returns
    -------
    xarray.Dataset
        Coordinates time (s), step (the frame's LAMMPS step, along time), bead, contact and radius
        (m, along bead); variables position, displacement (m), velocity (m/s) over time x bead and
        contact_force (N) over time x contact (contact i between bead i and bead i+1). Stored with
        ``to_netcdf`` (scipy's engine, NetCDF 3: steps up to 2**31 - 1) and read back identical.
    """
    import xarray as xr

    timed = "v_time" in dump_columns(path)
    wanted = [c for _, c, _, _ in _BEAD_COLUMNS] + ["d_fc", "radius"] + (["v_time"] if timed else [])
    times = None if timed else step_times(scene_step_plan(scene), scene.run.timestep)
    dd = read_dump(path, times, columns=wanted)
    n = int(scene.chain.beads)
    first = sum(e.beads_in_front for e in active_effects(scene))  # a striker's atom is ID 1
    beads = slice(first, first + n)
    time = dd.columns["v_time"][:, first] if timed else np.asarray(dd.time, dtype=np.float64)
    coords = {
        "time": ("time", time, {"units": "s", "long_name": "time"}),
        "step": ("time", dd.step.astype(np.int64), {"units": "1", "long_name": "LAMMPS step"}),
        "bead": ("bead", np.arange(1, n + 1, dtype=np.int64), {"units": "1", "long_name": "bead i"}),
        "contact": (
            "contact",
            np.arange(1, n, dtype=np.int64),
            {"units": "1", "long_name": "contact i (between bead i and bead i+1)"},
        ),
        "radius": ("bead", dd.columns["radius"][0, beads], {"units": "m", "long_name": "bead radius R_i"}),
    }
    data = {
        name: (("time", "bead"), dd.columns[col][:, beads], {"units": units, "long_name": long})
        for name, col, units, long in _BEAD_COLUMNS
    }
    if scene_static_load(scene):  # displace/atom counts from t = 0: the static displacement added, as in snapshots
        data["displacement"][1][...] += precompressed_displacements(scene)[0]
    # contact i's force lives on bead i's atom
    data["contact_force"] = (
        ("time", "contact"),
        dd.columns["d_fc"][:, first : first + n - 1],
        {"units": "N", "long_name": "contact force F_{i,i+1}"},
    )
    how = "its v_time column" if timed else "the run's step plan (a dump without v_time)"
    info = {**(attrs or {}), "description": f"the whole-chain dump {Path(path).name}; frame times from {how}"}
    return xr.Dataset(data, coords=coords, attrs=info)
