"""The package's own house rules, checked on its source (python-control's docstrings_test style).

* no import circle anywhere in ``obsdesign`` (module-level and function-level imports alike);
* every module under 500 lines;
* every name in every ``__all__`` exists;
* every parameter of a public function or method is documented in its numpydoc docstring;
* every field of a public dataclass is documented in its docstring (Attributes or Parameters);
* ``obsdesign/export`` never imports the simulator.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "obsdesign"
MODULES = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts and p.name != "__main__.py")


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path) -> set[str]:
    """Modules of the package imported anywhere in ``path`` (resolved to module names)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    tree = ast.parse(path.read_text(encoding="utf-8"))
    typing_only = set()
    for node in ast.walk(tree):  # imports under "if TYPE_CHECKING:" are for annotations only
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            typing_only.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            candidates = [target] + [f"{target}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            candidates = [a.name for a in node.names]
        else:
            continue
        for c in candidates:
            if c.startswith("obsdesign") and c in KNOWN:
                found.add(c)
    found.discard(name)
    return found


KNOWN = {_module_name(p) for p in MODULES}


def _graph() -> dict[str, set[str]]:
    graph = {_module_name(p): _imports(p) for p in MODULES}
    # Importing a module imports its parent packages first; a package __init__ that imports a
    # submodule is an edge like any other.
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if state.get(nxt) is None:
                found = visit(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if state.get(node) is None:
            found = visit(node)
            if found:
                return found
    return None


def _package_edges(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """Edges between a module and the modules it names, without the edge from a package's
    ``__init__`` to its own submodules (that is how a package exposes its rooms, not a circle)."""
    out = {}
    for mod, deps in graph.items():
        out[mod] = {d for d in deps if not d.startswith(mod + ".")}
    return out


def test_the_cycle_finder_finds_a_cycle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_circle():
    cycle = _cycle(_package_edges(_graph()))
    assert cycle is None, " -> ".join(cycle)


def test_export_does_not_import_the_simulator():
    graph = _graph()
    bad = {m: sorted(d for d in deps if d.startswith("obsdesign.sim"))
           for m, deps in graph.items() if m.startswith("obsdesign.export")}
    assert not any(bad.values()), bad


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_module_is_under_500_lines(path):
    assert len(path.read_text(encoding="utf-8").splitlines()) < 500


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_every_name_in_all_exists(path):
    module = importlib.import_module(_module_name(path))
    for name in getattr(module, "__all__", ()):
        assert getattr(module, name, None) is not None, f"{module.__name__}.__all__ names {name!r}, which is missing"


def _documented(doc: str, section: str = "Parameters") -> set[str]:
    """Names of a numpydoc ``Parameters`` (or other) section (``a, b : type`` lines count each)."""
    match = re.search(rf"\n\s*{section}\n\s*-+\n(.*?)(\n\s*\n\s*[A-Z][a-z]+\n\s*-+\n|\Z)", doc, re.S)
    if not match:
        return set()
    names = set()
    for line in match.group(1).splitlines():
        m = re.match(r"\s{0,8}(\*{0,2}[A-Za-z_][\w, *]*?)\s*(:|$)", line)
        if m and not line.startswith(" " * 9):
            names.update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return names


def _public_functions():
    """Functions named in the ``__all__`` of public modules (no ``_private`` part in the module name)."""
    seen = set()
    for path in MODULES:
        name = _module_name(path)
        if any(part.startswith("_") for part in name.split(".")):
            continue
        module = importlib.import_module(name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            if inspect.isfunction(obj) and obj.__module__.startswith("obsdesign") and id(obj) not in seen:
                seen.add(id(obj))
                yield f"{obj.__module__}.{obj.__qualname__}", obj


PUBLIC = sorted(_public_functions(), key=lambda item: item[0])


@pytest.mark.parametrize("name, func", PUBLIC, ids=[n for n, _ in PUBLIC])
def test_public_parameters_are_documented(name, func):
    params = [p for p in inspect.signature(func).parameters.values() if p.name not in ("self", "cls")]
    if not params:
        return
    doc = inspect.getdoc(func) or ""
    missing = [p.name for p in params if p.name not in _documented("\n" + doc)]
    assert not missing, f"{name}: parameters not in the Parameters section: {missing}"


def _public_dataclasses():
    """Dataclasses named in the ``__all__`` of public modules, defined in the package."""
    seen = set()
    for path in MODULES:
        name = _module_name(path)
        if any(part.startswith("_") for part in name.split(".")):
            continue
        module = importlib.import_module(name)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            if (isinstance(obj, type) and dataclasses.is_dataclass(obj) and obj.__module__.startswith("obsdesign")
                    and id(obj) not in seen):
                seen.add(id(obj))
                yield f"{obj.__module__}.{obj.__qualname__}", obj


DATACLASSES = sorted(_public_dataclasses(), key=lambda item: item[0])
#: In files being rewritten for the sampled-controller room (issue 16): document them there.
UNDOCUMENTED_FIELDS_ALLOWED = {"obsdesign.sim.simulate.LoopInputs", "obsdesign.sim.registry.Entry",
                               "obsdesign.export.codegen.ExportSpec"}


def test_documented_reads_attributes_sections():
    doc = "\nA result.\n\nAttributes\n----------\nrates : dict\n    By rho.\na, b : float\n    Two.\n\nNotes\n-----\nx : y\n"
    assert _documented(doc, "Attributes") == {"rates", "a", "b"}
    assert _documented(doc) == set()


@pytest.mark.parametrize("name, cls", DATACLASSES, ids=[n for n, _ in DATACLASSES])
def test_public_dataclass_fields_are_documented(name, cls):
    """Every field of a public dataclass is in its docstring's Attributes (or Parameters) section."""
    doc = "\n" + inspect.cleandoc(cls.__doc__ or "")
    documented = _documented(doc, "Attributes") | _documented(doc, "Parameters")
    missing = [f.name for f in dataclasses.fields(cls) if not f.name.startswith("_") and f.name not in documented]
    if name in UNDOCUMENTED_FIELDS_ALLOWED:
        assert missing, f"{name} documents its fields now: remove it from UNDOCUMENTED_FIELDS_ALLOWED"
        pytest.xfail("in a file being rewritten (issue 16)")
    assert not missing, f"{name}: fields not in the Attributes section: {missing}"
