"""granchain plan costs a reference run (cli/info.py planned_bars: REFERENCE.numpy_speed) and says so,
on the terminal and in --json: a LAMMPS run's integrator and companions may differ (on a kinked law
without a dashpot LAMMPS bounds its bars with its own runs at 2 dt and 4 dt, where the reference's
Verlet may take RK4 runs)."""

import json

from granchain.backends import LAMMPS, REFERENCE
from granchain.cli import main
from granchain.workflows.error_estimates import planned_companions

from .test_plan_cost import concrete


def test_plan_names_the_backend_it_costs(tmp_path, capsys):
    p = concrete(tmp_path, "bilinear", "verlet", finer=10.0)
    assert main(["plan", str(p), "--method", "verlet", "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert plan["backend"] == REFERENCE.name
    assert LAMMPS.name in plan["backend_note"].lower()
    assert main(["plan", str(p), "--method", "verlet"]) == 0
    lines = capsys.readouterr().out.splitlines()
    label = [line for line in lines if line.startswith("backend")]
    assert len(label) == 1
    assert REFERENCE.name in label[0]
    assert LAMMPS.name in label[0].lower()


def test_the_label_says_what_differs_on_a_kinked_law(tmp_path):
    """The note's example holds on this chain: the reference's Verlet plan is costed with RK4 runs,
    a LAMMPS run of the same plan would bound its bars with its own runs at 2 dt and 4 dt."""
    from granchain.scene import parse_scene
    from granchain.workflows.plan import plan_scene

    sc = parse_scene(concrete(tmp_path, "bilinear", "verlet", finer=10.0).read_text(), source="b.toml")
    stable = plan_scene(sc, method="verlet").stable_timestep
    ref = planned_companions(sc, "verlet", stable, numpy_speed=REFERENCE.numpy_speed)
    lmp = planned_companions(sc, "verlet", stable, numpy_speed=LAMMPS.numpy_speed)
    assert {c.role for c in ref} == {"rk4 reference"}
    assert [(c.method, c.factor, c.role) for c in lmp] == [("verlet", 2.0, "companion"), ("verlet", 4.0, "companion")]
