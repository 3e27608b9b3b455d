"""The front's half-amplitude arrival (postprocess.fronts): each contact's crossing-time ladder, recorded
the same way by the pair styles and the reference, read off at half the leading pulse's rise; on a
precompressed chain it is the wave speed's arrival, and its speed tends to the sound speed c0."""

import math
import re
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from granchain.peaks import lead_fall, lead_floor
from granchain.physics.materials import MATERIALS
from granchain.physics.models import precompressed_sound_speed
from granchain.postprocess.fronts import (
    FRONT_FRACTION,
    FRONT_RESOLUTION,
    LADDER_PER_OCTAVE,
    LADDER_SLOTS,
    front_times,
    ladder_level,
)
from granchain.postprocess.observables import fit_wave_speed, measure_observables
from granchain.problem import contact_positions
from granchain.scene import parse_scene
from granchain.templates import render_deck
from granchain.workflows.run import plan_for, run_scene
from tests.scenegen import scenes


def test_the_deck_lays_the_ladder_the_fronts_module_reads():
    sc, _ = plan_for(parse_scene(PRECOMPRESSED.format(beads=30, material="brass", radius=4.76e-3, f0=100.0, amp=0.1)))
    deck = render_deck(sc).deck
    m = re.search(r"^pair_style\s+chain/\S+ .*\bladder (\d+) (\d+)", deck, re.M)
    assert m
    assert (int(m.group(1)), int(m.group(2))) == (LADDER_PER_OCTAVE, LADDER_SLOTS)
    yardstick = render_deck(sc, yardstick="builtin").deck  # (its ladder stays empty: pair_style granular)
    for d in (deck, yardstick):
        assert re.search(rf"^fix\s+\S+ all property/atom d2_ladder {LADDER_SLOTS + 1}$", d, re.M)


def test_the_deck_passes_the_leading_pulses_fall_under_precompression_only():
    """pair_style ... fall R with R = lead_fall (LAMMPS's force resolution) on a precompressed chain, and
    the stop check waits for the same fall; without precompression neither (a maximum counts at once)."""
    text = PRECOMPRESSED.format(beads=30, material="brass", radius=4.76e-3, f0=100.0, amp=0.1)
    sc, _ = plan_for(parse_scene(text))
    sc = replace(sc, run=replace(sc.run, stop_after_contact=20))
    deck = render_deck(sc).deck
    m = re.search(r"^pair_style\s+chain/\S+ lead \S+ \S+ fall (\S+) ", deck, re.M)
    assert m
    assert float(m.group(1)) == lead_fall(sc) > 0
    assert re.search(rf'^variable\s+wave_passed equal ".* <= d_fpeak\[\d+\] - {re.escape(m.group(1))}"$', deck, re.M)
    bare = replace(sc, effects=replace(sc.effects, precompression=0.0))
    deck = render_deck(bare).deck
    assert lead_fall(bare) == 0.0
    assert re.search(r"^pair_style\s+chain/\S+ lead ", deck, re.M)
    assert not re.search(r"^(pair_style|variable)\s.*(\bfall\b| <= d_fpeak)", deck, re.M)


def ladder_of(rise, t_grid: np.ndarray, f0: float, floor: float, peak: float) -> np.ndarray:
    """The ladder row of a force rising as rise(t) (exact crossing times by bisection on t_grid)."""
    crossed, ring = 0, np.zeros(LADDER_SLOTS)
    while f0 + ladder_level(crossed, floor) <= f0 + peak:
        level = ladder_level(crossed, floor)
        lo, hi = t_grid[0], t_grid[-1]
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if rise(mid) < level else (lo, mid)
        ring[crossed % LADDER_SLOTS] = 0.5 * (lo + hi)
        crossed += 1
    return np.concatenate([[crossed], ring])


@settings(max_examples=60, deadline=None)
@given(
    amplitude=st.floats(1e-3, 1e4),
    width=st.floats(1e-7, 1e-3),
    floor_fraction=st.floats(1e-7, 1e-2),
    f0=st.sampled_from([0.0, 1.0, 250.0]),
)
def test_front_times_reads_the_half_amplitude_crossing_off_the_ladder(amplitude, width, floor_fraction, f0):
    """A smooth rise to its amplitude: the time read off the ladder is where the rise crosses
    FRONT_FRACTION of it, to far below the rise time (the cubic between rungs)."""

    def rise(t):
        return amplitude * (1.0 - math.exp(-((t / width) ** 2)))

    t = np.array([0.0, 4.0 * width])
    peak = rise(t[-1])
    level = FRONT_FRACTION * peak
    lo, hi = t[0], t[-1]
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if rise(mid) < level else (lo, mid)
    floor = floor_fraction * amplitude
    row = ladder_of(rise, t, f0, floor, peak)
    got = front_times(row[None, :], np.array([f0 + peak]), f0, floor)[0]
    assert abs(got - 0.5 * (lo + hi)) < 1e-4 * width


def test_front_times_is_nan_without_a_leading_pulse_or_its_rungs():
    floor = 1e-3
    row = np.concatenate([[3.0], np.arange(1.0, LADDER_SLOTS + 1)])  # three rungs crossed
    assert np.isnan(front_times(row[None, :], np.array([np.nan]), 0.0, floor)[0])
    # an amplitude far above the rungs crossed: half of it was never climbed
    assert np.isnan(front_times(row[None, :], np.array([1e3]), 0.0, floor)[0])
    # below the floor: nothing to read
    assert np.isnan(front_times(row[None, :], np.array([1.5 * floor]), 0.0, floor)[0])
    # an amplitude LAMMPS cannot tell from the total force's resolution (FRONT_RESOLUTION F0): not read
    amplitude, floor = 5e-5, 1e-7
    rise = ladder_of(lambda t: amplitude * t, np.array([0.0, 1.0]), 0.0, floor, amplitude)
    for f0, readable in (
        (1.0, True),
        (0.5 * amplitude / FRONT_RESOLUTION, True),
        (2 * amplitude / FRONT_RESOLUTION, False),
    ):
        got = front_times(rise[None, :], np.array([f0 + amplitude]), f0, floor)[0]
        assert np.isfinite(got) == readable


def kept(row: np.ndarray, f0: float, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """A ladder row's kept rungs in order: (their total forces, their crossing times)."""
    crossed = int(row[0])
    k = np.arange(max(0, crossed - LADDER_SLOTS), crossed)
    return np.array([f0 + ladder_level(int(j), floor) for j in k]), row[1 + k % LADDER_SLOTS]


#: the two backends' forces agree step for step to about 1e-9 of themselves (tests/test_lammps.py);
#: on a rise the samples that bracket a rung are a few steps of that apart
FORCE_AGREEMENT = 1e-8


KICKED_DAMPED = """
[chain]
beads = 12
radius = 0.002
material = "aluminium-6061-t6"
[contact]
law = "hertz"
[loading]
kind = "velocity"
velocity = {v!r}
[run]
end_time = "auto"
timestep = "auto"
[outputs]
peak_force = true
histories = [1, 2]
[damping]
dashpot = 2.0
[precompression]
force = {f0!r}
"""


@settings(max_examples=6, deadline=None)
@given(scene=scenes(max_beads=40, precompressed=True))
# a dashpot on a kicked bead: rungs its force is above at t = 0 were crossed then (LAMMPS's first
# evaluation); a run whose shorter last step is a LAMMPS run of its own, whose setup recomputes the
# dashpot's forces at full-step velocities (contact 9's maximum one step before the end)
@example(scene=parse_scene(KICKED_DAMPED.format(v=0.05, f0=1.0), source="kicked.toml"))
@example(scene=parse_scene(KICKED_DAMPED.format(v=0.0546875, f0=0.125), source="kicked.toml"))
@example(scene=parse_scene(KICKED_DAMPED.format(v=0.0625, f0=0.125), source="kicked.toml"))
def test_lammps_and_reference_verlet_climb_the_same_ladder(scene):
    """Generated precompressed chains (every law, loading and effect): the pair styles and the
    reference's Verlet record the same rungs, each at the same time as far as their forces agree (a
    force apart by df crosses a rung df / (dF/dt) later; df: twice the largest difference of their
    force histories, peaks and leading pulses, and at least FORCE_AGREEMENT of the force), and the same
    half-amplitude arrivals."""
    sc, _ = plan_for(scene, "lammps", None, 1e-2)
    lam = run_scene(sc, backend="lammps", rtol=1e-2).solution
    ref = run_scene(sc, method="verlet", rtol=1e-2).solution
    f0, floor = float(sc.effects.precompression), lead_floor(sc)
    apart = [lam.history_force - ref.history_force, lam.peak_force - ref.peak_force]
    apart.append(np.nan_to_num(lam.leading_pulse_force - ref.leading_pulse_force))
    df = 2 * max(float(np.max(np.abs(d), initial=0.0)) for d in apart) + 1e-12 * f0
    assert lam.front_ladder.shape == ref.front_ladder.shape == (sc.chain.beads - 1, LADDER_SLOTS + 1)
    tol = np.zeros(sc.chain.beads - 1)  # each contact's time tolerance: the largest of its rungs'
    for c, (a, b) in enumerate(zip(lam.front_ladder, ref.front_ladder, strict=True)):
        if a[0] != b[0]:  # a leading pulse within df of a rung: one run crossed it, the other not
            top = f0 + ladder_level(int(min(a[0], b[0])), floor)
            assert abs(a[0] - b[0]) == 1
            assert abs(ref.leading_pulse_force[c] - top) <= df
            tol[c] = np.inf
            continue
        force, t_ref = kept(b, f0, floor)
        t_lam = kept(a, f0, floor)[1]
        if force.size < 2:
            np.testing.assert_allclose(t_lam, t_ref, rtol=1e-9)
            continue
        # the rise's dF/dt at each rung but the top one, just below the maximum, where it flattens; rungs
        # crossed at one sample's time (a jump: the dashpot's force on a kicked bead at t = 0) have an
        # infinite slope there, and both runs record that sample's time exactly
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = np.abs(np.gradient(force, t_ref))[:-1]
        slope[~np.isfinite(slope)] = np.inf
        bound = np.maximum(df, FORCE_AGREEMENT * force[:-1]) / slope
        assert np.all(np.abs(t_lam - t_ref)[:-1] <= bound)
        tol[c] = np.max(bound)
    both = np.isfinite(lam.front_time) & np.isfinite(ref.front_time)
    assert np.array_equal(both, np.isfinite(lam.front_time) | np.isfinite(ref.front_time))
    assert np.all(np.abs(lam.front_time - ref.front_time)[both] <= tol[both])


PRECOMPRESSED = """
[chain]
beads = {beads}
radius = {radius!r}
material = "{material}"

[contact]
law = "hertz"

[loading]
kind = "step"
amplitude = {amp!r}
duration = 1.0

[run]
end_time = "auto"
timestep = "auto"

[precompression]
force = {f0!r}

[outputs]
peak_force = true
"""


def sound_speed(sc) -> float:
    """c0 of a uniform precompressed Hertz chain (physics.models), centres the static overlap closer."""
    f0 = float(sc.effects.precompression)
    spacing = sc.diameter - float(sc.law.static_overlap(f0))
    return precompressed_sound_speed(float(sc.law.k), f0, sc.mass, spacing)


def speeds(sc, sol, contacts: np.ndarray) -> tuple[float, float]:
    """(half-amplitude, first-maximum) speeds fitted over the contacts given (1-based)."""
    at = contact_positions(sc)
    half = fit_wave_speed(contacts, sol.front_time[contacts - 1], sc.diameter, at)
    first = fit_wave_speed(contacts, sol.leading_pulse_time[contacts - 1], sc.diameter, at)
    return half[0], first[0]


def test_half_amplitude_arrival_is_computed_from_the_solution_by_both_backends_alike():
    """front_time is what front_times makes of the solution's own ladder and leading pulse."""
    sc, _ = plan_for(
        parse_scene(PRECOMPRESSED.format(beads=40, material="chrome-steel-52100", radius=3e-3, f0=20.0, amp=0.5)),
        "lammps",
    )
    for sol in (run_scene(sc, backend="lammps").solution, run_scene(sc, method="rk4").solution):
        again = front_times(sol.front_ladder, sol.leading_pulse_force, 20.0, lead_floor(sc))
        np.testing.assert_array_equal(np.isfinite(again), np.isfinite(sol.front_time))
        ok = np.isfinite(again)
        assert ok.sum() > 10
        np.testing.assert_array_equal(again[ok], sol.front_time[ok])


@pytest.mark.slow
@settings(max_examples=3, deadline=None)
@given(
    material=st.sampled_from(sorted(m for m in MATERIALS if MATERIALS[m].youngs_modulus > 1e10)),
    radius=st.floats(2e-3, 8e-3),
    f0=st.floats(5.0, 200.0),
)
def test_precompressed_front_speed_tends_to_c0(material, radius, f0):
    """A step of 1e-3 F0 on a 300-bead precompressed Hertz chain: the half-amplitude speed is within
    0.5% of c0 on LAMMPS and on the reference (RK4), the two agree as granchain compare asks (within
    its rtol 1e-3 and the fits' errors), the speed over the chain's far half is closer to c0 than over
    its near half (dispersion's lag grows ever slower) and the first maximum lags more there; a larger
    perturbation (1e-1 F0) is faster (the nonlinear wave's speed rises with the force ratio, ref. 9):
    the small one's speed is c0's, less the dispersive lag, and not a nonlinear wave's."""
    text = PRECOMPRESSED.format(beads=300, material=material, radius=radius, f0=f0, amp=1e-3 * f0)
    sc0 = parse_scene(text, source="precompressed.toml")
    lam_sc, _ = plan_for(sc0, "lammps", None, 5e-4)
    ref_sc, _ = plan_for(sc0, "reference", "rk4", 5e-4)
    lam = run_scene(lam_sc, backend="lammps").solution
    ref = run_scene(ref_sc, method="rk4").solution
    c0 = sound_speed(lam_sc)
    obs = [measure_observables(s, sol) for s, sol in ((lam_sc, lam), (ref_sc, ref))]
    for o in obs:
        assert abs(o["wave_speed"] / c0 - 1) < 5e-3
    apart = abs(obs[0]["wave_speed"] - obs[1]["wave_speed"])
    assert apart <= 1e-3 * obs[1]["wave_speed"] + obs[0]["wave_speed_stderr"] + obs[1]["wave_speed_stderr"]
    a, b = lam_sc.window
    near, far = np.arange(a, (a + b) // 2), np.arange((a + b) // 2, b + 1)
    v_near, v_far, first_far = speeds(ref_sc, ref, near)[0], *speeds(ref_sc, ref, far)
    assert abs(v_far / c0 - 1) < abs(v_near / c0 - 1)
    assert abs(first_far / c0 - 1) > abs(v_far / c0 - 1)
    big = parse_scene(text.replace(f"amplitude = {1e-3 * f0!r}", f"amplitude = {1e-1 * f0!r}"), source="big.toml")
    big_sc, _ = plan_for(big, "lammps", None, 5e-4)
    v_big = measure_observables(big_sc, run_scene(big_sc, backend="lammps").solution)["wave_speed"]
    assert v_big > obs[0]["wave_speed"]


def test_a_precompressed_chains_wave_speed_is_its_half_amplitude_arrivals():
    """On a precompressed chain the wave speed fits the half-amplitude arrivals, not the first maxima;
    without precompression it stays the first maximum's (the paper's definition)."""
    sc, _ = plan_for(
        parse_scene(PRECOMPRESSED.format(beads=60, material="brass", radius=4.76e-3, f0=100.0, amp=0.1)), "lammps"
    )
    sol = run_scene(sc, method="verlet").solution
    a, b = sc.window
    c = np.arange(a, b + 1)
    half, first = speeds(sc, sol, c)
    assert half != first
    assert measure_observables(sc, sol)["wave_speed"] == pytest.approx(half, rel=1e-12)
    bare = replace(sc, effects=replace(sc.effects, precompression=0.0))  # (its contacts one diameter apart)
    assert measure_observables(bare, sol)["wave_speed"] == pytest.approx(speeds(bare, sol, c)[1], rel=1e-12)


def leading_pulses_of_both(material: str, radius: float, beads: int, f0: float, ratio: float):
    """LAMMPS's and the reference Verlet's runs of a precompressed chain (a step of ratio x F0) at
    LAMMPS's planned step, every contact's history at every step: (scene, plan, lammps, reference,
    LAMMPS's force resolution: the largest difference of the two runs' forces; the reference integrates
    displacements and resolves about 1e5 times finer)."""
    text = PRECOMPRESSED.format(beads=beads, material=material, radius=radius, f0=f0, amp=ratio * f0)
    sc, plan = plan_for(parse_scene(text, source="precompressed.toml"), "lammps")
    every = tuple(range(1, beads))
    sc = replace(sc, outputs=replace(sc.outputs, histories=every, history_interval=sc.run.timestep))
    lam = run_scene(sc, backend="lammps").solution
    ref = run_scene(sc, method="verlet").solution
    n = min(lam.history_force.shape[0], ref.history_force.shape[0])
    resolution = float(np.max(np.abs(lam.history_force[:n] - ref.history_force[:n])))
    return sc, plan, lam, ref, resolution


@pytest.mark.slow
@settings(max_examples=5, deadline=None)
@given(
    material=st.sampled_from(sorted(MATERIALS)),
    radius=st.floats(2e-3, 8e-3),
    beads=st.integers(80, 200),
    f0=st.floats(-2.0, 3.0).map(lambda e: 10.0**e),
    ratio=st.floats(-6.0, -2.0).map(lambda e: 10.0**e),
)
# the 300-bead brass chain of docs/observables.md: LAMMPS's round-off made leading pulses at 12 contacts
@example(material="brass", radius=4.76e-3, beads=300, f0=100.0, ratio=1e-3)
def test_lammps_round_off_is_never_a_leading_pulse(material, radius, beads, f0, ratio):
    """Generated precompressed chains, a step of ratio x F0: every leading pulse LAMMPS reports rises
    above its force resolution, and the two backends find a leading pulse at the same contacts, but
    where the reference's first maximum (its largest rise, where it has no leading pulse) lies within
    that resolution of the floor: there LAMMPS's round-off decides."""
    sc, _, lam, ref, resolution = leading_pulses_of_both(material, radius, beads, f0, ratio)
    rise = lam.leading_pulse_force - f0
    has_lam, has_ref = np.isfinite(rise), np.isfinite(ref.leading_pulse_force)
    assert np.all(rise[has_lam] > resolution), (
        f"leading pulses {np.sort(rise[has_lam])[:3]} N at or below LAMMPS's resolution {resolution:.3g} N "
        f"(contacts {np.flatnonzero(has_lam & (rise <= resolution))[:10] + 1})"
    )
    first = np.where(has_ref, ref.leading_pulse_force, ref.peak_force) - f0
    near = np.abs(first - lead_floor(sc)) <= resolution
    apart = (has_lam != has_ref) & ~near
    assert not apart.any(), f"a leading pulse in one backend only at contacts {np.flatnonzero(apart)[:10] + 1}"


def deepest_fall(force: np.ndarray, f0: float, floor: float) -> np.ndarray:
    """Per contact (a column of force histories), the deepest fall of the force below its running
    peak once that peak rose more than floor above f0 (0: it never did). A leading pulse waits for a
    fall of lead_fall (peaks.lead_fall): a contact has one where this reaches it (on the samples)."""
    run = np.maximum.accumulate(force, axis=0)
    return np.max(np.where(run - f0 > floor, run - force, 0.0), axis=0, initial=0.0)


def undecided(sc, ref, resolution: float) -> np.ndarray:
    """The contacts where LAMMPS's round-off (its forces within resolution of the reference's) decides
    whether there is a leading pulse: the reference's peak within resolution of the floor, or its
    deepest fall below its running peak within twice resolution of lead_fall (a fall is the difference
    of two forces)."""
    f0, floor = float(sc.effects.precompression), lead_floor(sc)
    fall = deepest_fall(ref.history_force, f0, floor)
    near_floor = np.abs(ref.peak_force - f0 - floor) <= resolution
    near_fall = np.abs(fall[: sc.chain.beads - 1] - lead_fall(sc)) <= 2 * resolution
    return near_floor | near_fall


def at_reference_maxima(sc, lam, ref, resolution: float, within: float) -> np.ndarray:
    """Per contact, whether LAMMPS's leading pulse (if any) is a maximum of the reference's force: one
    of the reference's local maxima (on its samples at every step) lies within `within` of its time,
    with a force within twice resolution of it (the parabola's vertex against a sample, both within
    resolution of the true force). A round-off maximum on the reference's monotone rise is not."""
    f, t = ref.history_force, np.arange(ref.history_force.shape[0]) * sc.run.timestep
    is_max = np.zeros(f.shape, dtype=bool)
    is_max[1:-1] = (f[1:-1] > f[2:]) & (f[1:-1] >= f[:-2])
    ok = ~np.isfinite(lam.leading_pulse_force)
    for c in np.flatnonzero(~ok):
        k = np.flatnonzero(is_max[:, c])
        near = np.abs(t[k] - lam.leading_pulse_time[c]) <= within
        ok[c] = bool(np.any(np.abs(f[k[near], c] - lam.leading_pulse_force[c]) <= 2 * resolution))
    return ok


@pytest.mark.slow
@pytest.mark.parametrize(
    ("material", "radius", "beads", "f0", "ratio"),
    [
        # the largest first maximum 1.4e-7 N, the floor 1.2e-7 N, LAMMPS's resolution 4.9e-8 N; lead_fall
        # 1.2e-7 N: no overshoot falls that far, in either backend
        ("brass", 7.81e-3, 172, 0.014, 7.7e-6),
        # the first maximum 1.27e-6 N, LAMMPS's resolution 2.9e-7 N: at contact 121 a round-off maximum
        # 53 us before the reference's; at contact 142 one on a rise the run ends in (a maximum counted
        # at once). Counted after a fall of lead_fall (6.1e-7 N), the reference has no leading pulse
        # anywhere (its first overshoot falls by 4.5e-7 N); LAMMPS's round-off deepens that fall past
        # lead_fall at a few contacts, each at the reference's overshoot
        ("tungsten-carbide", 4.76e-3, 149, 1.0, 1e-6),
    ],
)
def test_lammps_first_maximum_within_a_few_resolutions(material, radius, beads, f0, ratio):
    """Where the step's first maximum is only a few times LAMMPS's force resolution, round-off on the
    rise above the floor makes maxima of its own; counted at once, they made LAMMPS's leading pulse
    earlier than the reference's by more than half the chain's shortest period (or one on a rise the
    run ends in, where the reference has none). A maximum counts once the force has fallen lead_fall
    (LAMMPS's resolution) below it: every leading pulse LAMMPS reports is a maximum of the reference's
    force, the two backends find one at the same contacts but where round-off decides (undecided),
    and where both do, at the same maximum."""
    sc, plan, lam, ref, resolution = leading_pulses_of_both(material, radius, beads, f0, ratio)
    half_period = math.pi / plan.omega_max
    off = ~at_reference_maxima(sc, lam, ref, resolution, half_period)
    assert not off.any(), (
        f"LAMMPS's leading pulses at contacts {np.flatnonzero(off)[:10] + 1} are no maxima of the reference's force"
    )
    has_lam, has_ref = np.isfinite(lam.leading_pulse_force), np.isfinite(ref.leading_pulse_force)
    apart = (has_lam != has_ref) & ~undecided(sc, ref, resolution)
    assert not apart.any(), f"a leading pulse in one backend only at contacts {np.flatnonzero(apart)[:10] + 1}"
    both = has_lam & has_ref
    late = np.abs(lam.leading_pulse_time - ref.leading_pulse_time)[both]
    assert np.all(late <= half_period), f"arrivals apart by up to {late.max():.3g} s"
