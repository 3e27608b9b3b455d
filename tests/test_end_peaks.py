"""The effects' own contacts (a striker's, a wall's) report a peak only once it has passed: a run that
ends while the wall's force still rises, or before the wave reaches it, reports its largest force so
far marked as no peak (ChainSolution.wall_peak_complete), with no error bar and no compared value."""

import csv
import json

import pytest

from granchain.postprocess.comparison_table import compare_runs
from granchain.scene import parse_scene
from granchain.workflows.error_estimates import END_PEAK_INCOMPLETE
from granchain.workflows.run import run_scene

from .conftest import make_scene_text

BACKENDS = {"reference": ("reference", "verlet"), "lammps": ("lammps", None)}


def walled(end_time: float, f0: float, striker: bool) -> object:
    """A 10-bead brass chain on a wall, bead 1 kicked at 1 m/s (or struck by a bead at 1 m/s), with a
    precompression f0 (0: none), run to end_time at 1e-8 s."""
    loading = f'kind = "{"striker" if striker else "velocity"}"\nvelocity = 1.0'
    text = make_scene_text(beads=10, loading=loading, end_time=end_time, outputs="peak_force = true")
    text += '[boundary]\nfar_end = "wall"\n' + (f"[precompression]\nforce = {f0!r}\n" if f0 else "")
    return parse_scene(text, source="walled.toml")


def run(sc, backend):
    name, method = BACKENDS[backend]
    return run_scene(sc, backend=name, method=method, error_estimate=True)


@pytest.mark.parametrize("backend", list(BACKENDS))
@pytest.mark.parametrize(("f0", "striker"), [(0.0, False), (1.0, True)])
def test_a_wall_the_wave_has_not_passed_reports_no_peak(backend, f0, striker):
    long = run(walled(4e-4, f0, striker), backend)
    s = long.solution
    assert s.wall_peak_complete is True, "the wave passed the wall well before 0.4 ms"
    assert long.errors.end_peaks["wall_peak_force"]["error"] is not None
    t_wall = s.wall_time_of_peak
    # ended on the rise (9/10 of the way to the peak), and before the wave reached the wall
    for end in (0.9 * t_wall, 0.3 * t_wall):
        short = run(walled(end, f0, striker), backend)
        assert short.solution.wall_peak_complete is False, end
        assert short.solution.wall_peak_force < s.wall_peak_force
        bar = short.errors.end_peaks["wall_peak_force"]
        assert bar["error"] is None
        assert bar["status"] == END_PEAK_INCOMPLETE
    if striker:  # the striker's contact, ended on its rise
        short = run(walled(0.5 * s.striker_time_of_peak, f0, striker), backend)
        assert short.solution.striker_peak_complete is False
        assert s.striker_peak_complete is True


def test_compare_shows_no_wall_peak_where_the_wave_has_not_passed_it():
    sc = walled(4e-4, 1.0, True)
    t_wall = run(sc, "reference").solution.wall_time_of_peak
    short = walled(0.9 * t_wall, 1.0, True)
    wall = "dynamic_wall_peak_force"  # precompressed: the wall's force less F0 (F0 = 1 N)
    rows = {r.quantity: r for r in compare_runs(run(short, "lammps"), run(short, "reference"))}
    assert "wall_peak_force" not in rows
    assert rows[wall].a is None
    assert rows[wall].b is None
    assert "did not reach or pass the wall" in rows[wall].verdict
    a, b = run(sc, "lammps"), run(sc, "reference")
    rows = {r.quantity: r for r in compare_runs(a, b)}
    assert rows[wall].ok
    assert rows[wall].a is not None
    assert rows[wall].b == b.solution.wall_peak_force - 1.0


@pytest.mark.parametrize("backend", list(BACKENDS))
@pytest.mark.parametrize("wall", [False, True])
def test_a_free_precompressed_chain_keeps_its_momentum_and_says_so(backend, wall, tmp_path, capsys):
    """Precompression pushes bead 1 and, on a free chain, pulls bead N as hard: no net force, so the
    momentum at the end is what was put in, and granchain run says why; a wall takes some."""
    from granchain.cli import main
    from granchain.physics.effects import unbalanced_forces

    text = make_scene_text(
        beads=10, loading='kind = "velocity"\nvelocity = 1.0', end_time=1e-4, outputs="peak_force = true"
    )
    text += "[precompression]\nforce = 2.0\n" + ('[boundary]\nfar_end = "wall"\n' if wall else "")
    (tmp_path / "p.toml").write_text(text)
    sc = parse_scene(text, source="p.toml")
    assert [e.name for e in unbalanced_forces(sc)] == (["wall", "precompression"] if wall else [])
    name, method = BACKENDS[backend]
    args = ["run", str(tmp_path / "p.toml"), "--backend", name, "--out", str(tmp_path / "r"), "--error-estimate", "off"]
    assert main(args + (["--method", method] if method else [])) == 0
    out = capsys.readouterr().out
    line = next(s for s in out.splitlines() if "momentum at the end" in s)
    if wall:
        assert "the wall takes some" in line
        return
    assert "balance" in line
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["conservation"]["momentum"] == pytest.approx(sc.initial_momentum, rel=1e-9)


def struck_precompressed(f0: float, velocity: float, end_time: float) -> object:
    """A 10-bead brass chain at a precompression f0 struck by a bead at velocity, run to end_time at 1e-8 s."""
    loading = f'kind = "striker"\nvelocity = {velocity!r}'
    text = make_scene_text(beads=10, loading=loading, end_time=end_time, outputs="peak_force = true")
    return parse_scene(text + f"[precompression]\nforce = {f0!r}\n", source="struck.toml")


def test_a_striker_peak_below_the_precompression_is_complete_on_both_backends():
    """The striker's contact starts unloaded: its peak (0.81 N, below F0 = 20 N) is complete once its
    force fell to half of it (it bounced off at 5.2e-5 s), whatever F0 the chain's contacts carry."""
    sc = struck_precompressed(20.0, 0.01, 1e-4)
    runs = {b: run(sc, b) for b in BACKENDS} | {"rk4": run_scene(sc, backend="reference", method="rk4")}
    for name, r in runs.items():
        s = r.solution
        assert 0.0 < s.striker_peak_force < 20.0, name
        assert s.striker_velocity < 0.0, name  # bounced off: its contact force is 0 since
        assert s.striker_peak_complete is True, name
        assert 0.0 < s.striker_time_of_peak < 1e-4, name
    rows = {r.quantity: r for r in compare_runs(runs["lammps"], runs["reference"])}
    row = rows["striker_peak_force"]
    assert row.a is not None
    assert row.b is not None
    assert row.ok, row.verdict


def test_a_lasting_load_is_not_run_again_for_its_plateau():
    """Behind a step load still acting at the end, the force at the window's last contact rises toward
    the load's level: no longer run completes it while the load acts, so it is not an unmeasured output
    and an "auto" end is not run again for it (the 300-bead brass chain at F0 = 100 N with a 0.1 N step,
    planned for rtol 1e-4, was run again to 3 crossings for it)."""
    import warnings

    from granchain.workflows.run import PlanExtendedWarning

    text = make_scene_text(beads=60, loading='kind = "step"\namplitude = 0.1\nduration = 1.0', end_time=1e-3)
    text = text.replace("end_time = 0.001\ntimestep = 1e-08", 'end_time = "auto"\ntimestep = "auto"')
    text += "[precompression]\nforce = 100.0\n"
    sc = parse_scene(text, source="step.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlanExtendedWarning)
        result = run_scene(sc, backend="lammps", rtol=1e-4)
    assert result.solution.end_time <= result.plan.scene.run.end_time
    assert result.observables()["leading_peak_force"] is not None


def test_a_damaged_wall_flag_in_a_run_directory_is_one_clear_error(tmp_path):
    """summary.json's wall_peak_complete must be true or false: a damaged one is a LoadRunError naming
    it, not a truthy string that compare would take for a passed peak."""
    from granchain.workflows.load import LoadRunError, load_run

    out = tmp_path / "r"
    run_scene(walled(1e-4, 0.0, False), method="verlet", out=out, error_estimate=False)
    summary = json.loads((out / "summary.json").read_text())
    summary["wall_peak_complete"] = "garbage"
    (out / "summary.json").write_text(json.dumps(summary))
    with pytest.raises(LoadRunError, match="wall_peak_complete: 'garbage' is not true or false"):
        load_run(out)


@pytest.mark.parametrize("end", [0.4, 0.9, 0.99])
def test_a_wall_the_wave_has_not_reached_prints_not_reached_not_a_round_off_force(tmp_path, capsys, end):
    """A 60-bead brass chain on a wall, kicked with 0.4 N s: its Hertz precursor touches the wall
    ahead of the wave (6.8e-36 N at 0.9 of the time of its peak, 0.44 ms), a force below
    REACHED_FRACTION of the chain's largest peak that is round-off, printed as "not reached" with
    no number; a run ended on the rise (0.99 of the way to the peak) prints its largest force so far."""
    from granchain.cli import main
    from granchain.peaks import REACHED_FRACTION

    def text(end_time):
        loading = 'kind = "impulse"\nimpulse = 0.4\nduration = 1e-6'
        scene = make_scene_text(
            beads=60, loading=loading, end_time=end_time, timestep=5e-8, outputs="peak_force = true"
        )
        return scene + '[boundary]\nfar_end = "wall"\n'

    full = run_scene(parse_scene(text(8e-4), source="wall.toml"), backend="reference", method="verlet")
    (tmp_path / "w.toml").write_text(text(end * full.solution.wall_time_of_peak))
    args = ["run", str(tmp_path / "w.toml"), "--backend", "reference", "--method", "verlet", "--out"]
    assert main([*args, str(tmp_path / "r"), "--error-estimate", "off", "-q"]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if "wall_peak_force" in s)
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["wall_peak_complete"] is False
    # the scale is every contact's largest force so far (end_contact_reached), not max_peak_force: before
    # the wall's reflection has passed them no contact's peak is complete (peaks.reflection_pending)
    largest = max(float(r["peak_force"]) for r in csv.DictReader((tmp_path / "r" / "peaks.csv").open()))
    reached = summary["wall_peak_force"] > REACHED_FRACTION * largest
    assert reached == (end == 0.99), summary["wall_peak_force"]
    if reached:
        assert "largest force so far, not a peak" in line, line
    else:
        assert "-   not reached: the wave had not reached the wall's contact" in line, line
        assert f"{summary['wall_peak_force']:g}" not in line.split("not reached")[0], line


def test_run_marks_each_force_of_a_precompressed_chain_dynamic_or_total(tmp_path, capsys):
    """Under precompression granchain run's peaks are dynamic (F - F0) and the wall's total force was
    printed among them unmarked (a glass chain at F0 = 5 N: max_peak_force 32.67 N beside
    wall_peak_force 60.54 N): every force line says which it is, and the wall's is dynamic, as compare
    names it (dynamic_wall_peak_force), with its total alongside."""
    from granchain.cli.terminal import print_result

    result = run_scene(walled(4e-4, 1.0, True), backend="reference", method="verlet", error_estimate=False)
    print_result(result, tmp_path)
    lines = capsys.readouterr().out.splitlines()
    s = result.summary()
    assert any("forces (precompressed)" in x and "F0 = 1 N" in x for x in lines), lines
    for name in ("leading_peak_force", "max_peak_force", "leading_peak_force_nondim"):
        line = next(x for x in lines if x.split()[:1] == [name])
        assert "above F0)" in line, line
        assert float(line.split(")")[1].split()[0]) == pytest.approx(s["observables"][name], rel=1e-5)
    assert "(N, total)" in next(x for x in lines if x.split()[:1] == ["static_force"])
    assert not any(x.split()[:1] == ["wall_peak_force"] for x in lines), lines
    wall = next(x for x in lines if x.split()[:1] == ["dynamic_wall_peak_force"])
    assert "(N, above F0)" in wall, wall
    assert float(wall.split(")")[1].split()[0]) == pytest.approx(s["wall_peak_force"] - 1.0, rel=1e-5)
    assert f"total {s['wall_peak_force']:.6g} N" in wall, wall
    striker = next(x for x in lines if x.split()[:1] == ["striker_peak_force"])
    assert "(N)" in striker, striker  # the striker's contact carries no F0
