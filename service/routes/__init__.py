"""HTTP routes: each validates, converts, calls one :mod:`rcsa.app` function and answers.

Every router carries its full path prefix (``/v1/...``) so that a route's path is its
template in metrics and logs.
"""

from __future__ import annotations

from . import (
           analyses,
           batches,
           docs,
           health,
           libraries,
           lobes,
           measurements,
           plots,
           predictions,
           web,
)

__all__ = ["ROUTERS"]

ROUTERS = (health.router, predictions.router, batches.router, measurements.router, libraries.router,
           lobes.router, analyses.router, plots.router, web.router, docs.router)
