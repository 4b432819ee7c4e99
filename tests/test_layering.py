"""The arrows between chaospound's modules point down (issue 14, item 8).

Imports are read from the source with :mod:`ast`, at module level and inside
functions alike (a function-level import is still an edge: it only moves the
cycle to run time). The layers, from the bottom:

* ``chaospound.kernels``: the numba decorators, the packed-vector layout, the
  cache guard and the composition's free names; nothing of chaospound outside it;
* ``chaospound.physics`` (models, contact laws, ground motions) and
  ``chaospound.solvers`` (tableaux, steppers, controllers): each imports only
  itself and the kernels package, never the other: physics and solvers never
  meet except in the engine;
* ``chaospound.engine``: composes them (it imports solvers and the kernels
  package, and of physics only the corner codes; models, laws and motions are
  named as data and joined in the generated module);
* the edge below the drivers: ``scene``, ``messages`` and the shared system
  vocabulary ``dynamics.system``;
* the drivers and analyses: ``simulate``, ``dynamics.*``;
* the sweep (``sweep``, its task runner ``point``, the Dask backend
  ``distributed``, ``grid``) and the store;
* the tools on top: ``plot``, ``cli``, ``bench``.

Nothing below the sweep knows about files, plots or the command line.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "chaospound"

#: modules at or below the drivers: none of them may import plot, store or cli
BELOW_SWEEP = (
    "chaospound.kernels",
    "chaospound.physics",
    "chaospound.solvers",
    "chaospound.engine",
    "chaospound.scene",
    "chaospound.messages",
    "chaospound.simulate",
    "chaospound.dynamics",
)
#: what the kernels must never import (everything of chaospound outside the kernels)
TOOLS = ("chaospound.plot", "chaospound.store", "chaospound.cli")


def _modules() -> dict[str, tuple[Path, bool]]:
    modules = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts.pop()
        modules[".".join(parts)] = (path, is_package)
    return modules


def import_graph() -> dict[str, set[str]]:
    """Module name -> the chaospound modules it imports anywhere in its source."""
    modules = _modules()
    graph = {}
    for name, (path, is_package) in modules.items():
        package = name if is_package else name.rpartition(".")[0]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                # "from pkg import mod" imports the module pkg.mod
                targets = [f"{module}.{alias.name}" if f"{module}.{alias.name}" in modules
                           else module for alias in node.names]
            else:
                continue
            for target in targets:
                while target and target not in modules:  # "import a.b.c" of a package
                    target = target.rpartition(".")[0]
                if target and target != name:
                    edges.add(target)
        graph[name] = edges
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for succ in sorted(graph[node]):
            if succ not in index:
                visit(succ)
                low[node] = min(low[node], low[succ])
            elif succ in on_stack:
                low[node] = min(low[node], index[succ])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def _under(name: str, prefixes) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_the_graph_sees_function_level_and_relative_imports():
    graph = import_graph()
    assert "chaospound.engine.compose" in graph["chaospound.simulate"]  # relative
    assert "chaospound.distributed" in graph["chaospound.sweep"]  # inside a function
    assert "chaospound.scene" in graph["chaospound"]  # inside __getattr__
    assert "chaospound.cli.options" in graph["chaospound.cli.simulate"]  # the cli package
    assert _under("chaospound.cli.sweep", TOOLS)  # a tool package's modules are tools too


def test_no_import_cycles():
    assert _cycles(import_graph()) == []


def test_kernels_import_only_kernels():
    graph = import_graph()
    wrong = {(name, target) for name, edges in graph.items()
             if _under(name, ["chaospound.kernels"])
             for target in edges if not _under(target, ["chaospound.kernels"])}
    assert wrong == set()


def _imports_outside(graph, package: str, allowed) -> set:
    return {(name, target) for name, edges in graph.items() if _under(name, [package])
            for target in edges if not _under(target, allowed)}


def test_physics_and_solvers_never_import_each_other():
    graph = import_graph()
    assert _imports_outside(graph, "chaospound.physics",
                            ["chaospound.physics", "chaospound.kernels"]) == set()
    assert _imports_outside(graph, "chaospound.solvers",
                            ["chaospound.solvers", "chaospound.kernels"]) == set()


def test_the_engine_joins_physics_and_solvers_only_by_name():
    graph = import_graph()
    allowed = ["chaospound.engine", "chaospound.solvers", "chaospound.kernels",
               "chaospound.physics.corners"]
    assert _imports_outside(graph, "chaospound.engine", allowed) == set()


def test_nothing_below_the_sweep_imports_plot_store_or_cli():
    graph = import_graph()
    wrong = {(name, target) for name, edges in graph.items() if _under(name, BELOW_SWEEP)
             for target in edges if _under(target, TOOLS)}
    assert wrong == set()
