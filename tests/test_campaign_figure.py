"""The campaign plot's axes and legend name each column with its unit, and it says which points it leaves
out for lacking a value (issue 43 item 3); its text stays inside the canvas."""

from __future__ import annotations

import textwrap

import pytest

from granchain.campaigns.plot import axis_label, campaign_figure, column_unit
from granchain.campaigns.run import run_campaign
from granchain.campaigns.spec import parse_campaign

from .conftest import CAMPAIGN_SCENE
from .figure_checks import check_figure

#: two step loads and two end times; no contact's peak is complete by 2e-5 s, so those two points are
#: done without a max_peak_force
BODY = '[vary]\n"loading.amplitude" = [10.0, 40.0]\n"run.end_time" = [2e-5, 1e-4]\n'


@pytest.fixture(scope="module")
def workspace(tmp_path_factory):
    text = (
        '[campaign]\nbackend = "reference"\nmethod = "verlet"\nerror_estimate = false\n\n'
        f"{textwrap.dedent(BODY)}\n[scene]\n" + CAMPAIGN_SCENE.replace("\n[", "\n[scene.")
    )
    ws = tmp_path_factory.mktemp("campaign") / "ws"
    run_campaign(parse_campaign(text), ws, workers=1)
    return ws


@pytest.mark.parametrize(
    ("column", "unit"),
    [
        ("loading.amplitude", "N"),
        ("loading.impulse", "N s"),
        ("chain.material.density", "kg/m^3"),
        ("leading_peak_force", "N"),
        ("leading_peak_force_error", "N"),
        ("wave_speed", "m/s"),
        ("leading_pulse_decay_length", "contacts"),
        ("wall_time", "s"),
        ("pulses", "pulses"),
    ],
)
def test_columns_have_their_units(column, unit):
    assert column_unit(column) == unit
    assert axis_label(column) == f"{column} ({unit})"


def test_a_search_transition_has_the_searched_keys_unit():
    record = {"search": {"key": "loading.duration"}}
    assert column_unit("transition", record) == "s"
    assert column_unit("loading.duration_low", record) == "s"


def test_the_campaign_figure_has_units_and_says_what_it_leaves_out(workspace):
    fig, data = campaign_figure(workspace, "loading.amplitude", "max_peak_force", hue="run.end_time")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "loading.amplitude (N)"
    assert ax.get_ylabel() == "max_peak_force (N)"
    assert len(data) == 2  # the two points run long enough for a complete peak
    note = " ".join(t.get_text() for t in fig.texts)
    assert "2 of 4 points not drawn, without a value of max_peak_force (2 done, no value)" in note
    check_figure(fig)


def test_every_point_drawn_no_note(workspace):
    fig, data = campaign_figure(workspace, "loading.amplitude", "steps", hue="run.end_time")
    assert fig.axes[0].get_ylabel() == "steps (steps)"
    assert len(data) == 4
    assert not fig.texts
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend == ["run.end_time = 2e-05 s", "run.end_time = 0.0001 s"]
    check_figure(fig)
