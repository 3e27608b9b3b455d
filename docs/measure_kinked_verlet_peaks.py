"""Where Verlet's erratic error on the kinked laws (bilinear, Thornton) comes from: the peak's reading
or the trajectory (docs/error-bars.md, "Verlet on the kinked laws").

    python docs/measure_kinked_verlet_peaks.py N [SEED [history]]   # N generated scenes per law (no dashpot)

and first the two bundled kinked scenes, plastic-short-impulse and thornton-short-impulse.

For each scene (tests/scenegen.py, a kinked law without a dashpot, planned for rtol 1e-3 for reference
Verlet), reference Verlet runs at dt, 2 dt and 4 dt and reference RK4 (event location) at dt / 2 and
dt (the truth and its own error) give, per complete peak above round-off (1e3 ulps), three readings
of the peak force:

* force: the running peak of the force samples refined by the parabola through three of them (the
  pair styles' and ForceSamplePeaks's reading, what the runs report);
* overlap parabola: the loading curve at the running peak of the overlap samples refined by the
  parabola through three of them;
* overlap Hermite: the loading curve at the maximum of the cubic Hermite interpolant of the overlap
  over the step where the relative velocity turns (overlaps and relative velocities at both ends).

Each reading's Richardson estimate from dt, 2 dt, 4 dt (order 2; granchain.richardson with its
checks, and the nominal |Q(dt) - Q(2 dt)| / 3 without them) is compared to the true error
|Q(dt) - RK4(dt / 2)|. The trajectory: the observed order of each bead's displacement error at the
end time (dt against 2 dt against RK4). ``history``: the Verlet runs anchor alpha_max at the turn's
interpolated maximum (HistoryVerlet). Writes /tmp/kinked_verlet_peaks_SEED[h].json, prints the table;
``python docs/measure_kinked_verlet_peaks.py summary FILE.json ...`` prints the table of several;
``... variants [history]`` the rows of plastic-short-impulse's variants (function variants), with
``history`` for a Verlet whose alpha_max is the turn's interpolated maximum (HistoryVerlet).
"""

import json
import math
import sys
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, seed, settings

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import granchain.reference.solver as solver
from granchain.problem import ChainProblem
from granchain.reference.hermite import hermite_max
from granchain.reference.observers import ForceSamplePeaks
from granchain.reference.verlet import VerletIntegrator
from granchain.richardson import richardson
from granchain.workflows.plan import highest_frequency
from granchain.workflows.run import plan_for
from tests.scenegen import scenes

warnings.simplefilter("ignore")
SUMMARY = sys.argv[1:2] == ["summary"]
VARIANTS = sys.argv[1:2] == ["variants"]
OTHER = SUMMARY or VARIANTS or sys.argv[1:2] == ["bounds"]
N = int(sys.argv[1]) if len(sys.argv) > 1 and not OTHER else 6
SEED = int(sys.argv[2]) if len(sys.argv) > 2 and not OTHER else 1
READINGS = ("force", "overlap parabola", "overlap Hermite")


class OverlapPeaks(ForceSamplePeaks):
    """ForceSamplePeaks, and beside it the overlap's running peak read two ways (module docstring)."""

    last = None

    def __init__(self, state):
        super().__init__(state)
        a = state.overlap().copy()
        self.law = state.law
        self.a_now, self.a_prev, self.a_prev2 = a, np.zeros_like(a), np.zeros_like(a)
        self.d_now = state.v[:-1] - state.v[1:]
        self.tt = [0.0, -math.inf, -math.inf]  # t_now, t_prev, t_prev2
        self.par = a.copy()
        self.her = a.copy()
        OverlapPeaks.last = self

    def after_step(self, state, t0, t1):
        out = super().after_step(state, t0, t1)
        a = state.u[:-1] - state.u[1:]
        d = state.v[:-1] - state.v[1:]
        self.a_prev2, self.a_prev, self.a_now = self.a_prev, self.a_now, a
        d_prev, self.d_now = self.d_now, d
        self.tt = [t1, self.tt[0], self.tt[1]]
        np.maximum(self.par, a, out=self.par)
        np.maximum(self.her, a, out=self.her)
        turn = np.nonzero((d_prev > 0.0) & (d <= 0.0))[0]
        if turn.size:
            p, _ = hermite_max(self.tt[1], t1, self.a_prev[turn], a[turn], d_prev[turn], d[turn])
            self.her[turn] = np.maximum(self.her[turn], p)
        if math.isfinite(self.tt[2]):
            mid = np.nonzero((self.a_prev > a) & (self.a_prev >= self.a_prev2))[0]
            if mid.size:
                ta, tb = self.tt[2] - self.tt[1], t1 - self.tt[1]
                det = ta * tb * (tb - ta)
                fa, fb = self.a_prev2[mid] - self.a_prev[mid], a[mid] - self.a_prev[mid]
                c1 = (fa * tb * tb - fb * ta * ta) / det
                c2 = (ta * fb - tb * fa) / det
                ok = c2 < 0.0
                s = np.where(ok, np.clip(-c1 / (2.0 * np.where(ok, c2, -1.0)), ta, tb), 0.0)
                val = self.a_prev[mid] + np.where(ok, (c1 + c2 * s) * s, 0.0)
                self.par[mid] = np.maximum(self.par[mid], val)
        return out

    def readings(self):
        f = self.law.force_at_peak_overlap
        return (
            self.fpk.copy(),
            np.asarray(f(np.maximum(self.par, 0.0)), dtype=float),
            np.asarray(f(np.maximum(self.her, 0.0)), dtype=float),
        )


class HistoryVerlet(VerletIntegrator):
    """Verlet whose history (alpha_max) is raised, before the force at t_(n+1), to the vertex of the
    parabola through the overlaps at t_(n-1), t_n, t_(n+1) where the middle one is a local maximum: the
    unloading branch anchored at the turn's interpolated maximum, not at the largest sample."""

    def __init__(self, state):
        super().__init__(state)
        self.a1, self.a2 = state.overlap().copy(), np.full(state.n - 1, -np.inf)
        self.t1, self.t2 = 0.0, -math.inf

    def step(self, state, t0, t1, h, a_ext, on_split):
        u, v = state.u, state.v
        half = 0.5 * h
        v += half * state.a_int
        if a_ext:
            v[self.load_bead] += half * a_ext
        u += h * v
        a = u[:-1] - u[1:]
        mid = np.nonzero((self.a1 > a) & (self.a1 >= self.a2))[0]
        if mid.size and math.isfinite(self.t2):
            ta, tb = self.t2 - self.t1, t1 - self.t1
            det = ta * tb * (tb - ta)
            fa, fb = self.a2[mid] - self.a1[mid], a[mid] - self.a1[mid]
            c1 = (fa * tb * tb - fb * ta * ta) / det
            c2 = (ta * fb - tb * fa) / det
            ok = c2 < 0.0
            s = np.where(ok, np.clip(-c1 / (2.0 * np.where(ok, c2, -1.0)), ta, tb), 0.0)
            vertex = np.full_like(a, -np.inf)
            vertex[mid] = self.a1[mid] + np.where(ok, (c1 + c2 * s) * s, 0.0)
            state.law.update_history(state.alpha_hist, vertex)
        self.a2, self.a1, self.t2, self.t1 = self.a1, a.copy(), self.t1, t1
        state.accel(u, state.a_int, v)
        v += half * state.a_int
        if a_ext:
            v[self.load_bead] += half * a_ext
        state.law.update_history(state.alpha_hist, a)
        return t0


def variants(history: bool) -> None:
    """plastic-short-impulse at 30 beads: with and without the kink at the maximum (unloading_coeff
    0.8: k_u = 5 k; 0: k_u = k) and without and with precompression (20 N: no contact closes from zero)."""
    from granchain.scene import parse_scene

    if history:
        solver.VerletIntegrator = HistoryVerlet
    text = (Path(__file__).resolve().parents[1] / "granchain/scenes/plastic-short-impulse.toml").read_text()
    text = text.replace("beads = 60", "beads = 30").replace("window = [5, 40]", "window = [5, 25]")
    text = text.replace("end_time = 1e-3", 'end_time = "auto"').replace("timestep = 1e-8", 'timestep = "auto"')
    for beta in ("0.8", "0.0"):
        for pre in ("", "\n[precompression]\nforce = 20.0\n"):
            study(
                parse_scene(text.replace("unloading_coeff = 0.8", f"unloading_coeff = {beta}") + pre, source="v.toml")
            )
            r = rows[-1]
            traj = np.asarray(r["trajectory_orders"])
            print(
                f"| {beta} | {'20 N' if pre else '-'} | {'interpolated' if history else 'sampled'} | "
                + " | ".join(
                    f"{r[n]['above']} / {r[n]['sign_changes']} / {r[n]['estimated']} / "
                    f"{sum(1 for x in r[n]['ratios'] if not 1 / 3 <= x <= 3)}"
                    for n in READINGS[:2]
                )
                + f" | {np.mean((traj > 1.5) & (traj < 2.5)):.0%} |",
                flush=True,
            )


solver.ForceSamplePeaks = OverlapPeaks
rows = []


def run(problem, end, dt, method):
    sol = solver.solve_chain(problem, end, dt, method)
    if method == "rk4":
        return sol, None
    s0 = problem.with_ends().front
    n = problem.beads - 1
    return sol, [r[s0 : s0 + n] for r in OverlapPeaks.last.readings()]


def study(sc):
    sc, _ = plan_for(sc, "reference", "verlet", 1e-3)
    problem = ChainProblem.from_scene(sc)
    dt, end = sc.run.timestep, sc.run.end_time
    runs = [run(problem, end, k * dt, "verlet") for k in (1, 2, 4)]
    truth, _ = run(problem, end, dt / 2, "rk4")
    rk_dt, _ = run(problem, end, dt, "rk4")
    jump = math.pi / highest_frequency(sc)[0]
    sols = [r[0] for r in runs]
    measured = sols[0].complete & truth.complete & rk_dt.complete
    times = tuple(s.time_of_peak for s in sols)
    row = {
        "law": sc.contact.law if hasattr(sc, "contact") else str(type(sc.law).__name__),
        "beads": sc.chain.beads,
        "kind": sc.loading.kind,
        "pre": float(sc.effects.precompression),
        "wall": str(sc.effects.far_end),
        "steps": int(sols[0].steps),
        "rk4_own": float(np.nanmax(np.abs(rk_dt.peak_force - truth.peak_force)[measured] / truth.peak_force[measured]))
        if measured.any()
        else None,
    }
    for k, name in enumerate(READINGS):
        q = [r[1][k] for r in runs]
        true = np.abs(q[0] - truth.peak_force)
        above = measured & (true > 1e3 * np.spacing(np.abs(truth.peak_force)))
        est = richardson(q[0], q[1], q[2], 2, times=times, jump_time=jump, orders=(2.0, 2.0))
        ok = above & est.reliable
        d1, d2 = q[0] - q[1], q[1] - q[2]
        row[name] = {
            "above": int(above.sum()),
            "estimated": est.error[ok].size,
            "ratios": (est.error[ok] / true[ok]).tolist(),
            "nominal": (np.abs(d1[above]) / 3.0 / true[above]).tolist(),
            "sign_changes": int(np.sum(above & (d1 * d2 < 0))),
            "rel_true": (true[above] / truth.peak_force[above]).tolist(),
            # per peak (above): Q at dt, 2 dt, 4 dt, the truth, and Richardson's verdict and estimate
            "q": np.stack([q[0][above], q[1][above], q[2][above], truth.peak_force[above]], 1).tolist(),
            "reliable": est.reliable[above].tolist(),
            "richardson": est.error[above].tolist(),
            "status": [str(x) for x in est.status[above]],
            # the peaks' times at dt, 2 dt, 4 dt and half the shortest period (another pulse: richardson)
            "times": np.stack([t[above] for t in times], 1).tolist(),
            "jump": jump,
        }
    # the trajectory at the end time: each bead's displacement error against RK4 at dt / 2
    e1 = np.abs(sols[0].displacement - truth.displacement)
    e2 = np.abs(sols[1].displacement - truth.displacement)
    big = e1 > 1e3 * np.spacing(np.max(np.abs(truth.displacement)))
    row["trajectory_orders"] = np.log2(e2[big] / e1[big]).tolist()
    rows.append(row)
    print(row["law"], [(n, row[n]["above"], row[n]["sign_changes"]) for n in READINGS], end=" ")
    print(row["law"], row["beads"], row["kind"], row["pre"], row["steps"], flush=True)


@seed(SEED)
@settings(max_examples=N, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(sc=scenes(law="bilinear", max_beads=60).filter(lambda s: not s.effects.dashpot))
def bilinear(sc):
    study(sc)


@seed(SEED)
@settings(max_examples=N, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(sc=scenes(law="thornton", max_beads=60).filter(lambda s: not s.effects.dashpot))
def thornton(sc):
    study(sc)


def summary(rows):
    """The table of docs/error-bars.md; a scene drawn twice (hypothesis repeats draws) counts once."""
    seen, unique = set(), []
    for r in rows:
        key = (r["law"], r["beads"], r["kind"], r["pre"], r["wall"], r["steps"], r["rk4_own"])
        if key not in seen:
            seen.add(key)
            unique.append(r)
    rows = unique
    lines = [
        "| law | reading | peaks | sign changes dt/2dt/4dt | Richardson estimated | est/true 5-50-95% (min-max) |"
        " outside 1/3-3 | nominal order 2: est/true 5-50-95% | nominal outside |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for law in ("bilinear", "thornton"):
        sub = [r for r in rows if r["law"] == law]
        for name in READINGS:
            rr = np.concatenate([np.asarray(r[name]["ratios"]) for r in sub] or [np.zeros(0)])
            nn = np.concatenate([np.asarray(r[name]["nominal"]) for r in sub] or [np.zeros(0)])
            above = sum(r[name]["above"] for r in sub)
            sc = sum(r[name]["sign_changes"] for r in sub)

            def q(x):
                if not x.size:
                    return "-"
                p = np.percentile(x, [5, 50, 95])
                return f"{p[0]:.2f} - {p[1]:.2f} - {p[2]:.2f} ({x.min():.2f} - {x.max():.2f})"

            out = int(np.sum((rr < 1 / 3) | (rr > 3)))
            nout = int(np.sum((nn < 1 / 3) | (nn > 3)))
            head = f"| {law} ({len(sub)} scenes) | {name} | {above} | {sc} | "
            lines.append(head + f"{rr.size} | {q(rr)} | {out} | {q(nn)} | {nout} |")
    lines.append("")
    for law in ("bilinear", "thornton"):
        orders = np.concatenate([np.asarray(r["trajectory_orders"]) for r in rows if r["law"] == law] or [np.zeros(0)])
        if orders.size:
            p = np.percentile(orders, [5, 50, 95])
            lines.append(
                f"{law} trajectory (end-time displacements, {orders.size} beads): observed order 5-50-95% "
                f"{p[0]:.2f} - {p[1]:.2f} - {p[2]:.2f}; within 1.5-2.5: {np.mean((orders > 1.5) & (orders < 2.5)):.0%}"
            )
    return "\n".join(lines)


def bound_estimates(r: dict, reading: str = "force") -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Cheap estimators from the runs at dt, 2 dt, 4 dt alone, per peak of one scene's row: name ->
    (estimate, true error), nan where an estimator gives no bar (another pulse in a companion).

    d1 = Q(dt) - Q(2 dt), d2 = Q(2 dt) - Q(4 dt). Richardson: its bar where its checks pass.
    bound p=1: max(|d1|, |d2| / 2); bound p=2: max(|d1|, |d2| / 4); |d1|: the first difference alone.
    Richardson + bound: Richardson's bar where its checks pass, else the bound.
    """
    x = r[reading]
    if not x.get("q"):
        return {}
    q = np.asarray(x["q"], dtype=float)
    t = np.asarray(x["times"], dtype=float)
    true = np.abs(q[:, 0] - q[:, 3])
    d1, d2 = np.abs(q[:, 0] - q[:, 1]), np.abs(q[:, 1] - q[:, 2])
    same = (np.abs(t[:, 0] - t[:, 1]) <= x["jump"]) & (np.abs(t[:, 1] - t[:, 2]) <= x["jump"])
    rich = np.where(np.asarray(x["reliable"]), np.asarray(x["richardson"], dtype=float), np.nan)
    b1 = np.where(same, np.maximum(d1, d2 / 2.0), np.nan)
    b2 = np.where(same, np.maximum(d1, d2 / 4.0), np.nan)
    return {
        "Richardson (checks pass)": (rich, true),
        "|d1|": (np.where(same, d1, np.nan), true),
        "bound p=2: max(|d1|, |d2|/4)": (b2, true),
        "bound p=1: max(|d1|, |d2|/2)": (b1, true),
        "Richardson, else bound p=2": (np.where(np.isfinite(rich), rich, b2), true),
        "Richardson, else bound p=1": (np.where(np.isfinite(rich), rich, b1), true),
    }


def bounds_table(rows, reading: str = "force"):
    """The estimators' distributions per law (bound_estimates; a scene drawn twice counts once)."""
    seen, unique = set(), []
    for r in rows:
        key = (r["law"], r["beads"], r["kind"], r["pre"], r["wall"], r["steps"], r["rk4_own"])
        if key not in seen:
            seen.add(key)
            unique.append(r)
    lines = [
        f"reading: {reading}",
        "| law | estimator | peaks | with a bar | below 1/3 | above 3 | est/true 5-50-95% (min-max) |",
        "|---|---|---|---|---|---|---|",
    ]
    for law in ("bilinear", "thornton"):
        sub = [bound_estimates(r, reading) for r in unique if r["law"] == law]
        sub = [s for s in sub if s]
        for name in sub[0] if sub else ():
            est = np.concatenate([s[name][0] for s in sub])
            true = np.concatenate([s[name][1] for s in sub])
            ok = np.isfinite(est)
            ratio = est[ok] / true[ok]
            p = np.percentile(ratio, [5, 50, 95]) if ratio.size else [np.nan] * 3
            lines.append(
                f"| {law} ({len(sub)} scenes) | {name} | {est.size} | {ok.sum()} ({ok.mean():.0%}) | "
                f"{int(np.sum(ratio < 1 / 3))} | {int(np.sum(ratio > 3))} | {p[0]:.2f} - {p[1]:.2f} - {p[2]:.2f} "
                f"({ratio.min():.2f} - {ratio.max():.3g}) |"
            )
    return "\n".join(lines)


BOUNDS = sys.argv[1:2] == ["bounds"]

if __name__ == "__main__" and BOUNDS:  # bounds FILE.json ...: the cheap estimators' table
    rows_ = [r for f in sys.argv[2:] for r in json.load(open(f))]
    print(bounds_table(rows_, "force"))
elif __name__ == "__main__" and VARIANTS:  # variants [history]
    variants(sys.argv[2:3] == ["history"])
elif __name__ == "__main__" and SUMMARY:  # summary FILE.json ...: the table of several samples
    print(summary([r for f in sys.argv[2:] for r in json.load(open(f))]))
elif __name__ == "__main__":
    from granchain.scene.reader import load_scene

    if sys.argv[3:4] == ["history"]:
        solver.VerletIntegrator = HistoryVerlet
    for name in ("plastic-short-impulse", "thornton-short-impulse"):  # the bundled kinked scenes
        study(load_scene(name))
    bilinear()
    thornton()
    json.dump(rows, open(f"/tmp/kinked_verlet_peaks_{SEED}{'h' if sys.argv[3:4] == ['history'] else ''}.json", "w"))
    print(summary(rows))
