"""No test asserts how long something took: speed is measured in ``benchmarks/``, never here.

A wall-clock (or CPU-time) bound in a test fails on a loaded machine for nothing and can keep
good work from landing. This test reads every test module and refuses an ``assert`` whose
expression reads a clock or a runtime figure. Waiting for a server with a deadline is allowed
(that loop is not an assertion); a hang is caught by pytest-timeout.
"""

from __future__ import annotations

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent
#: names that, read inside an assert, make it a timing assertion
CLOCKS = ("monotonic", "perf_counter", "process_time", "time.time", "runtime_s", "cpu_seconds",
          "wall_seconds", "elapsed")


ORDER = (ast.Lt, ast.LtE, ast.Gt, ast.GtE)


def timed_assertions(source: str) -> list[tuple[int, str]]:
    """The ``(line, text)`` of each assert in *source* that orders a clock reading against a bound."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Assert):
            continue
        for compare in ast.walk(node.test):
            if isinstance(compare, ast.Compare) and any(isinstance(op, ORDER) for op in compare.ops):
                text = ast.unparse(compare)
                if any(clock in text for clock in CLOCKS):
                    found.append((node.lineno, ast.unparse(node.test)))
                    break
    return found


def test_the_detector_finds_a_timed_assertion():
    assert timed_assertions("import time\nt0 = time.monotonic()\nassert time.monotonic() - t0 < 3\n")
    assert timed_assertions("assert out['runtime_s'] <= 1.5\n")
    assert timed_assertions("assert ok and r['cpu_seconds'] <= 1.5 * r['estimated_seconds'], r\n")
    assert not timed_assertions("assert 'runtime_s' in doc\n")  # reported, not bounded
    assert not timed_assertions("deadline = 5\nassert len(steps) < 20\n")


def test_no_test_asserts_a_duration():
    offenders = {}
    for path in sorted(TESTS.rglob("*.py")):
        if path == Path(__file__).resolve():
            continue
        found = timed_assertions(path.read_text())
        if found:
            offenders[str(path.relative_to(TESTS))] = found
    assert not offenders, f"timing belongs in benchmarks/, not in tests: {offenders}"
