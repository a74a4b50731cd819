"""Stability lobe diagrams for milling: the Altintas–Budak zero-order (ZOA) solution.

The dynamic milling system is averaged over one tooth period (zero-order Fourier term of
the directional factors) and the characteristic equation is solved in closed form for
every chatter frequency at once (Altintas & Budak 1995; Altintas 2012, §4.4).

Conventions
-----------
* Tool-point direct receptances ``Φxx``, ``Φyy`` in m/N, time dependence ``exp(i ω t)``
  (a damped receptance has ``Im Φ <= 0``), cross terms neglected (as in the paper).
* x is the feed direction, y is normal to it; the tool turns clockwise and the immersion
  angle φ is measured clockwise from +y. Up-milling enters at ``φst = 0``; down-milling
  leaves at ``φex = π``.
* Arrays are frequency-first, ``(nfreq,)``; speed grids are ``(nspeed,)``.

Algorithm (readable form; the code is the vectorised equivalent)::

    for each chatter frequency ω (a grid point of the FRF):
        Φ0 = [[αxx Φxx, αxy Φyy], [αyx Φxx, αyy Φyy]]       # oriented FRF
        a0 = Φxx Φyy (αxx αyy − αxy αyx);  a1 = αxx Φxx + αyy Φyy
        for each root Λ of a0 Λ² + a1 Λ + 1 = 0:                # Λ = −1/eig(Φ0)
            κ = ΛI/ΛR;  b = −2π ΛR (1 + κ²)/(N Kt)            # keep b > 0 (ΛR < 0)
            ε = π − 2 atan(κ)                                   # in (0, 2π)
            for k in lobes: n_k = 60 ω / (N (ε + 2kπ))          # rpm

Request bodies of the service/CLI are validated by :mod:`rcsa.analysis.lobes.request`.

References
----------
.. [1] Y. Altintas, E. Budak, "Analytical prediction of stability lobes in milling",
   CIRP Annals 44(1):357–362, 1995.
.. [2] Y. Altintas, *Manufacturing Automation*, 2nd ed., Cambridge University Press,
   2012, §4.4 (zero-order solution of milling stability).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal, NamedTuple

import numpy as np

from rcsa.errors import InputError
from rcsa.model import fields
from rcsa.model.bounds import (
    MAX_CUTTING_COEFFICIENT_N_M2,
    MAX_RADIAL_RATIO,
    MAX_SPEED_COUNT,
    MAX_SPEED_RPM,
    MAX_TEETH,
    MIN_CUTTING_COEFFICIENT_N_M2,
    MIN_RADIAL_IMMERSION,
    MIN_SPEED_RPM,
)
from rcsa.model.wire import json_float, json_list
from rcsa.physics.receptance import check_frequency_hz

__all__ = [
    "check_speed_grid",
    "MIN_LINES_PER_HALF_POWER_BAND",
    "frf_grid_notes",
    "MAX_AUTO_LOBES",
    "MAX_SPEED_COUNT",
    "MAX_TEETH",
    "Cut",
    "Lobe",
    "LobeResult",
    "Milling",
    "check_cut",
    "check_frf",
    "depth_limit_envelopes",
    "directional_factors",
    "engagement_angles_rad",
    "stability_lobes",
    "zoa_depth_limit",
]

Milling = Literal["up", "down"]

# MAX_SPEED_COUNT (largest spindle-speed grid) and MAX_TEETH live with every other request
# bound in rcsa.model.bounds.
#: Upper bound on the number of lobes, automatic or requested.
MAX_AUTO_LOBES = 200


class Cut(NamedTuple):
    """The cutting parameters of a lobe diagram, checked (:func:`check_cut`)."""

    teeth: int
    tangential_coefficient_n_m2: float
    radial_ratio: float
    radial_immersion: float
    milling: Milling


def check_cut(teeth: object, tangential_coefficient_n_m2: object, radial_ratio: object,
              radial_immersion: object, milling: object) -> Cut:
    """Check the cutting parameters (bounds in :mod:`rcsa.model.bounds`).

    Raises
    ------
    InputError
        Naming the field: ``teeth`` an integer in 1…``MAX_TEETH``, ``Kt > 0``,
        ``Kr >= 0``, ``0 < a_e/D <= 1``, ``milling`` up or down.
    """
    return Cut(fields.integer(teeth, "teeth", ge=1, le=MAX_TEETH),
               fields.number(tangential_coefficient_n_m2, "tangential_coefficient_n_m2", gt=0.0,
                             ge=MIN_CUTTING_COEFFICIENT_N_M2, le=MAX_CUTTING_COEFFICIENT_N_M2),
               fields.number(radial_ratio, "radial_ratio", ge=0.0, le=MAX_RADIAL_RATIO),
               _immersion(radial_immersion),
               fields.string(milling, "milling", choices=("up", "down")))  # type: ignore[arg-type]


# --------------------------------------------------------------------------- geometry


def engagement_angles_rad(radial_immersion: float, milling: Milling) -> tuple[float, float]:
    """Entry and exit angles of a tooth for a radial immersion ``a_e / D``.

    Parameters
    ----------
    radial_immersion : float
        Radial depth of cut over tool diameter, ``0 < a_e/D <= 1`` (1 = slotting).
    milling : {"up", "down"}
        Up-milling enters at φ = 0; down-milling leaves at φ = π.

    Returns
    -------
    phi_start_rad, phi_exit_rad : float
        Angles measured clockwise from +y, rad.

    References
    ----------
    Altintas (2012) §2.4: up-milling ``φst = 0, φex = arccos(1 − 2a_e/D)``; down-milling
    ``φst = arccos(2a_e/D − 1), φex = π``.

    Examples
    --------
    >>> [round(a, 6) for a in engagement_angles_rad(0.5, "down")]
    [1.570796, 3.141593]
    """
    a = _immersion(radial_immersion)
    if milling == "up":
        return 0.0, float(math.acos(1.0 - 2.0 * a))
    if milling == "down":
        return float(math.acos(2.0 * a - 1.0)), math.pi
    raise InputError("milling", f"must be 'up' or 'down', got {milling!r}")


def directional_factors(
    phi_start_rad: float, phi_exit_rad: float, radial_ratio: float
) -> np.ndarray:
    """Time-averaged directional factors ``[[αxx, αxy], [αyx, αyy]]`` (dimensionless).

    Parameters
    ----------
    phi_start_rad, phi_exit_rad : float
        Entry and exit angles, rad (see :func:`engagement_angles_rad`).
    radial_ratio : float
        ``Kr = Kn/Kt``, radial (normal) over tangential cutting coefficient.

    Returns
    -------
    numpy.ndarray, shape (2, 2)

    References
    ----------
    Altintas & Budak (1995), eq. (8); Altintas (2012) §4.4::

        αxx = ½ [ cos2φ − 2Kr φ + Kr sin2φ ]   αxy = ½ [ −sin2φ − 2φ + Kr cos2φ ]
        αyx = ½ [ −sin2φ + 2φ + Kr cos2φ ]     αyy = ½ [ −cos2φ − 2Kr φ − Kr sin2φ ]

    each evaluated between ``φst`` and ``φex``.

    Examples
    --------
    Slotting gives ``[[−π Kr, −π], [π, −π Kr]]``:

    >>> np.round(directional_factors(0.0, np.pi, 0.5) / np.pi, 12)
    array([[-0.5, -1. ],
           [ 1. , -0.5]])
    """
    kr = float(radial_ratio)

    def antiderivative(phi: float) -> np.ndarray:
        c2, s2 = math.cos(2.0 * phi), math.sin(2.0 * phi)
        return np.array(
            [
                [c2 - 2.0 * kr * phi + kr * s2, -s2 - 2.0 * phi + kr * c2],
                [-s2 + 2.0 * phi + kr * c2, -c2 - 2.0 * kr * phi - kr * s2],
            ]
        )

    return 0.5 * (antiderivative(phi_exit_rad) - antiderivative(phi_start_rad))


# --------------------------------------------------------------------------- ZOA core


def _oriented_eigenvalues(alpha: np.ndarray, frf_xx: np.ndarray, frf_yy: np.ndarray) -> np.ndarray:
    """Eigenvalues of the oriented FRF ``α · diag(Φxx, Φyy)``, shape (..., nfreq, 2).

    Closed form of ``λ² − a1 λ + a0 = 0``; the square root is kept on one continuous
    branch along frequency (the last axis of the FRFs; so a column follows one eigenvalue
    curve), and the smaller root is taken from Vieta's ``λ1 λ2 = a0`` to avoid cancellation
    when ``a0 → 0`` (one flexible direction, or ``det α = 0``).
    """
    a1 = alpha[0, 0] * frf_xx + alpha[1, 1] * frf_yy
    a0 = (alpha[0, 0] * alpha[1, 1] - alpha[0, 1] * alpha[1, 0]) * frf_xx * frf_yy
    s = np.sqrt(a1 * a1 - 4.0 * a0)
    # Principal sqrt jumps sign across its branch cut: flip back where consecutive values
    # point in opposite directions (the vectorised form of tracking eigenvalue curves).
    flip = np.ones(s.shape)
    flip[..., 1:] = np.where((s[..., 1:] * np.conj(s[..., :-1])).real < 0.0, -1.0, 1.0)
    s = s * np.cumprod(flip, axis=-1)
    plus, minus = 0.5 * (a1 + s), 0.5 * (a1 - s)
    plus_is_big = np.abs(plus) >= np.abs(minus)
    big = np.where(plus_is_big, plus, minus)
    with np.errstate(divide="ignore", invalid="ignore"):
        small = np.where(big != 0, a0 / big, 0.0)
    lam1 = np.where(plus_is_big, big, small)
    lam2 = np.where(plus_is_big, small, big)
    return np.stack([lam1, lam2], axis=-1)


def zoa_depth_limit(
    frf_xx: np.ndarray,
    frf_yy: np.ndarray,
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    alpha: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Limiting axial depth and phase ε per chatter frequency and eigenvalue.

    Parameters
    ----------
    frf_xx, frf_yy : numpy.ndarray, shape (nfreq,)
        Direct receptances at the tool point, m/N, complex.
    teeth : int
        Number of teeth ``N``.
    tangential_coefficient_n_m2 : float
        ``Kt``, N/m².
    alpha : numpy.ndarray, shape (2, 2)
        Directional factors (:func:`directional_factors`).

    Returns
    -------
    depth_limit_m : numpy.ndarray, shape (nfreq, 2)
        ``b_lim = −2π ΛR (1 + κ²)/(N Kt)``, m; NaN where it is not positive (no chatter
        possible at that frequency on that eigenvalue).
    epsilon_rad : numpy.ndarray, shape (nfreq, 2)
        Phase between inner and outer modulations ``ε = π − 2 atan κ``, in (0, 2π), rad.

    References
    ----------
    Altintas & Budak (1995) eqs. (12)–(16); Altintas (2012) §4.4.
    """
    lam = _oriented_eigenvalues(alpha, frf_xx, frf_yy)
    with np.errstate(divide="ignore", invalid="ignore"):
        big_lambda = -1.0 / lam  # roots of a0 Λ² + a1 Λ + 1 = 0
        lr, li = big_lambda.real, big_lambda.imag
        kappa = li / lr
        depth = -2.0 * np.pi * lr * (1.0 + kappa * kappa) / (teeth * tangential_coefficient_n_m2)
    valid = np.isfinite(depth) & (lr < 0.0) & (depth > 0.0)
    depth = np.where(valid, depth, np.nan)
    epsilon = np.where(valid, np.pi - 2.0 * np.arctan(np.where(valid, kappa, 0.0)), np.nan)
    return depth, epsilon


def _lobe_speed_rpm(
    frequency_hz: np.ndarray, epsilon_rad: np.ndarray, teeth: int, k: int
) -> np.ndarray:
    """Spindle speed of lobe ``k``: ``n = 60 ω_c / (N (ε + 2kπ))``, rpm."""
    return 60.0 * 2.0 * np.pi * frequency_hz / (teeth * (epsilon_rad + 2.0 * np.pi * k))


def _curve_on_grid(
    speed_rpm: np.ndarray, depth_m: np.ndarray, frequency_hz: np.ndarray, grid_rpm: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample a polyline (ordered by frequency) at every grid speed it spans.

    Each pair of consecutive valid points is a straight segment in the (speed, depth)
    plane; every grid speed inside a segment's speed interval gets the linearly
    interpolated depth and chatter frequency. Returns ``(grid_index, depth, freq)`` for
    all (segment, grid point) pairs — vectorised with ``np.repeat`` instead of a loop.
    """
    ok = np.isfinite(depth_m)
    i = np.flatnonzero(ok[:-1] & ok[1:])
    n0, n1 = speed_rpm[i], speed_rpm[i + 1]
    j_lo = np.searchsorted(grid_rpm, np.minimum(n0, n1), side="left")
    j_hi = np.searchsorted(grid_rpm, np.maximum(n0, n1), side="right")
    counts = np.maximum(j_hi - j_lo, 0)
    seg = np.repeat(np.arange(i.size), counts)
    start = np.cumsum(counts) - counts
    j = j_lo[seg] + np.arange(seg.size) - start[seg]
    dn = (n1 - n0)[seg]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(dn != 0.0, (grid_rpm[j] - n0[seg]) / dn, 0.0)
    b = depth_m[i][seg] + t * (depth_m[i + 1] - depth_m[i])[seg]
    f = frequency_hz[i][seg] + t * (frequency_hz[i + 1] - frequency_hz[i])[seg]
    return j, b, f


def _needs_more_lobes(
    frequency_hz: np.ndarray,
    depth_m: np.ndarray,
    epsilon_rad: np.ndarray,
    teeth: int,
    lobes_count: int,
    grid_rpm: np.ndarray,
    envelope_m: np.ndarray,
) -> np.ndarray:
    """Grid speeds where an uncomputed lobe (``k >= lobes_count``) could be lower.

    Lobes ``k >= K`` map a chatter frequency ω only to speeds ``<= n_K(ω)``. At speed
    ``s`` the omitted points therefore have depths ``{b(ω) : n_K(ω) >= s}``; if the
    smallest is below the envelope, the envelope there is not the true limit (it would
    overstate stability) and is withdrawn. Point-wise bound, vectorised with a running
    minimum over points sorted by ``n_K``.
    """
    ok = np.isfinite(depth_m)
    n_next = np.stack(
        [_lobe_speed_rpm(frequency_hz, epsilon_rad[:, e], teeth, lobes_count) for e in range(2)],
        axis=1,
    )[ok]
    b = depth_m[ok]
    order = np.argsort(n_next)
    n_sorted = n_next[order]
    # running minimum of b over points in decreasing speed order
    b_desc_min = np.minimum.accumulate(b[order][::-1])
    count_at_or_above = n_sorted.size - np.searchsorted(n_sorted, grid_rpm, side="left")
    missing_min = np.where(
        count_at_or_above > 0, b_desc_min[np.maximum(count_at_or_above - 1, 0)], np.inf
    )
    return np.isfinite(envelope_m) & (missing_min < envelope_m)


def _min_per_index(
    j: np.ndarray, b: np.ndarray, f: np.ndarray, size: int
) -> tuple[np.ndarray, np.ndarray]:
    """Smallest ``b`` (and its ``f``) for each grid index; NaN where none."""
    depth = np.full(size, np.nan)
    freq = np.full(size, np.nan)
    if j.size:
        order = np.lexsort((b, j))
        js = j[order]
        first = np.ones(js.size, dtype=bool)
        first[1:] = js[1:] != js[:-1]
        depth[js[first]] = b[order][first]
        freq[js[first]] = f[order][first]
    return depth, freq


# --------------------------------------------------------------------------- result


class Lobe(NamedTuple):
    """One stability lobe sampled on the requested speed grid (where it exists)."""

    index: int
    """Lobe number ``k`` (number of whole waves between consecutive teeth)."""
    spindle_speed_rpm: np.ndarray
    """Speeds covered by this lobe, rpm, shape (m,)."""
    depth_limit_m: np.ndarray
    """Lower envelope of this lobe's branches at those speeds, m, shape (m,)."""


@dataclass(frozen=True, slots=True)
class LobeResult:
    """Stability lobe diagram.

    Attributes
    ----------
    spindle_speed_rpm : numpy.ndarray, shape (nspeed,)
        Requested speed grid, rpm.
    depth_limit_m : numpy.ndarray, shape (nspeed,)
        Lower envelope over all lobes, m; NaN where no computed lobe reaches the speed,
        or where a lobe beyond ``n_lobes`` could be lower (never an optimistic value).
    chatter_frequency_hz : numpy.ndarray, shape (nspeed,)
        Chatter frequency of the governing lobe, Hz (NaN where uncovered).
    governing_lobe : numpy.ndarray, shape (nspeed,)
        Index ``k`` of the governing lobe, ``-1`` where uncovered.
    lobes : tuple of Lobe
        Each lobe on the speed grid, ``k = 0 .. n_lobes − 1``.
    same_frf_in_y : bool
        True when no y receptance was given and ``Φyy = Φxx`` was assumed.
    min_depth_limit_m : float
        Absolute stability limit: smallest ``b_lim`` over all chatter frequencies, m
        (independent of the speed grid).
    min_depth_chatter_frequency_hz : float
        Chatter frequency at that minimum, Hz.
    min_depth_spindle_speed_rpm : numpy.ndarray, shape (n_lobes,)
        Speed at which lobe ``k`` reaches ``min_depth_limit_m``, rpm.
    """

    spindle_speed_rpm: np.ndarray
    depth_limit_m: np.ndarray
    chatter_frequency_hz: np.ndarray
    governing_lobe: np.ndarray
    lobes: tuple[Lobe, ...]
    same_frf_in_y: bool
    min_depth_limit_m: float
    min_depth_chatter_frequency_hz: float
    min_depth_spindle_speed_rpm: np.ndarray

    def __post_init__(self) -> None:
        for name in (
            "spindle_speed_rpm",
            "depth_limit_m",
            "chatter_frequency_hz",
            "governing_lobe",
            "min_depth_spindle_speed_rpm",
        ):
            getattr(self, name).flags.writeable = False

    @property
    def n_lobes(self) -> int:
        """Number of lobes computed."""
        return len(self.lobes)

    @classmethod
    def from_dict(cls, doc: object) -> LobeResult:
        """A result read back from its JSON form (:meth:`to_dict`, or the contract's fields alone).

        ``null`` is read as NaN. Without ``min_depth_limit_m`` (a result written by another
        program) the envelope's lowest value on the speed grid stands in for the absolute limit.

        Parameters
        ----------
        doc : dict
            ``spindle_speed_rpm``, ``depth_limit_m``, ``chatter_frequency_hz`` (lists, one
            value per speed) and ``lobes`` (``index``, ``spindle_speed_rpm``, ``depth_limit_m``).

        Returns
        -------
        LobeResult

        Raises
        ------
        InputError
            Naming the field that is missing, not a list of numbers, or of another length.
        """
        if not isinstance(doc, dict):
            raise InputError("", "a stability-lobes result must be a JSON object")
        speed = _result_array(doc, "spindle_speed_rpm")
        n = speed.size
        depth = _result_array(doc, "depth_limit_m", n)
        chatter = _result_array(doc, "chatter_frequency_hz", n)
        if not isinstance(doc.get("lobes", []), list):
            raise InputError("lobes", "must be a list of {index, spindle_speed_rpm, depth_limit_m}")
        lobes = []
        for i, raw in enumerate(doc.get("lobes", [])):
            if not isinstance(raw, dict) or isinstance(raw.get("index"), bool) or not isinstance(raw.get("index"), int):
                raise InputError(f"lobes[{i}]", "must be an object {index, spindle_speed_rpm, depth_limit_m}")
            lobe_speed = _result_array(raw, "spindle_speed_rpm", where=f"lobes[{i}].")
            lobes.append(Lobe(raw["index"], lobe_speed,
                              _result_array(raw, "depth_limit_m", lobe_speed.size, where=f"lobes[{i}].")))
        governing = doc.get("governing_lobe")
        governing_lobe = (np.array(governing, dtype=int) if isinstance(governing, list) and len(governing) == n
                          else np.full(n, -1))
        given_min = doc.get("min_depth_limit_m")
        finite = depth[np.isfinite(depth)]
        min_depth = (float(given_min) if isinstance(given_min, int | float) and not isinstance(given_min, bool)
                     else float(finite.min()) if finite.size else math.nan)
        min_chatter = doc.get("min_depth_chatter_frequency_hz")
        min_speeds = doc.get("min_depth_spindle_speed_rpm")
        return cls(speed, depth, chatter, governing_lobe, tuple(lobes), doc.get("frf_y_source") == "same_as_x",
                   min_depth, float(min_chatter) if isinstance(min_chatter, int | float) else math.nan,
                   np.array([math.nan if v is None else v for v in min_speeds], dtype=float)
                   if isinstance(min_speeds, list) else np.full(len(lobes), math.nan))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready response (contract "Stability lobes"), NaN written as ``None``.

        Contract fields: ``spindle_speed_rpm``, ``depth_limit_m`` (lower envelope),
        ``chatter_frequency_hz``, ``lobes`` (``index``, ``spindle_speed_rpm``,
        ``depth_limit_m``). Extra fields: ``frf_y_source`` (``"same_as_x"`` or
        ``"given"``), ``min_depth_limit_m``, ``min_depth_chatter_frequency_hz``,
        ``min_depth_spindle_speed_rpm`` and ``governing_lobe``.
        """
        return {
            "spindle_speed_rpm": json_list(self.spindle_speed_rpm),
            "depth_limit_m": json_list(self.depth_limit_m),
            "chatter_frequency_hz": json_list(self.chatter_frequency_hz),
            "lobes": [
                {
                    "index": lobe.index,
                    "spindle_speed_rpm": json_list(lobe.spindle_speed_rpm),
                    "depth_limit_m": json_list(lobe.depth_limit_m),
                }
                for lobe in self.lobes
            ],
            "frf_y_source": "same_as_x" if self.same_frf_in_y else "given",
            "min_depth_limit_m": json_float(self.min_depth_limit_m),
            "min_depth_chatter_frequency_hz": json_float(self.min_depth_chatter_frequency_hz),
            "min_depth_spindle_speed_rpm": json_list(self.min_depth_spindle_speed_rpm),
            "governing_lobe": [int(k) for k in self.governing_lobe],
        }


def _result_array(doc: dict[str, Any], key: str, n: int | None = None, where: str = "") -> np.ndarray:
    """A list of numbers (``null`` as NaN) of a result document, of length ``n`` when given."""
    raw = doc.get(key)
    if not isinstance(raw, list) or not all(v is None or (isinstance(v, int | float) and not isinstance(v, bool))
                                            for v in raw):
        raise InputError(where + key, "must be a list of numbers (null where there is no value)")
    if n is not None and len(raw) != n:
        raise InputError(where + key, f"must have one value per speed ({n}), got {len(raw)}")
    return np.array([math.nan if v is None else v for v in raw], dtype=float)


# --------------------------------------------------------------------------- public API


#: Fewer FRF lines than this across the dominant mode's half-power band make the zero-order
#: lobes kinked (each line is one chatter frequency, i.e. one point per lobe).
MIN_LINES_PER_HALF_POWER_BAND = 5


def frf_grid_notes(frequency_hz: np.ndarray, h: np.ndarray) -> list[str]:
    """A warning when the FRF grid is too coarse for zero-order lobes (kinked envelopes).

    The zero-order lobes are drawn through the FRF's lines: each line is one chatter
    frequency, one point of every lobe. Across the half-power band of the dominant mode
    (where ``|h| >= peak/√2``) the lobes are steep; with fewer than
    :data:`MIN_LINES_PER_HALF_POWER_BAND` lines there, the envelope is a chain of straight
    kinks and its minima are missed.

    Parameters
    ----------
    frequency_hz : numpy.ndarray, shape (nfreq,)
    h : numpy.ndarray, shape (nfreq,), complex
        The receptance the lobes use, m/N.

    Returns
    -------
    list of str
        Empty when the grid resolves the dominant mode.

    Examples
    --------
    >>> f = np.arange(100.0, 2000.0, 20.0)
    >>> h = 1.0 / (1e7 * (1 - (f / 800.0) ** 2 + 2j * 0.02 * f / 800.0))
    >>> frf_grid_notes(f, h)[0][:40]
    'the FRF grid (20 Hz lines) has 1 line(s)'
    >>> frf_grid_notes(np.arange(100.0, 2000.0, 2.0), 1.0 / (1e7 * (1 - (np.arange(100.0, 2000.0, 2.0) / 800.0) ** 2
    ...                + 2j * 0.02 * np.arange(100.0, 2000.0, 2.0) / 800.0)))
    []
    """
    f = np.asarray(frequency_hz, dtype=float)
    mag = np.abs(np.asarray(h))
    if f.size < 3 or not np.any(mag > 0):
        return []
    i = int(np.argmax(mag))
    above = mag >= mag[i] / np.sqrt(2.0)
    lo = hi = i
    while lo > 0 and above[lo - 1]:
        lo -= 1
    while hi < f.size - 1 and above[hi + 1]:
        hi += 1
    lines = hi - lo + 1
    if lines >= MIN_LINES_PER_HALF_POWER_BAND:
        return []
    step = float(np.median(np.diff(f[max(i - 2, 0) : i + 3])))
    # half-power width of a mode: 2 ζ f; the fitted width is below one line here, so bound it by the lines seen
    width = max(float(f[hi] - f[lo]), step)
    return [f"the FRF grid ({step:.3g} Hz lines) has {lines} line(s) across the half-power band of the dominant mode "
            f"at {f[i]:.0f} Hz: the zero-order lobes pass through too few chatter frequencies there (kinked "
            f"envelope, minima missed); use lines of {width / MIN_LINES_PER_HALF_POWER_BAND:.2g} Hz or finer"]


def stability_lobes(
    frequency_hz: object,
    frf_xx: object,
    frf_yy: object | None = None,
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: object,
    n_lobes: int | None = None,
) -> LobeResult:
    """Zero-order (Altintas–Budak) stability lobes of a milling operation.

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Frequency grid of the receptances, Hz (> 0, strictly increasing). Every grid
        point is a candidate chatter frequency.
    frf_xx : array_like, shape (nfreq,)
        Direct tool-point receptance in the feed direction x, m/N, complex,
        ``exp(i ω t)`` convention (damped: ``Im <= 0``).
    frf_yy : array_like, shape (nfreq,), optional
        Direct receptance normal to the feed, m/N. ``None``: ``Φyy = Φxx`` is assumed
        and the result says so (``same_frf_in_y``).
    teeth : int
        Number of teeth ``N`` (1 … 100).
    tangential_coefficient_n_m2 : float
        Tangential cutting coefficient ``Kt``, N/m² (> 0).
    radial_ratio : float
        ``Kr = Kn/Kt`` (≥ 0, dimensionless).
    radial_immersion : float
        Radial depth of cut over diameter, ``0 < a_e/D <= 1``.
    milling : {"up", "down"}
        Up- or down-milling (sets entry/exit angles).
    spindle_speed_rpm : array_like, shape (nspeed,)
        Speed grid for the envelope, rpm (> 0, strictly increasing).
    n_lobes : int, optional
        Lobes ``k = 0 … n_lobes − 1``. Default: enough for the lowest grid speed at the
        highest chatter frequency (``ceil(60 f_max/(N n_min)) + 1``), at most
        ``MAX_AUTO_LOBES``. Speeds that the computed lobes do not settle — none reaches
        them, or an omitted higher lobe could give a smaller depth there — are NaN in
        the envelope (never an optimistic guess).

    Returns
    -------
    LobeResult

    Raises
    ------
    InputError
        On any invalid argument (names the offending field).

    References
    ----------
    Altintas & Budak (1995); Altintas (2012) §4.4 (see module docstring).

    Examples
    --------
    Single mode, 4 teeth, half-immersion down-milling:

    >>> f = np.linspace(100.0, 2000.0, 3801)
    >>> w, wn, z, k = 2*np.pi*f, 2*np.pi*800.0, 0.03, 2e7
    >>> h = 1.0 / (k * (1 - (w/wn)**2 + 2j*z*(w/wn)))
    >>> r = stability_lobes(f, h, teeth=4, tangential_coefficient_n_m2=7e8,
    ...                     radial_ratio=0.3, radial_immersion=0.5, milling="down",
    ...                     spindle_speed_rpm=np.linspace(3000, 20000, 500))
    >>> r.same_frf_in_y, round(r.min_depth_limit_m * 1e3, 2)
    (True, 2.22)
    """
    f = check_frequency_hz(frequency_hz)
    hxx = check_frf(frf_xx, f.size, "frf_x")
    same_y = frf_yy is None
    hyy = hxx if same_y else check_frf(frf_yy, f.size, "frf_y")
    n_teeth, kt, kr, immersion, milling = check_cut(teeth, tangential_coefficient_n_m2, radial_ratio,
                                                    radial_immersion, milling)
    grid = check_speed_grid(spindle_speed_rpm)

    phi_st, phi_ex = engagement_angles_rad(immersion, milling)
    alpha = directional_factors(phi_st, phi_ex, kr)
    depth, epsilon = zoa_depth_limit(
        hxx, hyy, teeth=n_teeth, tangential_coefficient_n_m2=kt, alpha=alpha
    )
    if not np.any(np.isfinite(depth)):
        raise InputError(
            "frf_x",
            "no frequency gives a positive depth limit: the receptances cannot chatter "
            "in this cut (check the sign convention and the units, m/N)",
        )

    f_valid = f[np.any(np.isfinite(depth), axis=1)]
    if n_lobes is None:
        needed = math.ceil(60.0 * float(f_valid.max()) / (n_teeth * float(grid[0]))) + 1
        lobes_count = min(needed, MAX_AUTO_LOBES)
    else:
        lobes_count = fields.integer(n_lobes, "n_lobes", ge=1, le=MAX_AUTO_LOBES)

    # Absolute minimum (grid-independent) and where each lobe reaches it.
    flat = int(np.nanargmin(depth))
    i_min, branch_min = np.unravel_index(flat, depth.shape)
    min_depth = float(depth[i_min, branch_min])
    f_min = float(f[i_min])
    eps_min = float(epsilon[i_min, branch_min])
    k_all = np.arange(lobes_count)
    min_speeds = 60.0 * 2.0 * np.pi * f_min / (n_teeth * (eps_min + 2.0 * np.pi * k_all))

    env = np.full(grid.size, np.inf)
    env_f = np.full(grid.size, np.nan)
    env_k = np.full(grid.size, -1, dtype=np.int64)
    lobes: list[Lobe] = []
    for k in range(lobes_count):  # loop over lobes and eigenvalues, never over frequency
        parts = [
            _curve_on_grid(_lobe_speed_rpm(f, epsilon[:, e], n_teeth, k), depth[:, e], f, grid)
            for e in range(2)
        ]
        j = np.concatenate([p[0] for p in parts])
        b = np.concatenate([p[1] for p in parts])
        fc = np.concatenate([p[2] for p in parts])
        lobe_depth, lobe_freq = _min_per_index(j, b, fc, grid.size)
        covered = np.isfinite(lobe_depth)
        lobes.append(Lobe(k, grid[covered].copy(), lobe_depth[covered]))
        better = covered & (lobe_depth < env)
        env[better] = lobe_depth[better]
        env_f[better] = lobe_freq[better]
        env_k[better] = k

    env[~np.isfinite(env)] = np.nan
    unsure = _needs_more_lobes(f, depth, epsilon, n_teeth, lobes_count, grid, env)
    env[unsure], env_f[unsure], env_k[unsure] = np.nan, np.nan, -1
    for lobe in lobes:
        lobe.spindle_speed_rpm.flags.writeable = False
        lobe.depth_limit_m.flags.writeable = False
    return LobeResult(
        spindle_speed_rpm=grid,
        depth_limit_m=env,
        chatter_frequency_hz=env_f,
        governing_lobe=env_k,
        lobes=tuple(lobes),
        same_frf_in_y=same_y,
        min_depth_limit_m=min_depth,
        min_depth_chatter_frequency_hz=f_min,
        min_depth_spindle_speed_rpm=min_speeds,
    )


# --------------------------------------------------------------------------- validation


def _immersion(value: object) -> float:
    return fields.number(value, "radial_immersion", gt=0.0, ge=MIN_RADIAL_IMMERSION, le=1.0)


def check_frf(values: object, nfreq: int, field: str) -> np.ndarray:
    """A tool-point FRF (m/N) as a read-only complex array, shape (nfreq,).

    ``InputError`` on ``field`` for a wrong shape, non-finite values, or a positive
    imaginary part at the resonance peak (the ``exp(−iωt)`` convention: conjugate the data).
    """
    h = np.array(values, dtype=complex)
    if h.shape != (nfreq,):
        raise InputError(
            field, f"expected shape ({nfreq},) (one value per frequency), got {h.shape}"
        )
    if not np.all(np.isfinite(h)):
        raise InputError(field, "contains NaN or infinite values")
    peak = int(np.argmax(np.abs(h)))
    if h[peak].imag > 0:
        raise InputError(
            field,
            "imaginary part is positive at the resonance peak: expected the exp(i ω t) "
            "convention (damped receptance has Im <= 0); conjugate the data",
        )
    h.flags.writeable = False
    return h


def check_speed_grid(values: object) -> np.ndarray:
    """A validated, read-only grid of spindle speeds (rpm): 1-D, finite, within the bounds, strictly increasing.

    Raises
    ------
    InputError
        Naming ``spindle_speed_rpm``.
    """
    n = np.array(values, dtype=float)
    field = "spindle_speed_rpm"
    if n.ndim != 1 or n.size == 0:
        raise InputError(field, f"must be a non-empty 1-D grid of speeds, got shape {n.shape}")
    if n.size > MAX_SPEED_COUNT:
        raise InputError(field, f"at most {MAX_SPEED_COUNT} speeds, got {n.size}")
    if not np.all(np.isfinite(n)) or np.any(n <= 0):
        raise InputError(field, "speeds must be finite and > 0 rpm")
    if np.any(n < MIN_SPEED_RPM) or np.any(n > MAX_SPEED_RPM):
        raise InputError(field, f"speeds must lie between {MIN_SPEED_RPM:g} and {MAX_SPEED_RPM:g} rpm")
    if np.any(np.diff(n) <= 0):
        raise InputError(field, "speeds must be strictly increasing")
    n.flags.writeable = False
    return n


# --------------------------------------------------------------------------- many FRFs at once


def _curve_rows_on_grid(speed_rpm: np.ndarray, depth_m: np.ndarray, grid_rpm: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_curve_on_grid` of every row of ``(nrows, nfreq)`` polylines at once.

    Returns ``(row · nspeed + grid_index, depth)`` for all (segment, grid point) pairs;
    segments never join two rows. The arithmetic is that of :func:`_curve_on_grid`, so each
    row's values equal its own call's.
    """
    ok = np.isfinite(depth_m)
    r, c = np.nonzero(ok[:, :-1] & ok[:, 1:])
    n0, n1 = speed_rpm[r, c], speed_rpm[r, c + 1]
    j_lo = np.searchsorted(grid_rpm, np.minimum(n0, n1), side="left")
    j_hi = np.searchsorted(grid_rpm, np.maximum(n0, n1), side="right")
    counts = np.maximum(j_hi - j_lo, 0)
    seg = np.repeat(np.arange(r.size), counts)
    start = np.cumsum(counts) - counts
    j = j_lo[seg] + np.arange(seg.size) - start[seg]
    dn = (n1 - n0)[seg]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(dn != 0.0, (grid_rpm[j] - n0[seg]) / dn, 0.0)
    b0 = depth_m[r, c]
    b = b0[seg] + t * (depth_m[r, c + 1] - b0)[seg]
    return r[seg] * grid_rpm.size + j, b


def _unsettled_rows(depth_m: np.ndarray, next_speed_rpm: np.ndarray, grid_rpm: np.ndarray,
                    envelope_m: np.ndarray) -> np.ndarray:
    """:func:`_needs_more_lobes` of every row at once, shape (nrows, nspeed).

    Per row: the smallest depth ``b`` of the points whose first omitted lobe reaches speed
    ``s`` or beyond (``n_K ≥ s``), against the envelope at ``s``. The points and the grid
    speeds of a row are sorted together (a grid speed before points of equal speed), and a
    running minimum from the top gives every grid speed the minimum over the points above.
    """
    rows, npoints, nspeed = depth_m.shape[0], depth_m.shape[1], grid_rpm.size
    ok = np.isfinite(depth_m)
    speed = np.concatenate([np.where(ok, next_speed_rpm, -np.inf), np.broadcast_to(grid_rpm, (rows, nspeed))], axis=1)
    depth = np.concatenate([np.where(ok, depth_m, np.inf), np.full((rows, nspeed), np.inf)], axis=1)
    is_point = np.concatenate([np.ones((rows, npoints)), np.zeros((rows, nspeed))], axis=1)
    order = np.lexsort((is_point, speed), axis=-1)
    above_min = np.minimum.accumulate(np.take_along_axis(depth, order, axis=1)[:, ::-1], axis=1)[:, ::-1]
    position = np.argsort(order, axis=1)[:, npoints:]  # where each grid speed went
    missing_min = np.take_along_axis(above_min, position, axis=1)
    out: np.ndarray = np.isfinite(envelope_m) & (missing_min < envelope_m)
    return out


def depth_limit_envelopes(
    frequency_hz: object,
    frf_xx: object,
    frf_yy: object | None = None,
    *,
    teeth: int,
    tangential_coefficient_n_m2: float,
    radial_ratio: float,
    radial_immersion: float,
    milling: Milling,
    spindle_speed_rpm: object,
) -> np.ndarray:
    """The lower envelope of :func:`stability_lobes` for many FRFs at once (e.g. Monte-Carlo draws).

    Row ``d`` of the result equals ``stability_lobes(frequency_hz, frf_xx[d], frf_yy[d],
    ...).depth_limit_m`` — the same automatic lobe count per row, the same withdrawal of
    speeds an omitted lobe could lower — but all rows are computed together: one array
    operation per lobe over every row, never a loop over rows. A row whose FRF cannot chatter
    in this cut is NaN throughout (where :func:`stability_lobes` refuses it).

    Parameters
    ----------
    frequency_hz : array_like, shape (nfreq,)
        Frequency grid, Hz (> 0, strictly increasing).
    frf_xx : array_like, shape (nrows, nfreq)
        Direct tool-point receptances in x, m/N, complex.
    frf_yy : array_like, shape (nrows, nfreq), optional
        In y; ``None``: ``Φyy = Φxx`` for every row.
    teeth, tangential_coefficient_n_m2, radial_ratio, radial_immersion, milling, spindle_speed_rpm
        As for :func:`stability_lobes`.

    Returns
    -------
    numpy.ndarray, shape (nrows, nspeed)
        Depth limits, m; NaN where unsettled (as in :attr:`LobeResult.depth_limit_m`).

    Raises
    ------
    InputError
        On an invalid argument (names the field).
    """
    f = check_frequency_hz(frequency_hz)
    hxx = np.asarray(frf_xx, dtype=complex)
    if hxx.ndim != 2 or hxx.shape[1] != f.size or not np.all(np.isfinite(hxx)):
        raise InputError("frf_x", f"expected finite values of shape (nrows, {f.size}), got {hxx.shape}")
    hyy = hxx if frf_yy is None else np.asarray(frf_yy, dtype=complex)
    if hyy.shape != hxx.shape or not np.all(np.isfinite(hyy)):
        raise InputError("frf_y", f"expected finite values of shape {hxx.shape}, got {hyy.shape}")
    n_teeth, kt, kr, immersion, milling = check_cut(teeth, tangential_coefficient_n_m2, radial_ratio,
                                                    radial_immersion, milling)
    grid = check_speed_grid(spindle_speed_rpm)
    alpha = directional_factors(*engagement_angles_rad(immersion, milling), kr)
    depth, epsilon = zoa_depth_limit(hxx, hyy, teeth=n_teeth, tangential_coefficient_n_m2=kt, alpha=alpha)
    rows = hxx.shape[0]
    valid = np.any(np.isfinite(depth), axis=2)  # (nrows, nfreq)
    f_max = np.max(np.where(valid, f, -np.inf), axis=1)
    needed = np.where(np.isfinite(f_max), np.ceil(60.0 * f_max / (n_teeth * float(grid[0]))) + 1, 1)
    lobes_count = np.minimum(needed, MAX_AUTO_LOBES).astype(int)  # per row, as stability_lobes counts

    env = np.full(rows * grid.size, np.inf)
    for k in range(int(lobes_count.max())):  # loop over lobes and eigenvalues, never over rows or frequency
        used = (k < lobes_count)[:, None]
        for e in range(2):
            j, b = _curve_rows_on_grid(_lobe_speed_rpm(f, epsilon[:, :, e], n_teeth, k),
                                       np.where(used, depth[:, :, e], np.nan), grid)
            np.minimum.at(env, j, b)
    envelope = env.reshape(rows, grid.size)
    envelope[~np.isfinite(envelope)] = np.nan
    k_next = lobes_count[:, None, None]
    next_speed = 60.0 * 2.0 * np.pi * f[None, :, None] / (n_teeth * (epsilon + 2.0 * np.pi * k_next))
    unsure = _unsettled_rows(depth.reshape(rows, -1), next_speed.reshape(rows, -1), grid, envelope)
    envelope[unsure] = np.nan
    return envelope
