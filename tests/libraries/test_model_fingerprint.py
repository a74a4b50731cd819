"""The result-cache key follows the physics by itself: the model fingerprint is the code's meaning.

``model_fingerprint(root)`` hashes the syntax tree (docstrings left out) of every module that
determines a prediction; a copy of the package with one number changed in the segment solver
must give another fingerprint (and so other result keys), an unchanged copy the same one, and
a copy whose docstrings, comments or layout changed the same one too (stored results stay
valid across a documentation commit).
"""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from rcsa.libraries import results_cache
from rcsa.libraries.results_cache import model_fingerprint, result_key, shared_part
from rcsa.reference import ra1
from tests.helpers import REPO

PACKAGE = REPO / "src" / "rcsa"


@pytest.fixture
def copy(tmp_path):
    """A copy of the package's files (bytecode left out)."""
    target = tmp_path / "rcsa"
    shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns("__pycache__"))
    return target


def _flip_one_byte(path):
    data = bytearray(path.read_bytes())
    i = data.index(b"MAX_DECAY_PER_PIECE = 3.0") + len(b"MAX_DECAY_PER_PIECE = ")
    data[i:i + 1] = b"4"
    path.write_bytes(bytes(data))


def _key(monkeypatch, fingerprint: str) -> str:
    monkeypatch.setattr(results_cache, "model_fingerprint", lambda root=None: fingerprint)
    doc = ra1()
    combination = {"id": "T1", "holder": doc["holder"], "tool": doc["tool"], "joints": doc["joints"]}
    shared = shared_part({"spindle": doc["spindle"]}, None)
    return result_key(combination, shared, results_cache.frequency_sha256(np.arange(1.0, 11.0)))


def test_unchanged_copy_has_the_installed_fingerprint(copy):
    installed = model_fingerprint()
    assert len(installed) == 64 and int(installed, 16) >= 0
    assert model_fingerprint(copy) == installed == model_fingerprint(PACKAGE)


def test_one_byte_of_the_physics_changes_the_fingerprint_and_the_keys(copy, monkeypatch):
    before = model_fingerprint(copy)
    _flip_one_byte(copy / "physics" / "segments.py")
    after = model_fingerprint(copy)
    assert after != before
    assert _key(monkeypatch, after) != _key(monkeypatch, before)


@pytest.mark.parametrize("path", ["model/new_module.py", "physics/sub/deeper.py", "measured/hybrid.py",
                                  "measured/artifact_identification.py"])
def test_every_model_source_counts(copy, path):
    before = model_fingerprint(copy)
    target = copy / path
    target.parent.mkdir(parents=True, exist_ok=True)
    with target.open("a", encoding="utf-8") as fh:
        fh.write("\nCHANGED = 1\n")
    assert model_fingerprint(copy) != before


def test_a_docstring_comment_or_layout_change_keeps_the_fingerprint_and_the_keys(copy, monkeypatch):
    before = model_fingerprint(copy)
    segments = copy / "physics" / "segments.py"
    text = segments.read_text(encoding="utf-8")
    first_def = text.index('    """', text.index("\ndef segment_terms("))
    text = text[:first_def] + '    """Reworded: a docstring says nothing the interpreter runs.\n\n' + \
        text[first_def + len('    """'):]
    text = text.replace('"""Exact', '"""Exactly', 1)                 # the module docstring
    text = text.replace("MAX_DECAY_PER_PIECE = 3.0", "MAX_DECAY_PER_PIECE = (  # a comment\n    3.0\n)")
    segments.write_text("# a new first comment line\n" + text, encoding="utf-8")
    assert segments.read_text(encoding="utf-8") != (PACKAGE / "physics" / "segments.py").read_text(encoding="utf-8")
    assert model_fingerprint(copy) == before
    assert _key(monkeypatch, model_fingerprint(copy)) == _key(monkeypatch, before)


@pytest.mark.parametrize(("old", "new"), [("MAX_DECAY_PER_PIECE = 3.0", "MAX_DECAY_PER_PIECE = 3.5"),
                                          ("MAX_DECAY_PER_PIECE = 3.0", "MAX_DECAY_PER_PIECE = 3"),
                                          ("MAX_DECAY_PER_PIECE = 3.0", 'MAX_DECAY_PER_PIECE = 3.0\n"""a string"""')])
def test_a_change_of_meaning_changes_the_fingerprint(copy, old, new):
    # an int for a float, or a string statement that is not a docstring, are changes of meaning
    before = model_fingerprint(copy)
    segments = copy / "physics" / "segments.py"
    segments.write_text(segments.read_text(encoding="utf-8").replace(old, new, 1), encoding="utf-8")
    assert model_fingerprint(copy) != before


def test_code_that_does_not_compute_results_does_not_count(copy):
    before = model_fingerprint(copy)
    (copy / "libraries" / "sync.py").write_text("# anything\n", encoding="utf-8")
    (copy / "physics" / "__pycache__").mkdir(exist_ok=True)
    (copy / "physics" / "__pycache__" / "segments.cpython-311.pyc").write_bytes(b"\0")
    (copy / "model" / "notes.txt").write_text("not a module\n", encoding="utf-8")
    assert model_fingerprint(copy) == before
