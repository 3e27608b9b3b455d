"""Output sizes, the words a user reads, refusals before the run."""

import re
import warnings
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.cli import main, resolve_scene
from granchain.scene import SceneError, parse_scene
from granchain.workflows.plan import plan_scene
from granchain.workflows.run import (
    OUTPUT_WARN_BYTES,
    OutputSizeWarning,
    output_size_warning,
    output_sizes,
    run_scene,
)
from tests.conftest import make_scene_text

KEYS = {
    "chain": ["beads", "radius", "material"],
    "loading": ["kind", "velocity"],
    "run": ["end_time", "timestep"],
}


@settings(max_examples=60, deadline=None)
@given(
    section=st.sampled_from(sorted(KEYS)),
    data=st.data(),
)
def test_a_typo_in_a_key_names_the_key_it_looks_like(section, data):
    key = data.draw(st.sampled_from(KEYS[section]))
    i = data.draw(st.integers(0, len(key) - 1))
    typo = key[:i] + data.draw(st.sampled_from("xz")) + key[i + 1 :]  # one letter changed
    text = make_scene_text(loading='kind = "velocity"\nvelocity = 1.0')
    lines = text.splitlines()
    current = None
    for n, line in enumerate(lines):
        if line.startswith("["):
            current = line.strip("[]")
        elif current == section and line.split("=")[0].strip() == key:
            lines[n] = line.replace(key, typo, 1)
            break
    with pytest.raises(SceneError) as e:
        parse_scene("\n".join(lines), source="typo.toml")
    assert repr(typo) in str(e.value)
    assert repr(key) in str(e.value)


def test_history_interval_longer_than_the_run_is_refused():
    text = make_scene_text(outputs="histories = [1]\nhistory_interval = 1e-3", end_time=2e-4)
    with pytest.raises(SceneError, match=r"history_interval = 0.001 is invalid: at most the run's end_time"):
        parse_scene(text, source="long.toml")


def test_histories_default_to_the_planned_interval_not_every_step():
    text = make_scene_text(outputs="histories = [1, 5]")
    text = "\n".join(line for line in text.splitlines() if not line.startswith("history_interval"))
    sc = parse_scene(text, source="h.toml")  # conftest's scenes give every step explicitly; not this one
    assert sc.outputs.history_interval == "auto"
    planned = plan_scene(sc).scene
    assert planned.outputs.history_interval >= planned.run.timestep
    explicit = parse_scene(make_scene_text(outputs="histories = [1, 5]\nhistory_interval = 1e-8"), source="h.toml")
    assert plan_scene(explicit).scene.outputs.history_interval == 1e-8  # an explicit interval wins


def test_a_dump_over_a_gigabyte_is_announced_before_the_run(monkeypatch):
    base = parse_scene(make_scene_text(beads=400, outputs="histories = [1]\nhistory_interval = 1e-8"), source="d.toml")
    sc = replace(base, outputs=replace(base.outputs, dump_interval=1e-8))
    sizes = output_sizes(sc)
    assert sizes["chain.dump"] > OUTPUT_WARN_BYTES  # 2e4 frames of 400 beads
    # LAMMPS writes it (Backend.work_files): announced with the interval that fits
    assert re.search(r"chain.dump about .* GB \(\[outputs\] dump_interval >= ", output_size_warning(sc, "lammps"))
    ran = []
    monkeypatch.setattr("granchain.workflows.run.run_reference", lambda *a, **k: (ran.append(1), 1 / 0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(ZeroDivisionError):  # the run started, unannounced
            run_scene(sc)
    assert ran == [1]
    # the reference writes no chain.dump: no warning of one
    assert not [w for w in caught if issubclass(w.category, OutputSizeWarning)]


def test_default_outputs_stay_small_on_every_bundled_scene():
    from granchain.scene import bundled_scenes
    from granchain.workflows.run import plan_for

    for name in bundled_scenes():
        sc, _ = plan_for(resolve_scene(name), "lammps")
        for file, size in output_sizes(sc).items():
            assert size < 50e6, (name, file, size)


def test_run_prints_units(tmp_path, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["run", "effect-striker", "--rtol", "1e-2", "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    for line in out.splitlines():
        if line.startswith("  "):
            assert "(" in line, line
            assert ")" in line, line  # every quantity says its unit


def test_materials_command_lists_every_built_in_material(capsys):
    from granchain.physics.materials import MATERIALS

    assert main(["materials"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in MATERIALS)
    assert main(["materials", "unobtainium"]) == 2
    assert "no built-in material of that name" in capsys.readouterr().err


def test_a_run_that_ends_before_measuring_says_so(tmp_path, capsys):
    """A fixed end time too short for the window: told what was missed (exit 0: the user chose it)."""
    text = resolve_scene("default").source_text.replace("end_time = 7e-4", "end_time = 1e-4")
    text = "\n".join(x for x in text.splitlines() if not x.startswith("snapshots"))  # (beyond the end)
    p = tmp_path / "short.toml"
    p.write_text(text)
    assert main(["run", str(p), "--out", str(tmp_path / "r"), "-q", "--error-estimate", "off"]) == 0
    err = capsys.readouterr().err
    assert "granchain: not measured: leading_peak_force:" in err
    assert "wave_speed" in err


def test_an_auto_end_time_that_misses_the_window_exits_1(tmp_path, capsys, monkeypatch):
    """end_time = "auto" promises the window: a plan that falls short (here forced so) exits 1."""
    from granchain.workflows.planning import end_time, travel

    for module in (end_time, travel):  # the planner's every use of it
        monkeypatch.setattr(module, "front_travel_time", lambda scene, last, slow: 1e-5)  # a plan too short
    text = resolve_scene("default").source_text.replace("end_time = 7e-4", 'end_time = "auto"')
    text = "\n".join(x for x in text.splitlines() if not x.startswith("snapshots"))
    p = tmp_path / "auto.toml"
    p.write_text(text)
    assert main(["run", str(p), "--out", str(tmp_path / "r"), "-q", "--error-estimate", "off"]) == 1
    assert "granchain: not measured: leading_peak_force:" in capsys.readouterr().err


def test_quiet_silences_the_plan_and_the_striker_peak_is_printed_with_its_error(tmp_path, capsys):
    assert main(["run", "classic-two-spheres", "--out", str(tmp_path / "r"), "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert "plan (" not in err
    line = next(x for x in out.splitlines() if x.strip().startswith("striker_peak_force"))
    assert " +- " in line


@pytest.mark.parametrize("beads", [2, 4])
def test_a_wave_speed_the_scene_can_never_measure_is_not_a_missed_output(tmp_path, capsys, beads):
    """2 beads (one contact) and 4 (window 1-2: two contacts) can never give the wave-speed fit its 3
    arrivals: the run of an "auto" end time exits 0 (it missed nothing it could measure) and still says
    why the wave speed is not measured, from the scene; a leading peak it could measure still counts."""
    from granchain.postprocess.observables import unmeasured_outputs, wave_speed_unmeasurable

    text = make_scene_text(
        beads=beads,
        loading='kind = "velocity"\nvelocity = 1.0',
        end_time="auto",
        timestep="auto",
        outputs="peak_force = true",
    )
    p = tmp_path / f"b{beads}.toml"
    p.write_text(text)
    scene = parse_scene(text, source=str(p))
    assert "can never give" in wave_speed_unmeasurable(scene)
    assert wave_speed_unmeasurable(parse_scene(text.replace(f"beads = {beads}", "beads = 5"), source="b5.toml")) is None
    assert main(["run", str(p), "--out", str(tmp_path / "r"), "--error-estimate", "off"]) == 0
    out, err = capsys.readouterr()
    assert "not measured: wave_speed" not in err
    # a row of its own or, where it does not apply, the line of its reason (cli.terminal._print_inapplicable)
    assert "wave_speed (m/s)" in out or "wave_speed" in s_inapplicable(tmp_path / "r")
    assert "the wave-speed fit needs 3, which this scene can never give" in out
    # the leading peak still counts: a run that ends before it is a missed output
    short = run_scene(
        replace(scene, run=replace(scene.run, end_time=1e-7, timestep=1e-9, stop_after_contact=None)),
        error_estimate=False,
    )
    names = [line.split(":")[0] for line in unmeasured_outputs(short.scene, short.solution)]
    assert "leading_peak_force" in names
    assert "wave_speed" not in names


@pytest.mark.parametrize(("duration", "whole"), [(1.0, False), (1e-6, True)])
def test_the_load_impulse_line_says_up_to_the_end_when_the_load_outlasts_the_run(duration, whole, tmp_path, capsys):
    """A step of 100 N for 0.01 s on a run planned to 0.00264 s delivered A t_end = 0.0916 N s, labelled
    'A T delivered by the force' (A T = 1 N s): the line says what it is."""
    from granchain.cli.terminal import print_result

    loading = f'kind = "step"\namplitude = 10.0\nduration = {duration!r}'
    sc = parse_scene(make_scene_text(beads=12, loading=loading, end_time=2e-5, timestep=1e-8), source="s.toml")
    result = run_scene(sc, backend="reference", out=tmp_path / "r")
    print_result(result, tmp_path / "r")
    line = next(x for x in capsys.readouterr().out.splitlines() if "impulse of the load" in x)
    assert ("A T delivered by the force" in line) == whole, line
    if not whole:
        assert "A t_end: delivered up to the end, t_end = 2e-05 s; the load lasts T = 1 s" in line, line
        assert line.split()[6] == f"{10.0 * result.solution.end_time:.6g}", line


def s_inapplicable(run_dir) -> list[str]:
    """The run's observables that do not apply to its scene (summary.json's observables_inapplicable)."""
    import json

    return json.loads((run_dir / "summary.json").read_text()).get("observables_inapplicable", [])
