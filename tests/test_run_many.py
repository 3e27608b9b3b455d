"""granchain.run_many: an ensemble's results are its scenes' single runs (every observable, error bar
and status), in the scenes' order; bad input is refused before anything runs; a second run over the
same run directories reads them back."""

from __future__ import annotations

import warnings
from unittest import mock

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import granchain
from granchain import progress
from granchain.exceptions import GranchainError, UsageError
from granchain.lammps import server

from .scenegen import brass_impulse_text, figure_scene_texts

#: summary.json keys measured on the wall clock (tools/check_identical.py's CLOCK_KEYS), and a LAMMPS
#: run's count on its kept instance: not computed, so not compared
CLOCK_KEYS = {"wall_time", "price", "provenance", "companion_wall_time", "check_wall_time", "overhead"}
CLOCK_EXTRA = {"startup_time", "process_time", "plugin_build_time", "loop_time", "output_time", "read_time"}


def computed(summary: dict) -> dict:
    """A summary without what the wall clock measured."""

    def strip(d):
        if isinstance(d, dict):
            return {k: strip(v) for k, v in d.items() if k not in CLOCK_KEYS}
        if isinstance(d, list):
            return [strip(v) for v in d]
        return d

    out = strip(dict(summary))
    if "extra" in out:
        out["extra"] = {k: v for k, v in out["extra"].items() if k not in CLOCK_EXTRA and k != "instance_run"}
    return out


def assert_same_results(many, single) -> None:
    """Every computed number of each pair the same: summary (observables, error bars, statuses) and peaks."""
    assert len(many) == len(single)
    for i, (m, s) in enumerate(zip(many, single, strict=True)):
        assert computed(m.summary) == computed(s.summary), f"scene {i}"
        pd.testing.assert_frame_equal(m.peaks, s.peaks, check_exact=True)


def ensemble(texts: list[str], picks: list[int]) -> list:
    """The scenes of texts in the order picks gives (a scene may come twice, in another group's turn)."""
    scenes = [granchain.parse_scene(t, source=f"generated-{i}.toml") for i, t in enumerate(texts)]
    return [scenes[i % len(scenes)] for i in picks]


def run_both(scenes, backend: str, **kw):
    """(run_many's results, each scene's single run), warnings silenced (both make the same ones)."""
    with progress.quiet(), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        single = [granchain.run(s, backend=backend, **kw) for s in scenes]
        many = granchain.run_many(scenes, backend=backend, **kw)
    return many, single


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(
    texts=st.lists(figure_scene_texts(max_steps=1500), min_size=1, max_size=3),
    picks=st.lists(st.integers(0, 2), min_size=1, max_size=4),
    bars=st.sampled_from([True, False]),
)
def test_run_many_is_each_scene_run_singly_on_the_reference(texts, picks, bars):
    many, single = run_both(ensemble(texts, picks), "reference", error_estimate=bars)
    assert_same_results(many, single)


@pytest.mark.slow
@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(
    texts=st.lists(figure_scene_texts(max_steps=5000), min_size=1, max_size=3),
    picks=st.lists(st.integers(0, 2), min_size=1, max_size=4),
)
def test_run_many_is_each_scene_run_singly_on_lammps(texts, picks):
    scenes = ensemble(texts, picks)
    starts = []
    real_start = server.LammpsServer.start

    def counted(self, plugin=None):
        starts.append(len(starts))
        return real_start(self, plugin)

    with mock.patch.object(server.LammpsServer, "start", counted):
        with progress.quiet(), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            single = [granchain.run(s, backend="lammps", error_estimate=True) for s in scenes]
            started_single = len(starts)
            many = granchain.run_many(scenes, backend="lammps", error_estimate=True)
    assert_same_results(many, single)
    # the shared work: the ensemble's runs go to one kept LAMMPS process, where each single run starts
    # its own (a LAMMPS error, a coarse companion's broken invariant, ends a child: the next run starts one)
    started_many = len(starts) - started_single
    assert started_many <= started_single
    if started_single == len(scenes):  # no child ended early: one child served the whole ensemble
        assert started_many == 1


def plain(n: int) -> list:
    return [granchain.parse_scene(brass_impulse_text(12, 0.01 * (i + 1)), source=f"p{i}.toml") for i in range(n)]


@pytest.mark.parametrize(
    ("scenes", "match"),
    [
        (None, "run_many takes a list of scenes"),
        ("default", "run_many takes a list of scenes"),
        ([], "scenes is empty"),
        ([3.0], r"scenes\[0\] = float: each scene must be a granchain Scene"),
    ],
)
def test_run_many_refuses_what_is_not_a_list_of_scenes(scenes, match):
    with pytest.raises(UsageError, match=match):
        granchain.run_many(scenes)


def test_run_many_refuses_out_not_one_per_scene(tmp_path):
    with pytest.raises(UsageError, match="out = 5: a directory"):
        granchain.run_many(plain(2), out=5)
    with pytest.raises(UsageError, match="out: 1 run directories for 2 scenes"):
        granchain.run_many(plain(2), out=[tmp_path / "a"])
    with pytest.raises(UsageError, match=r"out\[1\] = .*is out\[0\] too"):
        granchain.run_many(plain(2), out=[tmp_path / "a", tmp_path / "a"])


def test_a_bad_scene_stops_the_ensemble_before_its_first_run(tmp_path, monkeypatch):
    monkeypatch.setenv("GRANCHAIN_QUIET", "1")
    scenes = plain(3)
    scenes[2] = scenes[2].replace({"run.timestep": 1e-3, "run.end_time": 1e-2})  # far above the stability limit
    with pytest.raises(GranchainError, match="stability limit") as info:
        granchain.run_many(scenes, out=tmp_path / "ens")
    assert any("scenes[2] of run_many" in n for n in info.value.__notes__)
    assert not (tmp_path / "ens" / "00000").exists()  # nothing ran


def test_run_many_again_reads_its_run_directories_back(tmp_path, monkeypatch):
    monkeypatch.setenv("GRANCHAIN_QUIET", "1")
    scenes, out = plain(3), tmp_path / "ens"
    first = granchain.run_many(scenes, error_estimate=True, out=out)
    written = {p: p.stat().st_mtime_ns for p in out.glob("*/summary.json")}
    again = granchain.run_many(scenes, error_estimate=True, out=out)
    assert [r.path for r in again] == [out / f"{i:05d}" for i in range(3)]
    assert {p: p.stat().st_mtime_ns for p in out.glob("*/summary.json")} == written  # none run again
    assert_same_results(again, first)
    # other error bars are another run: refused over a directory it did not write, unless overwrite
    with pytest.raises(GranchainError, match="exists") as info:
        granchain.run_many(scenes, error_estimate=False, out=out)
    assert any("scenes[0] of run_many" in n for n in info.value.__notes__)
    redone = granchain.run_many(scenes, error_estimate=False, out=out, overwrite=True)
    assert all(r.summary["errors"] is None for r in redone)
