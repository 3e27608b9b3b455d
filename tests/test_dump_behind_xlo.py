"""A bead behind the box's initial lower face (issue 43 item 1: "the corner moves if a bead goes behind
xlo"): three brass beads driven at 30 m/s into a wall rebound, and bead 1 ends about 1 cm behind where
it started, past chain.data's xlo (a diameter behind it), so LAMMPS's shrink-wrapped lower face follows
it. The whole-chain dump's x column is the bead's centre in the deck's fixed frame whatever the box, so
the readers as docs/notebook.md calls them (ASE with units="si", MDAnalysis with additional_columns,
the xarray view) still give the run's own SI state (snapshots, histories) to 1e-12; MDAnalysis's own
float32 positions are measured from each frame's lower face, which moved (the docs say so). One LAMMPS
run of 8000 steps, about a second."""

from __future__ import annotations

import re
import warnings

import ase.io
import ase.units
import MDAnalysis as mda
import numpy as np
import pytest

import granchain

from .conftest import make_scene_text
from .test_dump_si import close, truth

OUTPUTS = "histories = [1, 2]\nsnapshots = [3e-4, 3.5e-4, 4e-4]\nhistory_interval = 2e-6\ndump_interval = 2e-6"
REBOUND = (
    make_scene_text(
        beads=3, loading='kind = "velocity"\nvelocity = 30.0', end_time=4e-4, timestep=5e-8, outputs=OUTPUTS
    )
    + '\n[boundary]\nfar_end = "wall"\n'
)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    scene = granchain.parse_scene(REBOUND, source="rebound.toml")
    out = tmp_path_factory.mktemp("behind_xlo") / "rebound"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = granchain.run(scene, backend="lammps", out=out)
    return result, out / "chain.dump"


def lower_faces(dump) -> np.ndarray:
    """Each frame's box lower face along x, as the dump's BOX BOUNDS give it."""
    return np.array([float(x) for x in re.findall(r"ITEM: BOX BOUNDS[^\n]*\n(\S+) ", dump.read_text())])


def check_frames(result, frames) -> int:
    """frames: (step, time, positions, velocities) of the beads, SI; each against the run's own state at
    its step (snapshots: positions and velocities; histories: velocities). Returns the frames checked
    against a snapshot."""
    times, _, grid, x0, snap, hist_v, hist_beads = truth(result)
    at_snapshot = 0
    for step, t, x, v in frames:
        close(t, times[step])
        if step == 0:
            close(x, x0)
        if step in snap:
            close(x, grid + snap[step][0])
            close(v, snap[step][1])
            at_snapshot += 1
        if step in hist_v:
            close(v[hist_beads], hist_v[step])
    return at_snapshot


def test_bead_1_goes_behind_the_initial_lower_face(run):
    result, dump = run
    faces = lower_faces(dump)
    grid = truth(result)[2]
    last = grid + result.snapshots.displacement.sel(time=4e-4, method="nearest").values
    assert last[0] < faces[0]  # behind chain.data's xlo
    assert faces[-1] < faces[0]  # and the box's face followed it
    assert np.all(result.snapshots.velocity.values[-1] < 0)  # every bead rebounds


def test_ase_reads_the_fixed_frame(run):
    result, dump = run
    _, beads, *_ = truth(result)
    frames = ase.io.read(dump, format="lammps-dump-text", index=":", units="si")
    to_m, to_mps = 1.0 / ase.units.m, ase.units.s / ase.units.m
    rows = [
        (a.info["timestep"], a.arrays["v_time"][0], a.positions[beads, 0] * to_m, a.get_velocities()[beads, 0] * to_mps)
        for a in frames
    ]
    assert check_frames(result, rows) == 3


def test_mdanalysis_columns_read_the_fixed_frame_and_its_positions_the_moving_face(run):
    result, dump = run
    _, beads, *_ = truth(result)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # masses guessed, element X unknown to MDAnalysis
        u = mda.Universe(str(dump), format="LAMMPSDUMP", additional_columns=["x", "vx", "v_time"], dt=1.0)
    rows, offsets = [], []
    for ts in u.trajectory:
        d = ts.data
        rows.append((d["step"], d["v_time"][0], d["x"][beads], d["vx"][beads]))
        offsets.append(np.median(d["x"][beads] - u.atoms.positions[beads, 0]))
    assert check_frames(result, rows) == 3
    # MDAnalysis's own positions: x less each frame's lower face (to float32), the face that moved
    faces = lower_faces(dump)
    np.testing.assert_allclose(offsets, faces, rtol=0, atol=1e-6 * np.max(np.abs(faces)))
    assert np.ptp(offsets) > 1e-2 * np.max(np.abs(faces))


def test_the_xarray_view_reads_the_fixed_frame(run):
    result, dump = run
    ds = granchain.load_dump(dump.parent)
    rows = zip(ds.step.values, ds.time.values, ds.position.values, ds.velocity.values, strict=True)
    assert check_frames(result, [(int(s), t, x, v) for s, t, x, v in rows]) == 3
    close(ds.position.values - truth(result)[2], ds.displacement.values)
