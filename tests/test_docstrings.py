"""The numpydoc sections of the library's docstrings are well formed and name the real parameters.

In the spirit of python-control's ``docstrings_test.py``: every public function, class and
public method is read with numpydoc's own parser (``numpydoc.docscrape``), and

* everywhere in :mod:`rcsa`, a docstring must parse without numpydoc complaining (unknown or
  repeated sections, malformed headers), and a ``Parameters`` section that is there must name
  every parameter of the signature and nothing else (no partial, stale or misspelt lists);
* in the public API (``rcsa.__all__``) and in the two bottom layers, :mod:`rcsa.physics` and
  :mod:`rcsa.model`, every callable that takes parameters must document each of them
  (classes in ``Parameters`` or ``Attributes``, as numpydoc allows for dataclasses).

"Public" is what a module lists in ``__all__`` (or, without one, the names without a leading
underscore defined in it); methods are the public ones a public class defines itself.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import warnings
from collections.abc import Callable, Iterator

import pytest

import rcsa

docscrape = pytest.importorskip("numpydoc.docscrape", reason="numpydoc comes with the test extra")

#: packages whose public callables must document every parameter (besides ``rcsa.__all__``)
STRICT_PACKAGES = ("rcsa.physics", "rcsa.model")

#: Callables in the strict scope that may lack a full Parameters section, with the reason.
#: An entry that becomes complete (or disappears) fails the test: delete it then.
ALLOWED_INCOMPLETE: dict[str, str] = {
}

#: parameters never documented
IMPLICIT = {"self", "cls"}


def _modules() -> list[str]:
    return ["rcsa", *sorted(m.name for m in pkgutil.walk_packages(rcsa.__path__, "rcsa."))]


def _public(module) -> Iterator[tuple[str, object]]:
    names = getattr(module, "__all__", None)
    for name in names if names is not None else [n for n in vars(module) if not n.startswith("_")]:
        obj = getattr(module, name)
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if names is None and getattr(obj, "__module__", None) != module.__name__:
            continue  # imported, not defined here
        yield name, obj


def _methods(cls: type) -> Iterator[tuple[str, Callable]]:
    for name, attr in vars(cls).items():
        if name.startswith("_"):
            continue
        if isinstance(attr, staticmethod | classmethod):
            attr = attr.__func__
        if inspect.isfunction(attr):
            yield name, attr


def _callables() -> dict[str, tuple[object, bool]]:
    """``qualified name -> (callable, strict)`` over the whole package, each object once."""
    found: dict[str, tuple[object, bool]] = {}
    seen: dict[int, str] = {}

    def add(obj: object, strict: bool) -> None:
        qual = f"{obj.__module__}.{obj.__qualname__}"
        if id(obj) in seen:
            if strict:
                found[seen[id(obj)]] = (obj, True)
            return
        seen[id(obj)] = qual
        found[qual] = (obj, strict)
        if inspect.isclass(obj):
            for _, method in _methods(obj):
                add(method, strict)

    for _, obj in _public(rcsa):
        add(obj, True)
    for name in _modules():
        module = importlib.import_module(name)
        strict = name.startswith(STRICT_PACKAGES)
        for _, obj in _public(module):
            add(obj, strict)
    return found


CALLABLES = _callables()


def _parameters(obj: object) -> list[str]:
    """The parameter names a docstring must give, ``*args``/``**kwargs`` without their stars."""
    if inspect.isclass(obj) and obj.__init__ is object.__init__ and obj.__new__ is object.__new__:
        return []
    if inspect.isclass(obj) and getattr(obj, "_is_protocol", False):  # a Protocol is never constructed
        return []
    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):  # some builtins and Protocols have none
        return []
    return [p.name for p in signature.parameters.values() if p.name not in IMPLICIT]


def _documented(doc, *sections: str) -> list[str]:
    """Names listed in the sections; ``a, b : float`` names two, ``*args`` names ``args``."""
    return [name.strip().lstrip("*") for section in sections for entry in doc[section]
            for name in entry.name.split(",") if name.strip()]


def _problems(obj: object, strict: bool) -> list[str]:
    text = inspect.getdoc(obj)
    if not text:
        return ["no docstring"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            doc = docscrape.NumpyDocString(text)
        except Exception as exc:  # numpydoc raises ValueError or warns (made an error here)
            return [f"malformed numpydoc: {exc}"]
    params = _parameters(obj)
    given = _documented(doc, "Parameters", "Other Parameters")
    problems = []
    if inspect.isclass(obj):
        given += _documented(doc, "Attributes")
    else:
        unknown = sorted(set(given) - set(params))
        if unknown:
            problems.append(f"documents parameters it does not have: {unknown}")
    missing = [p for p in params if p not in given]
    if missing and (strict or doc["Parameters"]):
        problems.append(f"parameters missing from its Parameters section: {missing}")
    return problems


@pytest.mark.parametrize("qualname", sorted(CALLABLES))
def test_numpydoc_sections(qualname):
    obj, strict = CALLABLES[qualname]
    problems = _problems(obj, strict)
    if qualname in ALLOWED_INCOMPLETE:
        assert problems, f"{qualname} is complete now: remove it from ALLOWED_INCOMPLETE"
        return
    assert not problems, f"{qualname}: " + "; ".join(problems)


def test_the_allow_list_names_existing_strict_callables():
    stale = [q for q in ALLOWED_INCOMPLETE if q not in CALLABLES or not CALLABLES[q][1]]
    assert not stale, f"not public, not strict or gone: {stale}"


def test_the_check_sees_the_whole_public_api():
    strict = {q for q, (_, s) in CALLABLES.items() if s}
    assert "rcsa.app.predictions.predict" in strict  # rcsa.predict, the public API
    assert "rcsa.physics.receptance.Receptance" in strict
    assert "rcsa.physics.elimination.march" in strict
    assert "rcsa.model.contract.parse_assembly" in strict
    assert "rcsa.measured.hybrid.measured_base" in CALLABLES
    assert len(strict) > 80 and len(CALLABLES) > 300


def test_the_check_catches_what_it_claims_to():
    def partial(a: float, b: float) -> float:
        """Sum.

        Parameters
        ----------
        a : float
        """
        return a + b

    def stale(a: float) -> float:
        """Identity.

        Parameters
        ----------
        a, c : float
        """
        return a

    def undocumented(a: float) -> float:
        """Identity."""
        return a

    def malformed(a: float) -> float:
        """Identity.

        Parameters
        ----------
        a : float

        Parameters
        ----------
        a : float
        """
        return a

    assert _problems(partial, strict=False) == ["parameters missing from its Parameters section: ['b']"]
    assert _problems(stale, strict=False) == ["documents parameters it does not have: ['c']"]
    assert _problems(undocumented, strict=False) == []
    assert _problems(undocumented, strict=True) == ["parameters missing from its Parameters section: ['a']"]
    assert _problems(malformed, strict=False)[0].startswith("malformed numpydoc")
