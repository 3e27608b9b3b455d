"""Postprocess on real runs: MDAnalysis dumps vs in-run peaks, wave speed, regimes, compare, plots."""

import csv

import numpy as np
import pytest

from granchain.cli import bundled_scenes, main, resolve_scene
from granchain.lammps.runner import run_lammps
from granchain.postprocess.comparison_table import compare_runs, format_table
from granchain.postprocess.dumps import peaks_from_samples, read_dump
from granchain.postprocess.response_regimes import classify_wave, count_pulses, fit_decay
from granchain.scene import parse_scene
from granchain.schedule import step_plan, step_times
from granchain.workflows.compare_backends import compare_scene
from granchain.workflows.plots import plot_run
from granchain.workflows.run import run_scene

from .conftest import BILINEAR, make_scene, make_scene_text
from .figure_checks import check_every_figure

SHORT = 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6'


def test_dump_peaks_vs_in_run_peaks(tmp_path):
    """Whole-chain dump every step, read through MDAnalysis, subsampled to coarser intervals."""
    sc = make_scene(beads=40, loading=SHORT, end_time=2e-4, timestep=1e-8, outputs="dump_interval = 1e-8")
    res, work = run_lammps(sc, work_dir=tmp_path)
    times = step_times(step_plan(sc.run.end_time, sc.run.timestep, sc.loading.duration), sc.run.timestep)
    dd = read_dump(work / "chain.dump", times)
    force = dd.columns["d_fc"][:, :-1]  # contact i lives on bead i; bead N has none
    inrun = res.solution.peak_force
    lines, errs = [], {}
    for stride in (1, 2, 5, 10, 20, 50):
        t, f = dd.time[::stride], force[::stride]
        raw, _ = peaks_from_samples(t, f, refine=False)
        ref, _ = peaks_from_samples(t, f, refine=True)
        e_raw = np.max(np.abs(raw - inrun) / inrun.max())
        e_ref = np.max(np.abs(ref - inrun) / inrun.max())
        errs[stride] = (e_raw, e_ref)
        lines.append(f"dump every {stride:3d} steps: max error raw {e_raw:.1e}, refined {e_ref:.1e}")
    print("\n".join(lines))
    assert errs[1][1] < 1e-12  # every step + the same three-point rule: the in-run peaks exactly
    for s in (5, 10, 20, 50):
        assert errs[s][1] < errs[s][0]  # refinement helps
    raws = [errs[s][0] for s in (2, 5, 10, 20, 50)]
    assert all(b > a for a, b in zip(raws, raws[1:], strict=False))  # coarser dumps, larger error
    # histories through MDAnalysis carry full precision: equal to the in-run reader's values
    assert dd.columns["d_fc"].dtype == np.float64


def test_wave_speeds_of_both_backends_agree():
    sc = resolve_scene("default")
    lam, _ = run_lammps(sc)
    ref = run_scene(sc)
    a, b = lam.observables()["wave_speed"], ref.observables()["wave_speed"]
    assert a
    assert b
    assert abs(a - b) / b < 1e-3
    assert lam.observables()["wave_speed_stderr"] < 1e-3 * a


def test_count_pulses_on_synthetic_signals():
    t = np.linspace(0, 1, 2001)
    one = np.exp(-(((t - 0.3) / 0.02) ** 2))
    assert count_pulses(one) == 1
    train = sum(a * np.exp(-(((t - c) / 0.02) ** 2)) for a, c in ((1.0, 0.2), (0.7, 0.4), (0.5, 0.6)))
    assert count_pulses(train) == 3
    plateau = np.clip(t * 10, 0, 1) * 0.4 + one  # a wave followed by a constant force: one pulse
    assert count_pulses(plateau) == 1
    assert count_pulses(np.zeros(10)) == 0


@pytest.mark.parametrize(
    ("f0", "amplitude", "regime"),
    [
        (0.0, 2.0, "single solitary wave"),
        (2000.0, 2.0, "weakly nonlinear wave"),  # 1e-3 F0: V_s(f_r) within 1e-4 of c0
        (200.0, 2.0, "weakly nonlinear wave"),
        (20.0, 2.0, "single solitary wave"),  # 0.1 F0: V_s(f_r) 0.55% above c0
        (0.002, 2.0, "single solitary wave"),
    ],
)
def test_pulses_are_counted_on_the_dynamic_force(f0, amplitude, regime):
    """A precompressed contact's history is F0 plus the wave: a 2 N pulse on 2000 N never rises a
    tenth of the total force, but is one pulse of the dynamic force F - F0; a train on F0 three."""
    t = np.linspace(0, 1, 2001)
    one = f0 + amplitude * np.exp(-(((t - 0.3) / 0.02) ** 2))
    assert count_pulses(one, static_force=f0) == 1
    assert classify_wave(one, static_force=f0) == regime
    train = f0 + sum(a * np.exp(-(((t - c) / 0.02) ** 2)) for a, c in ((2.0, 0.2), (1.4, 0.4), (1.0, 0.6)))
    assert count_pulses(train, static_force=f0) == 3
    assert classify_wave(train, static_force=f0) == regime.replace("single solitary wave", "wave train").replace(
        "weakly nonlinear wave", "weakly nonlinear wave train"
    )
    assert classify_wave(np.full(10, f0), static_force=f0) == "no wave"


def test_regime_single_wave_vs_wave_train():
    short = make_scene(
        beads=80,
        loading='kind = "impulse"\nimpulse = 0.4\nduration = 1e-6',
        end_time=7e-4,
        timestep=2e-8,
        outputs="histories = [60]",
    )
    long_ = make_scene(
        beads=80,
        loading='kind = "impulse"\nimpulse = 0.4\nduration = 1e-4',
        end_time=9e-4,
        timestep=2e-8,
        outputs="histories = [60]",
    )
    s = run_scene(short).solution
    ll = run_scene(long_).solution
    print(
        f"pulses at contact 60: short {count_pulses(s.history_force[:, 0])}, "
        f"long {count_pulses(ll.history_force[:, 0])}"
    )
    assert classify_wave(s.history_force[:, 0]) == "single solitary wave"
    assert classify_wave(ll.history_force[:, 0]) == "wave train"


def test_plastic_decay_exponential_then_inverse():
    sc = resolve_scene("plastic-short-impulse")
    sol = run_scene(sc).solution
    fit = fit_decay(sol.peak_force, last_contact=45)
    print(
        f"beta = 0.8: transition at contact {fit.transition_contact}, exponential decay {fit.decay_per_contact:.3f} "
        f"per contact, inverse power {fit.power:.3f} (Eq. 34: 0.9), rms log residual {fit.rms_log_residual:.3f}"
    )
    assert 2 < fit.transition_contact < 20
    assert fit.decay_per_contact > 0
    assert fit.power > 0
    assert fit.rms_log_residual < 0.1


def test_compare_passes_on_default_scene_and_writes_tables(tmp_path, capsys):
    assert main(["compare", "default", "--out", str(tmp_path / "c")]) == 0
    out = capsys.readouterr().out
    assert "leading_peak_force" in out
    assert "FAIL" not in out
    assert (tmp_path / "c" / "compare.csv").exists()
    assert (tmp_path / "c" / "compare.md").exists()
    assert (tmp_path / "c" / "lammps" / "deck.lmp").exists()
    assert (tmp_path / "c" / "reference" / "peaks.csv").exists()


def test_compare_fails_when_the_solvers_get_different_physics(tmp_path, monkeypatch, capsys):
    sc = make_scene(beads=30, law="bilinear", contact_extra=BILINEAR, loading=SHORT, end_time=1e-4, timestep=1e-8)
    other = make_scene(
        beads=30,
        law="bilinear",
        contact_extra=BILINEAR.replace("0.8", "0.7"),
        loading=SHORT,
        end_time=1e-4,
        timestep=1e-8,
    )
    rows, _, _ = compare_scene(sc, reference_scene=other)
    bad = [r.quantity for r in rows if not r.ok]
    assert "max_peak_force" in bad or "peak_force_contact_1" in bad or "dissipated_energy" in bad
    assert "FAIL" in format_table(rows)

    import granchain.workflows.compare_backends as wc

    real = wc.compare_scene
    monkeypatch.setattr(wc, "compare_scene", lambda s, **kw: real(s, reference_scene=other, **kw))
    p = tmp_path / "s.toml"
    p.write_text(sc.source_text)
    assert main(["compare", str(p), "--out", str(tmp_path / "c")]) == 1
    captured = capsys.readouterr()
    assert "FAIL" in captured.out
    assert "differ by more than rtol" in captured.err
    assert "**FAIL**" in (tmp_path / "c" / "compare.md").read_text()


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(set(bundled_scenes()) - {"default"}))
def test_compare_passes_on_bundled_scenes(name):
    """The compare passes; and every figure of its reference run is fit for a paper (figure_checks: the
    check of tests/test_figure_axes.py, here on the one run of a bundled scene the slow set makes)."""
    sc = parse_scene(bundled_scenes()[name], source=name)
    rows, _, reference = compare_scene(sc)
    print(format_table(rows))
    assert all(r.ok for r in rows), [r.quantity for r in rows if not r.ok]
    check_every_figure(reference)


def test_compare_runs_is_backend_agnostic():
    # the one comparison function also compares two reference methods
    sc = make_scene(end_time=1e-4, timestep=1e-8)
    rows = compare_runs(run_scene(sc, method="verlet"), run_scene(sc, method="rk4"), rtol=1e-3)
    assert all(r.ok for r in rows)


@pytest.mark.parametrize(
    ("extra", "loading", "kept"),
    [
        ("", None, True),  # a free chain after its pulse: the momentum is the impulse at any time
        ('[boundary]\nfar_end = "wall"\n', None, False),
        # precompression's push on bead 1 and pull on bead N balance on a free chain (unbalanced_forces)
        ("[precompression]\nforce = 5.0\n", None, True),
        ('[precompression]\nforce = 5.0\n[boundary]\nfar_end = "wall"\n', None, False),
        ("", 'kind = "step"\namplitude = 20.0\nduration = 1.0', False),  # the load still acts at the end
    ],
)
def test_momentum_is_compared_across_end_times_only_while_it_is_kept(extra, loading, kept):
    """Runs stopped by stop_after_contact end at different times (each at its own step): the momentum is
    compared then only if nothing changes it any more (found on a wall scene whose momentum row failed
    by 2.4e-3 between two correct runs 0.5 us apart)."""

    def run(method, dt):
        text = make_scene_text(beads=20, loading=loading, end_time=4e-4, timestep=dt)
        text = text.replace("[run]", "[run]\nstop_after_contact = 12") + extra
        return run_scene(parse_scene(text, source="t.toml"), method=method)

    a, b = run("verlet", 1e-8), run("rk4", 1.3e-8)
    assert a.solution.end_time != b.solution.end_time
    row = next(r for r in compare_runs(a, b, rtol=1e-3) if r.quantity == "momentum")
    if kept:
        assert row.a is not None
        assert row.ok
        assert row.not_measured is None
    else:
        assert row.a is None
        assert row.b is None
        assert "the momentum changes then" in row.not_measured


def test_plots_for_a_run(tmp_path):
    sc = make_scene(
        beads=30,
        law="bilinear",
        contact_extra=BILINEAR,
        loading=SHORT,
        end_time=1e-4,
        timestep=2e-8,
        outputs="histories = [1, 2, 3]\nsnapshots = [5e-5]",
    )
    run_scene(sc, out=tmp_path / "r")
    made = plot_run(tmp_path / "r")
    assert {p.name for p in made} == {"peaks.png", "histories.png", "snapshots.png"}
    for p in made:
        assert p.stat().st_size > 10_000
        assert p.with_name(p.stem + "_plot.csv").exists()


def _two_bead_dashpot(rtol: float, factor: float) -> str:
    """Two beads kicked at 1 m/s with a dashpot strong enough that RK4's peak (the elastic force where
    the overlap turns) and Verlet's (the total force's maximum) differ by about `factor` x rtol.

    Near the turn at t0 the overlap is alpha0 - a tau^2 / 2 (tau = t - t0, a = -alpha'' = 2 F / m on two
    beads of mass m: the pair's reduced mass is m / 2), so the total force F(alpha) + gamma alpha' is
    largest at tau = -gamma / F', by gamma^2 a / (2 F') above F(alpha0): a relative difference
    gamma^2 / (m F'), with F' = 1.5 F / alpha0 (Hertz). gamma is chosen for factor x rtol from an
    undamped run's F and alpha0.
    """
    text = make_scene_text(beads=2, loading='kind = "velocity"\nvelocity = 1.0', end_time="auto", timestep="auto")
    text = text.replace("[outputs]", "[outputs]\npeak_force = true")
    sc = parse_scene(text, source="two.toml")
    free = run_scene(sc, method="rk4", error_estimate=False).solution
    stiffness = 1.5 * float(free.peak_force[0]) / float(free.peak_overlap[0])
    gamma = float(np.sqrt(factor * rtol * sc.mass * stiffness))
    return text + f"[damping]\ndashpot = {gamma!r}\n"


def test_compare_on_a_dashpot_compares_peaks_of_one_definition(tmp_path, capsys):
    """On a scene with a dashpot RK4's peak and LAMMPS's (Verlet's) are different quantities: compare
    runs the reference with Verlet unless told otherwise, and says so; with --method rk4 the peak rows
    are marked not comparable, not failed. Before, the default compare ran RK4 and failed its peak rows."""
    rtol, factor = 1e-3, 10.0
    text = _two_bead_dashpot(rtol, factor)
    # the two definitions at a fine fixed step (each within 2e-4 of its converged value there)
    sc = parse_scene(text.replace("timestep = 'auto'", "timestep = 3e-8"), source="dash.toml")
    rk4, verlet = (run_scene(sc, method=m, error_estimate=False) for m in ("rk4", "verlet"))
    f_rk4, f_verlet = rk4.observables()["leading_peak_force"], verlet.observables()["leading_peak_force"]
    rel = (f_verlet - f_rk4) / f_verlet
    print(f"gamma {sc.effects.dashpot:.4g} N s/m: verlet {f_verlet:.6g} N, rk4 {f_rk4:.6g} N, rel {rel:.3g}")
    assert factor * rtol / 1.2 < rel < factor * rtol * 1.2  # the derivation's 10 rtol
    unlike = {r.quantity: r for r in compare_runs(verlet, rk4, rtol)}
    for q in ("leading_peak_force", "max_peak_force", "peak_force_contact_1", "arrival_time_contact_1"):
        assert unlike[q].ok
        assert unlike[q].verdict.startswith("not measured: not comparable: the runs' peaks are different quantities")
    assert unlike["momentum"].verdict == "yes"

    p = tmp_path / "dash.toml"
    p.write_text(text)
    assert main(["compare", str(p), "--out", str(tmp_path / "c"), "--rtol", str(rtol)]) == 0
    out, err = capsys.readouterr()
    assert "reference  verlet," in out
    assert "the reference runs verlet, not rk4, on a scene with a dashpot" in err
    with open(tmp_path / "c" / "compare.csv", newline="") as fh:
        rows = {r["quantity"]: r for r in csv.DictReader(fh)}
    for q in ("leading_peak_force", "max_peak_force", "peak_force_contact_1", "arrival_time_contact_1"):
        assert rows[q]["within_rtol"] == "yes", rows[q]

    assert main(["compare", str(p), "--out", str(tmp_path / "r"), "--rtol", str(rtol), "--method", "rk4"]) == 0
    out, _ = capsys.readouterr()
    assert "reference  rk4," in out
    assert "not comparable: the runs' peaks are different quantities" in out
    assert "FAIL" not in out
