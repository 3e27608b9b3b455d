"""Runs watch their invariants and stop with a clear error naming the invariant, time, step and contact,
and the fix; a time step above the predicted stability limit is refused before the run."""

import pytest

from granchain.cli import main
from granchain.reference.solver import InvariantError
from granchain.workflows.run import UnstableTimestepError, run_scene

from .conftest import make_scene

PULSE = 'kind = "impulse"\nimpulse = 0.4\nduration = 1e-6'


def test_unstable_timestep_refused_before_the_run():
    sc = make_scene(beads=60, loading=PULSE, end_time=5e-4, timestep=1e-5)
    with pytest.raises(UnstableTimestepError, match="above the stability limit.*--force"):
        run_scene(sc)


def test_blow_up_stops_with_the_invariant_and_the_fix(tmp_path, capsys):
    sc = make_scene(beads=100, loading=PULSE, end_time=7e-4, timestep=2e-5)  # 3x the stability limit
    with pytest.raises(InvariantError) as e:
        run_scene(sc, force=True)
    err = e.value
    assert err.invariant in ("finite state", "overlap far below the radius", "energy balance")
    assert err.step > 0
    assert err.time > 0
    assert 1 <= err.contact <= 99
    assert "would choose" in str(err)
    p = tmp_path / "s.toml"
    p.write_text(sc.source_text)
    assert main(["run", str(p), "--force", "--out", str(tmp_path / "o")]) == 2
    assert "invariant" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_beads_passing_through_each_other_are_caught():
    # 3 km/s into a chain at a coarse step: overlaps beyond half the radius (or a blow-up)
    sc = make_scene(beads=20, loading='kind = "velocity"\nvelocity = 3000.0', end_time=2e-5, timestep=2e-7)
    with pytest.raises(InvariantError, match="overlap|finite"):
        run_scene(sc, force=True)


def test_a_sound_run_is_not_stopped():
    sol = run_scene(make_scene(end_time=1e-4, timestep=1e-8)).solution
    assert sol.steps > 0


# ---- both backends watch the same invariants and stop at the same place


@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_energy_created_by_a_coarse_verlet_step_stops_the_run(backend):
    # below the Verlet stability limit LAMMPS and the reference stay finite, but the first collision
    # at this step creates 28% of the energy put in: both stop on the energy balance, at the same time
    sc = make_scene(beads=100, loading=PULSE, end_time=7e-4, timestep=6e-6)
    with pytest.raises(InvariantError) as e:
        run_scene(sc, backend=backend, method="verlet", force=True)
    assert e.value.invariant == "energy balance"
    assert e.value.time == pytest.approx(7e-6)
    assert e.value.step == 2
    assert "created by the integrator" in str(e.value)
    assert "would choose" in str(e.value)


@pytest.mark.parametrize("backend", ["reference", "lammps"])
def test_overlap_watch_names_step_and_contact_in_both_backends(backend):
    sc = make_scene(beads=20, loading='kind = "velocity"\nvelocity = 1000.0', end_time=2e-5, timestep=1e-7)
    with pytest.raises(InvariantError) as e:
        run_scene(sc, backend=backend, method="verlet", force=True)
    assert e.value.invariant == "overlap far below the radius"
    assert (e.value.step, e.value.contact) == (40, 1)
    assert "reduce the load" in str(e.value)


def test_momentum_and_energy_checks_can_fail():
    from granchain.invariants import check_solution

    sc = make_scene(beads=30, loading=PULSE, end_time=1e-4, timestep=1e-8)
    sol = run_scene(sc).solution
    check_solution(sc, sol)  # a sound run passes the post-run check
    sol.momentum *= 1 + 1e-5
    with pytest.raises(InvariantError, match="momentum"):
        check_solution(sc, sol)
    sol.momentum /= 1 + 1e-5
    sol.kinetic = sol.kinetic * 1.1
    with pytest.raises(InvariantError, match="energy balance"):
        check_solution(sc, sol)
    sol.velocity[3] = float("nan")
    with pytest.raises(InvariantError, match="finite state"):
        check_solution(sc, sol)


def test_lammps_in_run_momentum_and_energy_watch_can_fire(tmp_path):
    # the deck's own watch, fed a wrong expectation, stops LAMMPS mid-run and becomes an InvariantError
    from granchain.lammps.runner import LammpsError, invariant_from_lammps, run_deck
    from granchain.templates import render_deck

    sc = make_scene(beads=30, loading=PULSE, end_time=1e-4, timestep=1e-8)
    deck = render_deck(sc)
    for key, wrong, invariant in (
        ('variable        watch_p_expected equal "0.0', 'variable        watch_p_expected equal "1e-3', "momentum"),
        ('variable        watch_work equal "0.0', 'variable        watch_work equal "1.0', "energy balance"),
    ):
        assert key in deck.deck
        with pytest.raises(LammpsError) as e:
            run_deck(deck.deck.replace(key, wrong, 1), deck.data, work_dir=tmp_path / invariant.replace(" ", "_"))
        broken = invariant_from_lammps(e.value, sc)
        assert broken is not None
        assert broken.invariant == invariant
        assert broken.step == 50  # the first energy sample (every 10000 / 200 steps)
