"""Raw impact-hammer (tap-test) time signals → receptance FRF.

Each file holds one tap: columns time (s), hammer force and response (acceleration,
velocity or displacement), like ``ImpactTesting_Point1_Channel1_CH1.txt`` of the
leekunhwee data. With X and F the FFTs of the (windowed) response and force of tap k,

    H1 = Σ_k conj(F_k) X_k / Σ_k |F_k|²        (the H1 estimate; = X/F for one tap)
    γ² = |Σ_k conj(F_k) X_k|² / (Σ_k |F_k|² · Σ_k |X_k|²)   (coherence, two taps or more)

then H1 is converted to receptance (accelerance: H = −H1/ω², mobility: H = H1/(iω)).
numpy's forward FFT uses e^{−iωt}, which matches the contract's e^{+iωt} time dependence,
so a damped driving-point receptance comes out with Im H <= 0. The 0 Hz bin is always
dropped (receptance is singular there).

Sample rate: declared (``sample_rate_hz``; then the time column, if any, must agree within
1 %), or taken from the time column. Time stamps are often printed with few digits (the
leekunhwee file: 7 significant digits, ``9.999805e-001``), so one step, or the median step,
is quantised to a unit of the last digit (±0.5 % of the 19.53 µs step there) while the mean
step over the record, (t_last − t_first)/(n − 1), is good to that unit over the whole span
(1e-7 in 1 s). The rate is then the *roundest* number within that uncertainty (fewest
significant digits: 51 200 Hz, not 51 199.9985 Hz), so the frequency lines are exact
multiples of rate/n (1.0, 2.0, … Hz for a 1 s record) and a later request up to 5000 Hz is
not refused for lying 1.5e-4 Hz above a measured 4999.99985 Hz.

Windows (both optional, both recorded in provenance):

* force window ``force_window_s``: the force is kept within ±w/2 of its peak and set to 0
  elsewhere (removes noise in the force channel outside the pulse);
* exponential window ``exponential_tau_s``: force and response are both multiplied by
  exp(−(t − t0)/τ); this adds a known damping σ = 1/τ (1/s) to every mode, not removed here.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from rcsa.errors import InputError
from rcsa.measured.importers._common import decode_text, finish, numeric_rows, read_source
from rcsa.measured.importers.units import parse_signal_unit
from rcsa.measured.store.measurement import Measurement, MeasurementMeta, Provenance
from rcsa.model.bounds import MAX_TAP_SAMPLES

__all__ = ["h1_estimate", "read_tap"]

_QUANTITY = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}
#: A sampling is "uniform" if every step is within 1 % of the mean step, plus one unit of the
#: stamps' last printed digit (7-digit stamps: steps of 19.5 and 19.6 µs around 19.53 µs).
#: A declared sample rate must agree with the time column to 1 % too.
_DT_RTOL = 0.01
#: Time stamps whose digits are counted to find their printing resolution (evenly spread).
_DIGIT_SAMPLE = 257
#: Double-hit test: after the pulse has decayed below 5 % of its peak, a return above 20 %.
_PULSE_END, _SECOND_HIT = 0.05, 0.20
_ROLES = {"t": "t", "time": "t", "force": "force", "f": "force", "response": "response",
          "acc": "response", "a": "response", "x": "response", "_": "skip", "skip": "skip"}  # fmt: skip


def _double_hit(force: np.ndarray, dt: float) -> str | None:
    a = np.abs(force)
    peak = int(np.argmax(a))
    below = np.flatnonzero(a[peak:] < _PULSE_END * a[peak])
    if below.size == 0:
        return None
    after = peak + int(below[0])
    again = np.flatnonzero(a[after:] > _SECOND_HIT * a[peak])
    if again.size == 0:
        return None
    i = after + int(again[0])
    return f"a second force pulse at t = {i * dt:.6g} s reaches {a[i] / a[peak]:.0%} of the first"


def _stamp_digits(t: np.ndarray) -> int:
    """Significant digits the stamps were printed with (the most any sampled stamp needs)."""
    idx = np.unique(np.linspace(0, t.size - 1, min(t.size, _DIGIT_SAMPLE)).astype(int))
    digits = 1
    for x in (float(v) for v in t[idx]):
        while x != 0.0 and digits < 17 and float(f"{x:.{digits - 1}e}") != x:
            digits += 1
    return digits


def _last_digit_unit(x: float, digits: int) -> float:
    """One unit of the last printed digit of ``x`` (at least its float spacing)."""
    if x == 0.0:
        return 0.0
    return max(float(10.0 ** (np.floor(np.log10(abs(x))) - digits + 1)), float(np.spacing(abs(x))))


def roundest_within(x: float, tolerance: float) -> float:
    """The number with the fewest significant digits within ``tolerance`` of ``x`` > 0.

    >>> roundest_within(51199.99847, 0.0052)
    51200.0
    >>> roundest_within(12345.6781, 0.0012)
    12345.678
    """
    k = int(np.floor(np.log10(x))) + 1
    while True:
        cand = float(f"{round(x / 10.0**k)}e{k}")  # the decimal, then its nearest double
        if abs(cand - x) <= tolerance:
            return cand
        k -= 1


def sample_rate_from_time(t: np.ndarray, where: str = "") -> tuple[float, str]:
    """Sample rate of a time column, Hz, and how it was found (module docstring).

    Raises
    ------
    InputError
        Field ``t``: fewer than 8 samples, not increasing, or not uniform.
    """
    steps = np.diff(t)
    if t.size < 8 or np.any(steps <= 0):
        raise InputError("t", f"{where}time must be strictly increasing (and at least 8 samples)")
    digits = _stamp_digits(t)
    unit = max(_last_digit_unit(float(t[0]), digits), _last_digit_unit(float(t[-1]), digits))
    span = float(t[-1] - t[0])
    dt = span / (t.size - 1)
    bad = np.flatnonzero(np.abs(steps - dt) > _DT_RTOL * dt + unit)
    if bad.size:
        i = int(bad[0])
        raise InputError(
            "t",
            f"{where}the sampling is not uniform: step {i + 1} (t = {t[i]:.9g} s) is "
            f"{steps[i]:.6g} s, the mean step {dt:.6g} s (more than 1 % apart); a missing or "
            "repeated sample?",
        )
    estimate = 1.0 / dt
    # the stamps' rounding (half a unit at each end) over the span, plus float arithmetic
    tolerance = estimate * unit / span + 8 * float(np.spacing(estimate))
    rate = roundest_within(estimate, tolerance)
    how = (
        f"sample rate {rate:.12g} Hz from the time column (mean step over {t.size} stamps of "
        f"{digits} significant digits: {estimate:.12g} Hz +/- {tolerance:.2g})"
    )
    return rate, how


def h1_estimate(
    force: Sequence[np.ndarray], response: Sequence[np.ndarray], dt_s: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """H1 FRF (response per force, in the signals' units) of one or more taps.

    Parameters
    ----------
    force, response : sequence of numpy.ndarray, each shape (nsamples,)
        Windowed signals of each tap, equal lengths.
    dt_s : float
        Sampling interval, s.

    Returns
    -------
    frequency_hz : numpy.ndarray, shape (nsamples // 2 + 1,)
        FFT bins, Hz, starting at 0.
    h1 : numpy.ndarray, complex, same shape
    coherence : numpy.ndarray or None
        None for a single tap (coherence is 1 by construction).
    """
    n = force[0].size
    sff = np.zeros(n // 2 + 1)
    sxx = np.zeros(n // 2 + 1)
    sfx = np.zeros(n // 2 + 1, dtype=np.complex128)
    for fk, xk in zip(force, response, strict=True):
        F, X = np.fft.rfft(fk), np.fft.rfft(xk)
        sff += np.abs(F) ** 2
        sxx += np.abs(X) ** 2
        sfx += np.conj(F) * X
    with np.errstate(divide="ignore", invalid="ignore"):
        h1 = sfx / sff
        coh = np.abs(sfx) ** 2 / (sff * sxx) if len(force) > 1 else None
    return np.fft.rfftfreq(n, dt_s), h1, coh


def read_tap(
    sources: str | os.PathLike[str] | bytes | Sequence[str | os.PathLike[str] | bytes],
    meta: MeasurementMeta,
    *,
    force_unit: str,
    response_unit: str,
    columns: str = "t,force,response",
    sample_rate_hz: float | None = None,
    force_window_s: float | None = None,
    exponential_tau_s: float | None = None,
    max_frequency_hz: float | None = None,
    allow_double_hit: bool = False,
    sensor_mass_kg: float | None = None,
    file_name: str = "",
) -> Measurement:
    """Import one or more raw taps as a ``direct_frf`` receptance (H1 estimate).

    Parameters
    ----------
    sources : path or bytes, or a sequence of them
        One file per tap, all with the same sampling and length.
    meta : MeasurementMeta
        ``meta.kind`` must be ``direct_frf``.
    force_unit : str
        ``N``, ``lbf``, ``kN`` …
    response_unit : str
        ``m/s^2``, ``g``, ``m/s``, ``m``, ``um`` … (decides the quantity).
    columns : str
        One token per column: ``t``, ``force``, ``response`` (alias ``acc``) or ``_``.
    sample_rate_hz : float, optional
        Declared sampling rate, Hz (CLI ``--sample-rate-hz``, form field ``sample_rate_hz``);
        checked against the time column (±1 %), which may then be absent. Default: from the
        time column (module docstring).
    force_window_s, exponential_tau_s : float, optional
        Windows, s (module docstring).
    max_frequency_hz : float, optional
        Keep bins up to this frequency, Hz.
    allow_double_hit : bool
        Accept a tap whose force shows a second pulse.
    sensor_mass_kg : float, optional
        Remove this accelerometer mass (driving point).
    file_name : str
        Name recorded when a single ``sources`` is bytes.
    """
    if meta.kind != "direct_frf":
        raise InputError(
            "kind",
            f"a tap test gives one driving-point FRF: kind must be direct_frf, not {meta.kind!r}",
        )
    fu, ru = (
        parse_signal_unit(force_unit, "force_unit"),
        parse_signal_unit(response_unit, "response_unit"),
    )
    if fu.kind != "force":
        raise InputError("force_unit", f"{force_unit!r} is not a force unit")
    if ru.kind == "force":
        raise InputError(
            "response_unit",
            f"{response_unit!r} is a force; give the response's unit (e.g. m/s^2, g)",
        )
    roles = [_ROLES.get(t.strip().lower()) for t in columns.split(",")]
    if (
        None in roles
        or roles.count("force") != 1
        or roles.count("response") != 1
        or roles.count("t") > 1
    ):
        raise InputError(
            "columns",
            f"{columns!r}: declare one force and one response column (t optional), e.g. t,force,response",
        )
    if "t" not in roles and sample_rate_hz is None:
        raise InputError("sample_rate_hz", "is required when there is no time column")
    if sample_rate_hz is not None and not (np.isfinite(sample_rate_hz) and sample_rate_hz > 0):
        raise InputError("sample_rate_hz", f"must be a rate > 0 Hz, got {sample_rate_hz!r}")
    srcs = (
        [sources] if isinstance(sources, str | bytes | bytearray | os.PathLike) else list(sources)
    )
    if not srcs:
        raise InputError("file", "no tap file given")
    forces: list[np.ndarray] = []
    responses: list[np.ndarray] = []
    names: list[str] = []
    shas: list[str] = []
    rate: float | None = None
    rate_how = ""
    for k, src in enumerate(srcs):
        data, name, sha = read_source(src, file_name if len(srcs) == 1 else "")
        label = name or f"tap {k + 1}"
        rows, lines = numeric_rows(decode_text(data), max_rows=MAX_TAP_SAMPLES)
        bad = next(
            (ln for row, ln in zip(rows, lines, strict=True) if len(row) != len(roles)), None
        )
        if bad is not None:
            raise InputError(
                "columns",
                f"{label} line {bad}: expected {len(roles)} values ({columns!r})",
            )
        table = np.array(rows, dtype=float)
        if not np.all(np.isfinite(table)):
            raise InputError("file", f"{label} contains NaN or infinite values")
        col = {r: table[:, i] for i, r in enumerate(roles) if r != "skip"}
        if "t" in col:
            rate_k, how = sample_rate_from_time(col["t"], f"{label}: ")
            if sample_rate_hz is not None:
                if abs(sample_rate_hz / rate_k - 1) > _DT_RTOL:
                    raise InputError(
                        "sample_rate_hz",
                        f"{label}: {sample_rate_hz:g} Hz was declared but the time column gives "
                        f"{rate_k:.12g} Hz",
                    )
                how = f"sample rate {sample_rate_hz:.12g} Hz (declared; the time column gives {rate_k:.12g} Hz)"
                rate_k = float(sample_rate_hz)
        else:
            rate_k, how = float(sample_rate_hz), f"sample rate {sample_rate_hz:.12g} Hz (declared)"  # type: ignore[arg-type]
        if rate is not None and (rate_k != rate or table.shape[0] != forces[0].size):
            raise InputError(
                "file",
                f"{label}: all taps need the same sampling rate and length "
                f"({rate_k:.12g} Hz x {table.shape[0]} vs {rate:.12g} Hz x {forces[0].size})",
            )
        rate, rate_how = rate_k, how
        dt = 1.0 / rate
        force, resp = col["force"] * fu.factor_to_si, col["response"] * ru.factor_to_si
        if not allow_double_hit and (msg := _double_hit(force, dt)):
            raise InputError(
                "force", f"{name}: double hit: {msg}; repeat the tap or pass allow_double_hit=True"
            )
        forces.append(force)
        responses.append(resp)
        names.append(name)
        shas.append(sha)

    n = forces[0].size
    t = np.arange(n) * dt
    steps = [f"H1 estimate from {len(srcs)} tap(s), {n} samples; {rate_how}"]
    if force_window_s is not None:
        if not force_window_s > 0:
            raise InputError("force_window_s", "must be > 0 s")
        for k, fk in enumerate(forces):
            t_peak = t[int(np.argmax(np.abs(fk)))]
            forces[k] = np.where(np.abs(t - t_peak) <= force_window_s / 2, fk, 0.0)
        steps.append(f"force window +/-{force_window_s / 2:g} s around the peak")
    if exponential_tau_s is not None:
        if not exponential_tau_s > 0:
            raise InputError("exponential_tau_s", "must be > 0 s")
        w = np.exp(-t / exponential_tau_s)
        forces = [fk * w for fk in forces]
        responses = [xk * w for xk in responses]
        steps.append(
            f"exponential window tau={exponential_tau_s:g} s on force and response (adds damping {1 / exponential_tau_s:g} 1/s)"
        )
    assert rate is not None  # srcs is not empty
    _, h1, coh = h1_estimate(forces, responses, dt)
    freq = np.arange(h1.size) * rate / n  # k * rate / n: exact for an integer rate
    keep = freq > 0
    if max_frequency_hz is not None:
        keep &= freq <= max_frequency_hz
    steps.append(
        "0 Hz bin dropped"
        + (f"; kept f <= {max_frequency_hz:g} Hz" if max_frequency_hz is not None else "")
    )
    prov = Provenance(
        source_format="tap",
        source_file=", ".join(names),
        source_sha256=shas[0] if len(shas) == 1 else "",
        original_quantity=_QUANTITY[ru.kind],
        original_units=f"{ru.text} per {fu.text}",
        conversions=tuple(steps)
        + (
            ()
            if len(shas) == 1
            else tuple(f"sha256 {n_}: {s}" for n_, s in zip(names, shas, strict=True))
        ),
    )
    return finish(
        freq[keep],
        {"h": h1[keep]},
        quantity=_QUANTITY[ru.kind],
        meta=meta,
        provenance=prov,
        coherence={"h": np.clip(coh[keep], 0.0, 1.0)} if coh is not None else None,
        sensor_mass_kg=sensor_mass_kg,
        bound_hint="above the hammer's band the force spectrum is too weak for H1: limit the "
        "band with max_frequency_hz (CLI --max-frequency-hz)",
    )
