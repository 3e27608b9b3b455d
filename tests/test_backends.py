"""The backend protocol: every registered backend answers the same questions, and its runs fill the
properties it says it implements (granchain.backends)."""

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings

from granchain.backends import BACKENDS, LAMMPS, METHODS, PROPERTIES, REFERENCE, FileIOBackend, backend_named
from granchain.exceptions import UsageError
from granchain.results import ChainSolution
from granchain.scene import parse_scene
from granchain.workflows.run import calculate_scene, integrator

from .conftest import make_scene
from .scenegen import overlap_fraction, scene_texts


def test_every_backend_declares_what_the_code_asks_of_it():
    for name, backend in BACKENDS.items():
        assert backend.name == name
        assert backend_named(name) is backend
        assert backend.implemented_properties
        assert set(backend.implemented_properties) <= set(PROPERTIES)
        assert backend.methods
        assert set(backend.methods) <= set(METHODS)
        assert backend.integrator(None, make_scene()) == backend.methods[0]  # (no dashpot)
        assert set(backend.work_files) <= {"histories.npy", "histories.csv", "chain.dump"}
    fields = {f.name for f in dataclasses.fields(ChainSolution)}
    assert {f for props in PROPERTIES.values() for f in props} <= fields


def test_an_unknown_backend_or_method_is_refused_with_the_choices():
    with pytest.raises(UsageError, match="backend = 'gromacs' is not known; choose one of reference, lammps"):
        integrator("gromacs", None, make_scene())
    with pytest.raises(UsageError, match="method = 'euler' is not known; choose rk4 or verlet"):
        integrator("reference", "euler", make_scene())
    with pytest.raises(UsageError, match="the LAMMPS backend integrates with velocity Verlet only"):
        integrator(LAMMPS, "rk4", make_scene())
    assert integrator(REFERENCE, None, make_scene()) == "rk4"
    assert integrator("lammps", None, make_scene()) == "verlet"


def test_the_file_backend_writes_its_input_and_names_its_command(tmp_path):
    from tests.conftest import make_scene

    sc = make_scene()
    assert isinstance(LAMMPS, FileIOBackend)
    LAMMPS.write_input(sc, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(LAMMPS.input_files(sc))
    assert LAMMPS.command(1) == ["lmp", "-in", "deck.lmp", "-screen", "none"]
    assert LAMMPS.command(4, "/x/lmp", "/x/mpirun")[:3] == ["/x/mpirun", "-np", "4"]


def _asked(scene, field: str) -> bool:
    """Whether a scene asks for what this ChainSolution field holds."""
    if field.startswith("history_"):
        return bool(scene.outputs.histories)
    if field.startswith("snapshot_"):
        return bool(scene.outputs.snapshots)
    if field.startswith("wall_"):
        return scene.effects.far_end == "wall"
    if field.startswith("striker_"):
        return scene.loading.kind == "striker"
    return True


def _filled(value) -> bool:
    """Computed: an array with its entries, or a number (nan: a contact the wave did not load)."""
    if isinstance(value, np.ndarray):
        return value.size > 0
    return isinstance(value, (int, float, np.number))


@settings(max_examples=3, deadline=None, suppress_health_check=list(HealthCheck))
@given(text=scene_texts(max_beads=20))
def test_every_backend_fills_its_implemented_properties_on_a_generated_scene(text):
    """Each registered backend's run of the same scene (with a snapshot besides the generator's
    histories) fills every field of every property it implements that the scene asks for, leaves
    the others empty, and its peaks and final state have the shapes of every other backend's."""
    sc = parse_scene(text.replace("peak_force = true\n", "peak_force = true\nsnapshots = [1e-7]\n"), source="g.toml")
    assume(overlap_fraction(sc) < 0.05)  # a load the contact laws describe (as scenegen.scenes)
    shapes = {}
    for backend in BACKENDS.values():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # accuracy notes: not the point here
            calc = calculate_scene(sc, backend=backend)
        try:
            sol = calc.result.solution
            assert calc.result.backend == backend.name
            assert isinstance(calc.result, backend.result_type)
            for prop, fields in PROPERTIES.items():
                for f in fields:
                    value = getattr(sol, f)
                    if prop in backend.implemented_properties and _asked(calc.result.scene, f):
                        assert _filled(value), f"{backend.name}: {prop}.{f} is not filled"
                    elif prop not in backend.implemented_properties:
                        assert value is None, f"{backend.name}: {prop}.{f} filled but not implemented"
            for f in PROPERTIES["peaks"] + PROPERTIES["final_state"]:
                shapes.setdefault(f, set()).add(np.shape(getattr(sol, f)))
            assert set(calc.files) >= ({"deck.lmp", "chain.data", "log.lammps"} if backend.work_in_tmp else set())
        finally:
            calc.discard()
        assert calc.work is None or not calc.work.directory.exists()
    assert all(len(s) == 1 for s in shapes.values()), shapes
