"""The reference solver: the chain's equations (granchain.problem) advanced by velocity Verlet or RK4
with event location at the laws' kinks, observers recording peaks, energy and histories, and SciPy's
DOP853 as an outside yardstick for Hertz chains."""
