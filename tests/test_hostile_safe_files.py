"""granchain.safe_files: the reads and writes every shared directory goes through never follow a
symbolic link, never read a FIFO or a device, stop at their limit, and never leave half a file."""

import os
import threading

import pytest

from granchain import safe_files as sf


@pytest.fixture
def victim(tmp_path):
    v = tmp_path / "victim"
    v.write_text("VICTIM")
    yield v
    assert v.read_text() == "VICTIM"


@pytest.mark.parametrize(
    "write",
    [
        lambda p: sf.write_text(p, "x"),
        lambda p: sf.write_bytes(p, b"x"),
        lambda p: sf.copy_file(p.parent / "src", p),
        lambda p: sf.create_new(p).close(),
    ],
    ids=["write_text", "write_bytes", "copy_file", "create_new"],
)
def test_no_write_through_a_link(tmp_path, victim, write):
    (tmp_path / "src").write_text("new")
    os.symlink(victim, tmp_path / "out")
    with pytest.raises(sf.UnsafeFileError, match="symbolic link"):
        write(tmp_path / "out")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "src", "victim"]  # no temporary file


@pytest.mark.parametrize(
    "read",
    [sf.read_text, sf.read_bytes, sf.file_size, lambda p: sf.read_head(p, 10), lambda p: sf.read_tail(p, 10)],
    ids=["read_text", "read_bytes", "file_size", "read_head", "read_tail"],
)
def test_no_read_through_a_link_of_a_fifo_or_a_device(tmp_path, victim, read):
    os.symlink(victim, tmp_path / "link")
    os.symlink("/dev/zero", tmp_path / "zero")
    os.mkfifo(tmp_path / "fifo")
    for name, said in (("link", "symbolic link"), ("zero", "symbolic link"), ("fifo", "not a regular file")):
        done = []

        def attempt(name=name, said=said, done=done):
            with pytest.raises(sf.UnsafeFileError, match=said):
                read(tmp_path / name)
            done.append(name)

        t = threading.Thread(target=attempt, daemon=True)  # a FIFO opened for reading would block
        t.start()
        t.join(5)
        assert done == [name], f"{name}: blocked or not refused"
    with pytest.raises(sf.UnsafeFileError, match="not a regular file|directory"):
        read(tmp_path)


def test_reads_stop_at_their_limit_and_copies_at_theirs(tmp_path):
    big = tmp_path / "big"
    with open(big, "wb") as fh:
        fh.truncate(10**9)  # sparse: no disk used
    with pytest.raises(sf.UnsafeFileError, match="1000000000 bytes, more than the 1000"):
        sf.read_bytes(big, limit=1000)
    with pytest.raises(sf.UnsafeFileError, match="more than"):
        sf.copy_file(big, tmp_path / "copy", limit=1000)
    assert not (tmp_path / "copy").exists()
    assert sf.read_head(big, 4) == b"\0" * 4
    assert sf.read_tail(big, 4) == b"\0" * 4
    (tmp_path / "bad").write_bytes(b"\xff\xfe")
    with pytest.raises(sf.UnsafeFileError, match="not utf-8 text"):
        sf.read_text(tmp_path / "bad")


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary_one(tmp_path):
    p = tmp_path / "f"
    sf.write_text(p, "old")

    def full_disk_write():
        with sf.open_for_write(p) as fh:
            fh.write("half")
            raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space left"):
        full_disk_write()
    assert p.read_text() == "old"
    assert [x.name for x in tmp_path.iterdir()] == ["f"]


def test_atomic_directory_replaces_only_what_granchain_owns(tmp_path):
    with sf.atomic_directory(tmp_path / "d", "run") as t:
        sf.write_text(t / "a", "1")
    assert sf.is_owned(tmp_path / "d")
    with pytest.raises(sf.UnsafeFileError, match="already exists"):
        with sf.atomic_directory(tmp_path / "d", "run"):
            pass
    with sf.atomic_directory(tmp_path / "d", "run", overwrite=True) as t:
        sf.write_text(t / "b", "2")
    assert sorted(p.name for p in (tmp_path / "d").iterdir()) == [sf.MARKER, "b"]
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "x").write_text("keep")
    with pytest.raises(sf.UnsafeFileError, match="not written by granchain"):
        with sf.atomic_directory(tmp_path / "mine", "run", overwrite=True):
            pass
    with pytest.raises(KeyError), sf.atomic_directory(tmp_path / "e", "run") as t:  # an error: nothing left
        raise KeyError
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "mine"]
    assert (tmp_path / "mine" / "x").read_text() == "keep"
