"""scene -> backend -> RunResult -> run directory."""

from __future__ import annotations

from pathlib import Path

from granchain.reference.solver import ChainProblem, solve_chain
from granchain.results import RunResult, check_output_dir, write_run_dir

BACKENDS = ("reference",)


def history_stride(scene) -> int:
    """Steps between history samples: history_interval / timestep, at least 1."""
    if scene.outputs.history_interval is None:
        return 1
    return max(1, round(scene.outputs.history_interval / scene.run.timestep))


def run_reference(scene, method: str = "rk4") -> RunResult:
    """Run the pure-Python reference solver on a scene."""
    sol = solve_chain(
        ChainProblem.from_scene(scene),
        scene.run.end_time,
        scene.run.timestep,
        method,
        histories=tuple(i - 1 for i in scene.outputs.histories),
        history_stride=history_stride(scene),
        snapshots=scene.outputs.snapshots,
    )
    return RunResult(scene=scene, backend="reference", solution=sol)


def run_scene(
    scene, backend: str = "reference", method: str | None = None, out: str | Path | None = None, overwrite: bool = False
) -> RunResult:
    """Run a scene on a backend; if out is given, write the run directory (checked before the run)."""
    if backend not in BACKENDS:
        raise ValueError(f"backend = {backend!r} is not available; choose one of {', '.join(BACKENDS)}")
    if out is not None:
        check_output_dir(out, overwrite)
    result = run_reference(scene, method or "rk4")
    if out is not None:
        write_run_dir(result, out, overwrite=overwrite)
    return result
