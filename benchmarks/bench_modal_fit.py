"""Hybrid natural frequencies: how well the modal fit's stated sd covers the true modes.

A measured spindle's prediction has no exact eigenvalues: its natural frequencies are modal-fit
estimates, each with a standard uncertainty ``sd`` (``rcsa.model.modal_fit``). On synthetic FRFs
of four known modes (``tests/model/test_modal_fit.py``: 600 Hz, a close pair at 1 380/1 450 Hz,
2 500 Hz) with 1 % and 3 % complex noise, every mode's ``z = (f_fit − f_true) / sd`` is taken
over ``--seeds`` noise draws. An sd that says the truth is ``rms z`` ≈ 1; below 1 it is
cautious (wider than the error), above 1 it understates the error.

The seeds are evaluation seeds (1000 onward): the tests tune and check on seeds 0–2, which are
not used here. Written to ``benchmarks/results/modal_fit.json``.

Run: ``.venv/bin/python benchmarks/bench_modal_fit.py [--seeds 40]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.model.test_modal_fit import MODES, F, synthetic  # noqa: E402

from rcsa.model.modal_fit import modal_fit  # noqa: E402
from record import load_average, write  # noqa: E402

#: Evaluation seeds start here, apart from the tests' seeds 0–2.
FIRST_SEED = 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    start = load_average()
    truth = np.array([fn for fn, _, _ in MODES])
    by_noise = {}
    pooled: list[float] = []
    for noise in (0.01, 0.03):
        z, found, times = [], [], []
        for seed in range(FIRST_SEED, FIRST_SEED + args.seeds):
            h = synthetic(noise, seed)
            t0 = time.perf_counter()
            fit = modal_fit(F, h)
            times.append(time.perf_counter() - t0)
            found.append(len(fit.modes))
            if len(fit.modes) == truth.size:
                z.extend((m.frequency_hz - fn) / m.sd_hz for m, fn in zip(fit.modes, truth, strict=True))
        za = np.abs(np.asarray(z))
        pooled.extend(za)
        by_noise[f"{noise:g}"] = {
            "noise_rel": noise, "seeds": args.seeds, "modes_true": int(truth.size),
            "fits_with_every_mode_once": int(sum(n == truth.size for n in found)),
            "rms_z": float(np.sqrt(np.mean(za**2))), "share_within_1sd": float(np.mean(za <= 1.0)),
            "share_within_3sd": float(np.mean(za <= 3.0)), "max_abs_z": float(za.max()),
            "median_fit_ms": float(np.median(times) * 1e3)}
        print(f"noise {noise:.0%}: rms z {by_noise[f'{noise:g}']['rms_z']:.2f} over {za.size} modes "
              f"({args.seeds} seeds), within 1 sd {np.mean(za <= 1):.0%}, within 3 sd {np.mean(za <= 3):.0%}, "
              f"max |z| {za.max():.2f}")
    figures = {"lines": int(F.size), "first_seed": FIRST_SEED, "by_noise": by_noise,
               "rms_z_pooled": float(np.sqrt(np.mean(np.square(pooled)))), "modes_pooled": len(pooled)}
    write("modal_fit", figures, load_start=start, out=args.out)


if __name__ == "__main__":
    main()
