"""`granchain campaign table` on workspaces and campaign files someone else made: damaged JSON of
every kind in the record, the state points, the job files and the table files, links planted where it
writes, a workspace it may only read; campaign files nested too deep or too large. Every case is a
table or one `granchain: error:` line (exit 2), never a traceback, and nothing is written through a
link or outside the workspace."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from granchain.campaigns import workspace as wsp
from granchain.campaigns.spec import CampaignError, campaign_from_dict, parse_campaign
from granchain.cli import main
from granchain.scene import MAX_SCENE_BYTES

from .conftest import CAMPAIGN_SCENE

ROOT = Path(__file__).resolve().parent.parent


def campaign_text(vary: str) -> str:
    return (
        '[campaign]\nbackend = "reference"\nmethod = "verlet"\nerror_estimate = false\n\n'
        f"[vary]\n{vary}\n[scene]\n" + CAMPAIGN_SCENE.replace("\n[", "\n[scene.")
    )


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> Path:
    """A workspace of 2 points run, its tables written."""
    d = tmp_path_factory.mktemp("made")
    (d / "c.toml").write_text(campaign_text('"loading.amplitude" = [10.0, 20.0]\n'))
    assert main(["campaign", "run", str(d / "c.toml"), "--out", str(d / "ws"), "--workers", "1"]) == 0
    return d / "ws"


def one_error_line(err: str) -> str:
    assert "Traceback (most recent call last)" not in err, err
    lines = [x for x in err.splitlines() if x.startswith("granchain: error: ")]
    assert len(lines) == 1, err
    return lines[0]


# ------------------------------------------------------------ campaign files too deep or too large


@pytest.mark.parametrize(
    "value",
    ["[" * 5000 + "]" * 5000, "{a = " * 5000 + "1" + "}" * 5000, "[" * 40 + "1" + "]" * 40, "[" * 300 + "]" * 300],
    ids=["arrays-5000", "tables-5000", "arrays-40", "arrays-300"],
)
def test_a_campaign_file_nested_too_deep_is_one_message(tmp_path, capsys, value):
    f = tmp_path / "c.toml"
    f.write_text(campaign_text(f'"loading.amplitude" = [10.0]\nx = {value}\n'))
    assert main(["campaign", "run", str(f), "--out", str(tmp_path / "ws")]) == 2
    assert "nests arrays or tables" in one_error_line(capsys.readouterr().err)
    assert not (tmp_path / "ws").exists()


def test_a_campaign_dict_nested_too_deep_or_in_itself_is_one_message():
    deep: list = []
    for _ in range(100):
        deep = [deep]
    itself: list = []
    itself.append(itself)
    for value in (deep, itself):
        with pytest.raises(CampaignError, match="nests arrays or tables more than [0-9]+ levels deep"):
            campaign_from_dict({"vary": {"x": value}})


def test_a_campaign_file_over_the_scene_files_limit_is_one_message(tmp_path, capsys):
    f = tmp_path / "c.toml"
    body = campaign_text('"loading.amplitude" = [10.0]\n')
    f.write_text(body + "#" * (MAX_SCENE_BYTES - len(body) + 1) + "\n")
    assert main(["campaign", "run", str(f), "--out", str(tmp_path / "ws")]) == 2
    assert f"is over {MAX_SCENE_BYTES:,} bytes" in one_error_line(capsys.readouterr().err)
    with pytest.raises(CampaignError, match="is over"):
        parse_campaign(f.read_text())


# ------------------------------------------------------------ a workspace it may only read


def _readable_copy(made: Path) -> Path:
    """A copy of the workspace that another user may read but not write (and its parent folder)."""
    d = Path(tempfile.mkdtemp(prefix="granchain-ro-"))
    shutil.copytree(made, d / "ws")
    for p in [d, *d.rglob("*")]:
        os.chmod(p, 0o755 if p.is_dir() else 0o644)
    return d


def test_campaign_table_csv_of_a_workspace_it_cannot_write_prints_the_table(made):
    """As another user (nobody) who may read the workspace but not write it: `campaign table --csv`
    prints the table (it failed writing table.csv, though its own message recommends it), and
    `campaign table` prints it with one warning that it could not be saved."""
    if os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("running as another user needs root and setpriv")
    d = _readable_copy(made)
    try:
        as_nobody = ["setpriv", "--reuid=nobody", "--regid=nogroup", "--clear-groups", sys.executable, "-m"]
        env = {**os.environ, "PYTHONPATH": str(ROOT), "HOME": str(d), "MPLCONFIGDIR": str(d)}
        probe = subprocess.run([*as_nobody, "granchain", "--version"], capture_output=True, text=True, env=env)
        if probe.returncode != 0:
            pytest.skip(f"nobody cannot run this Python: {probe.stderr.strip()[-200:]}")
        before = sorted(p.name for p in (d / "ws").iterdir())
        r = subprocess.run(
            [*as_nobody, "granchain", "campaign", "table", str(d / "ws"), "--csv"],
            capture_output=True,
            text=True,
            env=env,
        )
        assert r.returncode == 0, r.stderr
        assert r.stdout.splitlines()[1:] == (d / "ws" / "table.csv").read_text().splitlines()[1:]
        assert r.stderr == "", r.stderr
        r = subprocess.run(
            [*as_nobody, "granchain", "campaign", "table", str(d / "ws")], capture_output=True, text=True, env=env
        )
        assert r.returncode == 0, r.stderr
        assert "done" in r.stdout
        (warning,) = [x for x in r.stderr.splitlines() if x.startswith("granchain: warning: ")]
        assert "table.csv: cannot be written" in warning
        assert "the table is printed, not saved" in warning
        assert sorted(p.name for p in (d / "ws").iterdir()) == before
    finally:
        shutil.rmtree(d)


# ------------------------------------------------------------ any damage, under campaign table

VICTIM = b"VICTIM: not granchain's"
#: where a damage lands: (workspace path, "job" for the first job directory's file)
_TARGETS = [
    (".", wsp.RECORD),
    ("job", wsp.STATEPOINT),
    ("job", "signac_job_document.json"),
    ("job", "run/summary.json"),
    ("job", wsp.TASK),
    ("job", wsp.FAILURE),
    (".", ".signac/config"),
    (".", "table.csv"),
    (".", "table.parquet"),
]


def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


_WRONG = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
    st.sampled_from([[], {}, [1, "a", None], {"x": [1]}, "auto", "\ud800", "search", [{"a": 1}, {"a": "x", "b": [2]}]]),
    st.sampled_from([400, 900, 990]).map(lambda n: json.loads(_nested(n))),
)


_DAMAGE = st.one_of(
    st.tuples(st.just("cut"), st.integers(0, 3)),
    st.tuples(st.just("garbage"), st.binary(max_size=64)),
    st.tuples(st.just("nested"), st.sampled_from([600, 5000, 100_000])),
    st.tuples(st.just("retype"), st.tuples(st.integers(0, 10**6), _WRONG)),
    st.tuples(st.just("link"), st.sampled_from(["victim", "dangling", "directory"])),
)


def _paths_of(doc, prefix=()) -> list[tuple]:
    """Every path (keys and indices) into a JSON document, a few levels deep."""
    out = []
    if len(prefix) < 4 and isinstance(doc, (dict, list)):
        for k in doc if isinstance(doc, dict) else range(len(doc)):
            out.append((*prefix, k))
            out.extend(_paths_of(doc[k], (*prefix, k)))
    return out


def _retype(data: bytes, which: int, value) -> bytes:
    """The JSON document with one of its values (or itself) replaced by a value of another type."""
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):  # (a document an earlier damage nested too deep to parse)
        return json.dumps(value).encode()
    paths = _paths_of(doc)
    if not paths:
        return json.dumps(value).encode()
    *head, last = paths[which % len(paths)]
    node = doc
    for k in head:
        node = node[k]
    node[last] = value
    return json.dumps(doc).encode()


def _damage(ws: Path, where: str, name: str, how: tuple, victim: Path) -> None:
    jobs = sorted((ws / "workspace").iterdir())
    p = (jobs[0] if where == "job" else ws) / name
    kind, arg = how
    data = p.read_bytes() if p.is_file() and not p.is_symlink() else b""
    p.parent.mkdir(parents=True, exist_ok=True)
    p.unlink(missing_ok=True)  # (a link planted by an earlier damage is replaced, not written through)
    if kind == "link":
        target = {"victim": victim, "dangling": ws.parent / "nowhere", "directory": ws.parent}[arg]
        os.symlink(target, p)
        return
    data = {
        "cut": lambda: [data[: len(data) // 2], data[:1], b"", data[:-1]][arg],
        "garbage": lambda: arg,
        "nested": lambda: _nested(arg).encode(),
        "retype": lambda: _retype(data, *arg),
    }[kind]()
    p.write_bytes(data)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    damages=st.lists(st.tuples(st.sampled_from(_TARGETS), _DAMAGE), min_size=1, max_size=3),
    csv=st.booleans(),
)
@example(damages=[(("job", wsp.STATEPOINT), ("retype", (51806, True)))], csv=False)  # outputs = true: AttributeError
@example(damages=[((".", ".signac/config"), ("link", "dangling"))], csv=True)  # signac's LookupError
@example(damages=[((".", wsp.RECORD), ("retype", (3, [{"a": 1}, {"a": "x"}])))], csv=True)
def test_campaign_table_of_any_damaged_workspace_is_a_table_or_one_error_line(
    made, tmp_path_factory, capsys, damages, csv
):
    """Truncated, garbage, deeply nested JSON and values of the wrong type in the record, the state
    points, the job files and the job document; a table file replaced by garbage; a link planted at a
    file campaign table reads or writes: a table (exit 0) or one error line (exit 2), and what a link
    points to is untouched."""
    d = tmp_path_factory.mktemp("damaged")
    ws = d / "ws"
    shutil.copytree(made, ws)
    victim = d / "victim"
    victim.write_bytes(VICTIM)
    for (where, name), how in damages:
        _damage(ws, where, name, how, victim)
    capsys.readouterr()
    rc = main(["campaign", "table", str(ws), *(["--csv"] if csv else [])])
    out, err = capsys.readouterr()
    assert rc in (0, 2), err
    if rc == 2:
        one_error_line(err)
    else:
        assert "Traceback" not in err
    assert victim.read_bytes() == VICTIM, "written through a link"
    shutil.rmtree(d)
