"""From a backend's solution to the numbers a run reports, measured the same way for every backend.

The observables (leading peak force, wave speed, ... from complete peaks only), the response
regimes a run shows (single solitary wave or wave train; exponential then inverse-power decay), the
fronts of a long load on a bilinear chain (Table I), LAMMPS's dumps and histories read into arrays,
and the comparison of two runs of one scene with the models that apply beside them.
"""
