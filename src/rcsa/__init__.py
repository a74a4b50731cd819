"""rcsa: tool-point frequency response functions of spindle–holder–tool assemblies.

Exact Timoshenko receptance coupling (Budak, Ertürk & Özgüven, CIRP Annals 2006), measured
spindle FRFs, and a diagnosis of the gap between model and measurement.

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

from typing import Any

from .api import predict, predict_batch, stability_lobes
from .errors import FrequencyMismatch, InputError, NotFoundError, RcsaError, StoreError
from .frf import Receptance, TwoEnd
from .prediction import Prediction

__version__ = "0.1.0"

__all__ = [
    "FrequencyMismatch",
    "InputError",
    "NotFoundError",
    "Prediction",
    "RcsaError",
    "Receptance",
    "StoreError",
    "TwoEnd",
    "diagnose",
    "predict",
    "predict_batch",
    "stability_lobes",
]


def diagnose(request: Any, **kwargs: Any) -> dict[str, Any]:
    """Sim-to-real gap diagnosis of a base model against tap tests (``contract.md`` "Diagnosis").

    See :func:`rcsa.diagnosis.api.diagnose`; imported on first use.
    """
    from .diagnosis.api import diagnose as _diagnose

    return _diagnose(request, **kwargs)
