"""Fig. 1: the loading time T at which a step load's response turns from a single solitary wave into
a wave train, over amplitudes spanning at least three decades (a search campaign).

The campaign is the shipped granchain/campaigns/fig1-transition.toml (reference RK4, brass Hertz
chain, bisection in log T), with the amplitudes and the tolerance of the mode. Definition of the
transition (the paper gives none): the smallest T at which the force history at contact n has more
than one pulse (granchain.postprocess.response_regimes.count_pulses: a pulse is a maximum above a fraction of
the largest, separated by a dip), on a chain of 2n beads. n = 20 is the main definition; n = 10 (and
30 in --full) show how the prefactor moves with it: the exponent is set by the Hertz chain's
self-similarity (F -> a F, t -> a^(-1/6) t), the prefactor by where and how a "train" is counted.
"""

from __future__ import annotations

import math
import tomllib
from importlib import resources

import numpy as np

from granchain.reproduce.sections import Context, Figure, Row, SectionResult, cost_of, points

KEY, TITLE = "fig1", "Fig. 1: single solitary wave -> wave train"
MAIN_CONTACT = 20


def campaign(quick: bool, contact: int) -> dict:
    """The shipped fig1-transition search for one definition of the transition: pulses counted at
    `contact` on a chain of 2 `contact` beads, amplitudes 1 N to 1 kN (quick, 3) or 1 N to 10 kN
    (full, 9), bisection in log T to 2% (quick) or 0.2% (full)."""
    spec = tomllib.loads(resources.files("granchain.campaigns").joinpath("fig1-transition.toml").read_text())
    spec["vary"] = {
        "loading.amplitude": [1.0, 31.6227766017, 1000.0] if quick else {"log": [1.0, 1e4], "num": 9},
        "chain.beads": [2 * contact],
        "outputs.histories": [[contact]],
    }
    spec["search"]["tolerance"] = 0.02 if quick else 0.002
    spec["search"]["predicate"] = {**spec["search"]["predicate"], "contact": contact}
    return spec


def fit(amplitude: np.ndarray, t: np.ndarray, rel_err: np.ndarray) -> dict:
    """Fit the power law T = P A^s, as log T = log P + s log A by least squares.

    Parameters
    ----------
    amplitude, t : numpy.ndarray
        The load amplitudes (N) and the transition loading times found at them (s).
    rel_err : numpy.ndarray
        Each transition time's relative error: half its final bisection bracket over T.

    Returns
    -------
    dict
        ``exponent`` s, ``prefactor`` P (s N^-s), ``stderr`` the fit's standard error of s (nan
        below three points), and ``error`` the larger of that and the error the brackets alone
        leave in s.
    """
    x, y = np.log(amplitude), np.log(t)
    a = np.vstack([np.ones_like(x), x]).T
    (b, s), res, *_ = np.linalg.lstsq(a, y, rcond=None)
    n = len(x)
    sxx = float(np.sum((x - x.mean()) ** 2))
    stderr = math.sqrt(float(np.sum((y - b - s * x) ** 2)) / (n - 2) / sxx) if n > 2 else float("nan")
    bracket = float(np.max(rel_err)) * math.sqrt(2.0) / math.sqrt(sxx)
    return {"exponent": float(s), "prefactor": math.exp(b), "error": max(stderr, bracket), "stderr": stderr}


def _figure(ctx: Context, fits: dict, data: dict) -> Figure:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5))
    for (n, f), (a, t, e) in zip(fits.items(), data.values(), strict=True):
        line = ax.errorbar(
            a,
            t * 1e6,
            yerr=e * 1e6,
            fmt="o",
            ms=5,
            label=f"contact {n}: T = {f['prefactor'] * 1e6:.1f} us A^{f['exponent']:.4f}",
        )
        aa = np.geomspace(a.min(), a.max(), 50)
        ax.plot(aa, f["prefactor"] * aa ** f["exponent"] * 1e6, "-", color=line[0].get_color(), lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("amplitude A (N)")
    ax.set_ylabel("transition loading time T (us)")
    ax.set_title("Fig. 1: wave trains above the line, a single solitary wave below")
    ax.legend(fontsize=8)
    fig.tight_layout()
    ctx.figure(fig, "fig1")
    return Figure(
        "fig1",
        "Transition loading time over amplitude (symbols: bisection results, bars half the final bracket; lines: "
        "power-law fits), one set per definition of the transition (the contact whose history is counted). As in "
        "the paper, a -1/6 power law; the paper's prefactor and definition are not given, so only the exponent is "
        "compared.",
    )


def run(ctx: Context) -> SectionResult:
    """The section: the transition's exponent against the paper's -1/6, the prefactor of each
    definition (not printed), and Fig. 1."""
    res = SectionResult(KEY, TITLE)
    fits, data, tables = {}, {}, []
    for n in contacts(ctx.quick):
        ws = ctx.campaign(f"fig1-contact{n}", campaign(ctx.quick, n))
        res.campaigns.append(ws.name)
        tables.append(points(ws))
        from granchain.campaigns.run import load_campaign

        s = load_campaign(ws, table="search")
        ok = s[np.isfinite(s["transition"].astype(float))] if "transition" in s else s.iloc[0:0]
        if len(ok) < 2:
            res.notes.append(f"contact {n}: fewer than two transitions found ({len(ok)}); no fit")
            continue
        a, t = ok["loading.amplitude"].to_numpy(float), ok["transition"].to_numpy(float)
        e = ok["transition_error"].to_numpy(float)
        fits[n], data[n] = fit(a, t, e / t), (a, t, e)
    res.cost = cost_of(*tables)
    res.paper_cost = "RK4 at 5e-9 s; symbols at about 6 amplitudes, each found by its own sequence of runs (not given)"
    res.notes.append(__doc__.split("\n\n", 1)[1].strip())
    main = fits.get(MAIN_CONTACT)
    res.rows.append(
        Row(
            "fig1.exponent",
            "transition: exponent of T over A",
            "-",
            -1 / 6,
            "-1/6",
            ours=None if main is None else main["exponent"],
            ours_error=None if main is None else main["error"],
            model=-1 / 6,
            tol=0.0,
            tol_source="an exact fraction; our error bar only",
            reason="the Hertz chain's self-similarity (F -> a F, t -> a^(-1/6) t) makes it exact for any definition",
        )
    )
    for n, f in fits.items():
        res.rows.append(
            Row(f"fig1.prefactor_contact{n}", f"prefactor P of T = P A^s, contact {n}", "s N^(1/6)", None, "",
                ours=f["prefactor"], reason=f"not printed; definition: more than one pulse at contact {n} "
                f"(exponent {f['exponent']:.4f} +- {f['error']:.1e})")
        )  # fmt: skip
    if len(fits) > 1 and MAIN_CONTACT in fits:
        moves = ", ".join(
            f"contact {n}: {f['prefactor'] / fits[MAIN_CONTACT]['prefactor']:.3f}x" for n, f in fits.items()
        )
        res.notes.append(f"How the prefactor moves with the definition (relative to contact {MAIN_CONTACT}): {moves}.")
    if data:
        res.figures.append(_figure(ctx, fits, data))
    return res


def contacts(quick: bool) -> list[int]:
    """The contacts whose pulses define the transition: 20 (the main definition), 10, and 30 in full."""
    return [MAIN_CONTACT, 10] if quick else [MAIN_CONTACT, 10, 30]


def campaign_specs(quick: bool) -> dict[str, dict]:
    """The section's campaigns by workspace name (without the mode prefix)."""
    return {f"fig1-contact{n}": campaign(quick, n) for n in contacts(quick)}
