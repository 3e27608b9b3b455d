"""Run directories someone else may have written, read back: load_run, repr and _repr_html_ of what
it returns. A crafted or damaged summary.json or table is one LoadRunError (a GranchainError) naming
the file and the field, or loads where it is valid CSV; what a file says never reaches a notebook as
HTML or a terminal as a control sequence; a directory replaced while it is read is never read as a
mixture of two runs."""

import json
import shutil
import threading
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.cli import main
from granchain.exceptions import GranchainError
from granchain.results import StoredRun
from granchain.rundir import write_run_dir
from granchain.workflows.load import LoadRunError, load_run
from granchain.workflows.run import run_scene

from .conftest import make_scene

SMALL = dict(beads=12, end_time=2e-5, timestep=5e-8, outputs="histories = [1, 5]\nsnapshots = [1e-5]")
STRONGER = 'kind = "impulse"\nimpulse = 0.2\nduration = 1e-6'


@pytest.fixture(scope="module")
def runs():
    """Two runs of one chain that differ in every number (the impulse doubled)."""
    return run_scene(make_scene(**SMALL)), run_scene(make_scene(**SMALL, loading=STRONGER))


@pytest.fixture(scope="module")
def made(runs, tmp_path_factory) -> Path:
    return write_run_dir(runs[0], tmp_path_factory.mktemp("made") / "run")


@pytest.fixture
def d(made, tmp_path) -> Path:
    """A fresh copy of a real run directory to damage."""
    out = tmp_path / "run"
    shutil.copytree(made, out)
    return out


def _same(a, b) -> bool:
    """Whether two loaded runs hold the same summary and tables."""
    return (
        dict(a.summary) == dict(b.summary)
        and a.peaks.equals(b.peaks)
        and a.energy.equals(b.energy)
        and a.histories.equals(b.histories)
        and a.snapshots.equals(b.snapshots)
    )


# ------------------------------------------------------------------ a directory replaced meanwhile


@pytest.mark.parametrize("how", ["run --overwrite", "collect in place"])
def test_a_directory_replaced_while_it_is_read_is_never_a_mixture(runs, tmp_path, how):
    """run --overwrite (a new directory renamed over the old) or collect in place (new files renamed
    in one by one, summary.json last) of two different runs, again and again, while load_run reads the
    directory: every load is one run's summary and tables (or, should the writer never pause, an
    error saying so)."""
    refs = [load_run(write_run_dir(r, tmp_path / f"ref{k}")) for k, r in enumerate(runs)]
    d = write_run_dir(runs[0], tmp_path / "shared")
    stop = threading.Event()

    def writer():
        k = 0
        while not stop.is_set():
            _write(how, runs[k % 2], d)
            k += 1

    t = threading.Thread(target=writer)
    t.start()
    mixed, refused, loaded = [], [], 0
    try:
        end = time.monotonic() + 4
        while time.monotonic() < end:
            try:
                r = load_run(d)
            except LoadRunError as e:
                refused.append(str(e))
                continue
            loaded += 1
            if not any(_same(r, ref) for ref in refs):
                mixed.append(r.summary["observables"].get("max_peak_force"))
    finally:
        stop.set()
        t.join()
    assert loaded > 0
    assert all("changed each of" in e or "no such directory" in e for e in refused), refused[:3]
    assert mixed == [], f"{len(mixed)} of {loaded} loads mixed two runs"


def _write(how: str, result, d: Path) -> None:
    """Rewrite run directory d with result as run --overwrite does, or as collect in place does."""
    from granchain.workflows.collect import _write_in_place

    if how == "run --overwrite":
        write_run_dir(result, d, overwrite=True)
    else:
        _write_in_place(result, d)


@pytest.mark.parametrize("how", ["run --overwrite", "collect in place"])
def test_a_directory_rewritten_just_after_its_summary_is_read_loads_as_one_run(runs, tmp_path, monkeypatch, how):
    """The interleaving of the loop above, made to happen: the other run is written right after
    load_run has read summary.json. Then its tables are the other run's: load_run reads it again."""
    from granchain.workflows import load

    refs = [load_run(write_run_dir(r, tmp_path / f"ref{k}")) for k, r in enumerate(runs)]
    d = write_run_dir(runs[0], tmp_path / "shared")
    real, swapped = load.read_text, []

    def read_then_rewrite(where, name):
        text = real(where, name)
        if name == "summary.json" and not swapped:
            swapped.append(name)
            _write(how, runs[1], d)
        return text

    monkeypatch.setattr(load, "read_text", read_then_rewrite)
    got = load_run(d)
    assert swapped
    assert _same(got, refs[1])


# ------------------------------------------------------------------ crafted summary.json


def _edit(key_path: str, value):
    def edit(s: dict) -> None:
        *parents, last = key_path.split(".")
        for p in parents:
            s = s[p]
        s[last] = value

    return edit


def _nested(s: dict) -> None:
    v = 0
    for _ in range(500):  # deep, though within json's own limit
        v = [v]
    s["observables"]["window"] = v


SUMMARY_DAMAGE = {
    "provenance a list": (_edit("provenance", [1, 2]), "provenance"),
    "a finished_utc that is no time": (_edit("provenance.finished_utc", "yesterday"), "provenance.finished_utc"),
    "a started_utc that is a number": (_edit("provenance.started_utc", 5), "provenance.started_utc"),
    "plan {}": (_edit("provenance.plan", {}), "provenance.plan.method"),
    "a plan choice without a value": (
        _edit(
            "provenance.plan",
            {
                "method": "verlet",
                "rtol": 0.01,
                "omega_max": 1.0,
                "stable_timestep": 1e-8,
                "choices": [{"name": "timestep", "reason": "r"}],
            },
        ),
        "provenance.plan.choices[0].value",
    ),  # fmt: skip
    "conservation text": (_edit("conservation", "x"), "conservation"),
    "a conservation value text": (_edit("conservation.momentum", "x"), "conservation.momentum"),
    "price a list": (_edit("price", []), "price"),
    "price.steps text": (_edit("price.steps", "many"), "price.steps"),
    "extra a number": (_edit("extra", 5), "extra"),
    "wall_time text": (_edit("wall_time", "fast"), "wall_time"),
    "steps a float": (_edit("steps", 10.5), "steps"),
    "errors text": (_edit("errors", "none"), "errors"),
    "errors.observables a list": (_edit("errors", {"observables": [1]}), "errors.observables"),
    "an observable's error text": (
        _edit("errors", {"observables": {"max_peak_force": {"error": "big"}}}),
        "errors.observables.max_peak_force.error",
    ),
    "beads HTML": (_edit("beads", "<img src=x onerror=alert(1)>"), "beads"),
    "wall_peak_complete text": (_edit("wall_peak_complete", "yes"), "wall_peak_complete"),
    "command a string": (_edit("provenance.command", "rm -rf"), "provenance.command"),
    "collected a list": (_edit("provenance.collected", []), "provenance.collected"),
    "the observables nested 500 deep": (_nested, "nested deeper"),
    "no steps": (lambda s: s.pop("steps"), "steps: missing"),
}


@pytest.mark.parametrize("case", list(SUMMARY_DAMAGE), ids=list(SUMMARY_DAMAGE))
def test_a_summary_field_of_the_wrong_type_is_one_error_naming_it(d, case):
    edit, field = SUMMARY_DAMAGE[case]
    s = json.loads((d / "summary.json").read_text())
    edit(s)
    (d / "summary.json").write_text(json.dumps(s))
    with pytest.raises(LoadRunError) as e:
        load_run(d)
    assert str(d / "summary.json") in str(e.value)
    assert field in str(e.value)


@pytest.mark.parametrize(
    "text",
    ['{"a":' * 100_000 + "1" + "}" * 100_000, "[" * 100_000 + "]" * 100_000, '"a string"', "[]", "null"],
    ids=["objects 1e5 deep", "lists 1e5 deep", "a string", "a list", "null"],
)
def test_a_summary_that_is_not_an_object_or_nested_1e5_deep_is_one_error(d, text):
    (d / "summary.json").write_text(text)
    with pytest.raises(LoadRunError, match="summary.json"):
        load_run(d)


# ------------------------------------------------------------------ peaks.csv


def test_peaks_with_a_byte_order_mark_or_a_quoted_header_load_the_same(d, made):
    want = load_run(made)
    text = (d / "peaks.csv").read_text()
    header, rest = text.split("\n", 1)
    (d / "peaks.csv").write_bytes(b"\xef\xbb\xbf" + text.encode())  # as a spreadsheet program saves it
    assert load_run(d).peaks.equals(want.peaks)
    (d / "peaks.csv").write_text(",".join(f'"{h}"' for h in header.split(",")) + "\n" + rest)
    got = load_run(d)
    assert got.peaks.equals(want.peaks)
    assert (got.solution.peak_force == want.solution.peak_force).sum() == want.peaks.shape[0]


@pytest.mark.parametrize(
    ("column", "cell", "said"),
    [
        ("peak_force", "abc", "column 'peak_force' holds 'abc', not a number"),
        ("time_of_peak", "", "column 'time_of_peak' holds '', not a number"),
        ("contact", "1.5", "column 'contact' holds '1.5', not a contact number"),
        ("complete", "yes", "column 'complete' holds 'yes', not 0 or 1"),
        ("contact", "0", "contact 0 is not a contact of the 12-bead chain"),
        ("contact", "-3", "contact -3 is not a contact of the 12-bead chain"),
        ("contact", "12", "contact 12 is not a contact of the 12-bead chain"),
        ("contact", "2", "names a contact twice"),
    ],
)
def test_a_damaged_peak_cell_is_one_error_naming_it(d, column, cell, said):
    """Contacts are numbered from 1: contact 0 is an error, not the last contact (Python's index -1)."""
    lines = (d / "peaks.csv").read_text().splitlines()
    header = lines[0].split(",")
    row = lines[1].split(",")
    row[header.index(column)] = cell
    lines[1] = ",".join(row)
    (d / "peaks.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(LoadRunError) as e:
        load_run(d)
    assert str(d / "peaks.csv") in str(e.value)
    assert said in str(e.value)


# ------------------------------------------------------------------ what a file says, displayed


HOSTILE = "<img src=x onerror=alert(1)>\x1b]0;owned\x07\x1b[2J"


def test_text_from_summary_json_reaches_neither_html_nor_a_terminal_raw(d):
    s = json.loads((d / "summary.json").read_text())
    for key in ("backend", "method", "contact_law", "loading"):
        s[key] = f"{key}{HOSTILE}"
    # a declared observable's field must be of its kind (tests/test_summary_fields.py); a key this
    # granchain does not declare (a newer one's observable) is any JSON value
    s["observables"]["a_newer_observable"] = HOSTILE
    (d / "summary.json").write_text(json.dumps(s))
    r = load_run(d)
    text, page = repr(r), r._repr_html_()
    assert "\x1b" not in text
    assert "\x07" not in text
    assert "<img" not in page
    assert "\x1b" not in page
    for key in ("backend", "method", "contact_law", "loading"):
        assert key in text
        assert key in page


def test_a_stored_summary_of_any_type_is_escaped_in_html(runs):
    """The display escapes each value itself, whatever the summary holds (a result built by hand)."""
    r = runs[0]
    summary = dict(r.summary)
    summary.update(beads=HOSTILE, steps=HOSTILE, peaks={HOSTILE: HOSTILE})
    page = type(r)(**{**r.__dict__, "stored": StoredRun(summary=summary, peaks={})})._repr_html_()
    assert "<img" not in page
    assert "\x1b" not in page


def test_load_run_errors_are_granchain_errors(d):
    (d / "peaks.csv").write_text("contact,peak_force\n0,1.0\n")
    with pytest.raises(GranchainError):
        load_run(d)


# ------------------------------------------------------------------ any damage: the property

RUN_FILES = ["summary.json", "scene.toml", "peaks.csv", "histories.csv", "snapshots.csv", "energy.csv"]
_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20) | st.just(HOSTILE),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=6,
)


def _paths(value, prefix=()):
    """Every key path of a JSON document (summary.json's: every field at any depth)."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield (*prefix, k)
            yield from _paths(v, (*prefix, k))


def _set_field(d: Path, pick: float, value) -> None:
    try:
        s = json.loads((d / "summary.json").read_bytes())
    except (OSError, ValueError, RecursionError):
        return  # an earlier damage left no summary to retype
    paths = list(_paths(s))
    if not paths:
        return
    *parents, last = paths[min(int(pick * len(paths)), len(paths) - 1)]
    node = s
    for p in parents:
        node = node[p]
    node[last] = value
    (d / "summary.json").write_text(json.dumps(s))


def _damage(d: Path, damage, secret: Path) -> None:
    kind, name = damage[0], d / damage[1]
    data = name.read_bytes() if name.is_file() and not name.is_symlink() else b""
    if kind == "truncate":
        name.write_bytes(data[: int(damage[2] * len(data))])
    elif kind == "garbage":
        k = int(damage[2] * len(data))
        name.write_bytes(data[:k] + damage[3] + data[k + len(damage[3]) :])
    elif kind == "field":
        _set_field(d, damage[2], damage[3])
    elif kind == "nest":
        (d / "summary.json").write_text('{"backend": ' + "[" * damage[2] + "]" * damage[2] + "}")
    elif kind == "bom":
        name.write_bytes(b"\xef\xbb\xbf" + data)
    elif kind == "quote" and data:
        header, _, rest = data.partition(b"\n")
        name.write_bytes(b",".join(b'"' + h + b'"' for h in header.split(b",")) + b"\n" + rest)
    elif kind == "delete" and name.exists():
        name.unlink()
    elif kind == "link":
        name.unlink(missing_ok=True)
        name.symlink_to(secret)


_FILE = st.sampled_from(RUN_FILES)
_CSV = st.sampled_from([f for f in RUN_FILES if f.endswith(".csv")])
DAMAGE = st.one_of(
    st.tuples(st.just("truncate"), _FILE, st.floats(0, 1)),
    st.tuples(st.just("garbage"), _FILE, st.floats(0, 1), st.binary(min_size=1, max_size=16)),
    st.tuples(st.just("field"), st.just("summary.json"), st.floats(0, 1), _JSON),
    st.tuples(st.just("nest"), st.just("summary.json"), st.sampled_from([50, 5_000, 100_000])),
    st.tuples(st.just("bom"), _CSV),
    st.tuples(st.just("quote"), _CSV),
    st.tuples(st.just("delete"), _FILE),
    st.tuples(st.just("link"), _FILE),
)


def _use(r) -> None:
    """Everything a notebook does with a loaded run: its displays escaped, its tables and records."""
    text, page = repr(r), r._repr_html_()
    assert "\x1b" not in text
    assert "<img" not in page
    for table in ("peaks", "energy", "histories", "snapshots"):
        getattr(r, table)
    r.observables(), r.price(), r.provenance(), r.peak_status(), r.observables_missing()


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damages=st.lists(DAMAGE, min_size=1, max_size=3))
def test_any_damaged_run_directory_loads_or_is_one_granchain_error(made, tmp_path_factory, damages):
    """Whatever is cut, overwritten, retyped, nested, re-quoted, deleted or linked: load_run returns a
    run whose displays, tables and records work, or raises a GranchainError naming the directory."""
    tmp = tmp_path_factory.mktemp("h")
    secret = tmp / "secret"
    secret.write_text(SECRET)
    d = tmp / "run"
    shutil.copytree(made, d)
    for damage in damages:
        _damage(d, damage, secret)
    try:
        r = load_run(d)  # any other exception propagates: the test fails
    except GranchainError as e:
        refused = str(e)
    else:
        refused = None
    if refused is not None:
        assert str(d) in refused
        assert "\x1b" not in refused
    else:
        _use(r)
        assert SECRET not in repr(r)
    shutil.rmtree(tmp)


SECRET = "SECRET-CONTENT-NOT-TO-LEAK"


@pytest.mark.parametrize(
    "damage",
    [("edit", "plan {}"), ("edit", "provenance a list"), ("nest", "summary.json", 100_000), ("link", "peaks.csv")],
    ids=["plan {}", "provenance a list", "nested 1e5 deep", "a linked peaks.csv"],
)
def test_granchain_plot_of_a_damaged_run_directory_is_one_error_line(d, tmp_path, capsys, damage):
    secret = tmp_path / "secret"
    secret.write_text(SECRET)
    if damage[0] == "edit":
        s = json.loads((d / "summary.json").read_text())
        SUMMARY_DAMAGE[damage[1]][0](s)
        (d / "summary.json").write_text(json.dumps(s))
    else:
        _damage(d, damage, secret)
    assert main(["plot", str(d)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("granchain: error: "), err
    assert err.count("granchain: error:") == 1, err
    assert "Traceback" not in err
    assert str(d) in err
