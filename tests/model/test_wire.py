"""The wire form has one home: rcsa.model.wire writes and reads every ``{real, imag}``."""

from __future__ import annotations

import ast

import numpy as np
import pytest

from rcsa.errors import InputError
from rcsa.model.wire import complex_from_wire, complex_to_wire, json_float, json_list
from tests.helpers import REPO


def _built_wire_dicts(path, root=REPO):
    """``{"real": <expr>, "imag": <expr>}`` dicts built from computed values in a module."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Dict) and {getattr(k, "value", None) for k in node.keys} == {"real", "imag"}:
            literal = all(isinstance(v, ast.List) and all(isinstance(e, ast.Constant | ast.UnaryOp) for e in v.elts)
                          for v in node.values)
            if not literal:  # literal numbers are an OpenAPI example, not a conversion
                found.append(f"{path.relative_to(root)}:{node.lineno}")
    return found


def test_no_complex_array_is_written_by_hand_outside_the_wire_module():
    paths = [p for root in ("src/rcsa", "service") for p in (REPO / root).rglob("*.py")
             if p != REPO / "src" / "rcsa" / "model" / "wire.py"]
    found = [hit for p in paths for hit in _built_wire_dicts(p)]
    assert not found, f"use rcsa.model.wire.complex_to_wire / complex_from_wire: {found}"


def test_the_scan_sees_a_hand_written_wire_dict_and_lets_an_example_pass(tmp_path):
    (tmp_path / "m.py").write_text('def f(z):\n    return {"real": z.real.tolist(), "imag": z.imag.tolist()}\n'
                                   'EXAMPLE = {"real": [1.0e-7, -2.0], "imag": [-1.0e-9, 0.0]}\n')
    assert _built_wire_dicts(tmp_path / "m.py", tmp_path) == ["m.py:2"]


def test_round_trip_is_exact_and_missing_values_become_null():
    z = np.array([1e-7 - 3e-9j, -2.5e-300 + 0j, 1.0 + 1e300j])
    assert complex_from_wire(complex_to_wire(z), "h").tobytes() == z.tobytes()
    assert complex_from_wire(complex_to_wire(z, "numpy"), "h").tobytes() == z.tobytes()
    assert complex_to_wire(np.array([np.nan + 1j]), nonfinite_as_none=True) == {"real": [None], "imag": [1.0]}
    assert json_list(np.array([np.inf, 2.0])) == [None, 2.0] and json_float(np.float64("nan")) is None
    with pytest.raises(InputError, match="h.imag"):
        complex_from_wire({"real": [1.0], "imag": [1.0, 2.0]}, "h")
