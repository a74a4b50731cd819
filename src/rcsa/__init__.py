"""rcsa: tool-point frequency response functions of spindle–holder–tool assemblies.

Exact Timoshenko receptance coupling (Budak, Ertürk & Özgüven, CIRP Annals 2006), measured
spindle FRFs, and a diagnosis of the gap between model and measurement. The package is
layered (``docs/architecture.md``): :mod:`rcsa.physics` < :mod:`rcsa.model` <
:mod:`rcsa.measured` < :mod:`rcsa.analysis` < :mod:`rcsa.libraries` < :mod:`rcsa.app`, with
:mod:`rcsa.infra` as domain-free plumbing beside them.

The Python API of the contract:

>>> import rcsa
>>> from rcsa.reference import ra1
>>> result = rcsa.predict(ra1({"start_hz": 1300.0, "stop_hz": 1500.0, "step_hz": 1.0}))
>>> [round(f, 2) for f in result["natural_frequencies_hz"]]
[1383.61, 1444.68]
>>> result["peaks"][0]
{'frequency_hz': 1386.0, 'magnitude_m_n': 5.836...e-06}
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from rcsa._version import __version__
from rcsa.errors import FrequencyMismatch, InputError, NotFoundError, RcsaError, StoreError

if TYPE_CHECKING:
    from rcsa.app.analyses import diagnose, stability_lobes
    from rcsa.app.predictions import predict, predict_batch
    from rcsa.model.prediction import Prediction
    from rcsa.physics.receptance import Receptance

# The API is loaded on first use (PEP 562): `import rcsa` (and `rcsa --help`) then costs
# milliseconds, not the numpy/scipy/h5py of the whole library.
_LAZY = {
    "diagnose": "rcsa.app.analyses",
    "stability_lobes": "rcsa.app.analyses",
    "predict": "rcsa.app.predictions",
    "predict_batch": "rcsa.app.predictions",
    "Prediction": "rcsa.model.prediction",
    "Receptance": "rcsa.physics.receptance",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'rcsa' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))

__all__ = [
    "FrequencyMismatch",
    "InputError",
    "NotFoundError",
    "Prediction",
    "RcsaError",
    "Receptance",
    "StoreError",
    "__version__",
    "diagnose",
    "predict",
    "predict_batch",
    "stability_lobes",
]
