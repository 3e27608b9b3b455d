"""The reference solver's structure: integrators plus observers over one state.

Its behaviour is tests/test_reference.py's and the others'; here: the rules of the structure (short,
annotated functions; the public names other modules import), and that the two halves which now
compute the same maximum independently agree exactly: the integrator's history alpha_max and the
peak tracker's peak overlap.
"""

import ast
from pathlib import Path

import numpy as np
import pytest

from granchain.problem import ChainProblem, initial_state
from granchain.reference import integrators, observers, solver
from granchain.reference.hermite import hermite_max
from tests.conftest import PLASTIC_LAWS, make_scene

REFERENCE = Path(solver.__file__).parent
MAX_LINES = 80
MAX_MODULE_LINES = 600


def functions():
    for path in sorted(REFERENCE.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                yield path.name, node


@pytest.mark.parametrize(
    "name",
    [
        "solver.py",
        "state.py",
        "integrators.py",
        "stepping.py",
        "verlet.py",
        "rk4.py",
        "events.py",
        "observers.py",
        "hermite.py",
    ],
)
def test_functions_are_short_and_public_ones_annotated(name):
    for file, fn in functions():
        if file != name:
            continue
        lines = fn.end_lineno - fn.lineno + 1
        assert lines <= MAX_LINES, f"{file}: {fn.name} has {lines} lines"
        if fn.name.startswith("_") and fn.name != "__init__":
            continue
        args = [a for a in fn.args.args + fn.args.kwonlyargs if a.arg not in ("self", "cls")]
        missing = [a.arg for a in args if a.annotation is None]
        assert not missing, f"{file}: {fn.name} lacks type hints ({missing or 'return'})"
        assert fn.returns is not None, f"{file}: {fn.name} lacks type hints ({missing or 'return'})"


def test_modules_are_at_most_600_lines():
    for path in sorted(REFERENCE.glob("*.py")):
        lines = len(path.read_text().splitlines())
        assert lines <= MAX_MODULE_LINES, f"{path.name} has {lines} lines"


def test_the_names_other_modules_import_stay():
    # scipy_solver imports _hermite_max; tests and workflows import these from solver
    assert solver._hermite_max is hermite_max
    assert solver.EventLocationError is integrators.EventLocationError
    assert solver.KINK_ROUNDOFF == integrators.KINK_ROUNDOFF
    for name in integrators.__all__:  # the overview module names every integrator's public name
        assert hasattr(integrators, name), name
    assert solver.METHODS == ("rk4", "verlet")
    for name in (
        "solve_chain",
        "_solve",
        "ChainProblem",
        "InvariantError",
        "MAX_SPLITS_BASE",
        "MAX_SPLITS_PER_CONTACT",
    ):
        assert hasattr(solver, name), name


def test_every_observer_keeps_to_the_interface():
    hooks = ("start", "after_split", "after_step", "end_segment", "at_breakpoint", "finish")
    for cls in vars(observers).values():
        if isinstance(cls, type) and issubclass(cls, observers.Observer):
            for hook in hooks:
                assert callable(getattr(cls, hook)), (cls, hook)
            assert isinstance(cls.every, int)


@pytest.mark.parametrize("method", solver.METHODS)
@pytest.mark.parametrize("law", PLASTIC_LAWS)
@pytest.mark.parametrize("extra", ["", "[precompression]\nforce = 50.0\n"])
def test_history_is_the_peak_overlap(law, method, extra):
    # the integrator raises alpha_max to each step's largest overlap (RK4: the Hermite maximum where a
    # contact turns); the peak tracker keeps the running peak overlap from the same numbers: max is
    # exact, so the two agree to the last bit (from alpha_max at t = 0, the static overlap)
    sc = make_scene(beads=20, law=law, outputs=extra, end_time=1.5e-4, timestep=2e-8)
    problem = ChainProblem.from_scene(sc)
    sol = solver.solve_chain(problem, sc.run.end_time, sc.run.timestep, method, progress=None)
    alpha0 = initial_state(problem)[2]
    assert np.array_equal(sol.alpha_max, np.maximum(alpha0, sol.peak_overlap))
    assert sol.peak_overlap.max() > 0.0


def test_a_stop_takes_effect_after_every_observer_saw_the_step():
    # the early stop is checked every STOP_CHECK_EVERY steps; the step it fires at is the run's last,
    # and its energy row (the stop's breakpoint) is the last row
    sc = make_scene(beads=40, loading='kind = "velocity"\nvelocity = 3.0', end_time=1e-3, timestep=2e-8)
    sol = solver.solve_chain(ChainProblem.from_scene(sc), 1e-3, 2e-8, "verlet", stop_after=10, progress=None)
    assert sol.steps % solver.STOP_CHECK_EVERY == 0
    assert sol.end_time < 1e-3
    assert sol.energy_time[-1] == sol.end_time
    assert sol.complete[10]


def test_hermite_max_of_a_parabola():
    # alpha = 1 - (t - 0.3)^2 on [0, 1]: the cubic interpolant is the parabola itself
    a0, a1 = np.array([1 - 0.09]), np.array([1 - 0.49])
    d0, d1 = np.array([0.6]), np.array([-1.4])
    p, tp = hermite_max(0.0, 1.0, a0, a1, d0, d1)
    assert p[0] == pytest.approx(1.0, abs=1e-15)
    assert tp[0] == pytest.approx(0.3, abs=1e-15)
