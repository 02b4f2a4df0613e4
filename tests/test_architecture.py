"""The shape of the code: imports flow one way, with no circles; packages are discoverable;
tolerances live in one place.

Read from the source files (every import statement, also inside functions, but not those
under ``if TYPE_CHECKING:``, which never run), not from what happens to be imported.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import ROOT

PACKAGES = ("core", "adapters", "plugins", "refvm", "examples")

#: The layers of core, lowest first: a module may import its own layer and those below.
#: The hookspecs, the plugin-manager factory and the facade sit on top of the four; the
#: command line above everything.
LAYERS = {
    "core.model": 0,
    "core.engine": 1,
    "core.view": 2,
    "core.diagnosis": 3,
    "core": 4,  # core/__init__, hookspecs, plugins, facade, __main__, _version
    "core.cli": 5,
    "core.__main__": 5,  # `python -m core`: the command line
}


def module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def project_modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            if "build" in path.relative_to(ROOT).parts:
                continue
            out[module_name(path)] = path
    return out


MODULES = project_modules()


def _type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def _walk(node: ast.AST) -> Iterator[ast.AST]:
    """Every node, except the bodies of ``if TYPE_CHECKING:`` blocks."""
    for child in ast.iter_child_nodes(node):
        if isinstance(child, ast.If) and _type_checking(child):
            for other in child.orelse:
                yield other
                yield from _walk(other)
            continue
        yield child
        yield from _walk(child)


def imports_of(name: str) -> set[str]:
    """Project modules ``name`` imports (a ``from pkg import sub`` names the submodule)."""
    path = MODULES[name]
    tree = ast.parse(path.read_text(), str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in _walk(tree):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                mod = ".".join([*base, node.module] if node.module else base)
            else:
                mod = node.module or ""
            subs = [f"{mod}.{a.name}" for a in node.names]
            found = [s for s in subs if s in MODULES]
            targets = found if found else [mod]
        for t in targets:
            # the module itself, or the nearest package of it that is ours
            while t and t not in MODULES:
                t = t.rpartition(".")[0]
            if t and t != name:
                out.add(t)
    return out


GRAPH = {name: imports_of(name) for name in MODULES}


def layer(name: str) -> int | None:
    if not name.startswith("core"):
        return None
    best = None
    for prefix, rank in LAYERS.items():
        if name == prefix or name.startswith(prefix + "."):
            if best is None or len(prefix) > len(best[0]):
                best = (prefix, rank)
    assert best is not None, name
    return best[1]


def test_the_graph_is_read():
    """The import reader sees what is there (it would pass vacuously otherwise)."""
    assert "core.model.toolpath" in GRAPH["core.engine.profile"]
    assert "core.facade" in GRAPH["core.cli.main"]
    assert "core.hookspecs" in GRAPH["plugins.tangential"] or "core" in GRAPH["plugins.tangential"]
    assert len(MODULES) > 60


def test_no_import_circles():
    """No module reaches itself through the imports of others (Tarjan's strongly connected
    components of the import graph all have one member)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    circles: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(GRAPH[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert circles == []


def test_core_layers_import_downward_only():
    """model <- engine <- view <- diagnosis <- hooks, factory, facade <- cli: no module of
    core imports a layer above its own."""
    upward = [
        f"{a} -> {b}"
        for a, deps in GRAPH.items()
        for b in deps
        if layer(a) is not None and layer(b) is not None and layer(b) > layer(a)
    ]
    assert upward == []


def test_core_modules_import_submodules_not_the_core_package():
    """Inside core, imports name the module that defines a thing: the package ``core`` is the
    public API for adapters, plugins and users, and importing it from inside would tie every
    module to all of core."""
    offenders = [a for a, deps in GRAPH.items() if a.startswith("core.") and "core" in deps]
    assert offenders == []


@pytest.mark.parametrize(
    ("importer", "forbidden"),
    [
        ("core", ("adapters", "plugins", "refvm", "examples")),
        ("adapters", ("plugins", "refvm")),
        ("plugins", ("adapters", "refvm")),
        ("refvm", ("core", "adapters", "plugins")),
    ],
    ids=["core", "adapters", "plugins", "refvm"],
)
def test_packages_keep_to_their_side(importer, forbidden):
    """core imports no adapter or plugin; adapters and plugins import core, never each
    other; the reference interpreter imports none of ncperf."""
    bad = [
        f"{a} -> {b}"
        for a, deps in GRAPH.items()
        if a.split(".")[0] == importer
        for b in deps
        if b.split(".")[0] in forbidden
    ]
    assert bad == []


def test_adapters_do_not_import_each_other():
    """Each adapter stands alone (a CL file does not load the G-code reader): adapters share
    only adapters/source.py."""
    bad = [
        f"{a} -> {b}"
        for a, deps in GRAPH.items()
        if a.startswith("adapters.") and a != "adapters.source"
        for b in deps
        if b.startswith("adapters.")
        and b != "adapters.source"
        and b.split(".")[1] != a.split(".")[1]
    ]
    assert bad == []


def test_every_code_folder_is_a_package():
    """Packages are found by discovery (pyproject.toml), which needs an __init__.py: a code
    folder without one would silently be left out of the wheel."""
    missing = [
        str(folder.relative_to(ROOT))
        for pkg in PACKAGES
        for folder in [ROOT / pkg, *(p for p in (ROOT / pkg).rglob("*") if p.is_dir())]
        if any(folder.glob("*.py"))
        and not (folder / "__init__.py").exists()
        and "__pycache__" not in folder.parts
    ]
    assert missing == []


def test_no_epsilons_outside_the_tolerances():
    """Float literals of 1e-3 and below in core, adapters and plugins are tolerances and
    live in core/model/tolerances.py (each with its reason); elsewhere only as the value of
    a named, documented module constant (an iteration's stopping rule, a time step) or as an
    effect parameter's bound."""
    found = []
    for pkg in ("core", "adapters", "plugins"):
        for path in sorted((ROOT / pkg).rglob("*.py")):
            if path.name == "tolerances.py":
                continue
            tree = ast.parse(path.read_text())
            named = {
                id(node.value)
                for node in tree.body
                if isinstance(node, ast.Assign | ast.AnnAssign)
                and isinstance(node.value, ast.Constant)
            }
            # the bounds of an effect's parameter are physical values, not epsilons
            named |= {
                id(arg)
                for node in ast.walk(tree)
                if isinstance(node, ast.Call)
                and isinstance(node.func, ast.Name)
                and node.func.id == "Param"
                for arg in node.args
            }
            for node in ast.walk(tree):
                if (
                    isinstance(node, ast.Constant)
                    and isinstance(node.value, float)
                    and 0 < abs(node.value) <= 1e-3
                    and id(node) not in named
                ):
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {node.value!r}")
    assert found == []


def test_no_module_imports_another_modules_private_names():
    """A name starting with "_" is its module's own: other modules use the public layer
    (e.g. ToolPath.point_at, not the alignment's private helper)."""
    found = []
    for name, path in MODULES.items():
        for node in _walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.module != "__future__":
                found += [
                    f"{name}: from {node.module} import {a.name}"
                    for a in node.names
                    if a.name.startswith("_") and not a.name.startswith("__")
                ]
    assert found == []
