"""A frequency sweep's campaign figure shades the predicted pass bands and gaps (physics.bands for the
points' chain at its precompression) behind the measured transmission, with a legend entry each (issue
46 items 3-4): the shaded spans' edges are the band structure's, read from the drawn artists."""

from __future__ import annotations

import math

import numpy as np
import pytest
from matplotlib.patches import Rectangle

from granchain.campaigns.plot import BAND_COLOUR, GAP_COLOUR, campaign_figure
from granchain.campaigns.run import run_campaign
from granchain.campaigns.spec import parse_campaign
from granchain.physics.bands import dimer_edges

from .figure_checks import check_figure

STEEL, PTFE = (193e9, 0.30, 8000.0), (1.46e9, 0.46, 2200.0)  # the scene's stainless-steel-316 and ptfe
RADIUS, F0 = 2.38e-3, 10.0

SWEEP = f"""[campaign]
title = "Transmission spectrum of a precompressed steel/PTFE dimer through its band gap (a long title)"
backend = "reference"
method = "rk4"
error_estimate = false
[vary]
"loading.frequency" = [5000.0, 12000.0, 19000.0]
[scene.chain]
beads = 6
radius = {RADIUS}
material = ["stainless-steel-316", "ptfe", "stainless-steel-316", "ptfe", "stainless-steel-316", "ptfe"]
[scene.contact]
law = "hertz"
[scene.loading]
kind = "harmonic"
amplitude = 0.01
frequency = 5000.0
cycles = 8
ramp = 2
[scene.precompression]
force = {F0}
[scene.run]
end_time = "auto"
timestep = 5e-7
"""


def edges_hz() -> tuple[float, float, float]:
    """The dimer's closed-form edges (Hz), its Hertz spring written out: 1/E* = sum (1 - nu^2) / E,
    k = (3/2) K^(2/3) F0^(1/3), K = (4/3) E* sqrt(R / 2)."""
    e_star = 1 / sum((1 - nu**2) / e for e, nu, _ in (STEEL, PTFE))
    k = 1.5 * (4 / 3 * e_star * math.sqrt(RADIUS / 2)) ** (2 / 3) * F0 ** (1 / 3)
    m1, m2 = (rho * 4 / 3 * math.pi * RADIUS**3 for _, _, rho in (STEEL, PTFE))
    return tuple(w / (2 * math.pi) for w in dimer_edges(k, m1, m2))


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    ws = tmp_path_factory.mktemp("sweep") / "ws"
    run_campaign(parse_campaign(SWEEP), ws, workers=1)
    return ws


def spans(ax, colour) -> list[tuple[float, float]]:
    """The (left, right) data x of the axes' shaded spans of one colour."""
    from matplotlib.colors import to_rgba

    want = to_rgba(colour, 0.18)
    out = [
        (p.get_x(), p.get_x() + p.get_width())
        for p in ax.patches
        if isinstance(p, Rectangle) and np.allclose(p.get_facecolor(), want)
    ]
    return sorted(out)


@pytest.mark.slow  # 3 short runs on a Dask worker: about 8 s
def test_a_frequency_sweeps_figure_shades_the_predicted_bands_at_their_edges(sweep):
    fig, data = campaign_figure(sweep, "loading.frequency", "transmission_db")
    ax = fig.axes[0]
    acoustic_top, optical_bottom, optical_top = edges_hz()
    lo, hi = ax.get_xlim()
    bands, gaps = spans(ax, BAND_COLOUR), spans(ax, GAP_COLOUR)
    assert len(bands) == 2
    assert len(gaps) == 2
    # the acoustic band from the axis' left end, the optical band, the gap between, the stop band above
    assert bands[0] == pytest.approx((lo, acoustic_top), rel=1e-9)
    assert bands[1] == pytest.approx((optical_bottom, optical_top), rel=1e-9)
    assert gaps[0] == pytest.approx((acoustic_top, optical_bottom), rel=1e-9)
    assert gaps[1] == pytest.approx((optical_top, hi), rel=1e-9)
    assert all(p.get_zorder() < line.get_zorder() for p in ax.patches for line in ax.lines)
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("pass band (predicted, linearised at F0 = 10 N") for t in legend)
    assert any(t.startswith("band gap (predicted") for t in legend)
    assert len(data) == 3
    check_figure(fig)


@pytest.mark.slow
def test_a_sweep_over_another_key_has_no_bands(sweep):
    fig, _ = campaign_figure(sweep, "loading.frequency", "transmission_db")
    assert spans(fig.axes[0], BAND_COLOUR)  # (the same workspace: over frequency it has them)
    fig, _ = campaign_figure(sweep, "transmission", "transmission_db")
    assert not spans(fig.axes[0], BAND_COLOUR)
