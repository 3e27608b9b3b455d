"""What a backend is: a solver that turns a planned scene into a run's result, behind one interface.

Modelled on ASE's ``Calculator``: a backend names the properties it computes
(:attr:`Backend.implemented_properties`, keys of :data:`PROPERTIES`) and :meth:`Backend.calculate`
makes them. A backend that runs an external program through files follows ASE's
``FileIOCalculator`` (:class:`FileIOBackend`): write the input into a directory, run the program
there, read the results back; the run directory then also gets the files it wrote (:class:`WorkFiles`).
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

from granchain.exceptions import UsageError
from granchain.results import RunResult

#: what a backend may compute, each property with the ChainSolution fields that hold it (filled when
#: the scene asks for them: histories, snapshots, a wall's or a striker's contact)
PROPERTIES: dict[str, tuple[str, ...]] = {
    "peaks": ("peak_force", "time_of_peak", "force_min_after_peak", "complete"),
    "leading_pulse": ("leading_pulse_force", "leading_pulse_time"),
    "histories": ("history_time", "history_force", "history_velocity"),
    "snapshots": ("snapshot_time", "snapshot_displacement", "snapshot_velocity", "snapshot_force"),
    "energy": ("energy_time", "kinetic", "potential", "dissipated", "work"),
    "final_state": ("displacement", "velocity", "alpha_max", "momentum", "impulse_delivered"),
    "end_peaks": (
        "wall_peak_force",
        "wall_time_of_peak",
        "wall_peak_complete",
        "striker_peak_force",
        "striker_time_of_peak",
        "striker_peak_complete",
        "striker_velocity",
    ),
    "peak_overlap": ("peak_overlap",),
}


@dataclass
class WorkFiles:
    """The files a run wrote in a work directory of its own that its run directory gets a copy of.

    Attributes
    ----------
    directory : Path
        The work directory; :meth:`remove` deletes it once the files are copied (or not wanted).
    files : dict of str to Path
        File name in the run directory -> the file in the work directory.
    """

    directory: Path
    files: dict[str, Path] = field(default_factory=dict)

    def remove(self) -> None:
        """Delete the work directory and everything in it."""
        shutil.rmtree(self.directory, ignore_errors=True)


@dataclass
class Calculation:
    """One run of a backend: its result and the files it left for the run directory.

    Attributes
    ----------
    result : RunResult
        The run's result.
    work : WorkFiles or None
        The work directory of a file-based backend's run, None for a run made in memory.
    """

    result: RunResult
    work: WorkFiles | None = None

    @property
    def files(self) -> dict[str, Path]:
        """The files the run directory gets besides its own tables (none for a run made in memory)."""
        return dict(self.work.files) if self.work is not None else {}

    def discard(self) -> None:
        """Delete the run's work directory, if it has one (its files are copied, or not wanted)."""
        if self.work is not None:
            self.work.remove()


class Backend:
    """A solver: a planned scene in, a :class:`Calculation` out.

    Attributes
    ----------
    name : str
        The name ``--backend`` and scene files give, and a run directory's summary records.
    title : str
        The name in sentences ("the LAMMPS backend ...").
    implemented_properties : tuple of str
        The keys of :data:`PROPERTIES` its runs fill.
    methods : tuple of str
        The integrators it runs, its default first (:meth:`default_method` may choose another for a
        scene).
    method_text : str
        Its integrators in words, for the refusal of another.
    mpi : bool
        Whether it runs on MPI ranks (``--np``, a campaign's ``ranks``); else one process.
    work_files : tuple of str
        The files of ``guards.output_sizes`` it writes besides the run directory's own tables (they
        count in its disk estimate and its run directory gets them).
    work_in_tmp : bool
        Whether it writes its files in a work directory in the temporary directory first (its free
        disk is checked there too).
    absolute_positions : bool
        Whether it integrates the beads' absolute positions (each rounded to its ulp every step, up to
        the chain's length) rather than displacements from the undeformed chain: its round-off, and so
        the error bars' round-off floor (workflows.error_estimates.roundoff_floor), scales with the
        chain's length.
    numpy_speed : bool
        Whether its integrators cost what the reference's numpy RK4 does per step: then a kinked law's
        Verlet run is measured against RK4 runs by default (RK4's step is several times Verlet's, so they
        cost less than its own companions and give a truer bar; workflows.error_estimates.against_rk4_because).
    """

    name: ClassVar[str]
    title: ClassVar[str]
    implemented_properties: ClassVar[tuple[str, ...]]
    methods: ClassVar[tuple[str, ...]]
    method_text: ClassVar[str]
    mpi: ClassVar[bool] = False
    work_files: ClassVar[tuple[str, ...]] = ()
    work_in_tmp: ClassVar[bool] = False
    absolute_positions: ClassVar[bool] = False
    numpy_speed: ClassVar[bool] = False

    def default_method(self, scene) -> tuple[str, str | None]:
        """The integrator a run of this scene uses when none is asked for, and why where the scene
        changes it.

        Parameters
        ----------
        scene : granchain.scene.Scene
            The scene to run.

        Returns
        -------
        (str, str or None)
            The integrator (``methods[0]`` unless the scene calls for another) and the reason in words
            where it is not ``methods[0]``, else None.
        """
        return self.methods[0], None

    def integrator(self, method: str | None, scene) -> str:
        """The integrator a run of ``scene`` with ``method`` (None: the default) uses on this backend.

        Parameters
        ----------
        method : str or None
            An integrator some backend runs, or None.
        scene : granchain.scene.Scene
            The scene to run (the default may depend on it: :meth:`default_method`).

        Returns
        -------
        str
            ``method``, or this backend's default for the scene for None.

        Raises
        ------
        UsageError
            ``method`` is not one this backend runs.
        """
        if method is None:
            return self.default_method(scene)[0]
        if method not in self.methods:
            raise UsageError(f"method = {method!r}: the {self.title} backend integrates with {self.method_text} only")
        return method

    def prepare(self) -> None:
        """Make the backend ready to run, so that what would stop every run (a plugin that does not
        build) is said before any run starts; nothing for a backend that needs nothing."""

    def code_version(self) -> dict[str, str]:
        """What besides granchain's own source makes this backend's numbers (part of a campaign
        point's code version: a point made by another is stale); nothing for pure Python."""
        return {}

    @property
    def result_type(self) -> type[RunResult]:
        """The RunResult class of this backend's runs (what a run directory is read back as)."""
        return RunResult

    def calculate(self, scene, method: str, ranks: int = 1) -> Calculation:
        """Run a planned scene.

        Parameters
        ----------
        scene : Scene
            A concrete scene: nothing "auto" left in it.
        method : str
            One of :attr:`methods`.
        ranks : int
            MPI ranks (1 unless :attr:`mpi`).

        Returns
        -------
        Calculation
            The result (its solution fills :attr:`implemented_properties`) and any work files.
        """
        raise NotImplementedError

    def __repr__(self) -> str:
        """The backend's name, for reprs and messages."""
        return f"<granchain backend {self.name}>"


class FileIOBackend(Backend):
    """A backend that runs an external program on input files: write input, run, read results.

    :meth:`calculate` does the three in a work directory of its own; the three steps are also
    exposed one by one for a run made elsewhere (a deck directory run by hand or on a batch queue).
    """

    work_in_tmp = True

    def input_files(self, scene) -> dict[str, str]:
        """The program's input files for a planned scene: file name -> text."""
        raise NotImplementedError

    def write_input(self, scene, directory: Path) -> None:
        """Write the program's input for a planned scene (:meth:`input_files`) into ``directory``."""
        for name, text in self.input_files(scene).items():
            (Path(directory) / name).write_text(text)

    def command(self, ranks: int = 1, program: str = "", mpirun: str = "mpirun") -> list[str]:
        """The command line that runs the input in its directory on ``ranks`` MPI ranks."""
        raise NotImplementedError

    def read_results(self, scene, directory: Path, wall_time: float, extra: dict | None = None) -> RunResult:
        """The result of the program's run in ``directory``, read from the files it wrote."""
        raise NotImplementedError
