"""The application layer: what the CLI and the REST service call, and nothing else does.

Each function takes and returns plain contract documents (dicts) or the library's own
objects, validates at the edge, picks the default store where the caller gives none, and
never depends on how it was reached. Modules: :mod:`.predictions` (one assembly, batches),
:mod:`.analyses` (lobes, effects, identification, diagnosis), :mod:`.measurements` (the
store as users see it), :mod:`.libraries` (whole tool libraries, syncs, exports),
:mod:`.stores` (which store a call uses).
"""

from __future__ import annotations

from rcsa.app.analyses import diagnose, effects, identify, stability_lobes, stability_lobes_result
from rcsa.app.predictions import predict, predict_batch

__all__ = ["diagnose", "effects", "identify", "predict", "predict_batch", "stability_lobes", "stability_lobes_result"]
