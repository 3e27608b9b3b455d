"""The error-bar strategies' registry (granchain.workflows.errorbars.strategies.STRATEGIES).

The bars of a run are the first strategy's that applies: the RK4 reference runs where they apply,
else none where no bar is given (Withheld, before every estimate: RK4 with a dashpot gives none even
where checked bars are asked for), else one of the narrow ones (bounds, one companion, checked), which
never overlap, so their order is no choice; every strategy of the module is in the registry,
Richardson (which always applies) last. What each strategy gives is the
error-bar tests' (test_errorbars, test_kinked_error_bars, test_kinked_rk4_error_bars, ...); the price it
declares is test_plan_cost's.
"""

from hypothesis import given
from hypothesis import strategies as st

from granchain.integrators import INTEGRATORS
from granchain.workflows import error_estimates
from granchain.workflows.errorbars import strategies
from granchain.workflows.plan import plan_scene

from .scenegen import scenes

#: the strategies that estimate from the run's own companions before Richardson
NARROW = (strategies.Bounded, strategies.OneCompanion, strategies.Checked)


def test_every_strategy_is_registered_and_richardson_is_last():
    classes = {
        c
        for c in vars(strategies).values()
        if isinstance(c, type) and issubclass(c, strategies.ErrorBarStrategy) and c is not strategies.ErrorBarStrategy
    }
    assert {type(s) for s in strategies.STRATEGIES} == classes
    assert type(strategies.STRATEGIES[-1]) is strategies.Richardson
    assert len({s.name for s in strategies.STRATEGIES}) == len(strategies.STRATEGIES)


@given(
    sc=scenes(max_beads=12),
    method=st.sampled_from(sorted(INTEGRATORS)),
    checked=st.booleans(),
    numpy_speed=st.booleans(),
    rk4_runs=st.booleans(),
)
def test_one_strategy_gives_the_bars(sc, method, checked, numpy_speed, rk4_runs):
    sc = plan_scene(sc, method=method).scene  # a strategy is asked about a concrete scene (its step set)
    req = strategies.Request(method, sc, checked, numpy_speed, rk4_runs)
    applying = [type(s) for s in strategies.STRATEGIES if s.because(req)]
    assert applying[-1] is strategies.Richardson  # always applies
    narrow = [c for c in applying if c in NARROW]
    assert len(narrow) <= 1, narrow
    chosen = strategies.strategy(req)
    assert type(chosen) is applying[0]
    # the reasons the report keeps are the predicates' (error_estimates re-exports them)
    if isinstance(chosen, strategies.Bounded):
        assert chosen.because(req) == error_estimates.bounded_because(method, sc)
    if isinstance(chosen, strategies.OneCompanion):
        assert error_estimates.richardson_factors(method, sc, checked) == chosen.factors == (2.0,)
    if not isinstance(chosen, strategies.OneCompanion):
        assert error_estimates.richardson_factors(method, sc, checked) == (2.0, 4.0)
