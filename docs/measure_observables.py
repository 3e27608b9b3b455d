"""Measure how the front's speed and the leading pulse move with the time step (docs/observables.md).

    python docs/measure_observables.py

The 500-bead steel bilinear chain of issue 11 under a 2 kN step for 50 us, planned for LAMMPS, run
at dt 2.5e-8 and 1e-8 s: the wave speed from the times of the largest peaks and from the arrival
times (leading pulse) over the default window, and the leading pulse at the window's end.
"""

from dataclasses import replace

import numpy as np

import granchain
from granchain.postprocess.observables import fit_wave_speed
from granchain.scene import parse_scene

STEEL = """
[chain]
beads = 500
radius = 4.76e-3
[chain.material]
density = 7850
youngs_modulus = 200e9
poisson_ratio = 0.3
yield_strength = 1e9
[contact]
law = "bilinear"
unloading_coeff = 0.6
[loading]
kind = "step"
amplitude = 2000.0
duration = 5e-5
[run]
timestep = "auto"
end_time = "auto"
[outputs]
histories = [1, 100, 300]
"""

if __name__ == "__main__":
    plan = granchain.plan(parse_scene(STEEL, source="steel.toml"), method="verlet", rtol=1e-3).scene
    a, b = plan.window
    c = np.arange(a, b + 1)
    print(f"window {a}-{b}; dt, speed of the largest peaks, speed of the front, leading pulse at {b}")
    for dt in (2.5e-8, 1e-8):
        sol = granchain.run(replace(plan, run=replace(plan.run, timestep=dt)), backend="lammps").solution
        ok = sol.complete[c - 1]
        largest = fit_wave_speed(c[ok], sol.time_of_peak[c - 1][ok], plan.diameter)[0]
        front = fit_wave_speed(c, sol.leading_pulse_time[c - 1], plan.diameter)[0]
        print(f"{dt:g} s  {largest:.1f} m/s  {front:.1f} m/s  {sol.leading_pulse_force[b - 1]:.4g} N")
