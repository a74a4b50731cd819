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

from rcsa._version import __version__
from rcsa.app.analyses import diagnose, stability_lobes
from rcsa.app.predictions import predict, predict_batch
from rcsa.errors import FrequencyMismatch, InputError, NotFoundError, RcsaError, StoreError
from rcsa.model.prediction import Prediction
from rcsa.physics.receptance import Receptance

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
