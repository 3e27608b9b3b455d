"""The solution every backend returns (ChainSolution): the same fields from the reference and LAMMPS."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class ChainSolution:
    """What a solver run returns. Contacts are 0-based here (contact i joins beads i and i+1)."""

    method: str
    timestep: float
    steps: int
    wall_time: float
    end_time: float
    peak_force: np.ndarray  # (N-1,) N
    time_of_peak: np.ndarray  # (N-1,) s, nan for contacts never compressed
    history_contacts: tuple[int, ...] = ()
    history_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    history_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (samples, contacts)
    history_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # bead i of contact i
    snapshot_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    snapshot_displacement: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (snaps, N)
    snapshot_velocity: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    snapshot_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (snaps, N-1)
    energy_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    kinetic: np.ndarray = field(default_factory=lambda: np.zeros(0))
    potential: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work: np.ndarray = field(default_factory=lambda: np.zeros(0))
    displacement: np.ndarray = field(default_factory=lambda: np.zeros(0))  # final state
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))
    alpha_max: np.ndarray = field(default_factory=lambda: np.zeros(0))  # final bilinear history
    impulse_delivered: float = 0.0  # A * min(T, end_time)
    momentum: float = 0.0  # total momentum sum(m v) at the end
    extra_steps: int = 0  # steps beyond the grid's (RK4 event location: rejected and split steps)
    wall_peak_force: float | None = None  # far-end wall contact (only with a wall)
    wall_time_of_peak: float | None = None
    # the wave passed the wall's contact: its force fell to half its peak before the run ended
    # (peaks.every_contact_complete); otherwise wall_peak_force is the running maximum, not a peak
    wall_peak_complete: bool | None = None
    striker_peak_force: float | None = None  # striker-bead 1 contact (only with a striker)
    striker_time_of_peak: float | None = None
    striker_peak_complete: bool | None = None  # as wall_peak_complete, for the striker's contact
    striker_velocity: float | None = None  # at the end
    # the far-end wall's event (granchain.physics.event; None: not tracked, [outputs] event = false):
    # its end (None while it has not ended), the largest dynamic wall force and its time, the impulse
    # (total and dynamic) and the energy into the wall's contact, summed to the end or the run's end
    event_end_time: float | None = None
    wall_max_force: float | None = None
    wall_time_of_max: float | None = None
    wall_impulse: float | None = None
    wall_dynamic_impulse: float | None = None
    wall_energy: float | None = None
    # the chosen contacts' and sensor beads' largest total force over the event and its time
    # ([outputs] event_max_contacts, event_max_sensors; physics.event.EventMaxima), in the scene's order
    event_contact_max_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    event_contact_time_of_max: np.ndarray = field(default_factory=lambda: np.zeros(0))
    event_sensor_max_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    event_sensor_time_of_max: np.ndarray = field(default_factory=lambda: np.zeros(0))
    # smallest force sample of each contact since its peak (N-1,), N; and which peaks are complete
    # (peaks.complete_peaks). A backend that does not track them leaves them empty: no peak is complete.
    force_min_after_peak: np.ndarray = field(default_factory=lambda: np.zeros(0))
    complete: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    # the leading pulse of each contact (N-1,): its peak force and time as they stood when the
    # contact first completed (see leading_pulse); nan where it has not completed
    leading_pulse_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    leading_pulse_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    # (N-1,) m, the largest overlap of each contact (0 if never compressed); the reference tracks it,
    # LAMMPS does not (None: its results dump has no such column)
    peak_overlap: np.ndarray | None = None
    # each contact's crossing-time ladder (N-1, LADDER_SLOTS + 1) and the half-amplitude arrival read
    # off it (N-1,) s (granchain.postprocess.fronts); empty / nan from a backend without the ladder
    front_ladder: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    front_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    # sensor beads ([outputs] sensors, 1-based; granchain.postprocess.sensors): each one's average force
    # (F_left + F_right) / 2, its running peak (total, N), time (nan: not reached), smallest force since
    # and completeness (S,), and its history (samples, S) at the contact histories' steps
    sensor_beads: tuple[int, ...] = ()
    sensor_peak_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sensor_time_of_peak: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sensor_force_min_after_peak: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sensor_complete: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    sensor_history_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sensor_history_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    def __post_init__(self):
        """Fill the per-contact fields a backend left empty with nan (not measured)."""
        for name in ("leading_pulse_force", "leading_pulse_time", "front_time"):
            if np.size(getattr(self, name)) == 0:
                setattr(self, name, np.full(np.shape(self.peak_force), np.nan))
        self.complete = np.asarray(self.complete, dtype=bool)
        if self.complete.size == 0:
            self.complete = np.zeros(np.shape(self.peak_force), dtype=bool)
        elif self.complete.shape != np.shape(self.peak_force):
            raise ValueError(f"complete has shape {self.complete.shape}, peak_force {np.shape(self.peak_force)}")

    @property
    def energy_balance_error(self) -> np.ndarray:
        """kinetic + stored + dissipated - work, at every energy sample."""
        return self.kinetic + self.potential + self.dissipated - self.work
