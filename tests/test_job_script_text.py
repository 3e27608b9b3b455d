"""Text that reaches a job script (issue 40, item 3): any value with a control character (or, where a
directive takes it, whitespace) is refused with one message naming it, before any script is written;
an allowed value gives exactly the expected directive lines, no line more."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from granchain.campaigns import cluster as cl
from granchain.workflows import submit as sm

#: control characters (C0, DEL, C1) and the line and paragraph separators
CONTROL = st.one_of(
    st.characters(min_codepoint=0, max_codepoint=31),
    st.characters(min_codepoint=127, max_codepoint=159),
    st.sampled_from(["\u2028", "\u2029"]),
)
VALID = {
    "queue": "debug",
    "account": "proj",
    "walltime": "02:00:00",
    "memory": "4GB",
    "interface": "lo",
    "log_directory": "/shared/ws/jobs",
}


@st.composite
def with_control(draw, valid: str, allowed: str = "") -> str:
    """A valid value with a control character (not one of `allowed`) put anywhere in it (the ends included)."""
    at = draw(st.integers(0, len(valid)))
    return valid[:at] + draw(CONTROL.filter(lambda c: c not in allowed)) + valid[at:]


@given(field=st.sampled_from(sorted(VALID)), data=st.data())
def test_cluster_settings_refuse_any_control_character(field, data):
    value = data.draw(with_control(VALID[field]))
    s = cl.ClusterSettings(kind="slurm", **{**VALID, field: value})
    with pytest.raises(cl.ClusterError, match="output directory" if field == "log_directory" else field):
        cl.check(s)


@given(data=st.data())
def test_a_prologue_line_with_a_control_character_is_refused(data):
    line = data.draw(with_control("source /shared/venv/bin/activate", allowed="\t"))  # a tab is a shell blank
    with pytest.raises(cl.ClusterError, match="--prologue"):
        cl.check(cl.ClusterSettings(kind="slurm", prologue=(line,)))


@given(white=st.sampled_from([" ", "\u00a0", "\u3000"]), at=st.integers(0, 15))
def test_the_jobs_output_directory_refuses_whitespace(white, at):
    path = "/shared/ws/jobs"
    with pytest.raises(cl.ClusterError, match="whitespace"):
        cl.check_log_directory(path[:at] + white + path[at:])


@given(field=st.sampled_from(["queue", "account", "walltime", "memory"]), data=st.data())
def test_submit_settings_refuse_any_control_character(field, data):
    values = {"queue": "debug", "account": "proj", "walltime": "02:00:00", "memory": "4G"}
    values[field] = data.draw(with_control(values[field]))
    with pytest.raises(sm.SubmitError, match=f"--{field}"):
        sm.check_settings(1, **values)


def _fake_sbatch(tmp_path: Path, monkeypatch) -> None:
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir(exist_ok=True)
    (bin_dir / "sbatch").write_text("#!/bin/sh\necho 4242\n")
    (bin_dir / "sbatch").chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:/usr/bin:/bin")


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_submit_refuses_an_out_directory_with_a_control_character_before_writing(tmp_path, monkeypatch, data):
    r"""`granchain submit --out $'dir\ntouch X\n'` wrote `touch X` on a line of its own in job.sh."""
    from granchain.scene import load_scene

    _fake_sbatch(tmp_path, monkeypatch)
    name = data.draw(with_control("run-dir"))
    out = tmp_path / "runs" / name
    with pytest.raises(sm.SubmitError, match="--out"):
        sm.submit(load_scene("default"), out)
    assert not out.exists()


NAMES = st.from_regex(sm.NAME_PATTERN, fullmatch=True)
WALLTIMES = st.from_regex(sm.WALLTIME_PATTERN, fullmatch=True)
MEMORIES = st.from_regex(sm.MEMORY_PATTERN, fullmatch=True)
#: a directory's path as submit takes it: any printable text but a slash (spaces and quotes too)
DIRS = st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zl", "Zp"), blacklist_characters="/\x00"), min_size=1)


@settings(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(queue=st.none() | NAMES, account=st.none() | NAMES, walltime=WALLTIMES, memory=st.none() | MEMORIES, name=DIRS)
def test_submit_job_script_lines_are_exactly_the_directives(monkeypatch, queue, account, walltime, memory, name):
    """For allowed values, job.sh's lines are the shebang, exactly the expected #SBATCH lines, and the
    fixed body: no line more, the directory only in its cd line and its collect comment."""
    from hypothesis import assume

    assume(name not in (".", ".."))
    monkeypatch.setattr("granchain.lammps.build.build_plugin", lambda: Path("/cache/granchainplugin.so"))
    monkeypatch.setattr(sm, "lammps_commands", lambda: (Path("/venv/bin/lmp"), Path("/venv/bin/mpirun")))
    sm.check_settings(2, queue, account, walltime, memory)
    d = Path("/shared") / name
    lines = sm.job_script(d, 2, walltime, queue, account, memory, "granchain-run").splitlines()
    directives = ["#SBATCH -J granchain-run", "#SBATCH -n 2", f"#SBATCH -t {walltime}", "#SBATCH -o slurm-%j.out"]
    directives += [f"#SBATCH -p {queue}"] * bool(queue) + [f"#SBATCH -A {account}"] * bool(account)
    directives += [f"#SBATCH --mem={memory}"] * bool(memory)
    assert lines[0] == "#!/usr/bin/env bash"
    assert [line for line in lines if line.startswith("#SBATCH")] == directives
    assert lines[1 : 1 + len(directives)] == directives
    assert len(lines) == 1 + len(directives) + 9  # the body's nine lines, whatever the values


@settings(max_examples=30, deadline=None)  # the first example imports dask_jobqueue
@given(
    queue=st.none() | NAMES,
    account=st.none() | NAMES,
    walltime=WALLTIMES.filter(lambda w: cl.ClusterSettings(walltime=w).walltime_seconds() >= 60),
    memory=st.none() | st.from_regex(r"[1-9][0-9]{0,2} ?(MB|GB)", fullmatch=True),
    kind=st.sampled_from(["slurm", "pbs"]),
)
def test_worker_job_script_header_is_exactly_the_directives(tmp_path_factory, queue, account, walltime, memory, kind):
    """dask-jobqueue's worker job script for allowed settings: every header line is a directive of
    the queue's, the output directory's two directives hold it whole, and no other line appears."""
    s = cl.check(cl.ClusterSettings(kind=kind, queue=queue, account=account, walltime=walltime, memory=memory))
    logs = tmp_path_factory.mktemp("ws") / "jobs"
    jc = cl.JobCluster(s, 1, logs)
    cls = jc._cluster_class().job_cls
    script = cls(scheduler="tls://127.0.0.1:1", name="granchain-worker-0", **jc.job_options()).job_script()
    lines = [line for line in script.splitlines() if line]
    mark = "#SBATCH" if kind == "slurm" else "#PBS"
    header = [line for line in lines[1:] if line.startswith("#")]
    assert lines[0] == "#!/usr/bin/env bash"
    assert all(line.startswith(mark + " ") for line in header), header
    assert lines[1 : 1 + len(header)] == header
    body = lines[1 + len(header) :]
    assert body[:-1] == ["export GRANCHAIN_QUIET=1", "export HYDRA_BOOTSTRAP=fork"]
    assert "distributed.cli.dask_worker" in body[-1]
    outputs = [line.split()[2] for line in header if line.split()[1] in ("-e", "-o")]
    assert len(outputs) == 2
    assert all(o.startswith(f"{logs}/") for o in outputs)
    if walltime and kind == "slurm":
        assert f"#SBATCH -t {walltime}" in header
    if queue:
        assert f"{mark} -q {queue}" in header or f"{mark} -p {queue}" in header
