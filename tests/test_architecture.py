"""The import graph follows the pipeline (issue 17).

Every module of ``synthaug`` is read with :mod:`ast` (imports at the top *and*
inside functions, ``TYPE_CHECKING`` blocks included: a reader sees them all)
and mapped to its package. Three rules:

1. a package imports only packages earlier in :data:`ORDER` (the top-level
   helpers ``_checks``, ``_io``, ``_procs`` and the lazy ``synthaug/__init__``
   import no package; ``cli`` and ``demo`` sit at the end and may import all);
2. no private name (``_x``, dunders excepted) is imported from another package;
3. no circle between the modules of one package.

What is left is listed below, each entry with its reason; an entry that no
longer matches the code fails the test, so the lists only shrink.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "synthaug"

ORDER: tuple[str, ...] = ("render", "params", "effects", "data", "detectors", "distances", "fit", "evaluate",
                          "diagnose")
HELPERS: tuple[str, ...] = ("_checks", "_io", "_procs", "synthaug")  # import no pipeline package
ENDS: tuple[str, ...] = ("cli", "demo")  # may import anything

CONCURRENT = "file under concurrent edit; issue 17"

# (importing module, imported module): why the edge is still there.
ALLOWED_BACK_EDGES: dict[tuple[str, str], str] = {
}
# (importing module, imported module, name): why a private name still crosses packages.
ALLOWED_PRIVATE: dict[tuple[str, str, str], str] = {}
# modules of one circle: why it is still there.
ALLOWED_CYCLES: dict[frozenset[str], str] = {
}


@dataclass(frozen=True)
class Edge:
    source: str  # importing module, e.g. synthaug.fit.fitting
    target: str  # imported module, e.g. synthaug.params
    name: str | None  # the imported name of a ``from`` import
    line: int
    in_function: bool


def collect_modules(root: Path, package: str = "synthaug") -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` file under ``root`` (a package folder)."""
    mods = {}
    for f in sorted(root.rglob("*.py")):
        parts = [package, *f.relative_to(root).with_suffix("").parts]
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = f
    return mods


def import_edges(modules: dict[str, Path], package: str = "synthaug") -> list[Edge]:
    """Every import of a ``package`` module by a module of ``modules`` (top level and in functions)."""
    edges = []
    for mod, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        inside: set[int] = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                inside.update(id(sub) for sub in ast.walk(node) if sub is not node)
        here = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        for node in ast.walk(tree):
            found: list[tuple[str, str | None]] = []
            if isinstance(node, ast.Import):
                found = [(a.name, None) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = here.split(".")[:len(here.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                # ``from pkg import module`` is an edge to that module, ``from pkg import name`` one to pkg
                found = [(f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base, a.name) for a in node.names]
            for target, name in found:
                if target == package or target.startswith(package + "."):
                    edges.append(Edge(mod, target, name, node.lineno, id(node) in inside))
    return edges


def package_of(module: str) -> str:
    """``synthaug.fit.fitting`` -> ``fit``; ``synthaug.params`` -> ``params``; ``synthaug`` -> ``synthaug``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def rank(package: str) -> int:
    if package in HELPERS:
        return -1
    if package in ORDER:
        return ORDER.index(package)
    if package in ENDS:
        return len(ORDER)
    raise AssertionError(f"package {package!r} has no place in the pipeline order: add it to ORDER, HELPERS or ENDS")


def back_edges(edges: list[Edge]) -> list[Edge]:
    """Edges into a package that is not earlier in the order (helpers import no package at all)."""
    out = []
    for e in edges:
        a, b = package_of(e.source), package_of(e.target)
        if a == b or a in ENDS:
            continue
        if rank(b) >= rank(a) or (a in HELPERS and b not in HELPERS):
            out.append(e)
    return out


def private_imports(edges: list[Edge]) -> list[Edge]:
    """``from other_package... import _name`` (dunders such as ``__version__`` are public)."""
    return [e for e in edges if e.name and e.name.startswith("_") and not e.name.startswith("__")
            and package_of(e.source) != package_of(e.target)]


def module_cycles(edges: list[Edge]) -> list[frozenset[str]]:
    """Circles (strongly connected components of two or more modules) inside each package."""
    graph: dict[str, set[str]] = {}
    for e in edges:
        graph.setdefault(e.source, set())
        graph.setdefault(e.target, set())
        if e.source != e.target and package_of(e.source) == package_of(e.target):
            graph[e.source].add(e.target)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[frozenset[str]] = []

    def visit(v: str) -> None:  # Tarjan; the graphs are small, recursion is fine
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.add(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(frozenset(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def _describe(e: Edge) -> str:
    where = "in a function" if e.in_function else "top level"
    return f"{e.source}:{e.line} imports {e.target}{'.' + e.name if e.name else ''} ({where})"


@pytest.fixture(scope="module")
def edges() -> list[Edge]:
    return import_edges(collect_modules(ROOT))


# ----------------------------------------------------------------- the rules on the package
def test_every_package_has_a_place(edges):
    for e in edges:
        rank(package_of(e.source))
        rank(package_of(e.target))


def test_no_import_runs_up_the_pipeline(edges):
    bad = [e for e in back_edges(edges) if (e.source, e.target) not in ALLOWED_BACK_EDGES]
    assert not bad, "imports against the pipeline order " + " → ".join(ORDER) + ":\n" + \
        "\n".join(_describe(e) for e in bad)


def test_no_private_name_crosses_packages(edges):
    bad = [e for e in private_imports(edges) if (e.source, e.target, e.name) not in ALLOWED_PRIVATE]
    assert not bad, "private names imported from another package:\n" + "\n".join(_describe(e) for e in bad)


def test_no_circle_inside_a_package(edges):
    bad = [sorted(c) for c in module_cycles(edges) if c not in ALLOWED_CYCLES]
    assert not bad, f"circles between modules of one package: {bad}"


def test_allow_lists_name_what_is_still_there(edges):
    """An allow-listed edge that is gone must leave the list (it only shrinks)."""
    pairs = {(e.source, e.target) for e in back_edges(edges)}
    names = {(e.source, e.target, e.name) for e in private_imports(edges)}
    cycles = set(module_cycles(edges))
    stale = [k for k in ALLOWED_BACK_EDGES if k not in pairs] + [k for k in ALLOWED_PRIVATE if k not in names] + \
        [sorted(k) for k in ALLOWED_CYCLES if k not in cycles]
    assert not stale, f"fixed, remove from the allow-lists of {__name__}: {stale}"


# ----------------------------------------------------------------- the checker can fail
def _tree(tmp_path: Path, files: dict[str, str]) -> list[Edge]:
    root = tmp_path / "synthaug"
    for rel, text in files.items():
        f = root / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
    return import_edges(collect_modules(root))


def test_checker_finds_an_injected_back_edge(tmp_path):
    edges = _tree(tmp_path, {
        "__init__.py": "",
        "params.py": "def f():\n    from synthaug.fit.fitting import RESULT_VERSION\n",  # in a function
        "fit/__init__.py": "",
        "fit/fitting.py": "from synthaug.params import CaptureParams\nRESULT_VERSION = 1\n",
        "_io.py": "import synthaug.render.mesh\n",  # a helper importing a package
        "render/__init__.py": "",
        "render/mesh.py": "",
    })
    bad = back_edges(edges)
    assert sorted((e.source, e.target, e.in_function) for e in bad) == [
        ("synthaug._io", "synthaug.render.mesh", False), ("synthaug.params", "synthaug.fit.fitting", True)]


def test_checker_finds_private_names_and_circles(tmp_path):
    edges = _tree(tmp_path, {
        "__init__.py": "__version__ = '0'\n",
        "params.py": "def _spec():\n    pass\n",
        "effects/__init__.py": "",
        "effects/a.py": "from synthaug.params import _spec\nfrom synthaug import __version__\n"
                        "from . import b\n",  # relative import, inside the package
        "effects/b.py": "def g():\n    from synthaug.effects.a import x\n",
        "effects/c.py": "from synthaug.effects import a\n",  # into the circle, not part of it
    })
    assert [(e.source, e.name) for e in private_imports(edges)] == [("synthaug.effects.a", "_spec")]
    assert module_cycles(edges) == [frozenset({"synthaug.effects.a", "synthaug.effects.b"})]


def test_checker_rejects_an_unknown_package():
    with pytest.raises(AssertionError, match="no place"):
        rank("plugins")


def test_the_import_graph_picture_is_current():
    """``docs/import_graph.md`` (the Mermaid picture of the package graph) is the graph of the current code:
    a new package-to-package import, or one removed, means regenerating it with ``python tools/import_graph.py``."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("_import_graph", ROOT.parent / "tools" / "import_graph.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    packages, counts, back = tool.package_edges()
    assert back == []  # the picture shows no arrow up the pipeline
    page = (ROOT.parent / "docs" / "import_graph.md").read_text(encoding="utf-8")
    assert page == tool.mermaid(packages, counts, back), "docs/import_graph.md is stale: run python tools/import_graph.py"
    # the picture is not vacuous: every package of the pipeline is in it, with its arrows
    assert set(ORDER) <= set(packages) and ("diagnose", "fit") in counts and ("fit", "data") in counts
