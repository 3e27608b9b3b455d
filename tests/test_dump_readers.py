"""The whole-chain LAMMPS dump (chain.dump, [outputs] dump_interval) opens in the readers other tools
use: ASE's ``lammps-dump-text`` (it needs a ``type`` column and keeps only prefixed columns, hence
``v_radius``) and MDAnalysis's ``LAMMPSDUMP`` (types from ``type``, the radius as an additional
column), with every atom, the beads' radii and the positions; granchain's own reader is unchanged."""

from __future__ import annotations

import warnings

import ase.io
import MDAnalysis as mda
import numpy as np
import pytest

import granchain
from granchain.postprocess.dumps import read_dump
from granchain.schedule import scene_step_plan, step_times
from granchain.templates import atom_layout

TAPERED = """title = "dump readers: tapered chain"
[chain]
beads = 16
radius = 4.76e-3
taper = 0.95
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "impulse"
impulse = 0.05
duration = 1e-6
[run]
end_time = 6e-5
timestep = "auto"
[outputs]
dump_interval = 3e-6
"""

WALL = TAPERED.replace("taper = 0.95\n", "").replace('title = "dump readers: tapered chain"', 'title = "wall"') + (
    '[boundary]\nfar_end = "wall"\n'
)


@pytest.fixture(scope="module", params=["tapered", "wall"])
def dumped(request, tmp_path_factory):
    """A LAMMPS run with a whole-chain dump: (scene, run directory)."""
    text = TAPERED if request.param == "tapered" else WALL
    scene = granchain.parse_scene(text, source=f"{request.param}.toml")
    out = tmp_path_factory.mktemp("dump") / request.param
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = granchain.run(scene, backend="lammps", out=out)
    return r.scene, out


def expected(scene):
    """The atoms a deck writes, in ID order: (count, beads' slice, bead radii)."""
    lay = atom_layout(scene)
    o, n = lay["offset"], scene.chain.beads
    return lay["natoms"], slice(o, o + n), np.asarray(scene.bead_radii, dtype=float)


def test_ase_reads_every_frame_with_the_atoms_and_radii(dumped):
    scene, out = dumped
    natoms, beads, radii = expected(scene)
    frames = ase.io.read(out / "chain.dump", format="lammps-dump-text", index=":")
    times = step_times(scene_step_plan(scene), scene.run.timestep)
    assert len(frames) == read_dump(out / "chain.dump", times).time.size > 10
    for atoms in frames:
        assert len(atoms) == natoms
        np.testing.assert_allclose(atoms.arrays["v_radius"][beads], radii, rtol=1e-15)
        assert set(atoms.arrays["type"][beads]) >= {1}
    # the first frame: beads touching along x, D_i apart (sum of neighbouring radii)
    x = frames[0].positions[beads, 0]
    np.testing.assert_allclose(np.diff(x), radii[:-1] + radii[1:], rtol=1e-12)


def test_mdanalysis_reads_the_types_and_radii(dumped):
    scene, out = dumped
    natoms, beads, radii = expected(scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "Guessed all Masses to 1.0"
        u = mda.Universe(str(out / "chain.dump"), format="LAMMPSDUMP", additional_columns=["radius"], dt=1.0)
    assert len(u.atoms) == natoms
    order = np.argsort(u.atoms.ids)
    assert u.trajectory.n_frames > 10
    for ts in u.trajectory[:: max(1, u.trajectory.n_frames // 4)]:
        np.testing.assert_allclose(np.asarray(ts.data["radius"])[order][beads], radii, rtol=1e-15)
    types = np.asarray(u.atoms.types)[order]
    assert types[beads][0] == "1"
    assert len(set(types)) == (2 if scene.effects.far_end == "wall" else len(set(radii)))


def test_granchain_reads_its_columns_by_name_as_before(dumped):
    scene, out = dumped
    times = step_times(scene_step_plan(scene), scene.run.timestep)
    dd = read_dump(out / "chain.dump", times)
    natoms, beads, _ = expected(scene)
    assert dd.columns["d_fc"].shape == (dd.time.size, natoms)
    assert np.all(np.diff(dd.time) > 0)
    assert dd.columns["d_fc"][:, beads].max() > 0  # the wave is in it
    header = (out / "chain.dump").read_text().split("ITEM: ATOMS ", 1)[1].split("\n", 1)[0].split()
    assert header[:3] == ["id", "type", "radius"]
    assert {"x", "y", "z", "vx", "vy", "vz"} <= set(header)
