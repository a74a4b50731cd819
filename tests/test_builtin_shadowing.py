"""A method named after a builtin type (``JobStore.list``, ``LibraryStore.list``) does not
change what that name means in its class's annotations.

Inside a class body a ``def list`` rebinds ``list``: a type checker reads ``-> list[str]`` in
the same class as the method, not the builtin (mypy: "Function ... is not valid as a type"),
so such annotations are wrong for every reader but the interpreter. Those classes write
``builtins.list[...]``. The check reads the source (ast), so it finds the next copy of the
pattern too.
"""

from __future__ import annotations

import ast
import builtins

from tests.helpers import REPO

BUILTIN_TYPES = frozenset(n for n in dir(builtins) if isinstance(getattr(builtins, n), type))
SOURCES = sorted((REPO / "src").rglob("*.py")) + sorted((REPO / "service").rglob("*.py"))


def _annotations(cls: ast.ClassDef) -> list[ast.expr]:
    out: list[ast.expr] = []
    for node in ast.walk(cls):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            a = node.args
            out += [x.annotation for x in [*a.posonlyargs, *a.args, *a.kwonlyargs, a.vararg, a.kwarg]
                    if x is not None and x.annotation is not None]
            out += [node.returns] if node.returns is not None else []
        elif isinstance(node, ast.AnnAssign):
            out.append(node.annotation)
    return out


def _names(annotation: ast.expr) -> set[str]:
    """Bare names an annotation uses, string annotations parsed."""
    found = set()
    for node in ast.walk(annotation):
        if isinstance(node, ast.Name):
            found.add(node.id)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            try:
                found |= _names(ast.parse(node.value, mode="eval").body)
            except SyntaxError:
                pass
    return found


def shadowed_annotations(source: str) -> list[tuple[str, str, int]]:
    """``(class, name, line)`` of every annotation in a class that names a builtin type the class
    rebinds with a method of that name."""
    out = []
    for cls in ast.walk(ast.parse(source)):
        if not isinstance(cls, ast.ClassDef):
            continue
        rebound = {s.name for s in cls.body if isinstance(s, ast.FunctionDef | ast.AsyncFunctionDef)}
        rebound &= BUILTIN_TYPES
        out += [(cls.name, name, a.lineno) for a in _annotations(cls) for name in sorted(_names(a) & rebound)]
    return out


def test_the_check_finds_the_pattern():
    bad = "class Store:\n    def list(self) -> list[str]: ...\n    def ids(self, x: 'list[int]') -> None: ...\n"
    good = "import builtins\nclass Store:\n    def list(self) -> builtins.list[str]: ...\n"
    assert shadowed_annotations(bad) == [("Store", "list", 2), ("Store", "list", 3)]
    assert shadowed_annotations(good) == []


def test_no_annotation_names_a_builtin_its_class_rebinds():
    found = [f"{path.relative_to(REPO)}:{line}: {cls}.{name} shadows builtins.{name}; write builtins.{name}[...]"
             for path in SOURCES for cls, name, line in shadowed_annotations(path.read_text(encoding="utf-8"))]
    assert not found, "\n".join(found)
