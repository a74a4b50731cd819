"""The doctests of ``src/rcsa`` (``--doctest-modules``, see pyproject.toml) print alike everywhere.

Each doctest runs with numpy's print options pinned to one style (numpy 2's defaults, with
scalars printed as plain numbers as numpy 1.x did), whatever an earlier test or the
installed numpy set, and finds ``np`` in its namespace. This file sits at the root so that
``pytest src/rcsa/...`` alone gets it too; the suite's own fixtures are in tests/conftest.py.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from _pytest.doctest import DoctestItem

PRINT_STYLE = {"precision": 8, "threshold": 1000, "edgeitems": 3, "linewidth": 75, "suppress": False,
               "nanstr": "nan", "infstr": "inf", "sign": "-", "floatmode": "maxprec",
               "legacy": "1.25" if np.lib.NumpyVersion(np.__version__) >= "2.0.0" else False}


@pytest.fixture(autouse=True)
def _doctest_print_style(request: pytest.FixtureRequest) -> Iterator[None]:
    if not isinstance(request.node, DoctestItem):
        yield
        return
    request.getfixturevalue("doctest_namespace")["np"] = np
    with np.printoptions(**PRINT_STYLE):
        yield
