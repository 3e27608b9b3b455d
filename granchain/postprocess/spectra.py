"""Spectra of time series: a lock-in amplitude and phase over whole periods of a steady window, the
transmission between two of them, the spatial decay of amplitudes along a chain, and the one-sided
FFT amplitude spectrum with its window named.

Pure numpy, on arrays: a bead's displacement, velocity or a contact's force sampled on a uniform
time grid (a run's histories). Nothing here knows of scenes or backends.

Conventions (every function says which it uses):

* A harmonic of a drive at frequency f is x(t) = A cos(2 pi h f t + phi); its complex amplitude is
  Z = A exp(i phi), so x = Re(Z exp(i 2 pi h f t)). t is the time the drive's phase counts from
  (the drive starts at t = 0).
* The lock-in is a least-squares fit of a constant plus cos/sin pairs at every harmonic asked for,
  over whole drive periods only (Bendat & Piersol, *Random Data*, 4th ed., 2010, sec. 11.2: harmonic
  estimation by linear regression); on whole periods the columns are orthogonal to within the
  sampling, so this is the digital lock-in's demodulation Z = (2/T) int x exp(-i w t) dt, exact on a
  sinusoid wherever the samples fall.
* Its error bar is |Z(whole window) - Z(second half of the window)|: a transient still decaying or a
  drift shows as a change between the two, and so does noise, at about sqrt(2) times the whole
  window's standard error (half the samples).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from granchain.exceptions import GranchainError

__all__ = [
    "WINDOWS",
    "Decay",
    "LockIn",
    "SpectraError",
    "Spectrum",
    "SteadyWindow",
    "Transmission",
    "lock_in",
    "spatial_decay",
    "spectrum",
    "steady_window",
    "transmission",
]

#: relative spread of the time steps allowed for a grid to count as uniform (round-off of t = n dt
#: summed in doubles over 1e7 steps stays far below it)
UNIFORM_RTOL = 1e-6
#: the fewest whole drive periods a lock-in uses: its error bar compares the window with its
#: second half, which then still holds a whole period
MIN_PERIODS = 2
#: the fewest samples per period of the highest harmonic a lock-in accepts (Nyquist asks for more
#: than 2; at 4 the cos/sin columns over whole periods are still well conditioned)
MIN_SAMPLES_PER_PERIOD = 4

#: Periodic cosine-sum windows w[n] = sum_k (-1)^k a_k cos(2 pi k n / N) (Harris, Proc. IEEE 66, 51,
#: 1978, Table I; flat top: the HFT coefficients scipy.signal.windows.flattop uses, D'Antona &
#: Ferrero, *Digital Signal Processing for Measurement Systems*, 2006)
WINDOWS: dict[str, tuple[float, ...]] = {
    "boxcar": (1.0,),
    "hann": (0.5, 0.5),
    "hamming": (0.54, 0.46),
    "blackman": (0.42, 0.5, 0.08),
    "flattop": (0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368),
}


class SpectraError(GranchainError, ValueError):
    """A bad argument to a spectra function (non-uniform time grid, too few periods, a frequency
    above Nyquist ...): the message names the argument and the fix."""


@dataclass(frozen=True)
class SteadyWindow:
    """The part of a record a lock-in reads: whole drive periods from ``start``.

    Attributes
    ----------
    start, end : float
        The window's first and last time, s; end - start = periods / frequency.
    periods : int
        The number of whole drive periods in it.
    frequency : float
        The drive's frequency, Hz.
    """

    start: float
    end: float
    periods: int
    frequency: float


@dataclass(frozen=True)
class LockIn:
    """A lock-in's result: each harmonic's amplitude and phase over a steady window, with error bars.

    Attributes
    ----------
    frequency : float
        The drive's frequency f, Hz.
    harmonics : tuple of int
        The harmonics h (of f) measured, in the order of the arrays.
    amplitude, phase : numpy.ndarray
        A_h and phi_h of x = offset + sum_h A_h cos(2 pi h f t + phi_h); phase in radians in (-pi, pi].
    error : numpy.ndarray
        |Z_h(whole window) - Z_h(its last floor(periods / 2) periods)|, Z_h = A_h exp(i phi_h), in
        the unit of x: the amplitude's error bar; the phase's is ``phase_error``.
    offset : float
        The fitted constant (the static part of x over the window).
    residual_rms : float
        The rms of x minus the fit over the window (noise, transients and harmonics not asked for).
    window : SteadyWindow
        The whole periods used.
    samples : int
        The samples in the window.
    """

    frequency: float
    harmonics: tuple[int, ...]
    amplitude: np.ndarray
    phase: np.ndarray
    error: np.ndarray
    offset: float
    residual_rms: float
    window: SteadyWindow
    samples: int

    @property
    def complex_amplitude(self) -> np.ndarray:
        """Z_h = A_h exp(i phi_h) of each harmonic."""
        return self.amplitude * np.exp(1j * self.phase)

    @property
    def phase_error(self) -> np.ndarray:
        """arcsin(error / amplitude), radians (pi where the error bar reaches the amplitude)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(self.amplitude > 0, self.error / self.amplitude, np.inf)
        return np.where(ratio < 1.0, np.arcsin(np.minimum(ratio, 1.0)), math.pi)


@dataclass(frozen=True)
class Transmission:
    """The far amplitude against the drive's: ratio, in dB, its phase lag and error bars.

    Attributes
    ----------
    ratio : float
        A_far / A_drive.
    db : float
        20 log10(ratio) (an amplitude ratio).
    phase : float
        phi_far - phi_drive wrapped into (-pi, pi], radians (0 where amplitudes alone were given).
    ratio_error, db_error : float
        The error bars, from the amplitudes' relative errors added in quadrature (0 without them);
        db_error = 20 / ln(10) ratio_error / ratio.
    """

    ratio: float
    db: float
    phase: float
    ratio_error: float
    db_error: float


@dataclass(frozen=True)
class Decay:
    """An exponential fit A(x) = A0 exp(-rate x) to amplitudes along a chain.

    Attributes
    ----------
    rate : float
        The decay per unit of the positions given (per bead for bead indices, per cell for cell
        indices, per metre for positions in m); negative where the amplitudes grow.
    rate_error : float
        Its standard error, from the residuals of the straight-line fit of ln A (needs 3 points or more).
    db_per_unit : float
        The same decay in dB per unit, 20 rate / ln 10.
    amplitude0 : float
        A0, the fit's amplitude at position 0.
    points : int
        The number of amplitudes fitted.
    """

    rate: float
    rate_error: float
    db_per_unit: float
    amplitude0: float
    points: int


@dataclass(frozen=True)
class Spectrum:
    """A one-sided amplitude spectrum.

    Attributes
    ----------
    frequency : numpy.ndarray
        The bins' frequencies k / (N dt), Hz, k = 0 .. N // 2.
    amplitude : numpy.ndarray
        The amplitude of a sinusoid centred on each bin: 2 |X_k| / sum(w) (|X_0| / sum(w) at 0 and
        at Nyquist for even N), X the DFT of the windowed record.
    window : str
        The window's name (WINDOWS).
    resolution : float
        The bin spacing 1 / (N dt), Hz.
    enbw : float
        The window's equivalent noise bandwidth, N sum(w^2) / sum(w)^2 bins (1 boxcar, 1.5 Hann).
    """

    frequency: np.ndarray
    amplitude: np.ndarray
    window: str
    resolution: float
    enbw: float

    @property
    def peak_frequency(self) -> float:
        """The frequency of the largest bin above 0 Hz."""
        return float(self.frequency[1 + int(np.argmax(self.amplitude[1:]))])


# ------------------------------------------------------------------------- checks


def _uniform_time(t, name: str = "t") -> tuple[np.ndarray, float]:
    """t as a float array and its step, or a SpectraError naming `name` and the fix."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 * MIN_SAMPLES_PER_PERIOD:
        raise SpectraError(
            f"{name}: a 1-D array of at least {2 * MIN_SAMPLES_PER_PERIOD} times is needed, got shape "
            f"{t.shape}; pass the record's sample times"
        )
    if not np.all(np.isfinite(t)):
        raise SpectraError(f"{name}: has NaN or infinite times; drop those samples first")
    steps = np.diff(t)
    dt = float((t[-1] - t[0]) / (t.size - 1))
    if dt <= 0 or np.max(np.abs(steps - dt)) > UNIFORM_RTOL * dt:
        worst = float(np.max(np.abs(steps - dt)) / abs(dt)) if dt else math.inf
        raise SpectraError(
            f"{name}: the sample times are not uniform and increasing (steps differ from their mean by "
            f"{worst:.3g} of it, allowed {UNIFORM_RTOL:g}); resample the record onto a uniform grid "
            "first (numpy.interp)"
        )
    return t, dt


def _samples(x, t: np.ndarray, name: str = "x") -> np.ndarray:
    """x as a float array of t's length, or a SpectraError."""
    x = np.asarray(x, dtype=float)
    if x.shape != t.shape:
        raise SpectraError(f"{name}: has shape {x.shape}, t has {t.shape}; pass one sample per time")
    if not np.all(np.isfinite(x)):
        raise SpectraError(f"{name}: has NaN or infinite samples; drop those samples (and their times) first")
    return x


def _positive(value, name: str, fix: str) -> float:
    """value as a float, or a SpectraError naming `name` and the fix unless positive and finite."""
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise SpectraError(f"{name}: must be a positive finite number, got {value!r}; {fix}")
    return value


# ------------------------------------------------------------------------- the steady window


def steady_window(t, drive_end, frequency, ramp_cycles, transit_time) -> SteadyWindow:
    """The whole drive periods of a record after the drive's ramp and the wave's transit.

    The drive starts at t = 0 and ramps up over `ramp_cycles` periods; a point a wave reaches
    `transit_time` after the drive starts is steady from ramp_cycles / f + transit_time on (the
    latest start of the front's own transient: a damped chain settles sooner, a resonant one
    later, so pass a longer transit where the chain rings). The window holds the most whole periods
    from there that end by the drive's end and the record's.

    Parameters
    ----------
    t : array_like
        The record's sample times, s, uniform.
    drive_end : float or None
        When the drive stops, s; None: it runs past the record's end.
    frequency : float
        The drive's frequency, Hz.
    ramp_cycles : float
        The ramp's length in drive periods (0 without a ramp).
    transit_time : float
        The time the wave takes to reach the point recorded, s (0 at the driven bead).

    Returns
    -------
    SteadyWindow
        start, end, the number of whole periods.

    Raises
    ------
    SpectraError
        A bad argument, or fewer than MIN_PERIODS whole periods after the ramp and transit.
    """
    t, dt = _uniform_time(t)
    f = _positive(frequency, "frequency", "give the drive's frequency in Hz")
    ramp, transit = float(ramp_cycles), float(transit_time)
    if not (math.isfinite(ramp) and ramp >= 0 and math.isfinite(transit) and transit >= 0):
        raise SpectraError(
            f"ramp_cycles = {ramp_cycles!r}, transit_time = {transit_time!r}: both must be finite and >= 0; "
            "give the ramp in drive periods and the transit in seconds"
        )
    end = float(t[-1]) if drive_end is None else min(float(drive_end), float(t[-1]))
    start = max(ramp / f + transit, float(t[0]))
    periods = int(math.floor((end - start) * f * (1 + 1e-12)))
    if periods < MIN_PERIODS:
        raise SpectraError(
            f"t: the record holds {max(periods, 0)} whole drive period(s) between the steady start "
            f"{start:.6g} s (ramp {ramp:g} periods + transit {transit:.6g} s) and {end:.6g} s, at least "
            f"{MIN_PERIODS} are needed; run longer (end time >= {start + MIN_PERIODS / f:.6g} s) or drive longer"
        )
    return SteadyWindow(start, start + periods / f, periods, f)


def _as_window(window, t: np.ndarray, f: float) -> SteadyWindow:
    """A SteadyWindow from lock_in's `window` argument (None, (start, end) or a SteadyWindow)."""
    if isinstance(window, SteadyWindow):
        if not math.isclose(window.frequency, f, rel_tol=1e-12):
            raise SpectraError(
                f"window: was chosen for {window.frequency:g} Hz, the lock-in is at {f:g} Hz; "
                "choose it with steady_window at the lock-in's frequency"
            )
        return window
    if window is None:
        return steady_window(t, None, f, 0.0, float(t[0]) if t[0] > 0 else 0.0)
    try:
        start, end = (float(v) for v in window)
    except (TypeError, ValueError):
        raise SpectraError(
            f"window: {window!r} is not a SteadyWindow, a (start, end) pair or None; pass steady_window's result"
        ) from None
    start, end = max(start, float(t[0])), min(end, float(t[-1]))
    periods = int(math.floor((end - start) * f * (1 + 1e-12)))
    if periods < MIN_PERIODS:
        raise SpectraError(
            f"window: ({start:.6g}, {end:.6g}) s within the record holds {max(periods, 0)} whole period(s) at "
            f"{f:g} Hz, at least {MIN_PERIODS} are needed; widen it or record longer"
        )
    return SteadyWindow(start, start + periods / f, periods, f)


# ------------------------------------------------------------------------- the lock-in


def _fit(t: np.ndarray, x: np.ndarray, omega: float, harmonics) -> tuple[np.ndarray, float, float]:
    """The least-squares fit of c0 + sum_h (a_h cos h w t + b_h sin h w t): (Z_h = a_h - i b_h, c0,
    rms residual)."""
    cols = [np.ones_like(t)] + [f(h * omega * t) for h in harmonics for f in (np.cos, np.sin)]
    basis = np.stack(cols, axis=1)
    coef, *_ = np.linalg.lstsq(basis, x, rcond=None)
    residual = x - basis @ coef
    z = coef[1::2] - 1j * coef[2::2]
    return z, float(coef[0]), float(np.sqrt(np.mean(residual**2)))


def _harmonics(harmonics) -> tuple[int, ...]:
    try:
        hs = tuple(int(h) for h in harmonics)
        ok = len(hs) > 0 and all(h >= 1 for h in hs) and len(set(hs)) == len(hs)
        ok = ok and all(float(h) == float(g) for h, g in zip(hs, harmonics, strict=True))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise SpectraError(
            f"harmonics: {harmonics!r} is not a non-empty sequence of distinct integers >= 1; "
            "pass e.g. (1,) or (1, 2, 3)"
        )
    return hs


def lock_in(t, x, frequency, harmonics=(1,), window=None) -> LockIn:
    """Amplitude and phase of each harmonic of a drive in a record, over whole periods of its steady window.

    The fit is x(t) ~ c0 + sum_h A_h cos(2 pi h f t + phi_h) by least squares over the samples in
    [window.start, window.end), each end moved 1e-9 dt earlier against round-off in t (the module
    docstring says why it is the lock-in's demodulation). Its
    error bar is |Z_h(whole window) - Z_h(its last floor(periods / 2) periods)|, Z_h = A_h exp(i phi_h):
    a transient not yet decayed, a drift, or noise (about sqrt(2) of the whole window's standard
    error) shows in it.

    Parameters
    ----------
    t : array_like
        Sample times, s, uniform; the drive's phase counts from t = 0.
    x : array_like
        The samples (a displacement, velocity, force ...), one per time.
    frequency : float
        The drive's frequency f, Hz.
    harmonics : sequence of int
        The harmonics h of f to measure (1: the drive's own frequency).
    window : SteadyWindow, (start, end) or None
        The steady part of the record (steady_window chooses one); a pair is cut to whole periods
        from its start; None: whole periods from the record's start.

    Returns
    -------
    LockIn
        The amplitudes, phases, error bars, the window used and the fit's offset and rms residual.

    Raises
    ------
    SpectraError
        Non-uniform t, x not matching t, a harmonic at or above the Nyquist frequency 1/(2 dt) (or
        under MIN_SAMPLES_PER_PERIOD samples a period), fewer than MIN_PERIODS whole periods.
    """
    t, dt = _uniform_time(t)
    x = _samples(x, t)
    f = _positive(frequency, "frequency", "give the drive's frequency in Hz")
    hs = _harmonics(harmonics)
    nyquist = 0.5 / dt
    if max(hs) * f * MIN_SAMPLES_PER_PERIOD * dt > 1.0 + 1e-9:
        what = "above the Nyquist frequency" if max(hs) * f >= nyquist else "too close to the Nyquist frequency"
        raise SpectraError(
            f"frequency: harmonic {max(hs)} of {f:g} Hz is {what} {nyquist:g} Hz of the record "
            f"(dt = {dt:g} s); at least {MIN_SAMPLES_PER_PERIOD} samples a period are needed: record with "
            f"dt <= {1.0 / (MIN_SAMPLES_PER_PERIOD * max(hs) * f):.3g} s or ask for lower harmonics"
        )
    win = _as_window(window, t, f)
    inside = (t >= win.start - 1e-9 * dt) & (t < win.end - 1e-9 * dt)
    half_start = win.end - (win.periods // 2) / f
    second = (t >= half_start - 1e-9 * dt) & inside
    if np.count_nonzero(second) < MIN_SAMPLES_PER_PERIOD * max(hs) * (win.periods // 2):
        raise SpectraError(
            f"window: ({win.start:.6g}, {win.end:.6g}) s holds too few samples of the record; pass a window "
            "inside the record's times"
        )
    z, offset, rms = _fit(t[inside], x[inside], 2 * math.pi * f, hs)
    z_half, *_ = _fit(t[second], x[second], 2 * math.pi * f, hs)
    return LockIn(
        frequency=f,
        harmonics=hs,
        amplitude=np.abs(z),
        phase=np.angle(z),
        error=np.abs(z - z_half),
        offset=offset,
        residual_rms=rms,
        window=win,
        samples=int(np.count_nonzero(inside)),
    )


# ------------------------------------------------------------------------- transmission and decay


def _amplitude_of(value, name: str) -> tuple[float, float, float | None]:
    """(amplitude, its error, phase or None) of a LockIn's first harmonic, a complex amplitude or a number."""
    if isinstance(value, LockIn):
        return float(value.amplitude[0]), float(value.error[0]), float(value.phase[0])
    if isinstance(value, complex | np.complexfloating):
        return abs(value), 0.0, float(np.angle(value))
    try:
        amplitude = float(value)
    except (TypeError, ValueError):
        raise SpectraError(
            f"{name}: {value!r} is not a LockIn, a complex amplitude or a number; pass lock_in's result"
        ) from None
    if not (math.isfinite(amplitude) and amplitude >= 0):
        raise SpectraError(f"{name}: amplitude {amplitude!r} must be finite and >= 0; pass an amplitude")
    return amplitude, 0.0, None


def transmission(far, drive) -> Transmission:
    """The transmission far / drive of the first harmonic, linear and in dB, with its phase and error bar.

    Parameters
    ----------
    far, drive : LockIn, complex or float
        The far point's and the drive's (or the first bead's) amplitude: lock_in's result (its first
        harmonic, with its error bar and phase), a complex amplitude, or an amplitude alone.

    Returns
    -------
    Transmission
        ratio = A_far / A_drive, db = 20 log10(ratio), the phase lag, the error bars (the relative
        errors of both amplitudes in quadrature).

    Raises
    ------
    SpectraError
        A value that is none of those, or a drive amplitude of 0.
    """
    (a_far, e_far, p_far), (a_drive, e_drive, p_drive) = _amplitude_of(far, "far"), _amplitude_of(drive, "drive")
    if a_drive == 0:
        raise SpectraError("drive: its amplitude is 0, so no transmission is defined; pass the driven point's record")
    ratio = a_far / a_drive
    rel = math.hypot(e_far / a_far if a_far else 0.0, e_drive / a_drive)
    phase = 0.0 if p_far is None or p_drive is None else float(np.angle(np.exp(1j * (p_far - p_drive))))
    db = 20 * math.log10(ratio) if ratio > 0 else -math.inf
    return Transmission(ratio, db, phase, ratio * rel, 20 / math.log(10) * rel)


def spatial_decay(positions_or_indices, amplitudes) -> Decay:
    """The exponential decay of amplitudes along a chain: a straight-line fit of ln A against position.

    ln A_j = ln A0 - rate x_j by least squares; the rate's standard error is the slope's,
    s / sqrt(sum (x_j - mean x)^2), s^2 the residuals' sum of squares over (points - 2). In a band
    gap of a periodic chain, given cell indices and the amplitudes of one bead per cell, the rate is
    the decay per cell Im(q) of the Bloch wavenumber (granchain.physics.bands).

    Parameters
    ----------
    positions_or_indices : array_like
        Where each amplitude is: bead or cell indices (the rate is then per bead or per cell) or
        positions (per their unit).
    amplitudes : array_like
        The amplitudes there, > 0 (lock_in's amplitude of each bead).

    Returns
    -------
    Decay
        rate, its standard error, dB per unit, A0 and the number of points.

    Raises
    ------
    SpectraError
        Mismatched lengths, fewer than 3 points, amplitudes <= 0 or not finite, repeated positions only.
    """
    x, a = np.asarray(positions_or_indices, dtype=float), np.asarray(amplitudes, dtype=float)
    if x.ndim != 1 or x.shape != a.shape or x.size < 3:
        raise SpectraError(
            f"positions_or_indices, amplitudes: need two 1-D arrays of one length, at least 3 points; got shapes "
            f"{x.shape} and {a.shape}; pass one amplitude per bead or cell"
        )
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(a)) and np.all(a > 0)):
        raise SpectraError(
            "amplitudes: every amplitude must be finite and > 0 (and every position finite) for a fit of ln A; "
            "drop the points where the signal is lost in noise"
        )
    xc = x - x.mean()
    sxx = float(np.sum(xc**2))
    if sxx == 0:
        raise SpectraError("positions_or_indices: all equal; pass the amplitudes at different beads or cells")
    y = np.log(a)
    slope = float(np.sum(xc * (y - y.mean())) / sxx)
    intercept = float(y.mean() - slope * x.mean())
    s = math.sqrt(float(np.sum((y - (intercept + slope * x)) ** 2)) / (x.size - 2))
    rate = -slope
    return Decay(rate, s / math.sqrt(sxx), 20 * rate / math.log(10), math.exp(intercept), int(x.size))


# ------------------------------------------------------------------------- the FFT spectrum


def window_samples(name: str, n: int) -> np.ndarray:
    """The periodic window `name` (WINDOWS) of n samples; a SpectraError for an unknown name."""
    if name not in WINDOWS:
        raise SpectraError(f"window: {name!r} is not one of {', '.join(WINDOWS)}; pass one of those names")
    k = np.arange(n)
    return sum((-1) ** j * a * np.cos(2 * math.pi * j * k / n) for j, a in enumerate(WINDOWS[name]))


def spectrum(t, x, window="hann") -> Spectrum:
    """The one-sided FFT amplitude spectrum of a record, its window and frequency resolution stated.

    amplitude_k = 2 |X_k| / sum(w) with X = rfft(w x), w the periodic window (WINDOWS): a sinusoid
    of amplitude A centred on bin k reads A there (its coherent gain divided out); between bins the
    window's scalloping loss lowers it (Hann: to 0.849 A at worst, flat top: 0.999 A). The bins are
    1 / (N dt) apart: two tones closer than a few bins (the window's main lobe: 2 bins boxcar, 4
    Hann) are not told apart.

    Parameters
    ----------
    t : array_like
        Sample times, s, uniform.
    x : array_like
        The samples, one per time.
    window : str
        One of WINDOWS ("hann" by default; "flattop" for amplitudes between bins, "boxcar" for none).

    Returns
    -------
    Spectrum
        Frequencies, amplitudes, the window's name, the resolution and its equivalent noise bandwidth.

    Raises
    ------
    SpectraError
        Non-uniform t, x not matching t, an unknown window.
    """
    t, dt = _uniform_time(t)
    x = _samples(x, t)
    w = window_samples(window, t.size)
    spec = np.abs(np.fft.rfft(w * x)) / np.sum(w)
    spec[1:] *= 2.0
    if t.size % 2 == 0:
        spec[-1] /= 2.0  # the Nyquist bin has no mirror image
    enbw = float(t.size * np.sum(w**2) / np.sum(w) ** 2)
    return Spectrum(np.fft.rfftfreq(t.size, dt), spec, window, 1.0 / (t.size * dt), enbw)
