"""granchain accuracy on a scene with a dashpot: RK4's peak (the elastic force where the overlap turns)
and Verlet's and LAMMPS's (the total force's maximum) are different quantities there, so each method is
measured against a converged run of its own peak definition, and the study plans with Verlet."""

import numpy as np

from granchain.cli import main
from granchain.problem import ChainProblem
from granchain.reference.solver import solve_chain
from granchain.scene import parse_scene
from granchain.workflows.accuracy import PLAN_RTOL, accuracy_study, summary_text
from granchain.workflows.plan import plan_scene
from tests.scenegen import PEAKS, brass_text

# the reviewer's scene (/tmp/rev/acc.toml): 8 brass beads struck at 1 m/s, gamma = 20 N s/m
DASHPOT_SCENE = brass_text(8, 'kind = "velocity"\nvelocity = 1.0\n', "[damping]\ndashpot = 20.0\n" + PEAKS)


def dashpot_study(methods):
    """accuracy_study of DASHPOT_SCENE with these methods: one level, one repeat, no dump intervals."""
    return accuracy_study(
        parse_scene(DASHPOT_SCENE, source="dashpot.toml"), methods=methods, levels=1, repeats=1, dump_intervals=False
    )


def test_verlet_planned_error_is_its_step_error_not_the_peak_definitions_difference():
    study = dashpot_study(("verlet", "rk4"))
    q = next(q for q in study.plan_points if q.method == "verlet")
    # independently: Verlet at the planned step against Verlet at a 16x finer step
    scene = study.scene
    dt = plan_scene(scene, rtol=PLAN_RTOL, method="verlet").scene.run.timestep
    assert q.setting == dt
    problem, idx, end = ChainProblem.from_scene(scene), study.contacts - 1, scene.run.end_time
    coarse = solve_chain(problem, end, dt, "verlet").peak_force[idx]
    fine = solve_chain(problem, end, dt / 16, "verlet").peak_force[idx]
    direct = float(np.max(np.abs(coarse - fine) / fine))
    print(f"study {q.error_peak:.3e}, Verlet vs Verlet at dt / 16 {direct:.3e}")
    # first order with a dashpot: the run at dt / 16 still carries 1/16 of the error the study sees
    assert direct <= q.error_peak <= 1.25 * direct
    assert (q.error_peak <= PLAN_RTOL) == (direct <= PLAN_RTOL)
    # each method against the converged run of its own peak definition, and the table says which
    assert q.reference == "verlet"
    assert {p.reference for p in study.points + study.plan_points if p.method == "rk4"} == {"rk4"}
    assert set(study.references) == {"verlet", "rk4"}
    assert study.references["verlet"].error < 0.1 * q.error_peak
    assert study.definition_gap > 10 * q.error_peak  # what RK4 as the yardstick would have added
    text = summary_text(study)
    assert "| verlet | " in text
    assert "| converged Verlet |" in text
    assert "| converged RK4 |" in text
    assert "different quantities" in text


def test_cli_plans_with_verlet_and_says_what_each_row_is_measured_against(tmp_path, capsys):
    path = tmp_path / "dashpot.toml"
    path.write_text(DASHPOT_SCENE)
    code = main(
        ["accuracy", str(path), "--methods", "verlet", "--levels", "1", "--repeats", "1", "--out", str(tmp_path / "a")]
    )
    cap = capsys.readouterr()
    assert code == 0
    assert "plan (verlet)" in cap.err
    assert "plan (rk4)" not in cap.err
    assert "converged Verlet" in cap.out
    assert "converged RK4" not in cap.out
    assert "verlet (planned)" in (tmp_path / "a" / "accuracy.csv").read_text()
    assert "| yes | converged Verlet |" in cap.out  # the planned step meets rtol against its own quantity


def test_dop853_is_not_run_on_a_scene_it_does_not_model(tmp_path, capsys):
    # DOP853 integrates a free elastic Hertz chain: no dashpot (nor wall, striker, precompression)
    study = dashpot_study(("rk4", "dop853"))
    assert {p.method for p in study.points} == {"rk4"}
    assert "dashpot" in study.skipped["dop853"]
    assert "not run: dop853" in summary_text(study)
    argv = ["accuracy", "effect-striker", "--methods", "dop853", "--levels", "1", "--repeats", "1"]
    code = main([*argv, "--out", str(tmp_path / "a")])
    err = capsys.readouterr().err
    assert code != 0
    assert "striker" in err
    assert "Traceback" not in err
