"""The Pareto figure's axes (issue 45): each objective's axis says its unit (the observable's, from
the registry), and an objective that is an expression of observables says its unit is unknown rather
than printing a bare expression as if it were dimensionless."""

from __future__ import annotations

import pandas as pd
from hypothesis import given, settings
from hypothesis import strategies as st

from granchain.campaigns.plot import pareto_figure
from granchain.postprocess.observables import units as observable_units

UNITS = observable_units()
NAMES = sorted(UNITS)


def _trials(n: int) -> pd.DataFrame:
    rows = [
        {
            "trial": k,
            "state": "complete",
            "objective": float(k),
            "objective_error": 0.1,
            "objective_2": float(n - k),
            "objective_2_error": 0.1,
            "job": f"{k:032x}",
        }
        for k in range(n)
    ]
    return pd.DataFrame(rows)


@settings(max_examples=25, deadline=None)
@given(first=st.sampled_from(NAMES), second=st.sampled_from(NAMES), n=st.integers(1, 6))
def test_each_pareto_axis_names_its_objective_and_unit(first, second, n):
    record = {
        "optimize": {"objective": first, "objective_2": second, "direction": "minimize", "direction_2": "minimize"}
    }
    fig, front = pareto_figure(record, _trials(n))
    ax = fig.axes[0]
    assert ax.get_xlabel() == f"{first} ({UNITS[first]})"
    assert ax.get_ylabel() == f"{second} ({UNITS[second]})"
    assert len(front) == n  # minimising x and n - x: no design dominates another


def test_an_expression_objective_says_its_unit_is_unknown():
    record = {
        "optimize": {
            "objective": "wall_max_force / 2",
            "objective_2": "leading_peak_force",
            "direction": "minimize",
            "direction_2": "maximize",
        }
    }
    fig, _ = pareto_figure(record, _trials(3))
    ax = fig.axes[0]
    assert ax.get_xlabel() == "wall_max_force / 2 (unit unknown)"
    assert ax.get_ylabel() == f"leading_peak_force ({UNITS['leading_peak_force']})"
