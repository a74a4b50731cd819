"""A bounded schemathesis run against the service's own OpenAPI with all its checks (``--checks all``).

Positive and negative cases for every operation, derandomized, with a write key so that
uploads and deletes are exercised too: no 500, no schema violation, no invalid input
accepted, no undocumented status, content type or header, no unsupported method answered,
no missing required header accepted, no resource used after its delete.

Left out: ``positive_data_acceptance`` — a schema cannot state every rule of a request (an
inner diameter below the outer one, bearings on the shaft, a stored measurement's id that
exists, the compute budget), so a schema-valid request may rightly be refused with a 4xx;
``ignored_auth`` — every request here carries a valid write key (so that writes are
exercised), which the check takes for generated credentials that should have been refused;
missing, invalid and under-scoped keys are tested route by route in ``test_auth.py`` and
``test_hostile_uvicorn.py``.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis.errors import Unsatisfiable
from schemathesis import GenerationMode
from schemathesis.checks import CHECKS as REGISTRY
from schemathesis.checks import ignored_auth, load_all_checks, positive_data_acceptance
from schemathesis.core.failures import FailureGroup
from schemathesis.python.asgi import shutdown_lifespans
from service.main import create_app

from .conftest import WRITE_KEY, settings_for

#: pytest-timeout's 600 s is the hang guard; a test of this module takes about a
#: minute on a 2-core machine at load 4 and can take ten times that at load 12-14
pytestmark = pytest.mark.timeout(1800)

load_all_checks()
CHECKS = [check for check in REGISTRY.get_all() if check not in (positive_data_acceptance, ignored_auth)]
#: Cases per operation and mode (positive, negative), derandomized: 25 × 2 for each of the ~50
#: operations is ~2 500 requests in about 28 s; 50 took 56 s of CI's six minutes.
EXAMPLES = 25


def _by_contract(path: str, exc: BaseException) -> bool:
    """Whether every failure is the contract's behaviour, not a bug: a batch answers 200
    with ``status: error`` for an invalid combination ("one bad combination never fails the
    others"), so schema-violating combinations are accepted on purpose."""
    subs = getattr(exc, "exceptions", None) or [exc]
    texts = [" ".join(str(x) for x in (e, getattr(e, "title", ""), getattr(e, "message", ""))) for e in subs]
    return path == "/v1/tool-point-frf/batch" and all(
        "Schema-violating request accepted" in t and "/properties/combinations/items/" in t for t in texts)


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
            if _by_contract(operation.path, exc):
                return
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
    assert len(operations) >= 15 and len(CHECKS) >= 12
    try:
        for operation in operations:
            for mode in (GenerationMode.POSITIVE, GenerationMode.NEGATIVE):
                try:
                    _fuzz(operation, mode, failures)()
                except Unsatisfiable:  # nothing to negate (an operation without parameters)
                    assert mode is GenerationMode.NEGATIVE, operation.label
                except ValueError as exc:  # schemathesis cannot negate some multipart binary parts
                    if "Unsupported type: 'Binary'" not in str(exc) or mode is not GenerationMode.NEGATIVE:
                        raise
    finally:
        shutdown_lifespans()
    assert not failures, "\n\n".join(failures[:10])
