"""[outputs] sensors: sensor beads' average force (F_{i-1,i} + F_{i,i+1}) / 2 (issue 42, item 3).

A piezo embedded in a bead reads the average of its two contact forces (Daraio et al., PRE 72, 016603,
2005); bead 1's left contact is a striker's, bead N's right one the wall's (a missing one: 0). Both
backends track it at every step as they track a contact's peak; the outputs report each sensor's peak
and time (granchain.postprocess.sensors), in summary.json, compare, campaign columns, plots and docs.
"""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.exceptions import GranchainError
from granchain.lammps.runner import run_lammps
from granchain.postprocess.comparison_table import compare_runs
from granchain.postprocess.dumps import peaks_from_samples
from granchain.postprocess.observables import SENSOR_OBSERVABLES
from granchain.postprocess.sensors import bead_average, sensor_key, sensor_static_forces
from granchain.problem import ChainProblem
from granchain.reference.solver import solve_chain
from granchain.scene import parse_scene
from granchain.workflows.run import run_reference

DOCS = Path(__file__).resolve().parents[1] / "docs" / "observables.md"


def scene_text(beads=8, loading="striker", wall=True, f0=0.0, g=0.0, sensors=(1, 4, 8), dt=5e-8, end=4e-5, extra=""):
    """A small stainless chain with sensor beads, every history sample a step."""
    load = {
        "striker": 'kind = "striker"\nvelocity = 0.44',
        "velocity": 'kind = "velocity"\nvelocity = 0.3',
        "impulse": 'kind = "impulse"\nimpulse = 1e-4\nduration = 2e-6',
    }[loading]
    text = f"""[chain]
beads = {beads}
radius = 2.38e-3
material = "stainless-steel-316"
[contact]
law = "hertz"
[loading]
{load}
[run]
end_time = {end!r}
timestep = {dt!r}
[outputs]
peak_force = true
histories = {list(range(1, beads))}
history_interval = {dt!r}
sensors = {list(sensors)}
{extra}"""
    if wall:
        text += '[boundary]\nfar_end = "wall"\n'
    if f0:
        text += f"[precompression]\nforce = {f0!r}\n"
    if g:
        text += f"[gravity]\ng = {g!r}\n"
    return text


@st.composite
def sensor_scenes(draw):
    beads = draw(st.integers(2, 8))
    loading = draw(st.sampled_from(["striker", "velocity", "impulse"]))
    wall = draw(st.booleans())
    f0 = draw(st.sampled_from([0.0, 0.0, 2.0]))
    g = 9.81 if wall and draw(st.booleans()) else 0.0
    low = 2 if loading == "impulse" else 1  # a force loading's bead 1 has no contact on its left: refused
    pool = list(range(low, beads + 1))
    if not pool:
        pool = [beads] if beads >= 2 else []
    sensors = draw(st.lists(st.sampled_from(pool), min_size=1, max_size=3, unique=True)) if pool else [2]
    return parse_scene(scene_text(beads, loading, wall, f0, g, sensors, end=3e-5), source="generated.toml")


def contact_histories(scene, method):
    """The reference's solution with every contact's history, the striker's and the wall's included (the
    solver's inner contacts: -1 is the striker's, N - 1 the wall's), every step."""
    n = scene.chain.beads
    front = 1 if scene.loading.kind == "striker" else 0
    wall = scene.effects.far_end == "wall"
    contacts = tuple(range(-front, n - 1 + wall))
    sol = solve_chain(
        ChainProblem.from_scene(scene),
        scene.run.end_time,
        scene.run.timestep,
        method,
        histories=contacts,
        sensors=tuple(b - 1 for b in scene.outputs.sensors),
        sensor_stride=1,
    )
    # each bead's two contacts' forces: a missing end contact is 0 (bead_average pads it)
    forces = np.asarray(sol.history_force)
    if not front:
        forces = np.pad(forces, ((0, 0), (1, 0)))
    if not wall:
        forces = np.pad(forces, ((0, 0), (0, 1)))
    left, right = forces[:, :-1], forces[:, 1:]  # (samples, N): bead b's are columns b - 1 of each
    return sol, left, right


# ---- (1) the sensor's force is the average of its two contacts' forces, at the same steps


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=sensor_scenes(), method=st.sampled_from(["verlet", "rk4"]))
def test_sensor_force_is_the_average_of_its_two_contacts_at_every_sample(scene, method):
    sol, left, right = contact_histories(scene, method)
    beads = np.asarray(scene.outputs.sensors) - 1
    expected = 0.5 * (left[:, beads] + right[:, beads])
    assert np.array_equal(sol.sensor_history_time, sol.history_time)  # the same steps
    scale = max(float(np.max(np.abs(expected))), 1e-300)
    assert np.max(np.abs(sol.sensor_history_force - expected)) <= 1e-14 * scale
    # at t = 0 it is the sensor's static force (F0 and gravity's weight averaged; a striker's contact 0)
    static = sensor_static_forces(scene)
    assert np.allclose(sol.sensor_history_force[0], static, rtol=1e-9, atol=1e-12 * scale)


# ---- (2) its tracked peak is as tight as a contact's against the dense history


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scene=sensor_scenes())
def test_sensor_peak_is_tracked_as_tightly_as_a_contacts(scene):
    """Verlet: each tracked peak against the three-point refinement of its history sampled every step
    (postprocess.dumps.peaks_from_samples): the sensors' within what the contacts' are."""
    sol, _, _ = contact_histories(scene, "verlet")
    t = sol.history_time
    n = scene.chain.beads
    front = 1 if scene.loading.kind == "striker" else 0
    chain = sol.history_force[:, front : front + n - 1]  # the bead-bead contacts
    cpk, _ = peaks_from_samples(t, chain)
    spk, _ = peaks_from_samples(t, sol.sensor_history_force)
    contact_gap = np.max(np.abs(sol.peak_force - cpk) / np.maximum(np.abs(cpk), 1e-300), initial=0.0)
    sensor_gap = np.abs(sol.sensor_peak_force - spk) / np.maximum(np.abs(spk), 1e-300)
    # tracked at every step: never below the largest sample, and as close to the dense refinement as a
    # contact's (both the same three-point rule; round-off apart)
    assert np.all(sol.sensor_peak_force >= sol.sensor_history_force.max(axis=0) * (1 - 1e-14))
    assert np.all(sensor_gap <= max(contact_gap, 1e-12))


# ---- (3) LAMMPS = the reference's Verlet, step for step


@pytest.mark.parametrize(
    ("loading", "wall", "f0", "g", "sensors"),
    [
        ("striker", True, 0.0, 9.81, (1, 4, 8)),
        ("velocity", False, 2.0, 0.0, (1, 5, 8)),
        ("impulse", True, 2.0, 0.0, (2, 8)),
    ],
)
def test_lammps_sensors_equal_reference_verlet(loading, wall, f0, g, sensors):
    sc = parse_scene(scene_text(8, loading, wall, f0, g, sensors, end=6e-5), source="lammps.toml")
    lam = run_lammps(sc)[0].solution
    ref = run_reference(sc, "verlet").solution
    scale = float(np.max(ref.sensor_peak_force))
    assert np.max(np.abs(lam.sensor_peak_force - ref.sensor_peak_force)) < 1e-9 * scale
    assert np.allclose(lam.sensor_time_of_peak, ref.sensor_time_of_peak, rtol=1e-9, atol=0.0, equal_nan=True)
    assert np.array_equal(lam.sensor_complete, ref.sensor_complete)
    assert np.array_equal(lam.sensor_history_time, ref.sensor_history_time)
    assert np.max(np.abs(lam.sensor_history_force - ref.sensor_history_force)) < 1e-9 * scale


# ---- (4) bad input: one message naming [outputs] sensors and the fix


@pytest.mark.parametrize(
    ("value", "fix"),
    [
        ("[0]", "beads 1..8"),
        ("[9]", "out of range"),
        ("[2, 2]", "without repeats"),
        ("[1.5]", "integers"),
        ('"3"', "integers"),
        ("true", "integers"),
    ],
)
def test_bad_sensors_name_the_key_and_the_fix(value, fix):
    text = scene_text(8).replace("sensors = [1, 4, 8]", f"sensors = {value}")
    with pytest.raises(GranchainError, match=r"\[outputs\] sensors") as e:
        parse_scene(text, source="bad.toml")
    assert fix in str(e.value)


def test_a_sensor_on_a_force_loaded_bead_1_is_refused_with_the_fix():
    with pytest.raises(GranchainError, match=r"\[outputs\] sensors.*applied force.*beads 2 and beyond"):
        parse_scene(scene_text(8, "impulse", sensors=(1, 4)), source="bad.toml")


def test_sensors_on_an_auto_chain_are_refused_with_the_fix():
    text = (
        scene_text(8, wall=False)
        .replace("beads = 8", 'beads = "auto"')
        .replace("histories = [1, 2, 3, 4, 5, 6, 7]\n", "")
    )
    with pytest.raises(GranchainError, match=r"\[outputs\] sensors.*beads = N"):
        parse_scene(text, source="bad.toml")


# ---- every place the outputs name a sensor's quantities


def test_every_sensor_quantity_is_in_summary_compare_campaign_plots_terminal_and_docs(tmp_path, capsys):
    from granchain.campaigns.table import _sensor_columns
    from granchain.cli.terminal import print_sensors
    from granchain.rundir import write_run_dir
    from granchain.workflows.load import load_run
    from granchain.workflows.plots.figures import write_histories

    sc = parse_scene(scene_text(6, wall=False, sensors=(2, 5), end=6e-5), source="places.toml")
    r = run_reference(sc, "verlet")
    keys = [sensor_key(q, b) for b in sc.outputs.sensors for q in SENSOR_OBSERVABLES]
    summary = r.summary
    for q in SENSOR_OBSERVABLES:
        assert len(summary["sensors"][q]) == 2
        assert None not in summary["sensors"][q]
    rows = {row.quantity for row in compare_runs(r, r)}
    assert set(keys) <= rows
    assert set(keys) <= set(_sensor_columns(summary))
    print_sensors(summary)
    printed = capsys.readouterr().out
    assert all(k in printed for k in keys)
    text = DOCS.read_text()
    assert all(f"`{q}_bead_<i>`" in text for q in SENSOR_OBSERVABLES)
    d = write_run_dir(r, tmp_path / "run")
    loaded = load_run(d)
    assert np.array_equal(loaded.solution.sensor_history_force, r.solution.sensor_history_force)
    write_histories(loaded)
    header = (d / "histories_plot.csv").read_text().splitlines()[0].split(",")
    assert all(f"sensor_force_bead_{b}" in header for b in sc.outputs.sensors)


def test_bead_average_pads_the_missing_end_contacts():
    f = np.array([[2.0, 4.0, 6.0]])
    assert np.array_equal(bead_average(f), [[1.0, 3.0, 5.0, 3.0]])
