"""One big run on a batch queue: render the deck, write a job script, sbatch it, and collect it back.

    granchain submit SCENE --out DIR [--ranks N] [--queue Q] [--account A] [--walltime T] [--wait]

:func:`submit` plans the scene for LAMMPS as ``granchain render --out`` does (granchain.workflows.
collect.render_dir: deck.lmp, chain.data, scene.toml, plan.json), writes ``DIR/job.sh`` (plain LAMMPS:
the environment's ``lmp`` under its ``mpirun``; no granchain runs in the job, only what runs LAMMPS)
and submits it with ``sbatch``; ``DIR/job.json`` records the job. :func:`wait` polls the queue
(``scontrol show job``, never a fixed sleep) until the job ends; a job that completed is collected
(granchain.workflows.collect.collect: DIR becomes the run directory ``granchain run`` writes), any
other end is a :class:`SubmitError` with the job's state, exit code and the last lines of its output
and of LAMMPS's log. ``granchain collect DIR`` does the same later, from any machine that sees DIR.

The run is one run of the deck: no error-estimate companions (as ``granchain run --error-estimate
off``); its peaks, energies and histories are those ``granchain run --np N`` gives.
"""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
import time
import unicodedata
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from granchain.backends import LAMMPS
from granchain.exceptions import GranchainError

#: the job script and the record of the submission, written in DIR beside the deck
JOB_SCRIPT = "job.sh"
JOB_RECORD = "job.json"

# every pattern is matched with fullmatch (a "$" also matches before a trailing newline, which would
# end a job script's directive and start a line of its own) and is ASCII (\d also matches '٤' or '႔')
#: a queue or account name, as the job script's #SBATCH lines may hold it
NAME_PATTERN = re.compile(r"[A-Za-z0-9_.,:@+-]{1,64}", re.ASCII)
#: a walltime: [D-]HH:MM:SS
WALLTIME_PATTERN = re.compile(r"(?:(\d+)-)?(\d{1,4}):([0-5]\d):([0-5]\d)", re.ASCII)
#: a memory amount for --mem ("4GB", "500M")
MEMORY_PATTERN = re.compile(r"(\d+)([KMGT])i?B?", re.I | re.ASCII)

#: SLURM states of a job that has not ended yet
ACTIVE = {"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED", "RESIZING", "STAGE_OUT"}
#: seconds between two looks at the queue while waiting (a job starts about 2 s after sbatch here)
POLL = 0.5


class SubmitError(GranchainError, RuntimeError):
    """A job that could not be submitted, or ended without finishing its run; the message says which,
    with the job's last output lines, and what to do."""


@dataclass
class Submission:
    """A submitted run: its directory, the job id and the job script."""

    directory: Path
    job_id: str
    script: Path


def job_text_problem(value: str, directive: bool = False) -> str | None:
    """What makes `value` unfit for a job script, or None: a control character (a newline or carriage
    return ends the line it is on, a comment or a directive, and starts a command of its own), a line
    or paragraph separator, and where a directive takes the text (``#SBATCH -o PATH``), whitespace,
    which ends the directive's argument."""
    for c in value:
        if unicodedata.category(c) in ("Cc", "Zl", "Zp"):
            return f"it holds the control character {c!r}"
        if directive and c.isspace():
            return f"it holds whitespace ({c!r}), which ends a job script directive's value"
    return None


def check_job_text(value: str, what: str, fix: str, directive: bool = False, error=None) -> None:
    """Refuse `value` (named `what`) if it cannot go into a job script as it is (job_text_problem),
    with `fix`; error: the GranchainError class raised (SubmitError by default)."""
    problem = job_text_problem(value, directive)
    if problem is not None:
        raise (error or SubmitError)(f"{what} = {value!r} cannot go into a job script: {problem}; {fix}")


def check_settings(ranks: int, queue: str | None, account: str | None, walltime: str, memory: str | None) -> None:
    """Refuse what would not make a valid job script, naming the flag and the fix."""
    if isinstance(ranks, bool) or not isinstance(ranks, int) or not 1 <= ranks <= 100_000:
        raise SubmitError(f"--ranks = {ranks!r} is invalid: a whole number of MPI ranks >= 1")
    for flag, v in (("--queue", queue), ("--account", account)):
        if v is not None and not NAME_PATTERN.fullmatch(v):
            raise SubmitError(f"{flag} = {v!r} is invalid: a name of letters, digits and _ . , : @ + -")
    if not WALLTIME_PATTERN.fullmatch(walltime):
        raise SubmitError(f"--walltime = {walltime!r} is invalid: HH:MM:SS or D-HH:MM:SS, e.g. 02:00:00")
    if memory is not None and not MEMORY_PATTERN.fullmatch(memory):
        raise SubmitError(f"--memory = {memory!r} is invalid: an amount such as 4GB or 500M")


def lammps_commands() -> tuple[Path, Path]:
    """(lmp, mpirun) of this environment: the LAMMPS wheel's lmp and the mpich wheel's mpirun."""
    from granchain.lammps.build import mpich_file

    bin_dir = Path(sys.executable).parent
    lmp = bin_dir / "lmp"
    if not lmp.exists():
        found = shutil.which("lmp")
        if found is None:
            raise SubmitError("no lmp in this environment: pip install 'lammps[mpi]==2025.7.22.4.0'")
        lmp = Path(found)
    mpirun = bin_dir / "mpirun"
    if not mpirun.exists():
        mpirun = mpich_file("bin/mpirun")
    return lmp, mpirun


def job_script(
    directory: Path,
    ranks: int,
    walltime: str,
    queue: str | None = None,
    account: str | None = None,
    memory: str | None = None,
    job_name: str = "granchain-run",
) -> str:
    """The job script: #SBATCH lines, the plugin's directory, and plain LAMMPS on `ranks` ranks."""
    from granchain.lammps.build import build_plugin

    lmp, mpirun = lammps_commands()
    plugin_dir = build_plugin().parent  # built here, on the shared cache; the job only loads it
    d = directory.resolve()
    lines = [
        "#!/usr/bin/env bash",
        f"#SBATCH -J {job_name}",
        f"#SBATCH -n {ranks}",
        f"#SBATCH -t {walltime}",
        "#SBATCH -o slurm-%j.out",  # in the job's working directory: sbatch --chdir DIR
    ]
    if queue:
        lines.append(f"#SBATCH -p {queue}")
    if account:
        lines.append(f"#SBATCH -A {account}")
    if memory:
        lines.append(f"#SBATCH --mem={memory}")
    run = LAMMPS.command(ranks, str(lmp), str(mpirun))
    lines += [
        "# written by granchain submit: plain LAMMPS on the deck granchain render wrote here; then",
        f"# granchain collect {shlex.quote(str(d))}   (granchain submit --wait does it when the job ends)",
        "set -e",
        f"cd {shlex.quote(str(d))}",
        f"export LAMMPS_PLUGIN_PATH={shlex.quote(str(plugin_dir))}",
        "export OMP_NUM_THREADS=1",
        "# ranks on one node: mpirun starts them itself (srun's MPI plugin, which a site may lack, stays out)",
        'if [ "${SLURM_JOB_NUM_NODES:-1}" = 1 ]; then export HYDRA_BOOTSTRAP=fork; fi',
        " ".join(shlex.quote(a) for a in run),
    ]
    return "\n".join(lines) + "\n"


def _job_name(out: Path) -> str:
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", out.name)[:40] or "run"
    return f"granchain-{name}"


def submit(
    scene,
    out: str | Path,
    ranks: int = 1,
    queue: str | None = None,
    account: str | None = None,
    walltime: str = "01:00:00",
    memory: str | None = None,
) -> Submission:
    """Render `scene` into the new directory `out`, write its job script and submit it with sbatch.

    Parameters
    ----------
    scene : Scene
        The scene as given ("auto" values are planned for LAMMPS's Verlet, as granchain render does).
    out : path
        A new directory (refused if it exists): the deck, the job script, and later the run directory.
    ranks : int
        MPI ranks of the job (``#SBATCH -n``); at least MIN_BEADS_PER_RANK beads per rank.
    queue, account, walltime, memory : str
        ``#SBATCH -p``, ``-A``, ``-t`` and ``--mem``.

    Returns
    -------
    Submission
        The directory, the job id and the script's path.
    """
    from granchain.workflows.collect import render_dir
    from granchain.workflows.run import check_resources, check_timestep, plan_for

    check_settings(ranks, queue, account, walltime, memory)
    if shutil.which("sbatch") is None:
        raise SubmitError(
            "sbatch is not on PATH: submit from a login node of a SLURM cluster (or render the deck with "
            "'granchain render SCENE --out DIR' and run it there by hand)"
        )
    concrete, plan = plan_for(scene, LAMMPS, None, None)
    check_timestep(concrete, LAMMPS.integrator(None, concrete))
    check_resources(concrete, LAMMPS, ranks, oversubscribe=True)  # the cores are the job's, not this machine's
    out = Path(out)
    # the directory's path goes into the script's cd line and its collect comment (quoted: spaces are fine)
    fix = "give a directory whose path has no control characters"
    check_job_text(str(out), "--out", fix)  # as given (a NUL byte stops resolve)
    check_job_text(str(out.resolve()), "--out", fix)  # whole, the working directory's part too
    script_text = job_script(out, ranks, walltime, queue, account, memory, _job_name(out))
    render_dir(concrete, out, plan, scene)
    script = out / JOB_SCRIPT
    script.write_text(script_text)
    try:
        r = subprocess.run(
            ["sbatch", "--parsable", "--chdir", str(out.resolve()), str(script.resolve())],
            capture_output=True,
            text=True,
            timeout=120,
        )
    except (OSError, subprocess.TimeoutExpired) as e:
        raise SubmitError(f"sbatch failed to run ({e}); the deck and job script are in {out}") from None
    if r.returncode != 0:
        raise SubmitError(
            f"sbatch refused the job: {' '.join(r.stderr.split())[-600:]}; check --queue, --account, --walltime and "
            f"--ranks against the site's limits (the deck and job script are in {out}: fix them and run "
            f"'sbatch {script}', or submit again to a new --out)"
        )
    job_id = r.stdout.strip().split(";")[0]
    if not job_id.isdigit():
        raise SubmitError(f"sbatch answered {r.stdout.strip()!r}, not a job id; the job script is {script}")
    record = {
        "job_id": job_id,
        "scheduler": "slurm",
        "ranks": ranks,
        "submitted_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        "script": JOB_SCRIPT,
    }
    (out / JOB_RECORD).write_text(json.dumps(record, indent=2) + "\n")
    return Submission(out, job_id, script)


def job_state(job_id: str) -> dict[str, str] | None:
    """The job's fields as ``scontrol show job -o`` gives them (JobState, ExitCode, Reason, ...);
    None once SLURM no longer knows it (purged after MinJobAge)."""
    try:
        r = subprocess.run(["scontrol", "show", "job", "-o", job_id], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return {"JobState": "UNKNOWN"}
    if r.returncode != 0:
        return None if "Invalid job id" in r.stderr else {"JobState": "UNKNOWN"}
    return dict(m.groups() for m in re.finditer(r"(\w+)=(\S*)", r.stdout))


def _tail(path: Path, lines: int = 10) -> str:
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return ""
    return "\n".join(text.strip().splitlines()[-lines:])[-1500:]


def wait(sub: Submission, poll: float = POLL, on_state=None) -> dict[str, str]:
    """Poll the queue until the job ends; returns its last fields. on_state(state) is called when the
    state changes (pending -> running -> ...). Raises SubmitError when it did not complete."""
    last = None
    info: dict[str, str] | None = {}
    while True:
        info = job_state(sub.job_id)
        state = None if info is None else info.get("JobState", "UNKNOWN")
        if state != last and on_state is not None and state is not None:
            on_state(state)
        last = state
        if state is None or (state not in ACTIVE and state != "UNKNOWN"):
            break
        time.sleep(poll)
    if info is None:  # purged: whether LAMMPS finished is for collect to tell from the files
        return {"JobState": "PURGED"}
    if info.get("JobState") == "COMPLETED" and info.get("ExitCode", "0:0") == "0:0":
        return info
    out = sub.directory / f"slurm-{sub.job_id}.out"
    parts = [
        f"job {sub.job_id} ended {info.get('JobState')} (exit code {info.get('ExitCode', '?')}, reason "
        f"{info.get('Reason', '?')}) without finishing its run in {sub.directory}"
    ]
    job_out = _tail(out)
    if job_out:
        parts.append(f"last lines of {out.name}:\n{job_out}")
    log = _tail(sub.directory / "log.lammps")
    if log:
        parts.append(f"last lines of log.lammps:\n{log}")
    parts.append(
        "fix the cause and submit again to a new --out (a cancelled or timed-out job: a longer --walltime or "
        "more --ranks)"
    )
    raise SubmitError("; ".join(parts[:1]) + "\n" + "\n".join(parts[1:]))


def cancel(sub: Submission) -> None:
    """Cancel this submission's job (and no other)."""
    try:
        subprocess.run(["scancel", sub.job_id], capture_output=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        pass


def submit_and_collect(scene, out, wait_for_it: bool = False, on_state=None, **settings):
    """submit(), and with wait_for_it the job awaited and its directory collected: (Submission, the
    collected RunResult or None). Ctrl-C while waiting cancels the job this call submitted."""
    sub = submit(scene, out, **settings)
    if not wait_for_it:
        return sub, None
    from granchain.workflows.collect import collect

    try:
        wait(sub, on_state=on_state)
    except KeyboardInterrupt:
        cancel(sub)
        raise
    return sub, collect(sub.directory)


__all__ = [
    "SubmitError",
    "Submission",
    "cancel",
    "check_job_text",
    "job_script",
    "job_state",
    "submit",
    "submit_and_collect",
    "wait",
]
