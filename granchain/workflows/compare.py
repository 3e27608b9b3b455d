"""granchain compare: the same scene on LAMMPS and on the reference solver, one table."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from granchain.postprocess.compare import compare_runs, write_compare
from granchain.results import check_output_dir, write_run_dir
from granchain.workflows.run import run_scene


def compare_scene(
    scene,
    rtol: float = 1e-3,
    out: str | Path | None = None,
    overwrite: bool = False,
    method: str = "rk4",
    np_: int = 1,
    reference_scene=None,
):
    """Run LAMMPS and the reference on a scene; returns (rows, lammps result, reference result).

    reference_scene: give the reference a different scene (only to show that a physics mismatch is
    caught; `granchain compare` never does this). out: a directory with lammps/, reference/,
    compare.csv and compare.md, written atomically.
    """
    if out is not None:
        check_output_dir(out, overwrite)
    lam = run_scene(scene, backend="lammps", np_=np_, keep_files=True)
    files, work = lam.extra.pop("_files"), lam.extra.pop("_work")
    try:
        ref = run_scene(reference_scene or scene, backend="reference", method=method)
        rows = compare_runs(lam, ref, rtol)
        if out is not None:
            out = Path(out)
            tmp = out.resolve().parent / f".{out.name}.partial-{os.getpid()}"
            shutil.rmtree(tmp, ignore_errors=True)
            try:
                tmp.mkdir(parents=True)
                write_run_dir(lam, tmp / "lammps", extra_files=files)
                write_run_dir(ref, tmp / "reference")
                write_compare(rows, tmp)
                if out.exists():
                    shutil.rmtree(out)
                os.replace(tmp, out)
            finally:
                shutil.rmtree(tmp, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return rows, lam, ref
