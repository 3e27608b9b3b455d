"""The physics every layer above builds on, with no run in it: the paper's chain as numbers.

Contact laws (``laws``: Hertz, bilinear Walton-Braun, Thornton), the effects beyond the paper's
bare chain (``effects``: a wall, a dashpot, precompression, a striker, per-bead radii and
materials), bead materials and the paper's scales (``materials``: E*, R*, k, tau; Eqs. 5-7), the
paper's analytic models one function per equation (``models``), the predictions for a scene with
their domains of validity (``predictions``), the estimates a planner needs before anything runs
(``estimates``), the regime a scene is expected in (``regimes``) and where beads sit at t = 0
(``positions``). Nothing here imports the scene module or anything above it (lint-imports).
"""
