"""The shaker on both backends (issue 46 item 1): LAMMPS and the reference's velocity Verlet step for step,
with every law, and the effects a shaker goes with (precompression, a wall, damping, gravity)."""

from __future__ import annotations

import numpy as np
import pytest

from granchain.lammps.runner import run_lammps
from granchain.scene import parse_scene
from granchain.templates import render_deck
from granchain.workflows.run import run_reference

from .conftest import LAW_NAMES, make_scene_text

SLOW = pytest.mark.slow  # (the fast set keeps Hertz with every effect but gravity, and the free chain)


def shaken(law: str = "hertz", extra: str = "", amplitude: float = 4e-8, ramp: float = 1.0) -> str:
    loading = f'kind = "shaker"\namplitude = {amplitude!r}\nfrequency = 20000.0\ncycles = 2\nramp = {ramp!r}\n'
    text = make_scene_text(
        beads=8, law=law, loading=loading, end_time=1.4e-4, timestep=2e-8, outputs="histories = [1, 4, 7]\n"
    )
    return text + extra


PRECOMPRESSED_WALL_DASHPOT = (
    '\n[precompression]\nforce = 10.0\n[boundary]\nfar_end = "wall"\n[damping]\ndashpot = 5.0\n'
)

#: the force histories' agreement, of their largest force: 1e-9 on a precompressed chain; where contacts
#: open and close (an uncompressed chain) 1e-8, the force drive's (tests/test_harmonic_load.py): LAMMPS's
#: absolute positions (~0.05 m, an ulp 7e-18 m) round a closing overlap of ~1e-8 m at 1e-9 of itself, and
#: Hertz's alpha^1.5 takes it from there (measured: 1.3e-9)
STEP_FOR_STEP, OPENING = 1e-9, 1e-8

CASES = [
    pytest.param(law, PRECOMPRESSED_WALL_DASHPOT, 1.0, marks=() if law == "hertz" else SLOW, id=f"{law}-wall-dashpot")
    for law in LAW_NAMES
] + [
    pytest.param(
        "hertz",
        '\n[precompression]\nforce = 5.0\n[boundary]\nfar_end = "wall"\n[gravity]\ng = 9.81\n'
        "[damping]\nkuwabara_kono = 1e-6\n",
        1.0,
        marks=SLOW,
        id="hertz-gravity-kuwabara-kono",
    ),
    # uncompressed and free, no ramp: the driver starts at A 2 pi f, pushes bead 1 and loses it
    pytest.param("hertz", "", 0.0, id="hertz-free-no-ramp"),
]
#: a law with kinks (bilinear, Thornton): Verlet crosses a kink a step early or late with the round-off of
#: either backend, as under the force drive (tests/test_harmonic_load.py: 1e-8; measured 4.5e-9, bilinear)
KINKED = ("bilinear", "thornton")
#: gravity's static state as chain.data's positions hold it is a round-off off the reference's (each
#: contact at its own weight; measured 1.3e-9 with Kuwabara-Kono damping): 1e-8, as the force drive's


@pytest.mark.parametrize(("law", "extra", "ramp"), CASES)
def test_lammps_and_the_reference_verlet_agree_step_for_step(law, extra, ramp):
    sc = parse_scene(shaken(law, extra, ramp=ramp), source="shaken.toml")
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    # (the driver's contact first, then every bead-bead contact: a harmonic scene records them all)
    assert tuple(lam.history_contacts) == tuple(ref.history_contacts) == (-1, *range(7))
    assert lam.history_force.shape == ref.history_force.shape
    scale = np.max(np.abs(ref.history_force))
    assert scale > 0.0
    tolerance = OPENING if (not extra or law in KINKED or "[gravity]" in extra) else STEP_FOR_STEP
    assert np.max(np.abs(lam.history_force - ref.history_force)) <= tolerance * scale
    # the final velocities, the chain's ringing after the driver stopped, as the force drive's test has
    # them (tests/test_harmonic_load.py): each a sum of the steps' kicks (measured: 1.7e-8 of the largest)
    assert np.max(np.abs(lam.velocity - ref.velocity)) <= 1e-7 * np.max(np.abs(ref.velocity))
    # (of the largest: a far contact an uncompressed chain barely reaches peaks at round-off)
    assert np.max(np.abs(lam.peak_force - ref.peak_force)) <= tolerance * scale
    # the driver's work, summed the same way on both; the energy balance holds on each
    assert lam.work[-1] == pytest.approx(ref.work[-1], rel=1e-6)
    put_in = np.max(np.abs(ref.work))
    for sol in (lam, ref):
        assert np.max(np.abs(sol.energy_balance_error)) < 1e-4 * put_in


def test_the_deck_moves_the_driver_and_pushes_nothing_else():
    """The deck's driver: atom 1, its contact force removed and its mass times x_d'' added; no F0 push on
    bead 1 (the driver holds it); it stops at T."""
    sc = parse_scene(shaken(extra=PRECOMPRESSED_WALL_DASHPOT), source="shaken.toml")
    deck = render_deck(sc).deck
    assert "fix             driver_hold driver setforce 0.0 0.0 0.0" in deck
    assert 'variable        drive equal "mass[1]*(' in deck
    assert "pre_push" not in deck
    assert "velocity        driver set 0.0 0.0 0.0" in deck
