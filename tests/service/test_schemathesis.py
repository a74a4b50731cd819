"""A bounded schemathesis run against the service's own OpenAPI: no 500, no schema violation.

Positive and negative cases for every operation, derandomized, with a write key so that
uploads and deletes are exercised too.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis.errors import Unsatisfiable
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.core.failures import FailureGroup
from schemathesis.python.asgi import shutdown_lifespans
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)
from service.main import create_app

from .conftest import WRITE_KEY, settings_for

CHECKS = [not_a_server_error, response_schema_conformance, content_type_conformance, status_code_conformance]
EXAMPLES = 50


def _fuzz(operation, mode: GenerationMode, failures: list[str]) -> Callable[[], None]:
    label = f"{operation.label} [{mode.value}]"

    @given(case=operation.as_strategy(generation_mode=mode, headers={"X-API-Key": WRITE_KEY}))
    @settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
              phases=[Phase.explicit, Phase.generate], suppress_health_check=list(HealthCheck))
    def run(case) -> None:
        response = case.call()
        try:
            case.validate_response(response, checks=CHECKS)
        except (AssertionError, FailureGroup) as exc:
            text = str(exc)
            failures.append(f"{label}: {text[:600]}\n... {text[-600:]}")

    return run


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore::DeprecationWarning")
def test_openapi_fuzzing_finds_no_server_error_and_no_schema_violation(tmp_path):
    app = create_app(settings_for(tmp_path / "store", seed_demo=True, max_frequency_lines=2000,
                                  async_batch_threshold=5, max_body_bytes=2 * 2**20))
    schema = schemathesis.openapi.from_asgi("/openapi.json", app)
    failures: list[str] = []
    operations = [result.ok() for result in schema.get_all_operations()]
    assert len(operations) >= 15
    try:
        for operation in operations:
            for mode in (GenerationMode.POSITIVE, GenerationMode.NEGATIVE):
                try:
                    _fuzz(operation, mode, failures)()
                except Unsatisfiable:  # nothing to negate (an operation without parameters)
                    assert mode is GenerationMode.NEGATIVE, operation.label
    finally:
        shutdown_lifespans()
    assert not failures, "\n\n".join(failures[:10])
