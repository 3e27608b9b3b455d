"""Read a finished LAMMPS deck's output files back into the solution every backend returns.

Everything read is a file the deck writes, by atom ID at full precision: the results dump
(templates.RESULT_COLUMNS), a precompressed chain's crossing-time ladder (LADDER_DUMP), the run's
last step and time, energy.txt, load_end.txt and the history and snapshot dumps. read_solution
assembles results.ChainSolution from peak_fields, energy_fields, history_fields and snapshot_fields;
granchain.lammps.runner.lammps_result (a run through the Python module and granchain collect alike)
calls it.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from granchain import safe_files
from granchain.exceptions import GranchainError
from granchain.peaks import complete_peaks, every_contact_complete, lead_floor, leading_pulse, unreached_as_nan
from granchain.physics.effects import active_effects
from granchain.physics.effects import work as effects_work
from granchain.physics.event import EVENT_FIELDS, EVENT_MAXIMA_FIELDS
from granchain.postprocess.dumps import read_dump
from granchain.postprocess.fronts import front_times
from granchain.postprocess.histories import read_histories
from granchain.postprocess.sensors import finish_sensors
from granchain.problem import ChainProblem, precompressed_displacements, scene_static_forces, scene_static_load
from granchain.results import ChainSolution
from granchain.schedule import scene_step_plan, step_times
from granchain.templates import RESULT_COLUMNS, RESULTS_DUMP, RUN_END_FILE, AtomLayout, atom_layout
from granchain.templates.drive import DRIVE_WORK_COLUMN
from granchain.templates.run_control import initial_mass_x

#: the most of a results file read (a 10^7-bead chain's peaks.dump is about 2.5 GB)
RESULTS_LIMIT = 8 * 1024**3


class ResultsError(GranchainError, RuntimeError):
    """A deck's results (templates.RESULTS_DUMP, RUN_END_FILE) are missing or incomplete."""


def _result_text(path: Path, limit: int) -> str:
    """A results file's text, read without following links and bounded; a ResultsError naming it
    when it is missing, a link, too large or not text."""
    try:
        return safe_files.read_text(path, limit)
    except FileNotFoundError:
        raise ResultsError(f"{path}: missing; the deck writes it during the run") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ResultsError(f"{path}: cannot be read as the deck's output ({e})") from None


def read_run_end(work: Path) -> tuple[int, float]:
    """The run's last step and time, as the deck printed them (templates.RUN_END_FILE)."""
    p = Path(work) / RUN_END_FILE
    try:
        step, t = safe_files.read_text(p, 4096).split()
        step, t = int(step), float(t)
    except FileNotFoundError:
        raise ResultsError(f"{p}: missing; the deck writes it when the run has finished") from None
    except (OSError, ValueError) as e:
        raise ResultsError(f"{p}: not the line 'step time' the deck writes at the end of the run ({e})") from None
    if step < 0 or not (np.isfinite(t) and t >= 0):
        # no run ends at a negative step or time: the file was damaged or edited, the physics is not at fault
        raise ResultsError(
            f"{p}: says step {step}, time {t!r}; a run ends at a step and a time of at least 0, so the file is "
            "damaged or edited (not what the deck writes): run the deck again"
        )
    return step, t


#: the deck's event file ([outputs] event: templates/event.lmp.j2, fix chain/event's vector)
EVENT_FILE = "event.txt"


def event_fields(scene, work: Path) -> dict:
    """The wall's event (physics.event.EVENT_FIELDS) from the deck's event.txt; {} without [outputs] event."""
    if not scene.wall_event:
        return {}
    p = Path(work) / EVENT_FILE
    try:
        ended, end, *values = (float(x) for x in _result_text(p, 4096).split())
    except ValueError as e:
        raise ResultsError(f"{p}: not the seven numbers the deck writes at the end of the run ({e})") from None
    nc, ns = len(scene.outputs.event_max_contacts), len(scene.outputs.event_max_sensors)
    if len(values) != 5 + 2 * (nc + ns) or ended not in (0.0, 1.0) or not np.isfinite([end, *values]).all():
        raise ResultsError(
            f"{p}: not the deck's event line (ended 0 or 1, its end time, five finite sums, then a largest force "
            f"and its time for each of the {nc + ns} tracked ones): damaged or edited; run the deck again"
        )
    out = dict(zip(EVENT_FIELDS[1:], values[:5], strict=True))
    maxima = np.asarray(values[5:], dtype=float).reshape(-1, 2)
    force, time = maxima[:, 0], maxima[:, 1]
    out |= dict(zip(EVENT_MAXIMA_FIELDS, (force[:nc], time[:nc], force[nc:], time[nc:]), strict=True))
    return {"event_end_time": end if ended else None, **out}


def read_results(work: Path) -> dict[str, np.ndarray]:
    """The deck's per-atom results at the end of the run (templates.RESULTS_DUMP), by atom ID.

    Keys: the dump's columns of templates.RESULT_COLUMNS without their d_ prefix (x, vx, fpeak,
    tpeak, fmin, flead, tlead, amax: whichever the deck declared), as float64 read from %.17g text,
    so exactly the doubles LAMMPS held.
    """
    names, data = _read_atom_dump(Path(work) / RESULTS_DUMP, "the deck writes it as its last file")
    return {c.removeprefix("d_"): data[:, names.index(c)] for c in RESULT_COLUMNS if c in names}


#: each contact's crossing-time ladder at the end of the run (the deck's results block, before RESULTS_DUMP)
LADDER_DUMP = "ladder.dump"


def read_ladder(work: Path) -> np.ndarray | None:
    """Every atom's crossing-time ladder (LADDER_DUMP: d2_ladder's columns, by atom ID), or None
    from a deck that writes none."""
    p = Path(work) / LADDER_DUMP
    if not p.exists():
        return None
    names, data = _read_atom_dump(p, "the deck writes it before its results")
    return data[:, [k for k, c in enumerate(names) if c.startswith("d2_ladder[")]]


def _read_atom_dump(p: Path, written: str) -> tuple[list[str], np.ndarray]:
    """A per-atom dump custom file of one snapshot, every atom in ID order: (its column names, its
    rows as float64 from %.17g text). ResultsError when it is missing, cut off or out of order."""
    try:
        lines = safe_files.read_text(p, RESULTS_LIMIT).split("\n", 9)
    except FileNotFoundError:
        raise ResultsError(f"{p}: missing; {written} when the run has finished") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ResultsError(f"{p}: cannot be read as the deck's results ({e})") from None
    header = [x + "\n" for x in lines[:9]] + [""] * (9 - min(len(lines), 9))
    body = lines[9] if len(lines) > 9 else ""
    if not header[0].startswith("ITEM: TIMESTEP") or not header[8].startswith("ITEM: ATOMS"):
        raise ResultsError(f"{p}: not a LAMMPS dump custom file (its header is incomplete)")
    try:
        natoms = int(header[3])
    except ValueError:
        raise ResultsError(f"{p}: not a LAMMPS dump custom file (no atom count)") from None
    names = header[8].split()[2:]
    rows = [line for line in body.splitlines() if line.strip()]
    try:
        if len(rows) != natoms:
            raise ValueError(f"{len(rows)} rows")
        data = np.loadtxt(rows, ndmin=2)
        if data.shape[1] != len(names):
            raise ValueError(f"{data.shape[1]} columns")
    except ValueError:
        raise ResultsError(
            f"{p}: does not hold {len(names)} columns for each of its {natoms} atoms: the dump was cut off"
        ) from None
    ids = data[:, names.index("id")].astype(int)
    if not np.array_equal(ids, np.arange(1, natoms + 1)):
        raise ResultsError(f"{p}: atom IDs are not 1..{natoms} in order (the deck writes it sorted by ID)")
    return names, data


def step_times_of(scene) -> np.ndarray:
    """Time after every step of the scene's run (steps are shortened at breakpoints)."""
    return step_times(scene_step_plan(scene), scene.run.timestep)


def x0_static(scene) -> np.ndarray:
    """The beads' x at t = 0: the data file's positions plus any static displacement."""
    u0 = precompressed_displacements(scene)[0] if scene_static_load(scene) else 0.0
    return np.asarray(scene.bead_positions, dtype=float) + u0


def x1_static(scene) -> float:
    """x of bead 1 at t = 0 (its static displacement under a precompression or gravity)."""
    if not scene_static_load(scene):
        return 0.0
    return float(precompressed_displacements(scene)[0][0])


def energy_column_names(path: Path, scene) -> list[str]:
    """The columns of a deck's energy samples: its title line ("# time kinetic potential [dissipated]
    x1 [the effects' columns]", templates/energy.lmp.j2), else what this scene's deck writes."""
    with open(path, encoding="utf-8") as f:
        first = f.readline()
    if first.startswith("#"):
        return first[1:].split()
    dissipated = scene.contact.law_class.history or any(e.dissipated_vectors for e in active_effects(scene))
    extra = [k for e in active_effects(scene) for k in e.energy_columns(AtomLayout.of(scene))]
    return ["time", "kinetic", "potential", *(["dissipated"] if dissipated else []), "x1", *extra]


def read_solution(
    scene, work: Path, total_steps: int, wall_time: float, end_time: float | None = None
) -> ChainSolution:
    """A finished deck's results in work as the solution every backend returns (results.ChainSolution).

    Atoms are read by ID (templates.atom_layout: a striker is atom 1, bead i atom i + offset, contact i
    lives on atom i + offset): the peaks (peak_fields), the energy samples (energy_fields), the
    histories and snapshots (history_fields, snapshot_fields), the final state and the effects' own
    contacts (Effect.end_fields). end_time: the run's last time if it stopped early.
    """
    n, ld = scene.chain.beads, scene.loading
    res = read_results(work)  # by atom ID: templates.RESULT_COLUMNS
    o = atom_layout(scene)["offset"]
    striker = ld.kind == "striker"  # (atom 1 a striker; a shaker's driver has no momentum of its own)
    end = scene.run.end_time if end_time is None else end_time
    v = res["vx"][o : o + n]
    masses = scene.bead_masses if scene.per_bead else scene.mass
    times = step_times_of(scene)
    # the extra atoms' results (Effect.end_fields: the wall's contact lives on bead N's atom; a striker
    # touches bead 1 unloaded, every other contact starts at F0)
    static = np.zeros(res["fpeak"].shape)
    forces = scene_static_forces(scene)  # each contact's own (F0 plus the weight above it)
    static[o : o + forces.size] = forces
    fmin = res["fmin"] if "fmin" in res else res["fpeak"]  # a deck without d_fmin: nothing is complete
    every = every_contact_complete(res["fpeak"], fmin, res["tpeak"], static)
    ends = {
        k: x
        for effect in active_effects(scene)
        for k, x in effect.end_fields(res["fpeak"], res["tpeak"], res["vx"], o + n - 1, every).items()
    }
    sol = ChainSolution(
        method="verlet",
        timestep=scene.run.timestep,
        steps=total_steps,
        wall_time=wall_time,
        end_time=end,
        **peak_fields(scene, work, res, o),
        **history_fields(scene, work, times),
        **snapshot_fields(scene, work, times, o),
        **energy_fields(scene, work),
        displacement=res["x"][o : o + n] - scene.bead_positions,  # the data file's positions (render_data)
        velocity=v,
        alpha_max=res["amax"][o : o + n - 1] if "amax" in res else np.zeros(n - 1),
        impulse_delivered=float(ld.impulse_until(end)),
        momentum=float(np.sum(masses * v)) + (scene.striker_mass * float(res["vx"][0]) if striker else 0.0),
        **ends,
        **event_fields(scene, work),
        **sensor_fields(scene, work, res, o, times),
    )
    if scene.outputs.sensors:
        finish_sensors(scene, sol)  # reached and complete, by the contacts' rules
    return sol


#: the sensor beads' d_sfc at the histories' steps (templates/sensors.lmp.j2 writes it)
SENSORS_DUMP = "sensors.dump"


def sensor_fields(scene, work: Path, res: dict[str, np.ndarray], o: int, times: np.ndarray) -> dict:
    """The sensor beads' running peaks from the results dump (res: d_speak, d_stpeak, d_sfmin on each
    sensor's atom) and their history (sensors.dump, d_sfc at the histories' steps); {} without sensors."""
    if not scene.outputs.sensors:
        return {}
    atoms = np.asarray(scene.outputs.sensors, dtype=int) - 1 + o  # bead b is atom b + o (0-based: b - 1 + o)
    out = {
        "sensor_peak_force": res["speak"][atoms],
        "sensor_time_of_peak": res["stpeak"][atoms],
        "sensor_force_min_after_peak": res["sfmin"][atoms],
    }
    if scene.outputs.history_interval is not None:  # the deck dumps d_sfc only then (a companion run: not)
        dd = read_dump(Path(work) / SENSORS_DUMP, times, columns=("d_sfc",))
        out.update(sensor_history_time=dd.time, sensor_history_force=dd.columns["d_sfc"])
    return out


def peak_fields(scene, work: Path, res: dict[str, np.ndarray], o: int) -> dict[str, np.ndarray]:
    """The solution's per-contact peak fields from the results dump (res) and the ladder dump: the
    running peak, its time and what completes it, the leading pulse, the crossing-time ladder and
    the half-amplitude arrival read off it (postprocess.fronts). o: the atom of contact 1 less one."""
    n, f0 = scene.chain.beads, scene.effects.precompression
    _check_finite_peaks(work, res)
    fpeak = res["fpeak"][o : o + n - 1]
    tpeak = unreached_as_nan(fpeak, res["tpeak"][o : o + n - 1], scene_static_forces(scene)[: n - 1])
    # the smallest force since each peak (a deck without d_fmin: no peak counts as complete)
    fmin = res["fmin"][o : o + n - 1] if "fmin" in res else fpeak
    if "flead" in res:
        flead, tlead = leading_pulse(res["flead"][o : o + n - 1], res["tlead"][o : o + n - 1], tpeak)
    else:  # a deck without the leading-pulse vectors (the built-in granular yardstick)
        flead, tlead = np.full(n - 1, np.nan), np.full(n - 1, np.nan)
    ladder, front = read_ladder(work), np.full(n - 1, np.nan)
    if ladder is not None:  # a precompressed chain's deck
        ladder = ladder[o : o + n - 1]
        # the pair style's ladder climbs from its one static force (the deck's lead_static: F0, under
        # gravity the largest, the wall's)
        lead_static = float(np.max(scene_static_forces(scene), initial=0.0))
        front = front_times(ladder, flead, lead_static, lead_floor(scene))
    else:
        ladder = np.zeros((0, 0))
    return {
        "peak_force": fpeak,
        "time_of_peak": tpeak,
        "force_min_after_peak": fmin,
        "complete": complete_peaks(fpeak, fmin, tpeak, f0),
        "leading_pulse_force": flead,
        "leading_pulse_time": tlead,
        "front_ladder": ladder,
        "front_time": front,
    }


def _check_finite_peaks(work: Path, res: dict[str, np.ndarray]) -> None:
    """Refuse a results dump whose running peaks (or what completes them) are not finite while every
    bead's position and velocity is: LAMMPS keeps finite maxima of finite forces, so the file is
    damaged (a run that blew up has a non-finite state, which check_solution reports as such)."""
    if not (np.isfinite(res["x"]).all() and np.isfinite(res["vx"]).all()):
        return
    for name in ("fpeak", "tpeak", "fmin", "flead", "tlead", "amax"):
        bad = np.flatnonzero(~np.isfinite(res[name])) if name in res else ()
        if len(bad):
            raise ResultsError(
                f"{Path(work) / RESULTS_DUMP}: d_{name} of atom {bad[0] + 1} is {float(res[name][bad[0]])!r}, although "
                "every bead's position and velocity are finite; LAMMPS writes finite running peaks, so the file is "
                "damaged or edited: run the deck again"
            )


def energy_fields(scene, work: Path) -> dict[str, np.ndarray]:
    """The energy samples (energy.txt: time, kinetic, stored, dissipated) and the energy put in by then:
    the initial kinetic + stored + dissipated energy, the work of f(t) (A times bead 1's displacement
    while it acts) and of the effects' external forces (Effect.work: precompression's static ones)."""
    ld = scene.loading
    e = np.loadtxt(io.StringIO(_result_text(work / "energy.txt", RESULTS_LIMIT)), comments="#", ndmin=2)
    # the deck appends the end of the run (energy.lmp.j2); where the last periodic sample is that, keep one
    keep = np.append(e[1:, 0] != e[:-1, 0], True)
    e = e[keep]
    names = energy_column_names(work / "energy.txt", scene)
    if "dissipated" not in names:  # no dissipation column: an elastic law without a dashpot
        e = np.insert(e, 3, 0.0, axis=1)
        names.insert(3, "dissipated")
    col = {name: e[:, k] for k, name in enumerate(names)}
    et, ke, pe, ed, x1 = (col[k] for k in ("time", "kinetic", "potential", "dissipated", "x1"))
    x1_0 = x1[0] if et[0] == 0.0 else float(x1_static(scene))
    work_done = np.full(et.shape, ke[0] + pe[0] + ed[0]) if et[0] == 0.0 else np.zeros(et.shape)
    if ld.is_harmonic:  # its work summed step by step in the deck (templates/loading_harmonic.lmp.j2)
        work_done = work_done + col[DRIVE_WORK_COLUMN]
    elif ld.is_step:
        dx = x1 - x1_0
        if (work / "load_end.txt").exists():
            x1_end = float(np.loadtxt(io.StringIO(_result_text(work / "load_end.txt", 4096)), ndmin=1)[1])
            dx = np.where(et > ld.duration, x1_end - x1_0, dx)
        work_done = work_done + ld.amplitude * dx
    xn = col.get("xN", x1)  # bead N's x where an effect needs it (energy_columns)
    mx = col.get("mx")  # the moving atoms' sum of m_i x_i where a body force needs it
    dx_mass = 0.0 if mx is None else mx - (mx[0] if et[0] == 0.0 else initial_mass_x(scene, x0_static(scene)))
    work_done = work_done + effects_work(ChainProblem.from_scene(scene), x1 - x1_0, xn - xn[0], dx_mass)
    return {"energy_time": et, "kinetic": ke, "potential": pe, "dissipated": ed, "work": work_done}


def history_fields(scene, work: Path, times: np.ndarray) -> dict:
    """The requested contacts' force and left-bead velocity histories (histories.npy, written by fix
    chain/history, or histories.dump); times: the time after every step."""
    # (a shaker's driver's contact first, -1: the deck records it on atom 1)
    hist = ((-1,) if scene.loading.is_shaker else ()) + tuple(i - 1 for i in scene.outputs.histories)
    h_t = np.zeros(0)
    h_f = h_v = np.zeros((0, len(hist)))
    if hist:
        h_t, h_f, h_v = read_histories(work, times)
    return {"history_contacts": hist, "history_time": h_t, "history_force": h_f, "history_velocity": h_v}


def snapshot_fields(scene, work: Path, times: np.ndarray, o: int) -> dict[str, np.ndarray]:
    """The whole-chain snapshots (snapshot_K.dump): displacements from the unloaded chain (a
    precompressed chain's static displacement added: displace/atom counts from t = 0), velocities
    and contact forces. o: the atom of bead 1 less one."""
    n, snaps = scene.chain.beads, scene.outputs.snapshots
    s_u, s_v, s_f = [], [], []
    u_static = np.zeros(n)
    if scene_static_load(scene):
        u_static = precompressed_displacements(scene)[0]
    for k in range(len(snaps)):
        dd = read_dump(work / f"snapshot_{k}.dump", times)
        s_u.append(dd.columns["v_ux"][-1][o : o + n] + u_static)
        s_v.append(dd.columns["v_vel"][-1][o : o + n])
        s_f.append(dd.columns["d_fc"][-1][o : o + n - 1])
    return {
        "snapshot_time": np.asarray(snaps, dtype=float),
        "snapshot_displacement": np.array(s_u).reshape(len(snaps), n),
        "snapshot_velocity": np.array(s_v).reshape(len(snaps), n),
        "snapshot_force": np.array(s_f).reshape(len(snaps), n - 1),
    }
