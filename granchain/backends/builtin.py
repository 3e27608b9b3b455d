"""The two built-in backends: the pure-numpy reference solver and LAMMPS with granchain's pair styles."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from typing_extensions import override

from granchain.backends.protocol import PROPERTIES, Backend, Calculation, FileIOBackend, WorkFiles
from granchain.invariants import ENERGY_WATCH, MOMENTUM_WATCH, contact_overlap_bounds
from granchain.peaks import event_floor, lead_fall, lead_floor, stop_force_floor
from granchain.postprocess.sensors import finish_sensors
from granchain.problem import ChainProblem
from granchain.results import RunResult
from granchain.schedule import history_stride


def driver_history(scene) -> tuple[int, ...]:
    """(-1,): a shaker's driver's contact with bead 1 (0-based, in front of contact 1), whose force history
    the spectral observables take as the drive's (postprocess.observables.spectral); () otherwise."""
    return (-1,) if scene.loading.is_shaker else ()


class ReferenceBackend(Backend):
    """granchain's own solver (granchain.reference): RK4 with event location, or velocity Verlet, in
    this process; the yardstick the other backends and every error estimate are measured against."""

    name = "reference"
    title = "reference"
    implemented_properties = tuple(PROPERTIES)
    methods = ("rk4", "verlet")
    method_text = "RK4 or velocity Verlet"
    numpy_speed = True

    @override
    def default_method(self, scene) -> tuple[str, str | None]:
        """RK4, but velocity Verlet on a scene with velocity-dependent damping: there RK4's peak is another quantity
        than Verlet's and LAMMPS's (postprocess.comparison_table.peak_definition) and RK4 gives no
        error bars (workflows.error_estimates.withheld_because); the reference's Verlet is still the
        independent numpy solver (see :meth:`Backend.default_method`)."""
        from granchain.postprocess.comparison_table import peak_definition

        rk4, verlet = peak_definition("rk4", scene), peak_definition("verlet", scene)
        if rk4 == verlet:
            return "rk4", None
        return "verlet", (
            f"verlet, not rk4, on a scene with a {scene.damping.noun}: rk4's peak is {rk4}, Verlet's (and LAMMPS's) "
            f"{verlet}, and rk4 gives no error bars there (--method rk4 runs RK4)"
        )

    @override
    def calculate(self, scene, method: str, ranks: int = 1) -> Calculation:
        """Solve the planned scene in this process (see :meth:`Backend.calculate`)."""
        from granchain.reference.solver import solve_chain

        with np.errstate(over="ignore", invalid="ignore"):  # the run watch reports blow-ups
            sol = solve_chain(
                ChainProblem.from_scene(scene),
                scene.run.end_time,
                scene.run.timestep,
                method,
                histories=driver_history(scene) + tuple(i - 1 for i in scene.outputs.histories),
                sensors=tuple(b - 1 for b in scene.outputs.sensors),
                # a sensor's history where the scene asks for one (a companion run's has no interval)
                sensor_stride=history_stride(scene) if scene.outputs.history_interval is not None else 0,
                history_stride=history_stride(scene),
                snapshots=scene.outputs.snapshots,
                stop_after=None if scene.run.stop_after_contact is None else scene.run.stop_after_contact - 1,
                stop_at_wall=scene.run.stop_after_wall,
                stop_at_reflection=scene.run.stop_after_reflection,
                stop_floor=stop_force_floor(scene),
                event_floor=event_floor(scene) if scene.wall_event else None,
                event_maxima=tuple(
                    tuple(i - 1 for i in x) for x in (scene.outputs.event_max_contacts, scene.outputs.event_max_sensors)
                ),
                lead_floor=lead_floor(scene),
                lead_fall=lead_fall(scene),
                # blow-up and garbage detectors (granchain.invariants), not accuracy targets; each
                # contact's overlap against its own bodies' radii
                max_overlap=contact_overlap_bounds(scene),
                energy_watch=ENERGY_WATCH,
                momentum_watch=MOMENTUM_WATCH,
            )
        if scene.outputs.sensors:
            finish_sensors(scene, sol)
        return Calculation(RunResult(scene=scene, backend=self.name, solution=sol))


class LammpsBackend(FileIOBackend):
    """LAMMPS with granchain's pair styles (granchain.lammps): the deck and data file rendered into a
    work directory, run by LAMMPS in a worker process (on MPI ranks), its output files read back."""

    name = "lammps"
    title = "LAMMPS"
    implemented_properties = tuple(p for p in PROPERTIES if p != "peak_overlap")  # no overlap column
    methods = ("verlet",)
    method_text = "velocity Verlet"
    mpi = True
    absolute_positions = True  # x up to the chain's length (peaks.position_resolution)
    work_files = ("histories.npy", "chain.dump")

    #: the input files :meth:`write_input` writes
    INPUT, DATA = "deck.lmp", "chain.data"

    @override
    def prepare(self) -> None:
        """Build granchain's LAMMPS plugin, or find it built (a missing compiler or a failed build is
        a PluginError)."""
        from granchain.lammps.build import build_plugin

        build_plugin()

    @override
    def code_version(self) -> dict[str, str]:
        """The plugin's key (a hash of its sources and the LAMMPS version)."""
        from granchain.lammps.build import plugin_key

        return {"plugin": plugin_key()}

    @property
    @override
    def result_type(self) -> type[RunResult]:
        """LammpsRunResult: its provenance says which LAMMPS and which plugin ran it."""
        from granchain.lammps.runner import LammpsRunResult

        return LammpsRunResult

    @override
    def calculate(self, scene, method: str = "verlet", ranks: int = 1) -> Calculation:
        """Render, run and read back the planned scene in a work directory of its own (see
        :meth:`Backend.calculate`); the Calculation's work files are LAMMPS's deck, log and dumps."""
        from granchain.lammps import runner

        result, work = runner.run_lammps(scene, np_=ranks)
        return Calculation(result, WorkFiles(work, runner.output_files(work)))

    @override
    def input_files(self, scene) -> dict[str, str]:
        """deck.lmp and chain.data of the planned scene (granchain.templates.render_deck)."""
        from granchain.templates import render_deck

        deck = render_deck(scene)
        return {self.INPUT: deck.deck, self.DATA: deck.data}

    @override
    def command(self, ranks: int = 1, program: str = "lmp", mpirun: str = "mpirun") -> list[str]:
        """``lmp -in deck.lmp -screen none``, under ``mpirun -np ranks`` for more than one rank."""
        run = [program, "-in", self.INPUT, "-screen", "none"]
        return [mpirun, "-np", str(ranks), *run] if ranks > 1 else run

    @override
    def read_results(self, scene, directory: Path, wall_time: float, extra: dict | None = None) -> RunResult:
        """The deck's output files in ``directory`` -> its result (granchain.lammps.runner.lammps_result)."""
        from granchain.lammps.runner import lammps_result

        return lammps_result(scene, Path(directory), wall_time, extra)
