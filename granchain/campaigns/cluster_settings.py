"""Settings of a campaign's batch-queue workers: the [cluster] table and its flags, each value a
name or a number checked against a strict pattern (a campaign file is shared, and nothing in it
reaches a job script but these values), and their one-line description."""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

from granchain.exceptions import GranchainError
from granchain.workflows.submit import NAME_PATTERN as _NAME
from granchain.workflows.submit import WALLTIME_PATTERN as _WALLTIME
from granchain.workflows.submit import check_job_text

KINDS = ("local", "slurm", "pbs")
#: the keys a [cluster] table may hold (flags: --cluster, --queue, ...; the same names with dashes)
KEYS = ("kind", "queue", "account", "walltime", "jobs", "cores_per_job", "memory", "interface", "replacements")
#: the jobs' submit command per kind (its absence on PATH is refused before anything starts)
SUBMIT = {"slurm": "sbatch", "pbs": "qsub"}

# matched with fullmatch, on the value as used (never stripped): "$" would also match before a trailing
# newline, which ends a job script's directive (a PBS header's end: its walltime, -e and -o dropped)
_MEMORY = re.compile(r"(\d+(?:\.\d+)?) ?(B|kB|KB|MB|GB|TB|KiB|MiB|GiB|TiB)", re.ASCII)
_INTERFACE = re.compile(r"[A-Za-z0-9_.:-]{1,32}", re.ASCII)


class ClusterError(GranchainError, ValueError):
    """A cluster setting is invalid, or the queue refused the jobs; the message says which and what to do."""


@dataclass(frozen=True)
class ClusterSettings:
    """Where a campaign's workers run.

    Parameters
    ----------
    kind : str
        "local" (a LocalCluster on this machine), "slurm" or "pbs" (worker jobs through dask-jobqueue).
    queue, account : str or None
        The partition / queue (``#SBATCH -p``) and the account (``-A``); None: the site's default.
    walltime : str
        Each worker job's time limit, ``[D-]HH:MM:SS``. The workers leave a few minutes before it
        (``--lifetime``): a point in flight goes back to the queue, a replacement job takes over.
    jobs : int
        Worker jobs kept in the queue.
    cores_per_job : int or None
        Cores each job asks for (None: ``ranks``, one worker per job); a job runs
        ``cores_per_job // ranks`` worker processes.
    memory : str or None
        Memory per job (``"4GB"``, ``#SBATCH --mem``); None: the queue's default (the Dask workers'
        memory limit is then 2 GB per core).
    interface : str or None
        The network interface the scheduler and the workers bind to (``ib0``, ``eth0``; ``lo`` when the
        driver and every job share one machine, as in tests); None: Dask's choice.
    replacements : int or None
        How many ended jobs are replaced by new ones (None: 2 per job, at least 3).
    prologue : tuple of str
        Shell lines a job runs before its worker starts (``source /shared/venv/bin/activate``); the
        caller's own, never a campaign file's.
    log_directory : str or None
        Where the jobs' stdout and stderr go (the workspace's ``jobs/`` by default).
    """

    kind: str = "local"
    queue: str | None = None
    account: str | None = None
    walltime: str = "01:00:00"
    jobs: int = 1
    cores_per_job: int | None = None
    memory: str | None = None
    interface: str | None = None
    replacements: int | None = None
    prologue: tuple[str, ...] = ()
    log_directory: str | None = None

    @property
    def batch(self) -> bool:
        """The workers are batch jobs (slurm, pbs), not a LocalCluster."""
        return self.kind in SUBMIT

    def cores(self, ranks: int) -> int:
        """Cores per job for points of `ranks` MPI ranks."""
        return self.cores_per_job if self.cores_per_job is not None else ranks

    def workers_per_job(self, ranks: int) -> int:
        """Dask worker processes per job for points of `ranks` MPI ranks: cores // ranks, at least 1."""
        return max(1, self.cores(ranks) // ranks)

    def memory_text(self, ranks: int) -> str:
        """Memory per job: the setting, else 2 GB per core (the Dask workers' memory limit)."""
        return self.memory if self.memory is not None else f"{2 * self.cores(ranks)}GB"

    def replacement_limit(self) -> int:
        """How many ended jobs may be replaced: the setting, else 2 per job, at least 3."""
        return self.replacements if self.replacements is not None else max(3, 2 * self.jobs)

    def walltime_seconds(self) -> int:
        """The walltime in s."""
        m = _WALLTIME.fullmatch(self.walltime)
        assert m is not None  # checked by check()
        d, h, mi, s = (int(x) if x else 0 for x in m.groups())
        return ((d * 24 + h) * 60 + mi) * 60 + s

    def lifetime_seconds(self) -> int:
        """A worker's --lifetime: the walltime less a margin (a tenth of it, at most 5 min, at least 20 s)."""
        w = self.walltime_seconds()
        return max(10, w - min(300, max(20, w // 10)))


def _where(source: str | None, key: str) -> str:
    flag = "--" + key.replace("_", "-")
    return f"{source}: [cluster] {key}" if source else flag


def check(settings: ClusterSettings, source: str | None = None, ranks: int = 1) -> ClusterSettings:
    """Every setting checked (a CampaignError-like ClusterError naming the key or flag and the fix).

    source: the campaign file the values came from (messages name its [cluster] key), or None (flags).
    """
    s = settings
    if s.kind not in KINDS:
        raise ClusterError(f"{_where(source, 'kind')} = {s.kind!r} is invalid: one of {', '.join(KINDS)}")
    for key in ("queue", "account"):
        v = getattr(s, key)
        if v is not None and (not isinstance(v, str) or not _NAME.fullmatch(v)):
            raise ClusterError(
                f"{_where(source, key)} = {v!r} is invalid: a {key} name (letters, digits and _ . , : @ + -)"
            )
    if not isinstance(s.walltime, str) or not _WALLTIME.fullmatch(s.walltime):
        raise ClusterError(
            f"{_where(source, 'walltime')} = {s.walltime!r} is invalid: HH:MM:SS or D-HH:MM:SS, e.g. '02:00:00'"
        )
    if s.walltime_seconds() < 60:
        raise ClusterError(f"{_where(source, 'walltime')} = {s.walltime!r}: at least a minute (00:01:00)")
    for key, low in (("jobs", 1), ("cores_per_job", 1), ("replacements", 0)):
        v = getattr(s, key)
        if v is None and key != "jobs":
            continue
        if isinstance(v, bool) or not isinstance(v, int) or v < low or v > 100_000:
            raise ClusterError(f"{_where(source, key)} = {v!r} is invalid: a whole number from {low} to 100000")
    if s.cores_per_job is not None and s.cores_per_job < ranks:
        raise ClusterError(
            f"{_where(source, 'cores_per_job')} = {s.cores_per_job}: a point runs on {ranks} MPI ranks, so a job "
            f"needs at least {ranks} cores (give cores_per_job >= ranks, a multiple of it)"
        )
    if s.memory is not None and (not isinstance(s.memory, str) or not _MEMORY.fullmatch(s.memory)):
        raise ClusterError(f"{_where(source, 'memory')} = {s.memory!r} is invalid: an amount such as '4GB' or '500MB'")
    _check_interface(s, source)
    for line in s.prologue:
        if not isinstance(line, str):
            raise ClusterError(f"--prologue {line!r} is invalid: one shell line per --prologue")
        check_job_text(line.replace("\t", " "), "--prologue", "one shell line per --prologue", error=ClusterError)
    if s.log_directory is not None:
        check_log_directory(s.log_directory)
    return s


def check_log_directory(path) -> None:
    """Refuse a directory for the jobs' output that cannot go into ``#SBATCH -o`` / ``#PBS -o`` as it is
    (dask-jobqueue writes it there unquoted): no control character, no whitespace."""
    check_job_text(
        str(path),
        "the jobs' output directory (the workspace --out's jobs/)",
        "give --out a path without spaces or control characters",
        directive=True,
        error=ClusterError,
    )


def _check_interface(s: ClusterSettings, source: str | None) -> None:
    if s.interface is not None:
        if not isinstance(s.interface, str) or not _INTERFACE.fullmatch(s.interface):
            raise ClusterError(f"{_where(source, 'interface')} = {s.interface!r} is invalid: a network interface name")
        import psutil

        have = sorted(psutil.net_if_addrs())
        if s.interface not in have:
            raise ClusterError(
                f"{_where(source, 'interface')} = {s.interface!r}: this machine has no such network interface; "
                f"it has {', '.join(have)}"
            )


def from_table(table, source: str) -> dict:
    """The settings a campaign file's [cluster] table gives (validated by :func:`check` once merged)."""
    if not isinstance(table, dict):
        raise ClusterError(f"{source}: cluster = {table!r} must be a table: write it as a [cluster] section")
    import difflib

    out = {}
    for key, value in table.items():
        if key not in KEYS:
            close = difflib.get_close_matches(str(key), KEYS, n=1, cutoff=0.6)
            hint = f"did you mean {close[0]!r}? " if close else ""
            extra = (
                "; what a job runs before its worker (source, module load) is the --prologue flag of whoever "
                "runs the campaign, not a campaign file's"
                if key in ("prologue", "job_script_prologue", "python", "directives")
                else ""
            )
            raise ClusterError(
                f"{source}: [cluster] has unknown key {key!r}; {hint}allowed keys: {', '.join(KEYS)}{extra}"
            )
        out[key] = value
    check(ClusterSettings(**{k: v for k, v in out.items()}), source)
    return out


def merge(file_values: dict | None, flags: dict, source: str | None = None) -> ClusterSettings | None:
    """The campaign file's [cluster] values with the flags given (not None) over them; None: no cluster
    asked for anywhere (the local cluster, or --workers / --scheduler)."""
    values = dict(file_values or {})
    values.update({k: v for k, v in flags.items() if v is not None and k != "prologue"})
    if not values and not flags.get("prologue"):
        return None
    prologue = tuple(flags.get("prologue") or ())
    try:
        return ClusterSettings(**values, prologue=prologue)
    except TypeError as e:  # an unknown key: from_table has refused it already; a caller's typo here
        raise ClusterError(f"cluster settings: {e}") from None


def describe(settings: ClusterSettings, ranks: int) -> str:
    """'2 SLURM jobs of 2 cores (1 worker of 2 ranks each), queue debug, walltime 01:00:00'."""
    s = settings
    w = s.workers_per_job(ranks)
    parts = [
        f"{s.jobs} {s.kind.upper()} job{'s' if s.jobs != 1 else ''} of {s.cores(ranks)} "
        f"core{'s' if s.cores(ranks) != 1 else ''} ({w} worker{'s' if w != 1 else ''}"
        + (f" of {ranks} ranks" if ranks > 1 else "")
        + " each)"
    ]
    if s.queue:
        parts.append(f"queue {s.queue}")
    if s.account:
        parts.append(f"account {s.account}")
    parts.append(f"walltime {s.walltime}")
    return ", ".join(parts)


# ------------------------------------------------------------------------------------ security
# TLS for every Dask cluster granchain starts: a campaign's scheduler, workers and nannies accept only
# peers holding this run's certificate.
#
# A Dask scheduler runs what a client sends it (``Client.run_on_scheduler``), a worker what the
# scheduler sends it: a plain ``tcp://`` scheduler on a shared machine (any local user finds its port
# in ``/proc/net/tcp``), or bound to a cluster's network (``--cluster slurm``), runs anyone's code as
# the user who started the campaign. Each cluster granchain starts (the local one, the batch jobs'
# scheduler) therefore gets :func:`campaign_security`: a certificate authority, key and certificate
# made for this run alone (distributed's ``Security.temporary``), ``require_encryption``, and the
# mutual TLS of distributed's ``tls://`` (a peer is refused unless its certificate is signed by this
# run's authority). The key never leaves the driver but to its own workers: in memory for local
# workers, and for batch jobs in files of mode 0600 inside a directory of mode 0700 that only the
# user can enter (:func:`private_directory`, on the shared filesystem the jobs read), removed when the
# campaign ends. The job scripts name those files; they hold no key.
#
# An external ``--scheduler`` address is the user's own cluster: its security is the user's choice
# (docs/clusters.md).


def campaign_security():
    """A distributed Security of this run's own certificate authority, key and certificate (in memory),
    with encryption required.

    Raises
    ------
    GranchainError
        The ``cryptography`` package, which makes the certificates, is not installed.
    """
    from distributed.security import Security

    try:
        return Security.temporary()
    except ImportError:
        raise GranchainError(
            "a campaign's Dask cluster needs TLS (else any user who reaches its port runs code as you), and "
            "its certificates need the cryptography package: pip install cryptography"
        ) from None


def private_directory(parent: str | Path | None) -> Path:
    """A new directory of mode 0700 in `parent` (the system's temporary directory if None) for this
    run's key files and job scripts; the caller removes it (:func:`remove_directory`).

    Raises
    ------
    UnsafeFileError
        `parent` is a symbolic link.
    """
    from granchain.safe_files import check_not_link

    if parent is not None:
        check_not_link(parent)
        Path(parent).mkdir(parents=True, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix=".granchain-tls-", dir=parent))  # mode 0700, a fresh name


def remove_directory(path: Path | None, cluster=None) -> None:
    """Remove a private directory and the key files in it (nothing when None or gone); `cluster`: the
    dask-jobqueue cluster whose open key files (its ``_job_<key>`` temporary files) are closed first."""
    for key in ("key", "cert", "ca_file"):
        f = getattr(cluster, f"_job_{key}", None)
        if f is not None:
            f.close()  # a NamedTemporaryFile: closing removes its file
    if path is not None:
        shutil.rmtree(path, ignore_errors=True)


def private_cluster_class(cluster_class, directory: Path):
    """A dask-jobqueue cluster class (SLURMCluster, PBSCluster) whose jobs' scripts are written, mode
    0600, into `directory` (:func:`private_directory`), not into the shared temporary directory under
    a name another user could take (dask's tmpfile makes a name, removes it and opens it again)."""
    base = cluster_class.job_cls

    class PrivateJob(base):
        def job_file(self):
            import contextlib

            @contextlib.contextmanager
            def written():
                fd, name = tempfile.mkstemp(suffix=".sh", dir=directory)  # a fresh name, O_EXCL, mode 0600
                try:
                    with os.fdopen(fd, "w") as f:
                        f.write(self.job_script())
                    yield name
                finally:
                    with contextlib.suppress(OSError):
                        os.unlink(name)

            return written()

    class PrivateCluster(cluster_class):
        job_cls = PrivateJob

    PrivateJob.__name__ = PrivateJob.__qualname__ = f"Private{base.__name__}"
    PrivateCluster.__name__ = PrivateCluster.__qualname__ = f"Private{cluster_class.__name__}"
    return PrivateCluster
