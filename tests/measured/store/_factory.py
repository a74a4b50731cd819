"""Deterministic synthetic measurements for the store tests (also used by the writer script).

A measurement is a pure function of its seed, so a process that only logged ``(id, seed)``
lets the test rebuild exactly what was stored and compare bit for bit.
"""

from __future__ import annotations

import numpy as np

from rcsa.measured.store import Measurement, MeasurementMeta, Provenance

ARTIFACT = {
    "diameter_m": 0.0127,
    "stickout_m": 0.08,
    "length_m": 0.1,
    "material": "steel",
    "holder": {"description": "shrink-fit HSK63"},
}


def make_measurement(seed: int, kind: str = "direct_frf", nfreq: int | None = None) -> Measurement:
    """A random but reproducible measurement of ``kind``."""
    rng = np.random.default_rng(seed)
    n = int(nfreq if nfreq is not None else rng.integers(20, 4000))
    f = 1.0 + np.cumsum(rng.uniform(0.25, 2.0, n))
    names = {
        "direct_frf": ["h"],
        "point_receptance": ["h", "l", "n", "p"],
        "artifact_frfs": ["h11", "h21", "h22", "h31"],
    }[kind]
    frfs = {
        k: (rng.normal(size=n) + 1j * rng.normal(size=n)) * 10.0 ** rng.uniform(-9, -5)
        for k in names
    }
    coherence = {names[0]: rng.uniform(0, 1, n)} if seed % 2 else {}
    meta = MeasurementMeta(
        spindle_id=f"spindle-{seed % 3}",
        direction="xy"[seed % 2],
        plane="spindle_nose" if kind != "direct_frf" else "holder_tip",
        kind=kind,
        machine="mc-1",
        points_m=(0.0, 0.02, 0.04) if kind == "artifact_frfs" else None,
        artifact=ARTIFACT if kind == "artifact_frfs" else None,
        notes=f"seed {seed} ünïcode",
    )
    prov = Provenance(
        source_format="api",
        source_file=f"s{seed}.csv",
        source_sha256="ab" * 32,
        original_quantity="accelerance",
        original_units="g/N",
        conversions=("scaled", "accelerance -> receptance"),
        sensor_mass_kg=0.004 if kind == "direct_frf" else None,
    )
    return Measurement(frequency_hz=f, frfs=frfs, meta=meta, provenance=prov, coherence=coherence)


def assert_same_data(got: Measurement, want: Measurement) -> None:
    """Bit-exact equality of every array and equality of the metadata."""
    assert got.frequency_hz.tobytes() == want.frequency_hz.tobytes()
    assert set(got.frfs) == set(want.frfs)
    for k in want.frfs:
        assert got.frfs[k].dtype == np.complex128
        assert got.frfs[k].tobytes() == want.frfs[k].tobytes(), k
    assert set(got.coherence) == set(want.coherence)
    for k in want.coherence:
        assert got.coherence[k].tobytes() == want.coherence[k].tobytes(), k
    assert got.meta == want.meta
    assert got.provenance == want.provenance
