"""Why chain.dump carries its time as a v_time column, not LAMMPS's ITEM: TIME header (docs/notebook.md,
"Other tools"): the installed MDAnalysis cannot open a dump with that header (2.11: its topology parser
counts the header lines and finds no id column), while ASE opens it and drops the time. If MDAnalysis
learns to read it, this test fails: then the decks could write ITEM: TIME (dump_modify time yes)."""

from __future__ import annotations

import warnings

import ase.io
import MDAnalysis as mda
import pytest


def frame(step: int, time: float, header: bool) -> str:
    """One frame of two atoms as chain_dump.lmp.j2 writes it (time in its v_time column), with LAMMPS's
    ITEM: TIME header too if header."""
    head = f"ITEM: TIME\n{time!r}\n" if header else ""
    atoms = "".join(f"{i} 1 0.001 {0.002 * (i - 1)!r} 0 0 0.5 0 0 {time!r} X\n" for i in (1, 2))
    return (
        f"{head}ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ms pp pp\n-0.002 0.004\n"
        f"-0.002 0.002\n-0.002 0.002\nITEM: ATOMS id type radius x y z vx vy vz v_time element\n{atoms}"
    )


def test_mdanalysis_cannot_open_a_dump_with_item_time_and_reads_v_time(tmp_path):
    timed, plain = tmp_path / "timed.dump", tmp_path / "plain.dump"
    timed.write_text(frame(0, 0.0, True) + frame(7, 3.5e-7, True))
    plain.write_text(frame(0, 0.0, False) + frame(7, 3.5e-7, False))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match="id column"):
            mda.Universe(str(timed), format="LAMMPSDUMP")
        u = mda.Universe(str(plain), format="LAMMPSDUMP", additional_columns=["v_time"], dt=1.0)
    assert [float(ts.data["v_time"][0]) for ts in u.trajectory] == [0.0, 3.5e-7]
    frames = ase.io.read(timed, format="lammps-dump-text", index=":", units="si")
    assert [a.info["timestep"] for a in frames] == [0, 7]
    assert all(set(a.info) == {"timestep"} for a in frames)  # ASE keeps no time from the header
