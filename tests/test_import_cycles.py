"""No two modules of povagent (or of its built-in plugins) import each other, however indirectly.

A circle of imports is two rooms that cannot be read, tested or moved apart: configuration that
reaches up into the engine for a retry policy, a row format that needs its own summaries. Every
import counts, wherever it is written (at the top, inside a function, under ``TYPE_CHECKING``):
an import moved into a function still ties the two modules together, it only hides the knot
until the function runs. The scan reads the source; it imports nothing.
"""

from __future__ import annotations

import ast
import functools
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: Folder -> the import name it is installed as (see ``package-dir`` in pyproject.toml).
PACKAGES = {"povagent": "povagent", "plugins": "povagent_plugins"}

#: ``(importer, imported) -> line`` of the first import of ``imported`` in ``importer``.
Edges = dict[tuple[str, str], int]


def module_files(folder: Path, name: str) -> dict[str, Path]:
    """Every module under ``folder`` by its dotted import name (a package by its own name)."""
    found = {}
    for path in sorted(folder.rglob("*.py")):
        parts = path.relative_to(folder).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join((name, *parts))] = path
    return found


def _imported_names(node: ast.AST, module: str, is_package: bool) -> Iterator[str]:
    """The dotted names an import statement may load: the module, and for ``from M import x``
    also ``M.x`` (which is a module when ``x`` is a submodule)."""
    if isinstance(node, ast.Import):
        for alias in node.names:
            yield alias.name
    elif isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:  # relative: resolved against the importing module's package
            package = module.split(".") if is_package else module.split(".")[:-1]
            package = package[: len(package) - (node.level - 1)]
            base = ".".join(package + ([base] if base else []))
        if base:
            yield base
        for alias in node.names:
            yield f"{base}.{alias.name}" if base else alias.name


def import_edges(modules: dict[str, Path]) -> Edges:
    """Every import from one of ``modules`` to another, wherever in the file it is written."""
    edges: Edges = {}
    for module, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            for name in _imported_names(node, module, path.name == "__init__.py"):
                if name in modules and name != module:
                    line = getattr(node, "lineno", 0)
                    edges[(module, name)] = min(edges.get((module, name), line), line)
    return edges


@functools.cache
def povagent_import_edges() -> tuple[dict[str, Path], Edges]:
    """The modules of povagent and its plugins by dotted name, and every import between them.

    Read once a process: the scan parses every file (a second or two), and the floors test
    (``test_import_floors``) asks the same question of the same tree four times. Callers only
    read what it returns."""
    files: dict[str, Path] = {}
    for folder, name in PACKAGES.items():
        files.update(module_files(ROOT / folder, name))
    return files, import_edges(files)


def import_knots(edges: Edges) -> list[list[str]]:
    """The groups of modules that import one another (strongly connected, two or more), each
    sorted, in sorted order (so a failure reads the same every time)."""
    graph: dict[str, list[str]] = {}
    for a, b in sorted(edges):
        graph.setdefault(a, []).append(b)
        graph.setdefault(b, [])
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[set[str]] = []

    def connect(v: str) -> None:  # Tarjan; the graph is a few hundred modules deep at most
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.add(w)
                if w == v:
                    break
            if len(group) > 1:
                groups.append(group)

    for v in sorted(graph):
        if v not in index:
            connect(v)
    return sorted(sorted(group) for group in groups)


def a_cycle_through(group: list[str], edges: Edges) -> list[str]:
    """A shortest cycle through the group's first module, in import order (``[a, b, c]``: a
    imports b, b imports c, c imports a)."""
    graph: dict[str, list[str]] = {}
    for a, b in sorted(edges):
        graph.setdefault(a, []).append(b)
    start = group[0]
    came_from: dict[str, str] = {}
    frontier = [start]
    while frontier:
        following = []
        for v in frontier:
            for w in graph.get(v, []):
                if w not in group:
                    continue
                if w == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(came_from[path[-1]])
                    return path[::-1]
                if w not in came_from:
                    came_from[w] = v
                    following.append(w)
        frontier = following
    raise AssertionError(f"{sorted(group)} is strongly connected yet has no cycle through {start}")


def describe(group: list[str], edges: Edges, files: dict[str, Path], root: Path = ROOT) -> str:
    """The group's modules, then one cycle through them with where each of its imports is
    written: ``a (a.py:3 imports b) -> b (b.py:9 imports a)``."""
    cycle = a_cycle_through(group, edges)
    steps = [f"{a} ({files[a].relative_to(root).as_posix()}:{edges[(a, b)]} imports {b})" for a, b in zip(cycle, cycle[1:] + cycle[:1])]
    return f"{len(group)} modules ({', '.join(group)}); one cycle: " + " -> ".join(steps)


def test_the_scan_finds_a_cycle_hidden_in_a_function_or_under_type_checking(tmp_path):
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from pkg.sub import b\n")
    (pkg / "sub" / "b.py").write_text("def later():\n    from .c import value\n")
    (pkg / "sub" / "c.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import pkg.a\nvalue = 1\n")
    (pkg / "d.py").write_text("import pkg.a\n")  # imports into the cycle, but is not part of it
    files = module_files(pkg, "pkg")
    edges = import_edges(files)
    assert edges[("pkg.sub.b", "pkg.sub.c")] == 2
    assert import_knots(edges) == [["pkg.a", "pkg.sub.b", "pkg.sub.c"]]
    assert describe(["pkg.a", "pkg.sub.b", "pkg.sub.c"], edges, files, tmp_path) == (
        "3 modules (pkg.a, pkg.sub.b, pkg.sub.c); one cycle: pkg.a (pkg/a.py:1 imports pkg.sub.b) -> "
        "pkg.sub.b (pkg/sub/b.py:2 imports pkg.sub.c) -> pkg.sub.c (pkg/sub/c.py:3 imports pkg.a)"
    )


def test_the_scan_finds_nothing_in_a_tree_without_cycles(tmp_path):
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("from pkg import a\n")
    (pkg / "a.py").write_text("import pkg.b\n")
    (pkg / "b.py").write_text("import os\n")
    assert import_knots(import_edges(module_files(pkg, "pkg"))) == []


def test_no_module_of_povagent_or_its_plugins_imports_itself_through_others():
    files, edges = povagent_import_edges()
    cycles = [describe(group, edges, files) for group in import_knots(edges)]
    assert cycles == [], (
        f"{len(cycles)} import cycle(s); move what both sides need into a module below them "
        "(a function-level or TYPE_CHECKING import still counts):\n" + "\n".join(cycles)
    )
