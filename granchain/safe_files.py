"""Reading and writing inside a directory someone else may have prepared: run directories, workspaces
and collect directories are shared, so no symlink or name in them may make granchain read or write
outside them.

The rules every reader and writer of such a directory follows:

- A file is opened with ``O_NOFOLLOW``: a symbolic link planted where granchain reads or writes is
  refused, never followed (``ln -s ~/victim RUN/peaks.png`` must not overwrite the victim).
- Only regular files are read or copied (a FIFO would block, ``/dev/zero`` would fill the disk), and
  a read is bounded (``limit`` bytes): a damaged or hostile file cannot exhaust memory.
- A file is written to a hidden temporary name beside it and renamed over the old one when it is
  complete, so a full disk or a kill leaves the old file (or none), never a truncated or 0-byte one,
  and a hard link planted at the name is replaced, not written through.
- A directory granchain wrote carries a marker file (:data:`MARKER`); ``--overwrite`` replaces
  only such a directory (:func:`atomic_directory`).

Every refusal is an :class:`UnsafeFileError`, an ``OSError`` whose ``str`` is one sentence naming the
path and the fix, so code that already turns ``OSError`` into a user error (a ``GranchainError``)
reports it the same way. (This module sits in the lowest import layer, beside ``granchain.exceptions``,
so it cannot raise a ``GranchainError`` itself.)
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import functools
import glob
import hashlib
import io
import os
import shutil
import socket
import stat
import time
from collections.abc import Iterable, Iterator
from pathlib import Path

#: Name of the file marking a directory granchain wrote (run, compare, accuracy, collect, laws
#: directories, campaign workspaces): ``--overwrite`` replaces only a directory that has it.
MARKER = ".granchain-owned"
_MARKER_TEXT = "granchain wrote this directory; --overwrite may replace it\nkind = {kind}\n"
_MARKER_MAGIC = "granchain wrote this directory"

#: Default bound of a read (bytes): far above any summary, scene or table granchain writes.
DEFAULT_LIMIT = 256 * 1024 * 1024

_O_CLOEXEC = getattr(os, "O_CLOEXEC", 0)
_O_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0)
_O_NONBLOCK = getattr(os, "O_NONBLOCK", 0)


class UnsafeFileError(OSError):
    """A file granchain refuses to read or write: a symlink, not a regular file, too large,
    unreadable text, or a directory it does not own."""

    def __str__(self) -> str:
        """The refusal's message (the path and why)."""
        return self.strerror or super().__str__()


def _refuse(path, code: int, message: str) -> UnsafeFileError:
    return UnsafeFileError(code, f"{path}: {message}", str(path))


def _link_message(path) -> UnsafeFileError:
    return _refuse(
        path,
        errno.ELOOP,
        "is a symbolic link; granchain does not read or write through links in a shared directory "
        "(remove the link, or copy the file it points to in its place)",
    )


def is_link(path: str | Path) -> bool:
    """Whether ``path`` itself is a symbolic link (its target is not looked at)."""
    return os.path.islink(path)


def check_not_link(path: str | Path) -> None:
    """Refuse a symbolic link at ``path`` (a directory below a workspace or run directory, say)."""
    if os.path.islink(path):
        raise _link_message(path)


def _open_read_fd(path: str | Path) -> tuple[int, os.stat_result]:
    """A read descriptor on a regular file at ``path``, not following a link there."""
    try:
        fd = os.open(path, os.O_RDONLY | _O_NOFOLLOW | _O_CLOEXEC | _O_NONBLOCK)
    except OSError as e:
        if e.errno == errno.ELOOP or (e.errno in (errno.EMLINK, errno.ENOTDIR) and os.path.islink(path)):
            raise _link_message(path) from None
        raise
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            what = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
            raise _refuse(path, errno.EINVAL, f"is {what}; granchain reads only regular files here (remove it)")
        if _O_NONBLOCK:
            os.set_blocking(fd, True)
        return fd, st
    except BaseException:
        os.close(fd)
        raise


def _too_large(path, size: int, limit: int) -> UnsafeFileError:
    return _refuse(
        path,
        errno.EFBIG,
        f"is {size} bytes, more than the {limit} granchain reads from such a file "
        "(damaged or not granchain's; remove it or take it from a fresh run)",
    )


@contextlib.contextmanager
def open_for_read(path: str | Path, mode: str = "r", *, encoding: str = "utf-8") -> Iterator[io.IOBase]:
    """Open a regular file for reading without following a link there (streaming: no size limit;
    the caller bounds what it reads). ``mode`` is "r" (text) or "rb"."""
    if mode not in ("r", "rb"):
        raise ValueError(f"open_for_read: mode {mode!r}; use 'r' or 'rb'")
    fd, _ = _open_read_fd(path)
    fh = os.fdopen(fd, mode, encoding=None if mode == "rb" else encoding, newline=None if mode == "rb" else "")
    with fh:
        yield fh


def file_size(path: str | Path) -> int:
    """The size of a regular file at ``path`` (refused if a link or not a regular file)."""
    fd, st = _open_read_fd(path)
    os.close(fd)
    return st.st_size


def read_bytes(path: str | Path, limit: int = DEFAULT_LIMIT) -> bytes:
    """The content of a regular file, refused if a link, not a regular file, or over ``limit`` bytes."""
    fd, st = _open_read_fd(path)
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > limit:
            raise _too_large(path, st.st_size, limit)
        data = fh.read(min(st.st_size, limit) + 1)  # (CPython sets the whole request aside first)
    if len(data) > limit:  # grew while read
        raise _too_large(path, len(data), limit)
    return data


def read_text(path: str | Path, limit: int = DEFAULT_LIMIT, encoding: str = "utf-8") -> str:
    """:func:`read_bytes` decoded; text that does not decode is refused with the path."""
    data = read_bytes(path, limit)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as e:
        raise _refuse(
            path, errno.EILSEQ, f"is not {encoding} text (byte {e.start}); damaged or not granchain's"
        ) from None


def escapes(name: str) -> str | None:
    """Why the relative ``name`` written in a shared file could point outside the directory it is
    read in (an absolute path, a ``..`` part, an empty name), or None: it stays below it by its
    letters (a symbolic link among its parts is :func:`read_text_inside`'s to refuse)."""
    if not name or not name.strip():
        return "is empty"
    if "\x00" in name:
        return "holds a NUL character"
    if os.path.isabs(name):
        return "is an absolute path"
    if ".." in Path(name).parts:
        return "has a '..' part"
    return None


def read_text_inside(directory: str | Path, name: str, limit: int = DEFAULT_LIMIT, encoding: str = "utf-8") -> str:
    """The text of the regular file ``name`` (relative) inside ``directory``, read only there.

    Refused (:class:`UnsafeFileError`) when ``name`` :func:`escapes` the directory, or when any of
    its parts is a symbolic link, wherever the link points: each part is opened with ``O_NOFOLLOW``
    relative to the descriptor of the one above it, so a link swapped in meanwhile is not followed
    either. ``directory`` itself is the caller's (a link there is followed). The file is read as
    :func:`read_text` reads one (a regular file, at most ``limit`` bytes).
    """
    where = Path(directory) / name
    why = escapes(name)
    if why is not None:
        raise _refuse(where, errno.EPERM, f"{why}; only a file inside {directory} is read")
    parts = [p for p in Path(name).parts if p != "."]
    if not parts:
        raise _refuse(where, errno.EISDIR, "is a directory; name a file")
    dfd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY | _O_CLOEXEC)
    try:
        here = Path(directory)
        for part in parts[:-1]:
            here = here / part
            try:
                nfd = os.open(part, os.O_RDONLY | os.O_DIRECTORY | _O_NOFOLLOW | _O_CLOEXEC, dir_fd=dfd)
            except OSError as e:
                if os.path.islink(here) or e.errno == errno.ELOOP:
                    raise _link_message(here) from None
                raise
            os.close(dfd)
            dfd = nfd
        try:
            fd = os.open(parts[-1], os.O_RDONLY | _O_NOFOLLOW | _O_CLOEXEC | _O_NONBLOCK, dir_fd=dfd)
        except OSError as e:
            if e.errno in (errno.ELOOP, errno.EMLINK) or os.path.islink(where):
                raise _link_message(where) from None
            raise
    finally:
        os.close(dfd)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            what = "a directory" if stat.S_ISDIR(st.st_mode) else "not a regular file"
            raise _refuse(where, errno.EINVAL, f"is {what}; granchain reads only regular files here")
        if st.st_size > limit:
            raise _too_large(where, st.st_size, limit)
        if _O_NONBLOCK:
            os.set_blocking(fd, True)
        with os.fdopen(fd, "rb") as fh:
            fd = -1
            data = fh.read(min(st.st_size, limit) + 1)
    finally:
        if fd >= 0:
            os.close(fd)
    if len(data) > limit:
        raise _too_large(where, len(data), limit)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as e:
        raise _refuse(where, errno.EILSEQ, f"is not {encoding} text (byte {e.start})") from None


def read_head(path: str | Path, size: int) -> bytes:
    """The first ``size`` bytes of a regular file (its whole content if shorter)."""
    fd, _ = _open_read_fd(path)
    with os.fdopen(fd, "rb") as fh:
        return fh.read(size)


def read_tail(path: str | Path, size: int) -> bytes:
    """The last ``size`` bytes of a regular file (its whole content if shorter)."""
    fd, st = _open_read_fd(path)
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > size:
            fh.seek(st.st_size - size)
        return fh.read(size)


def _tmp_name(path: Path) -> Path:
    return path.with_name(f".{path.name}.tmp-{os.getpid()}-{os.urandom(3).hex()}")


@contextlib.contextmanager
def open_for_write(path: str | Path, mode: str = "w", *, encoding: str = "utf-8") -> Iterator[io.IOBase]:
    """Write a file atomically without following a link: yields a file object on a hidden temporary
    file beside ``path``, renamed over ``path`` when the block ends without an error (removed
    otherwise: a full disk leaves no 0-byte or partial file). A symbolic link at ``path`` is refused.

    ``mode`` is "w" (text, universal newlines off) or "wb". Usable as a matplotlib target::

        with open_for_write(out / "peaks.png", "wb") as fh:
            fig.savefig(fh, format="png")
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"open_for_write: mode {mode!r}; use 'w' or 'wb'")
    path = Path(path)
    check_not_link(path)
    if path.is_dir():
        raise _refuse(path, errno.EISDIR, "is a directory; remove it or choose another output")
    tmp = _tmp_name(path)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | _O_CLOEXEC, 0o666)
    try:
        text = mode == "w"
        with os.fdopen(fd, mode, encoding=encoding if text else None, newline="" if text else None) as fh:
            yield fh
            fh.flush()
        check_not_link(path)  # planted while we wrote: os.replace would not follow it, but say so
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def create_new(path: str | Path, mode: str = "w", *, encoding: str = "utf-8") -> io.IOBase:
    """Open a new file for writing in a directory granchain has just made (its own temporary
    directory): refused if anything, a link included, is already at ``path`` (O_EXCL, O_NOFOLLOW).
    ``mode`` is "w" (text, no newline translation) or "wb"; the caller closes it."""
    if mode not in ("w", "wb"):
        raise ValueError(f"create_new: mode {mode!r}; use 'w' or 'wb'")
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | _O_NOFOLLOW | _O_CLOEXEC, 0o666)
    except FileExistsError:
        if os.path.islink(path):
            raise _link_message(path) from None
        raise
    text = mode == "w"
    return os.fdopen(fd, mode, encoding=encoding if text else None, newline="" if text else None)


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically, refusing a symbolic link there (:func:`open_for_write`)."""
    with open_for_write(path, "wb") as fh:
        fh.write(data)


def write_text(path: str | Path, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically, refusing a symbolic link there (:func:`open_for_write`)."""
    with open_for_write(path, "w", encoding=encoding) as fh:
        fh.write(text)


def save_figure(fig, path: str | Path, **kwargs) -> None:
    """``fig.savefig`` into ``path`` through :func:`open_for_write` (format from the suffix unless given)."""
    path = Path(path)
    kwargs.setdefault("format", path.suffix.lstrip(".").lower() or "png")
    with open_for_write(path, "wb") as fh:
        fig.savefig(fh, **kwargs)


def copy_file(src: str | Path, dst: str | Path, limit: int | None = DEFAULT_LIMIT) -> None:
    """Copy a regular file (never a link's target, a device or a FIFO; at most ``limit`` bytes,
    None: no limit) to ``dst``, written as :func:`open_for_write` does."""
    fd, st = _open_read_fd(src)
    limit = float("inf") if limit is None else limit
    with os.fdopen(fd, "rb") as fin:
        if st.st_size > limit:
            raise _too_large(src, st.st_size, limit)
        with open_for_write(dst, "wb") as fout:
            copied = 0
            while chunk := fin.read(1 << 20):
                copied += len(chunk)
                if copied > limit:
                    raise _too_large(src, copied, limit)
                fout.write(chunk)


def regular_files(directory: str | Path) -> list[str]:
    """Names of the regular files directly in ``directory`` (links, subdirectories and special
    files left out), sorted."""
    out = []
    with os.scandir(directory) as it:
        for entry in it:
            if entry.is_file(follow_symlinks=False):
                out.append(entry.name)
    return sorted(out)


# ---------------------------------------------------------------------------------------------------
# directories granchain owns


def mark_owned(directory: str | Path, kind: str) -> None:
    """Write the marker saying granchain wrote ``directory`` (``kind``: run, compare, accuracy, ...)."""
    write_text(Path(directory) / MARKER, _MARKER_TEXT.format(kind=kind))


def is_owned(directory: str | Path) -> bool:
    """Whether granchain wrote ``directory``: it is a real directory (not a link) holding the marker
    as a regular file. Nothing else counts, whatever names the directory holds (a directory of the
    user's with a summary.json beside their own files is not a run directory: docs/security.md)."""
    d = Path(directory)
    if os.path.islink(d) or not d.is_dir():
        return False
    try:
        text = read_bytes(d / MARKER, limit=4096).decode("utf-8", "replace")
    except OSError:
        return False
    return text.startswith(_MARKER_MAGIC)


def not_owned_message(directory: str | Path, option: str = "--out") -> str:
    """The refusal of ``--overwrite`` on a directory granchain did not write (one sentence, the fix)."""
    return (
        f"{directory}: exists and was not written by granchain (no {MARKER} marker), so --overwrite "
        f"will not replace it; choose another {option}, or move or remove that directory yourself"
    )


#: seconds another host's (or boot's) directory, whose lock cannot be asked here, must be unchanged to go
FOREIGN_AGE = 7 * 86400.0


@functools.lru_cache(maxsize=1)
def host_tag() -> str:
    """12 hex digits naming this host and boot (hostname, boot_id): a directory named with it is this
    kernel's, whose lock (hold_lock) says if its writer lives, in whatever PID namespace it runs."""
    try:
        with open("/proc/sys/kernel/random/boot_id", "rb") as fh:
            boot = fh.read(64)
    except OSError:
        boot = b""
    return hashlib.sha256(socket.gethostname().encode() + b"\0" + boot.strip()).hexdigest()[:12]


def make_locked(path: str | Path, mode: int = 0o777) -> int:
    """Make the directory ``path`` locked (hold_lock's descriptor returned): made and locked under a
    hidden name, then renamed, so no sweeper sees it unlocked. FileExistsError if ``path`` exists."""
    path = Path(path)
    staging = path.parent / f".granchain-new-{os.urandom(6).hex()}"
    os.mkdir(staging, mode)
    fd = hold_lock(staging)
    try:
        if os.path.lexists(path):  # rename would replace an empty directory there
            raise FileExistsError(errno.EEXIST, "exists", str(path))
        os.rename(staging, path)
    except BaseException:
        os.close(fd)
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return fd


def hold_lock(directory: str | Path) -> int:
    """Lock ``directory`` (flock, shared) while the returned descriptor is open: the kernel drops it
    when the writer dies, however (a file system without locks: owner_gone cannot lock it either)."""
    fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY | _O_NOFOLLOW | _O_CLOEXEC)
    with contextlib.suppress(OSError):
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    return fd


def _newest_change(path: str | Path, st: os.stat_result) -> float:
    newest = st.st_mtime
    with contextlib.suppress(OSError), os.scandir(path) as it:
        for entry in it:
            with contextlib.suppress(OSError):
                newest = max(newest, entry.stat(follow_symlinks=False).st_mtime)
    return newest


def owner_gone(path: str | Path, tag: str | None) -> bool:
    """Whether the temporary directory ``path``, named with host tag ``tag`` (None: a name without
    one), is provably a dead writer's and the user's to remove: a real directory (not a link) the
    user owns, and either this kernel's (``tag`` is host_tag()) with its lock free (hold_lock; a
    directory is made locked: make_locked), or another host's (or boot's, or unnamed) unchanged for
    FOREIGN_AGE."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.geteuid():
        return False
    if tag != host_tag():
        return time.time() - _newest_change(path, st) > FOREIGN_AGE
    try:
        fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | _O_NOFOLLOW | _O_CLOEXEC)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # refused while a live writer holds its lock
        finally:
            os.close(fd)
    except OSError:  # locked, gone, or no locks on this file system: not provably dead
        return False
    return True


def check_replaceable(out: str | Path, overwrite: bool, option: str = "--out", owned=None) -> None:
    """Refuse an existing ``out`` unless ``overwrite`` and granchain owns it (:func:`is_owned`, or the
    predicate ``owned(path) -> bool`` when given).

    Raises :class:`UnsafeFileError` (EEXIST) with the message the command line prints.
    """
    out = Path(out)
    if os.path.islink(out):
        raise _refuse(
            out,
            errno.ELOOP,
            f"is a symbolic link; granchain writes a directory only at a real path (choose another {option})",
        )
    if not out.exists():
        return
    if not out.is_dir():
        raise _refuse(out, errno.EEXIST, f"exists and is not a directory; choose another {option}")
    if not overwrite:
        raise _refuse(out, errno.EEXIST, f"already exists; choose another {option} or pass --overwrite to replace it")
    if not (owned(out) if owned is not None else is_owned(out)):
        raise UnsafeFileError(errno.EEXIST, not_owned_message(out, option), str(out))


#: the most UTF-8 bytes of a name that a hidden sibling's name (``.NAME.partial-...``) carries: with
#: its suffix, far below a file name's 255-byte limit (a longer NAME is cut, and a hash of it added)
SIBLING_NAME_BYTES = 160


def sibling_stem(name: str) -> str:
    """``name`` as a hidden sibling's name holds it: itself, or, if longer than SIBLING_NAME_BYTES,
    its start and 8 hex digits of its hash (names that differ keep different stems)."""
    raw = os.fsencode(name)
    if len(raw) <= SIBLING_NAME_BYTES:
        return name
    cut = os.fsdecode(raw[: SIBLING_NAME_BYTES - 9]).encode("utf-8", "ignore").decode()  # whole characters
    return f"{cut}~{hashlib.sha256(raw).hexdigest()[:8]}"


def _fresh_temp(parent: Path, prefix: str) -> Path:
    """``parent/<prefix><host tag>-<pid>-<random>``, not yet made (the caller makes it: make_locked);
    temporary directories with this prefix that are provably a dead writer's (owner_gone) go first."""
    for stale in parent.glob(f"{glob.escape(prefix)}*"):
        rest = stale.name[len(prefix) :].split("-")
        if owner_gone(stale, rest[0] if len(rest) == 3 else None):
            shutil.rmtree(stale, ignore_errors=True)
    return parent / f"{prefix}{host_tag()}-{os.getpid()}-{os.urandom(4).hex()}"


@contextlib.contextmanager
def atomic_directory(
    out: str | Path,
    kind: str | None,
    overwrite: bool = False,
    option: str = "--out",
    owned=None,
) -> Iterator[Path]:
    """Build a directory under a hidden temporary name beside ``out`` and rename it into place.

    Yields the temporary directory; when the block ends without an error the marker
    (:data:`MARKER`, ``kind``; none for ``kind`` None) is written and the directory renamed to
    ``out``. An existing ``out`` is replaced only with ``overwrite`` and only if granchain owns it
    (:func:`check_replaceable`); on any error the temporary directory is removed and ``out`` is left
    as it was: nothing half-written appears. Stale temporary directories of a killed writer (their
    pid gone) are removed first. ``owned``: as in :func:`check_replaceable`.
    """
    out = Path(out)
    check_replaceable(out, overwrite, option, owned)
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    tmp = _fresh_temp(parent, f".{sibling_stem(out.name)}.partial-")
    lock = make_locked(tmp)
    try:
        yield tmp
        if kind is not None:
            mark_owned(tmp, kind)
        if out.exists() or os.path.islink(out):
            check_replaceable(out, overwrite, option, owned)  # again: it may have appeared meanwhile
            old = parent / f".{sibling_stem(out.name)}.old-{os.getpid()}-{os.urandom(4).hex()}"
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        os.close(lock)


@contextlib.contextmanager
def atomic_files(
    directory: str | Path, last: str, keep: Iterable[str] = (), prefix: str = ".partial-"
) -> Iterator[Path]:
    """Add files to an existing directory, each complete or not at all, ``last`` last.

    Yields a path inside ``directory`` (``<prefix><pid>``, not yet made) for the block to write a
    directory at. When the block ends without an error, ``directory``'s own ``last`` is removed, the
    written files are renamed into ``directory`` one by one (those named in ``keep`` stay as they
    were) and ``last`` after them, so that its presence marks a complete set. On any error nothing is
    renamed. The temporary directory is removed in any case; stale ones of a killed writer first.
    """
    d = Path(directory)
    tmp = _fresh_temp(d, prefix)
    lock = -1
    try:
        yield tmp
        lock = hold_lock(tmp)  # as it is emptied into d: not taken for a dead writer's meanwhile
        keep = {*keep, last}
        made = sorted(p.name for p in tmp.iterdir() if p.name not in keep)
        (d / last).unlink(missing_ok=True)
        for name in made:
            os.replace(tmp / name, d / name)
        os.replace(tmp / last, d / last)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if lock >= 0:
            os.close(lock)
