"""The application layer: what the CLI and the REST service call, and nothing else does.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, picks the default store where the caller gives none, and
never depends on how it was reached. The two doors (``rcsa.cli``, ``service``) import
nothing else of rcsa but :mod:`rcsa.errors` and :mod:`rcsa._version` (import-linter
contracts ``service-through-app`` and ``cli-through-app``).

Modules: :mod:`.predictions` (one assembly, batches), :mod:`.analyses` (lobes, effects,
identification, diagnosis), :mod:`.measurements` (the store as users see it),
:mod:`.libraries` (batches and whole tool libraries prepared as work, stored libraries and
their exports), :mod:`.jobs` (answer now or queue a job: one decision, one handler),
:mod:`.figures` and :mod:`.exports` (pictures and CSV files), :mod:`.stores` (which store a
call uses), :mod:`.keys` (API keys), :mod:`.bounds` (the validation bounds the REST schemas
publish), :mod:`.examples` (RA-1), :mod:`.runtime` (SQLite and process liveness for the
service's own database).
"""

from __future__ import annotations

from rcsa.app.analyses import diagnose, effects, identify, stability_lobes, stability_lobes_result
from rcsa.app.predictions import predict, predict_batch

__all__ = ["diagnose", "effects", "identify", "predict", "predict_batch", "stability_lobes", "stability_lobes_result"]
