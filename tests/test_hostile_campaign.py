"""Campaign workspaces someone else may have prepared or damaged: `campaign run / table / plot` never
write or read through a symbolic link planted in one, a damaged file is one error line (or a point
counted incomplete), never a traceback; a string parameter cannot drive the terminal; a title cannot
break the figure; an expression cannot reach Python's recursion limit."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.campaigns import workspace as wsp
from granchain.campaigns.spec import CampaignError, parse_campaign
from granchain.cli import main

from .conftest import CAMPAIGN_SCENE

SCENE = CAMPAIGN_SCENE
ESCAPES = "a\x1b]0;pwned\x07\x1b[2J"


def campaign_text(vary: str, extra: str = "", title: str = "small") -> str:
    return (
        f'[campaign]\nbackend = "reference"\nmethod = "verlet"\ntitle = {json.dumps(title)}\n\n[vary]\n{vary}\n'
        f"{extra}\n[scene]\n" + SCENE.replace("\n[", "\n[scene.")
    )


VARY = '"loading.amplitude" = [10.0, 20.0]\nlabel = ' + json.dumps([ESCAPES, "b"]) + "\n"
PLOT = ["--x", "loading.amplitude", "--y", "max_peak_force"]
STEM = "max_peak_force-vs-loading.amplitude"


@pytest.fixture(scope="module")
def made(tmp_path_factory) -> tuple[Path, Path]:
    """(campaign file, its workspace): 2 scenes x 2 values of a free string parameter."""
    d = tmp_path_factory.mktemp("campaign")
    f = d / "c.toml"
    f.write_text(campaign_text(VARY))
    assert main(["campaign", "run", str(f), "--out", str(d / "ws"), "--workers", "1"]) == 0
    return f, d / "ws"


@pytest.fixture
def ws(made, tmp_path) -> Path:
    w = tmp_path / "ws"
    shutil.copytree(made[1], w, symlinks=True)
    return w


@pytest.fixture
def victim(tmp_path) -> Path:
    v = tmp_path / "victim"
    v.write_bytes(b"VICTIM")
    yield v
    assert v.read_bytes() == b"VICTIM", "written through a link"


def jobs(ws: Path) -> list[Path]:
    return sorted((ws / "workspace").iterdir())


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" not in err, err
    lines = [x for x in err.splitlines() if x.startswith("granchain: error: ")]
    assert len(lines) == 1, err
    return lines[0]


def plant(path: Path, target: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)
    os.symlink(target, path)


# -------------------------------------------------------------------- links: nothing through them


@pytest.mark.parametrize("name", ["campaign.toml", "base.toml", "campaign.json", "table.csv", "workspace", "plots"])
def test_campaign_run_refuses_a_link_in_the_workspace(made, ws, victim, capsys, name):
    plant(ws / name, victim)
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1"]) == 2
    assert f"{ws / name}: is a symbolic link" in one_error_line(capsys)


@pytest.mark.parametrize("name", ["campaign.json", "table.csv", "table.parquet", "plots"])
def test_campaign_table_and_plot_refuse_a_link_in_the_workspace(ws, victim, capsys, name):
    plant(ws / name, victim)
    assert main(["campaign", "table", str(ws)]) == 2
    assert "is a symbolic link" in one_error_line(capsys)
    assert main(["campaign", "plot", str(ws), *PLOT]) == 2
    assert "is a symbolic link" in one_error_line(capsys)


@pytest.mark.parametrize("suffix", ["csv", "png", "svg"])
def test_campaign_plot_never_writes_through_a_link_in_plots(ws, victim, capsys, suffix):
    (ws / "plots").mkdir(exist_ok=True)
    plant(ws / "plots" / f"{STEM}.{suffix}", victim)
    assert main(["campaign", "plot", str(ws), *PLOT, "--format", "png,svg"]) == 2
    assert "is a symbolic link" in one_error_line(capsys)


@pytest.mark.parametrize("name", ["run/summary.json", "task.json", "run/histories.csv", "run"])
def test_job_files_that_are_links_are_not_read(ws, tmp_path, capsys, name):
    job = jobs(ws)[0]
    secret = tmp_path / "secret"
    if name == "run":
        shutil.move(job / "run", secret)
    else:
        data = json.loads((job / name).read_text()) if name.endswith(".json") else None
        if name == "run/summary.json":
            data["observables"]["max_peak_force"] = 12345.678
        if name == "task.json":
            data["warnings"] = ["FROM-THE-LINK"]
        if data is None:
            shutil.copy(job / name, secret)
        else:
            secret.write_text(json.dumps(data))
    plant(job / name, secret)
    assert main(["campaign", "table", str(ws), "--csv"]) == 0
    out = capsys.readouterr().out
    assert "12345.678" not in out
    assert "FROM-THE-LINK" not in out
    if name in ("run/summary.json", "run"):  # its point is not complete: its run directory is not its own
        assert "missing" in out


def test_a_job_directory_that_is_a_link_is_set_aside_and_run_again(made, ws, tmp_path, capsys):
    job = jobs(ws)[0]
    elsewhere = tmp_path / "elsewhere"
    shutil.move(job, elsewhere)
    before = sorted(p.name for p in elsewhere.rglob("*"))
    os.symlink(elsewhere, job)
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1"]) == 0
    assert "moved to" in capsys.readouterr().err
    assert sorted(p.name for p in elsewhere.rglob("*")) == before  # nothing written there
    assert (ws / wsp.DAMAGED / job.name).is_symlink()
    assert (job / "run" / "summary.json").is_file()


def _tree(d: Path) -> list:
    """What is under d (names, sizes, modification times), links not followed."""
    return sorted((str(p.relative_to(d)), p.lstat().st_size, p.lstat().st_mtime_ns) for p in d.rglob("*"))


def _run_elsewhere(job: Path, tmp_path: Path) -> tuple[Path, list]:
    """The job's run directory moved out of the workspace and a link to it left in its place."""
    elsewhere = tmp_path / "elsewhere"
    shutil.move(job / "run", elsewhere)
    os.symlink(elsewhere, job / "run")
    return elsewhere, _tree(elsewhere)


def test_a_run_directory_that_is_a_link_is_set_aside_and_its_point_runs_again(made, ws, tmp_path, capsys):
    job = jobs(ws)[0]
    elsewhere, before = _run_elsewhere(job, tmp_path)
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1"]) == 0
    err = capsys.readouterr().err
    assert "had a symbolic link as its run directory" in err, err
    assert str(ws / wsp.DAMAGED) in err
    assert _tree(elsewhere) == before  # nothing read, written or removed there
    assert (ws / wsp.DAMAGED / f"{job.name}.run").is_symlink()
    assert wsp.job_state(job) == "done"
    assert not (job / "run").is_symlink()


def test_a_point_failed_on_a_run_link_says_what_to_do_and_retry_failed_recovers_it(made, ws, tmp_path, capsys):
    """A link planted after the driver looked: the worker refuses it, naming the point's directory and
    --retry-failed (not '--out', a flag campaigns do not take); --retry-failed then runs the point."""
    from granchain.campaigns.point_task import run_point

    job = jobs(ws)[0]
    elsewhere, before = _run_elsewhere(job, tmp_path)
    sp = json.loads((job / wsp.STATEPOINT).read_text())
    record = run_point({**sp, "job_dir": str(job), "source": "a point", "code": wsp.code_version(sp["backend"])})
    assert record["status"] == "failed"
    assert str(job / "run") in record["message"]
    assert "--retry-failed" in record["message"]
    assert "--out" not in record["message"]
    assert wsp.job_state(job) == "failed"
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1", "--retry-failed"]) == 0
    assert "had a symbolic link as its run directory" in capsys.readouterr().err
    assert wsp.job_state(job) == "done"
    assert _tree(elsewhere) == before


def test_a_failure_record_that_is_a_link_is_refused_and_said(tmp_path):
    """A failed point whose failure.json is a link planted in its job directory: nothing is written
    through the link, and the point's record (the driver's message) says the failure could not be
    recorded, not silently nothing."""
    from granchain.campaigns.point_task import run_point

    job, outside = tmp_path / "job", tmp_path / "outside.json"
    job.mkdir()
    outside.write_text("untouched")
    (job / wsp.FAILURE).symlink_to(outside)
    code = dict(wsp.code_version("reference"), source="0" * 16)  # refused: fails before any run
    record = run_point({"job_dir": str(job), "backend": "reference", "code": code, "scene": {}, "source": None})
    assert record["status"] == "failed"
    assert "install the same granchain on every worker" in record["message"]
    assert f"its {wsp.FAILURE} could not be written" in record["message"], record["message"]
    assert outside.read_text() == "untouched"
    assert (job / wsp.FAILURE).is_symlink()


# --------------------------------------------------------------- damaged files: incomplete or one line


def _summary_garbage(job, other):
    (job / "run" / "summary.json").write_text("garbage{")


def _summary_of_another_point(job, other):
    for name in ("summary.json", "scene.toml"):
        shutil.copy(other / "run" / name, job / "run" / name)


def _summary_not_its_scene(job, other):
    shutil.copy(other / "run" / "summary.json", job / "run" / "summary.json")


def _summary_a_list(job, other):
    (job / "run" / "summary.json").write_text("[1, 2]")


def _scene_damaged(job, other):
    (job / "run" / "scene.toml").write_text("[chain\n")


@pytest.mark.parametrize(
    "damage", [_summary_garbage, _summary_of_another_point, _summary_not_its_scene, _summary_a_list, _scene_damaged]
)
def test_a_point_with_a_damaged_or_mismatched_run_is_incomplete(ws, capsys, damage):
    job, other = jobs(ws)
    damage(job, other)
    assert wsp.job_state(job) == "missing"
    assert wsp.job_state(other) == "done"
    assert main(["campaign", "table", str(ws), "--csv"]) == 0
    assert "missing" in capsys.readouterr().out


def test_a_point_with_a_mismatched_run_runs_again(made, ws, capsys):
    job, other = jobs(ws)
    _summary_of_another_point(job, other)
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1"]) == 0
    assert "2 run now" in capsys.readouterr().out  # the job's two points (a free parameter's two values)
    assert wsp.job_state(job) == "done"
    assert (job / "run" / "scene.toml").read_text() != (other / "run" / "scene.toml").read_text()


def test_a_corrupt_statepoint_is_set_aside_and_its_point_runs_again(made, ws, capsys):
    job = jobs(ws)[0]
    (job / wsp.STATEPOINT).write_text("{corrupt")
    assert main(["campaign", "table", str(ws), "--csv"]) == 0  # read without signac: no JobsCorruptedError
    assert "missing" in capsys.readouterr().out
    assert main(["campaign", "run", str(made[0]), "--out", str(ws), "--workers", "1"]) == 0
    assert "damaged state point" in capsys.readouterr().err
    assert (ws / wsp.DAMAGED / job.name).is_dir()
    assert wsp.job_state(job) == "done"


@pytest.mark.parametrize(
    ("record", "said"),
    [
        ("[" * 100_000 + "]" * 100_000, "no readable campaign.json"),
        ('{"points": [{"params": {}, "job": "../../../etc"}], "code": {}}', "is not a signac job id"),
        ('{"points": "x", "code": {}}', "no list of points"),
        ("[1]", "not a JSON object"),
    ],
)
def test_a_damaged_campaign_json_is_one_error_line(ws, capsys, record, said):
    (ws / wsp.RECORD).write_text(record)
    assert main(["campaign", "table", str(ws)]) == 2
    assert said in one_error_line(capsys)


def test_a_damaged_signac_config_is_one_error_line(made, ws, capsys):
    (ws / ".signac" / "config").write_text("garbage [[[\n")
    assert main(["campaign", "table", str(ws)]) == 2
    assert ".signac/config" in one_error_line(capsys)


_WS_FILES = ["campaign.json", "run/summary.json", "run/scene.toml", "run/histories.csv", "task.json",
             wsp.STATEPOINT, "failure.json", ".signac/config"]  # fmt: skip


_DAMAGES = st.lists(
    st.tuples(
        st.sampled_from(_WS_FILES),
        st.integers(0, 3),
        st.one_of(
            st.binary(max_size=64),
            st.sampled_from(['{"observables": 5}', "null", "[]", '{"warnings": 3}', '{"message": [1]}']),
        ),
    ),
    min_size=1,
    max_size=3,
)


def _damaged_copy(made, tmp_path_factory, damages) -> Path:
    w = tmp_path_factory.mktemp("h") / "ws"
    shutil.copytree(made[1], w)
    for name, how, junk in damages:
        p = w / name if not name.startswith(("run/", "task", "signac", "failure")) else jobs(w)[0] / name
        data = p.read_bytes() if p.is_file() else b""
        junk = junk if isinstance(junk, bytes) else junk.encode()
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_bytes([data[: len(data) // 2], junk, data + junk, b""][how])
    return w


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damages=_DAMAGES)
def test_campaign_plot_of_any_damaged_workspace_is_a_figure_or_one_error_line(made, tmp_path_factory, damages):
    w = _damaged_copy(made, tmp_path_factory, damages)
    assert main(["campaign", "plot", str(w), *PLOT, "--out", str(w.parent / "fig")]) in (0, 2)
    shutil.rmtree(w.parent)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(damages=_DAMAGES)
def test_campaign_table_of_any_damaged_workspace_is_a_table_or_one_error_line(made, tmp_path_factory, damages):
    """Whatever is cut, replaced or appended in its files: campaign table prints a table (the damaged
    points incomplete) or one error line; a bug's exception propagates out of main and fails this."""
    w = _damaged_copy(made, tmp_path_factory, damages)
    assert main(["campaign", "table", str(w), "--csv"]) in (0, 2)
    shutil.rmtree(w.parent)


# ------------------------------------------------------------------- text that drives or breaks


def test_campaign_table_escapes_control_characters(ws, capsys):
    assert main(["campaign", "table", str(ws)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out
    assert "\x07" not in out
    assert "a\\x1b]0;pwned\\x07\\x1b[2J" in out


def test_a_mathtext_title_is_drawn_as_written(ws, capsys):
    record = json.loads((ws / wsp.RECORD).read_text())
    record["title"] = "$\\frac{1}{$"
    (ws / wsp.RECORD).write_text(json.dumps(record))
    assert main(["campaign", "plot", str(ws), *PLOT, "--format", "png,svg,pdf"]) == 0
    svg = (ws / "plots" / f"{STEM}.svg").read_text()
    assert "frac" in svg or "\\" in svg  # the text itself, not a formula


@pytest.mark.parametrize(
    "expression",
    ["(" * 200 + "x" + ")" * 200, " + ".join(["x"] * 1000), "-" * 500 + "x", "2 ** " * 400 + "x", "x" * 20000],
)
def test_an_expression_that_would_recurse_too_deep_is_one_message(expression):
    text = campaign_text(
        '"loading.amplitude" = [10.0]\nx = [1e-6]\n', extra=f'[derive]\n"loading.duration" = "{expression}"\n'
    )
    with pytest.raises(CampaignError, match=r"\[derive\] 'loading.duration'.*(deep|characters)"):
        parse_campaign(text)


# --------------------------------------------------------------------- full and read-only disks


def _mount_tmpfs(d: Path, options: str) -> None:
    if os.geteuid() != 0:
        pytest.skip("mounting a small or read-only filesystem needs root")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(d)], capture_output=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.decode().strip()}")


def test_a_full_disk_in_campaign_run_is_one_error_line_and_leaves_no_temporary_file(tmp_path, capsys):
    d = tmp_path / "tiny"
    d.mkdir()
    _mount_tmpfs(d, "size=150k")
    try:
        f = tmp_path / "c.toml"
        f.write_text(campaign_text('"loading.amplitude" = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0]\n'))
        rc = main(["campaign", "run", str(f), "--out", str(d / "ws"), "--workers", "1"])
        out, err = capsys.readouterr()
        assert "Traceback (most recent call last)" not in err
        if rc == 2:  # the workspace's own files could not be written
            assert err.strip().splitlines()[-1].startswith("granchain: error: ")
            assert "No space left" in err
        else:  # the points that found the disk full failed, each with its message, in the table
            assert rc == 1
            assert "failed" in out
        left = [p for p in d.rglob("*") if ".tmp" in p.name or ".partial-" in p.name]
        assert not left, left
    finally:
        subprocess.run(["umount", str(d)], check=False)


def test_a_read_only_workspace_is_one_error_line(made, tmp_path, capsys):
    d = tmp_path / "ro"
    d.mkdir()
    _mount_tmpfs(d, "size=20m")
    try:
        shutil.copytree(made[1], d / "ws")
        subprocess.run(["mount", "-o", "remount,ro", str(d)], check=True)
        # reading it needs no writing: --csv writes nothing there, without it the table is printed, not saved
        assert main(["campaign", "table", str(d / "ws"), "--csv"]) == 0
        assert capsys.readouterr().err == ""
        assert main(["campaign", "table", str(d / "ws")]) == 0
        out, err = capsys.readouterr()
        assert "done" in out
        assert err.startswith("granchain: warning: "), err
        assert "Read-only" in err, err
        assert "printed, not saved" in err, err
        for args in (
            ["campaign", "plot", str(d / "ws"), *PLOT],
            ["campaign", "run", str(made[0]), "--out", str(d / "ws"), "--workers", "1"],
        ):
            assert main(args) == 2, args
            line = one_error_line(capsys)
            assert "Read-only" in line or "not writable" in line, line
    finally:
        subprocess.run(["umount", str(d)], check=False)


# ------------------------------------------------- a campaign file's base: read only inside its folder

SECRET = "SECRET-LINE-OF-AN-OUTSIDE-FILE"
_PARTS = ["..", ".", "sub", "linkdir", "sublink", "inside.toml", "inner.toml", "valid.toml", "secret.toml"]
_PARTS += ["link_out.toml", "link_in.toml", "link_dev", "outside", "camp", "default"]


@pytest.fixture(scope="module")
def folders(tmp_path_factory) -> tuple[Path, Path]:
    """(the campaign's folder, a folder beside it): scenes and links inside and out."""
    root = tmp_path_factory.mktemp("basepaths")
    camp, out = root / "camp", root / "outside"
    (camp / "sub").mkdir(parents=True)
    out.mkdir()
    (camp / "inside.toml").write_text(SCENE)
    (camp / "sub" / "inner.toml").write_text(SCENE)
    (out / "valid.toml").write_text(SCENE)
    (out / "secret.toml").write_text(f"{SECRET} = = 1\n")
    os.symlink(out / "valid.toml", camp / "link_out.toml")
    os.symlink("inside.toml", camp / "link_in.toml")
    os.symlink("/dev/zero", camp / "link_dev")
    os.symlink(out, camp / "linkdir")
    os.symlink("sub", camp / "sublink")
    return camp, out


def _base_campaign(base: str) -> str:
    return f'[campaign]\nbase = {json.dumps(base)}\nbackend = "reference"\n[vary]\n"loading.amplitude" = [10.0]\n'


def _stays_inside(camp: Path, base: str) -> bool:
    """Whether the name reaches a file inside camp by its letters and with no link among its parts."""
    if os.path.isabs(base) or ".." in Path(base).parts:
        return False
    here = camp
    for part in Path(base).parts:
        here = here / part
        if here.is_symlink():
            return False
    return True


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    parts=st.lists(st.sampled_from(_PARTS), min_size=1, max_size=4),
    anchor=st.sampled_from(["", "camp", "outside", "/"]),
)
def test_a_campaign_files_base_is_read_only_inside_its_folder(folders, parts, anchor):
    """Any base name (relative with '..', absolute, through links in or out of the folder) is read
    only when it names a file inside the campaign's folder with no '..' and no link among its parts;
    otherwise it is refused naming base and the fix, and no outside file's content is shown."""
    camp, out = folders
    rel = "/".join(parts)
    base = {"": rel, "camp": f"{camp}/{rel}", "outside": f"{out}/{rel}", "/": f"/{rel}"}[anchor]
    try:
        c = parse_campaign(_base_campaign(base), source="c.toml", base_dir=camp)
    except CampaignError as e:
        msg = str(e)
        assert msg.startswith(f"c.toml: [campaign] base = {base!r}"), msg
        assert SECRET not in msg
        if not _stays_inside(camp, base) and base != "default":
            assert "inside its folder" in msg, msg
        return
    if base == "default":  # a bundled scene's name
        assert c.base_source == "default"
        return
    assert _stays_inside(camp, base), base
    assert Path(os.path.realpath(c.base_source)).is_relative_to(os.path.realpath(camp))


@pytest.mark.parametrize("base", ["../outside/valid.toml", "OUT/valid.toml", "link_out.toml", "linkdir/valid.toml"])
def test_campaign_run_refuses_a_base_outside_its_folder_before_anything_runs(folders, tmp_path, capsys, base):
    camp, out = folders
    f = camp / f"c-{tmp_path.name}.toml"
    f.write_text(_base_campaign(base.replace("OUT", str(out))))
    try:
        assert main(["campaign", "run", str(f), "--out", str(tmp_path / "ws"), "--workers", "1"]) == 2
    finally:
        f.unlink()
    line = one_error_line(capsys)
    assert "[campaign] base = " in line, line
    assert "put the scene file beside the campaign file" in line, line
    assert not (tmp_path / "ws").exists()


def test_a_campaign_files_base_beside_or_below_it_and_a_bundled_name_are_read(folders):
    camp, _ = folders
    for base, source in [
        ("inside.toml", camp / "inside.toml"),
        ("sub/inner.toml", camp / "sub" / "inner.toml"),
        ("./sub/inner.toml", camp / "sub" / "inner.toml"),
    ]:
        assert parse_campaign(_base_campaign(base), source="c.toml", base_dir=camp).base_source == str(source)
    assert parse_campaign(_base_campaign("default"), source="c.toml", base_dir=camp).base_source == "default"
