"""granchain accuracy: work-precision outputs on a small real scene (LAMMPS included)."""

from granchain.workflows.accuracy import accuracy_study, write_study

from .conftest import make_scene


def test_work_precision_study(tmp_path):
    sc = make_scene(
        beads=40,
        loading='kind = "impulse"\nimpulse = 0.1\nduration = 1e-6',
        end_time=2e-4,
        timestep=1e-8,
        outputs="window = [10, 30]",
    )
    study = accuracy_study(sc, levels=5, repeats=1)
    files = write_study(study, tmp_path)
    assert all(f.exists() and f.stat().st_size > 0 for f in files)
    methods = {p.method for p in study.points}
    assert methods == {"lammps", "rk4", "verlet", "dop853"}
    orders = study.orders()
    print(orders, study.reference_error)
    assert orders["rk4"] > 3.3
    assert 1.7 < orders["verlet"] < 2.5
    assert 1.7 < orders["lammps"] < 2.5
    # the converged reference is far more accurate than anything it judges
    assert study.reference_error < 0.01 * min(p.error_peak for p in study.points if p.error_peak > 0)
    assert study.cheapest(1e-2) is not None
    assert study.dump_errors
    assert study.dump_errors[0][2] < 1e-12
    text = (tmp_path / "accuracy.md").read_text()
    assert "cheapest method" in text
    assert "One-time costs" in text
    # the current plan's point: each integrator at the step planned for rtol 1e-3,
    # measured; the planner's error model is calibrated with a margin, so the plan meets it
    from granchain.workflows.accuracy import PLAN_RTOL

    assert {q.method for q in study.plan_points} == {"lammps", "rk4", "verlet"}
    for q in study.plan_points:
        print(f"plan {q.method}: dt {q.setting:.3g} s, error {q.error_peak:.2e}")
        assert q.error_peak <= PLAN_RTOL
    assert "The planner's choice" in text
    assert "(planned)" in (tmp_path / "accuracy.csv").read_text()
