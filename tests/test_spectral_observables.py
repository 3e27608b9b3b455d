"""The spectral observables of a harmonic drive (issue 46 item 2: far_end_amplitude, transmission):
against the linearised chain's exact steady state (tests/linear_chain.py) on both backends, the far
end's history recorded by itself at >= 32 samples a period, and "not applicable" on a struck run.

The oracle: a precompressed brass chain of N = 5 beads, free far end, a dashpot gamma between beads
(so every internal mode decays: the transient of the switch-on is gone before the lock-in's window),
driven at 1e-3 F0 in the pass band (5 kHz, a third of the cutoff f_c = 14.8 kHz). Linearised about F0
each contact is a spring k = (3/2) K^(2/3) F0^(1/3) (K = (4/3) E* sqrt(R*), Hertz) in parallel with the
dashpot; the force a contact carries is (k + i w gamma)(U_(N-1) - U_N), U the exact steady state of
(K - w^2 M + i w C) U = F. The tolerances are the errors' sum, each bounded:

* reference (RK4, dt = 2.5e-7 s): 1e-4 relative. The step's error (omega_max dt)^4 ~ 3e-7 (omega_max =
  2 sqrt(k/m)); the Hertz nonlinearity shifts the fundamental by O((A/F0)^2) = 1e-6; the transient is
  down by 1e-5 at the window's start (its length is chosen from the oracle's slowest decay rate).
  Measured: 1.6e-7.
* LAMMPS (velocity Verlet, dt = 5e-8 s): 1e-3 relative, the runs' default rtol. Verlet's dashpot force
  lags the velocity by dt / 2 (first order: docs/damping.md), a stiffness shift of gamma w^2 dt / 2 whose
  share grows with dt; measured 2.2e-3 at 2.5e-7 s on the reference's Verlet and 4.4e-4 at 5e-8 s on
  LAMMPS (the first-order scaling).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from granchain.postprocess.observables.spectral import HISTORY_SAMPLES_PER_PERIOD, NOT_DRIVEN
from granchain.scene import parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import run_scene
from tests.linear_chain import state_matrix, steady_state

E, NU, RHO, R = 115e9, 0.3, 8500.0, 4.76e-3  # the scene's "brass"
N, F0, AMPLITUDE, GAMMA, FREQUENCY = 5, 10.0, 0.01, 100.0, 5000.0


def linear_chain() -> tuple[float, float]:
    """(k, m): the Hertz contact's tangent stiffness at F0 and a bead's mass, written out here."""
    e_star = E / (2 * (1 - NU**2))
    hertz = 4 / 3 * e_star * math.sqrt(R / 2)
    return 1.5 * hertz ** (2 / 3) * F0 ** (1 / 3), RHO * 4 / 3 * math.pi * R**3


def drive_cycles() -> int:
    """Cycles enough that the lock-in's window (the second half after the ramp) starts once the
    slowest transient of the linearised chain has decayed by 1e-5."""
    k, m = linear_chain()
    ev = np.linalg.eigvals(state_matrix([m] * N, [k] * (N - 1), dashpots=[GAMMA] * (N - 1))).real
    rate = -np.max(ev[ev < -1e-6 * np.max(np.abs(ev))])  # the rigid-body mode (0) does not load a contact
    return math.ceil(2 + 2 * math.log(1e5) / rate * FREQUENCY + 2)


def driven_text(timestep: float, cycles: int, frequency: float = FREQUENCY, beads: int = N) -> str:
    return f"""[chain]
beads = {beads}
radius = {R}
material = "brass"
[contact]
law = "hertz"
[loading]
kind = "harmonic"
amplitude = {AMPLITUDE}
frequency = {frequency}
cycles = {cycles}
ramp = 2
[precompression]
force = {F0}
[damping]
dashpot = {GAMMA}
[run]
end_time = {cycles / frequency}
timestep = {timestep}
"""


def exact_transmission(frequency: float = FREQUENCY) -> float:
    """|F_(N-1)| / A of the linearised chain's exact steady state (the drive A sin w t on bead 1)."""
    k, m = linear_chain()
    w = 2 * math.pi * frequency
    force = np.zeros(N, dtype=complex)
    force[0] = -1j * AMPLITUDE
    u = steady_state([m] * N, [k] * (N - 1), w, force, dashpots=[GAMMA] * (N - 1))
    return abs((k + 1j * w * GAMMA) * (u[-2] - u[-1])) / AMPLITUDE


@pytest.mark.parametrize(
    ("backend", "method", "timestep", "rtol"),
    [("reference", "rk4", 2.5e-7, 1e-4), ("lammps", None, 5e-8, 1e-3)],
    ids=["reference-rk4", "lammps"],
)
def test_transmission_matches_the_linear_chains_exact_steady_state(backend, method, timestep, rtol):
    scene = parse_scene(driven_text(timestep, drive_cycles()), source="driven.toml")
    result = run_scene(scene, backend=backend, method=method)
    o = result.observables()
    exact = exact_transmission()
    assert o["transmission"] == pytest.approx(exact, rel=rtol)
    assert o["transmission_db"] == pytest.approx(20 * math.log10(exact), abs=20 / math.log(10) * rtol)
    assert o["far_end_amplitude"] == pytest.approx(exact * AMPLITUDE, rel=rtol)
    assert o["drive_amplitude"] == pytest.approx(AMPLITUDE, rel=1e-9)
    assert o["far_end_contact"] == N - 1
    # the window: whole periods, ending by the drive's end, its error bar a small share of the value
    periods = (o["steady_window_end"] - o["steady_window_start"]) * FREQUENCY
    assert periods == pytest.approx(o["steady_window_periods"], abs=1e-6)
    assert o["steady_window_end"] <= scene.loading.duration * (1 + 1e-12)
    assert 0 < o["transmission_error"] < rtol * exact
    note = result.observables_notes()["transmission"]
    assert "whole periods" in note
    assert "not estimated" in note


def test_a_harmonic_scene_records_its_far_end_at_32_samples_a_period():
    scene = parse_scene(
        driven_text(1e-7, 4, frequency=40000.0, beads=9).replace("timestep = 1e-07", 'timestep = "auto"')
    )
    assert scene.outputs.histories == (8,)
    planned = plan_scene(scene).scene
    assert planned.outputs.history_interval * 40000.0 * HISTORY_SAMPLES_PER_PERIOD <= 1 + 1e-9


def test_a_struck_run_has_no_spectral_observable():
    text = driven_text(1e-7, 4).replace(
        'kind = "harmonic"\namplitude = 0.01\nfrequency = 5000.0\ncycles = 4\nramp = 2\n',
        'kind = "velocity"\nvelocity = 0.01\n',
    )
    result = run_scene(parse_scene(text.replace("end_time = 0.0008", "end_time = 2e-5")), backend="reference")
    o, missing = result.observables(), result.observables_missing()
    for key in ("far_end_amplitude", "drive_amplitude", "transmission", "transmission_db"):
        assert o[key] is None
        assert missing[key] == NOT_DRIVEN
