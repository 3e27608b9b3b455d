"""TLS for every Dask cluster granchain starts: a campaign's scheduler, workers and nannies accept only
peers holding this run's certificate.

A Dask scheduler runs what a client sends it (``Client.run_on_scheduler``), a worker what the
scheduler sends it: a plain ``tcp://`` scheduler on a shared machine (any local user finds its port
in ``/proc/net/tcp``), or bound to a cluster's network (``--cluster slurm``), runs anyone's code as
the user who started the campaign. Each cluster granchain starts (the local one, the batch jobs'
scheduler) therefore gets :func:`campaign_security`: a certificate authority, key and certificate
made for this run alone (distributed's ``Security.temporary``), ``require_encryption``, and the
mutual TLS of distributed's ``tls://`` (a peer is refused unless its certificate is signed by this
run's authority). The key never leaves the driver but to its own workers: in memory for local
workers, and for batch jobs in files of mode 0600 inside a directory of mode 0700 that only the
user can enter (:func:`private_directory`, on the shared filesystem the jobs read), removed when the
campaign ends. The job scripts name those files; they hold no key.

An external ``--scheduler`` address is the user's own cluster: its security is the user's choice
(docs/clusters.md).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref
from pathlib import Path

from granchain.exceptions import GranchainError


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


def private_directory(owner, parent: str | Path | None) -> Path:
    """A new directory of mode 0700 in `parent` (the system's temporary directory if None) for this
    run's key files and job scripts, removed with everything in it when `owner` is collected or the
    process ends (weakref.finalize); the caller may remove it sooner with :func:`remove_directory`.

    Raises
    ------
    UnsafeFileError
        `parent` is a symbolic link.
    """
    from granchain.safe_files import check_not_link

    if parent is not None:
        check_not_link(parent)
        Path(parent).mkdir(parents=True, exist_ok=True)
    path = Path(tempfile.mkdtemp(prefix=".granchain-tls-", dir=parent))  # mode 0700, a fresh name
    weakref.finalize(owner, shutil.rmtree, path, ignore_errors=True)
    return path


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


__all__ = ["campaign_security", "private_cluster_class", "private_directory", "remove_directory"]
