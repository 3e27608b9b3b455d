"""A checked wave speed whose step error is withheld keeps the fit's spread as its bar where the step's
error, on either reading of the failed check, is far below it."""

import numpy as np

from granchain.richardson import ErrorBars, checked, richardson
from granchain.workflows.error_estimates import FIT_DOMINATES, _observable_error, _withheld_step_bound

WITHHELD = "unreliable: the run at dt / 2 puts the error at 4.54e-05-6.49e-05, not within 3x of this estimate"


def _withheld_bars() -> ErrorBars:
    return ErrorBars(np.array([np.nan]), np.array([WITHHELD], dtype=object), np.array([np.nan]))


def test_fit_spread_kept_when_the_withheld_step_error_is_negligible():
    # the custom dimer's figures (RK4, --error-estimate checked): 149.881 m/s, fit's stderr 0.39 m/s,
    # runs at dt / 2, dt and 2 dt a few 1e-5 m/s apart
    finer, fine, coarse = 149.88145, 149.88140, 149.88126
    bound = _withheld_step_bound(finer, fine, coarse, 2.5)
    assert bound is not None
    assert bound < 0.39 / FIT_DOMINATES
    out = _observable_error("wave_speed", fine, _withheld_bars(), {"wave_speed_stderr": 0.39}, bound)
    assert out["error"] == 0.39
    assert out["step_error"] is None
    assert out["step_error_bound"] == bound
    assert "fit's spread alone" in out["status"]
    assert "withheld" in out["status"]


def test_no_bar_when_the_withheld_step_error_may_matter():
    bound = _withheld_step_bound(149.9, 149.8, 149.5, 2.5)  # differences of 0.1-0.3 m/s
    assert bound > 0.39 / FIT_DOMINATES
    out = _observable_error("wave_speed", 149.8, _withheld_bars(), {"wave_speed_stderr": 0.39}, bound)
    assert out["error"] is None
    assert out["status"].startswith("unreliable")
    assert _withheld_step_bound(None, 149.8, 149.5, 2.5) is None


def test_bound_covers_both_readings_of_the_check():
    # values at 4 dt, 2 dt, dt, dt / 2 whose order changes below dt: the check withholds the estimate
    q4, q2, q1, qh = 1.0 + 16e-4, 1.0 + 1e-4, 1.0 + 1e-5, 1.0 + 0.5e-5
    est = richardson([q1], [q2], [q4], 4)
    bars = checked(est, [qh], [q1], [q2], 4, orders=(2.5, 6.0))
    bound = _withheld_step_bound(qh, q1, q2, 2.5)
    e_withheld = abs(q1 - q2) / (2**4 - 1)
    assert bound >= e_withheld
    assert bound >= abs(qh - q1) / (1 - 2**-2.5)
    assert np.isnan(bars.error[0]) or bars.error[0] <= bound
