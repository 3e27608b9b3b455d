"""The whole-chain dump read as docs/notebook.md shows, in ASE, MDAnalysis and granchain's xarray
view, gives the run's own SI state: each frame's time (the run's step plan, the snapshot times), the
positions (the unloaded chain's plus the snapshots' displacements, which count from it) and the
velocities (the histories, recorded apart by fix chain/history, and the snapshots), to 1e-12
relative, on a struck tapered, a precompressed and a walled chain. Each LAMMPS run is about a second
(12 beads, 500 steps)."""

from __future__ import annotations

import warnings

import ase.io
import ase.units
import MDAnalysis as mda
import numpy as np
import pytest
import xarray as xr

import granchain
from granchain.postprocess.dumps import read_dump
from granchain.problem import precompressed_displacements, scene_static_load
from granchain.schedule import scene_step_plan, step_times
from granchain.templates import atom_layout

from .conftest import make_scene_text

RTOL = 1e-12

OUTPUTS = "histories = [1, 5]\nsnapshots = [8e-6, 1.6e-5]\nhistory_interval = 5e-8\ndump_interval = 5e-8"
WALL = '\n[boundary]\nfar_end = "wall"\n'


def scene_text(beads: int, extra: str = "") -> str:
    """A brass chain under a short impulse, 500 steps, dumped every step."""
    impulse = 'kind = "impulse"\nimpulse = 0.05\nduration = 1e-6'
    return make_scene_text(beads=beads, loading=impulse, end_time=2.5e-5, timestep=5e-8, outputs=OUTPUTS) + extra


SCENES = {
    "struck": scene_text(12).replace('material = "brass"', 'taper = 0.95\nmaterial = "brass"', 1),
    "precompressed": scene_text(12, "\n[precompression]\nforce = 100.0\n" + WALL),
    "walled": scene_text(6, WALL),
}


@pytest.fixture(scope="module", params=sorted(SCENES))
def run(request, tmp_path_factory):
    """A LAMMPS run of one scene with a dump every step: (result, its chain.dump)."""
    scene = granchain.parse_scene(SCENES[request.param], source=f"{request.param}.toml")
    out = tmp_path_factory.mktemp("dump_si") / request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = granchain.run(scene, backend="lammps", out=out)
    return result, out / "chain.dump"


def truth(result):
    """The run's own SI state, apart from chain.dump: (times by step, beads' slice among the atoms,
    the unloaded chain's and the start positions, {snapshot step: (displacement, velocity)},
    {step: history velocities}, the history beads' indices)."""
    scene = result.scene
    times = step_times(scene_step_plan(scene), scene.run.timestep)
    lay = atom_layout(scene)
    beads = slice(lay["offset"], lay["offset"] + scene.chain.beads)
    grid = np.asarray(scene.bead_positions, dtype=float)  # the unloaded chain
    x0 = grid + (precompressed_displacements(scene)[0] if scene_static_load(scene) else 0.0)
    snaps = result.snapshots
    at = {int(np.flatnonzero(times == t)[0]): t for t in snaps.time.values}
    snap = {k: (snaps.displacement.sel(time=t).values, snaps.velocity.sel(time=t).values) for k, t in at.items()}
    hist = result.histories
    hsteps = np.searchsorted(times, hist.time.values)
    assert np.allclose(times[hsteps], hist.time.values, rtol=RTOL, atol=0)
    velocity = {int(k): hist.velocity.values[i] for i, k in enumerate(hsteps)}
    return times, beads, grid, x0, snap, velocity, [c - 1 for c in hist.contact.values]


def close(got, want):
    np.testing.assert_allclose(got, want, rtol=RTOL, atol=RTOL * max(1e-300, float(np.max(np.abs(want)))))


def check_frames(result, frames):
    """frames: (step, time, positions, velocities) of the beads, SI, per frame read."""
    times, _, grid, x0, snap, hist_v, hist_beads = truth(result)
    seen = set()
    for step, t, x, v in frames:
        close(t, times[step])
        if step == 0:
            close(x, x0)
        if step in snap:
            close(x, grid + snap[step][0])
            close(v, snap[step][1])
        if step in hist_v:
            close(v[hist_beads], hist_v[step])
        seen.add(step)
    assert len(seen) == times.size  # every step
    assert set(snap) <= seen


def test_ase_reads_si_positions_velocities_times_and_no_element(run):
    result, dump = run
    _, beads, *_ = truth(result)
    frames = ase.io.read(dump, format="lammps-dump-text", index=":", units="si")
    to_m, to_mps = 1.0 / ase.units.m, ase.units.s / ase.units.m  # ASE's own units (Å, Å per ASE time) to SI
    check_frames(
        result,
        [
            (
                a.info["timestep"],
                a.arrays["v_time"][0],
                a.positions[beads, 0] * to_m,
                a.get_velocities()[beads, 0] * to_mps,
            )
            for a in frames
        ],
    )
    assert {s for a in frames for s in a.get_chemical_symbols()} == {"X"}  # not H, He, Li, ... by bead kind


def test_mdanalysis_reads_si_columns_and_positions_from_a_fixed_corner(run):
    result, dump = run
    _, beads, _, x0, snap, *_ = truth(result)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # masses guessed, element X unknown to MDAnalysis
        u = mda.Universe(str(dump), format="LAMMPSDUMP", additional_columns=["x", "vx", "v_time"], dt=1.0)
    frames, corner = [], []
    for ts in u.trajectory:
        d = ts.data
        frames.append((d["step"], d["v_time"][0], d["x"][beads], d["vx"][beads]))
        # MDAnalysis's own float32 positions, measured from the box's lower corner: the corner stays put,
        # so x minus them is one number for every bead and frame (to float32's resolution)
        corner.append(d["x"][beads] - u.atoms.positions[beads, 0])
    check_frames(result, frames)
    corner = np.concatenate(corner)
    assert np.ptp(corner) < 8 * np.finfo(np.float32).eps * np.max(np.abs(x0)) + 1e-9
    assert np.ptp(corner) < 1e-3 * max(np.max(np.abs(s[0])) for s in snap.values())  # far below the travel


def test_xarray_view_is_the_si_state_and_round_trips_through_netcdf(run, tmp_path):
    result, dump = run
    ds = granchain.load_dump(dump.parent)
    xr.testing.assert_identical(ds, result.dump)
    check_frames(
        result,
        [
            (int(s), t, x, v)
            for s, t, x, v in zip(ds.step.values, ds.time.values, ds.position.values, ds.velocity.values, strict=True)
        ],
    )
    grid = truth(result)[2]
    close(ds.position.values - grid, ds.displacement.values)
    assert {k: ds[k].attrs["units"] for k in ("time", "position", "displacement", "velocity", "contact_force")} == {
        "time": "s",
        "position": "m",
        "displacement": "m",
        "velocity": "m/s",
        "contact_force": "N",
    }
    ds.to_netcdf(tmp_path / "dump.nc")
    xr.testing.assert_identical(xr.load_dataset(tmp_path / "dump.nc"), ds)


def test_a_dump_without_the_new_columns_reads_the_same(run, tmp_path):
    # a chain.dump of a deck before v_time and element (its box shrink-wrapped): the view takes each
    # frame's time from the step plan, granchain's reader its columns by name, the same numbers
    result, dump = run
    lines = dump.read_text().splitlines()
    header = next(line for line in lines if line.startswith("ITEM: ATOMS")).split()[2:]
    keep = [i for i, c in enumerate(header) if c not in ("v_time", "element")]
    old = []
    for line in lines:
        if line.startswith("ITEM: ATOMS"):
            old.append("ITEM: ATOMS " + " ".join(header[i] for i in keep))
        elif len(f := line.split()) == len(header) and not line.startswith("ITEM"):
            old.append(" ".join(f[i] for i in keep))
        else:
            old.append(line.replace("ms pp pp", "ss pp pp"))
    (tmp_path / "chain.dump").write_text("\n".join(old) + "\n")
    new_view = result.dump
    old_view = granchain.postprocess.chain_dump.chain_dump_dataset(tmp_path / "chain.dump", result.scene)
    close(old_view.time.values, new_view.time.values)
    for name in ("position", "displacement", "velocity", "contact_force"):
        np.testing.assert_array_equal(old_view[name].values, new_view[name].values)
    times = step_times(scene_step_plan(result.scene), result.scene.run.timestep)
    a, b = read_dump(tmp_path / "chain.dump", times), read_dump(dump, times)
    for c in a.columns:
        np.testing.assert_array_equal(a.columns[c], b.columns[c])


def test_load_dump_names_a_run_without_one(tmp_path):
    scene = granchain.parse_scene(SCENES["walled"].replace("dump_interval = 5e-8\n", ""), source="walled.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = granchain.run(scene, backend="reference", out=tmp_path / "ref")
    assert result.dump is None
    with pytest.raises(granchain.GranchainError, match=r"no chain.dump.*dump_interval"):
        granchain.load_dump(tmp_path / "ref")


def test_the_view_leaves_a_strikers_atom_out(tmp_path):
    # the striker is atom 1, in front of bead 1: the view's beads are the chain's, from its start
    striker = 'kind = "striker"\nvelocity = 2.0'
    text = make_scene_text(beads=6, loading=striker, end_time=1e-5, timestep=5e-8, outputs="dump_interval = 5e-8")
    scene = granchain.parse_scene(text, source="striker.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = granchain.run(scene, backend="lammps", out=tmp_path / "striker").dump
    assert ds.bead.size == 6
    close(ds.position.values[0], np.asarray(scene.bead_positions, dtype=float))
    assert not ds.velocity.values[0].any()  # at rest until struck; the striker moves at 2 m/s
    assert ds.velocity.values[-1, 0] > 0
