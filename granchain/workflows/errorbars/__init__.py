"""The per-run error bars, one strategy per class (strategies.STRATEGIES, in the order tried).

granchain.workflows.error_estimates is the entry (estimate_errors, planned_companions) and keeps the
names other modules import; here: report (ErrorReport, Companion), reasons (why each strategy applies:
the *_because predicates, with the measurements behind them), strategies (the classes and their
registry), runs (the companion runs), bars (the bars from their solutions), observables (round-off
floors and the scalar observables' entries), facts (orders, companion steps and price).
"""
