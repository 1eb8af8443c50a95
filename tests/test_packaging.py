"""Packaging: every package folder is installed under its mapped import name."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAPPING = {"povagent": "povagent", "plugins": "povagent_plugins", "prompts": "povagent_prompts"}


def test_every_package_folder_is_listed_in_pyproject():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(config["packages"])
    found = set()
    for folder, name in MAPPING.items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder)
            found.add(".".join((name, *rel.parts)))
    assert found - listed == set(), "add these to [tool.setuptools] packages"
    assert listed - found == set(), "these listed packages have no folder"


#: Import names that differ from their distribution's name (PyPI normalised).
DISTRIBUTION_OF = {"PIL": "pillow", "yaml": "pyyaml", "pydantic_core": "pydantic-core",
                   # ROS 2's packages on PyPI are named ros-<package> (the ros extra)
                   "rclpy": "ros-rclpy", "std_msgs": "ros-std-msgs", "sensor_msgs": "ros-sensor-msgs",
                   "geometry_msgs": "ros-geometry-msgs", "nav_msgs": "ros-nav-msgs",
                   "rcl_interfaces": "ros-rcl-interfaces", "action_msgs": "ros-action-msgs"}
#: Modules only ever imported by pytest itself (a pytest plugin): they may import the ``test`` extra.
PYTEST_ONLY = {"povagent/testing/pytest_plugin.py"}
OURS = {"povagent", "povagent_plugins", "povagent_prompts"}
#: Packages a user installs for their hardware before an extra, and no extra lists (pip would
#: otherwise replace a chosen CPU/CUDA build): imported lazily only (the ``local`` extra's docs
#: say to install it first).
INSTALLED_FIRST = {"torch"}


def _normalised(name: str) -> str:
    import re

    return re.sub(r"[-_.]+", "-", name).lower()


def _requirement_names(requirements: list[str]) -> set[str]:
    import re

    return {_normalised(re.match(r"[A-Za-z0-9._-]+", r.strip()).group(0)) for r in requirements}


def third_party_imports(source: str) -> list[tuple[str, int, bool]]:
    """``(top-level package, line, lazy_or_guarded)`` of every absolute import of a package
    outside the standard library and povagent: lazy when inside a function, guarded when inside
    a ``try`` that catches ``ImportError`` (or ``ModuleNotFoundError``), or under ``TYPE_CHECKING``."""
    import ast
    import sys

    tree = ast.parse(source)
    out: list[tuple[str, int, bool]] = []

    def catches_import_error(node: ast.Try) -> bool:
        names = []
        for h in node.handlers:
            types = h.type.elts if isinstance(h.type, ast.Tuple) else [h.type]
            names += [t.id for t in types if isinstance(t, ast.Name)]
        return bool({"ImportError", "ModuleNotFoundError"} & set(names))

    def visit(node: ast.AST, soft: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = soft or (
                isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
                or (isinstance(child, ast.Try) and catches_import_error(child))
                or (isinstance(child, ast.If) and "TYPE_CHECKING" in ast.unparse(child.test))
            )
            if isinstance(child, ast.Import):
                tops = [a.name.split(".")[0] for a in child.names]
            elif isinstance(child, ast.ImportFrom) and child.level == 0 and child.module:
                tops = [child.module.split(".")[0]]
            else:
                tops = []
            for top in tops:
                if top not in sys.stdlib_module_names and top not in OURS:
                    out.append((top, child.lineno, inner))
            visit(child, inner)

    visit(tree, False)
    return out


def test_the_scanner_tells_module_level_imports_from_lazy_and_guarded_ones():
    source = (
        "import numpy as np\nimport os\nfrom povagent import hookimpl\nfrom typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import litellm\n"
        "try:\n    import httpx2\nexcept ImportError:\n    import httpx\n"
        "def f():\n    from tqdm.auto import tqdm\n"
    )
    assert third_party_imports(source) == [("numpy", 1, False), ("litellm", 6, True), ("httpx2", 8, True), ("httpx", 10, True), ("tqdm", 12, True)]


def test_every_package_povagent_imports_is_declared_in_pyproject():
    """A package povagent or its plugins import must be a dependency of povagent itself, not
    something that arrives through another package (``trimesh`` came with ``procthor``). An
    import that is lazy (in a function) or guarded (``except ImportError``) may instead name an
    optional extra; a pytest plugin module may import the ``test`` extra."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    required = _requirement_names(project["dependencies"])
    extras = {name: _requirement_names(reqs) for name, reqs in project.get("optional-dependencies", {}).items()}
    optional = set().union(*extras.values())
    undeclared = []
    for folder in ("povagent", "plugins", "prompts"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            for top, line, soft in third_party_imports(path.read_text(encoding="utf-8")):
                name = _normalised(DISTRIBUTION_OF.get(top, top))
                if name in required:
                    continue
                if rel in PYTEST_ONLY and name in extras.get("test", set()):
                    continue
                if soft and (name in optional or name in INSTALLED_FIRST):
                    continue
                undeclared.append(f"{rel}:{line}: {top}" + (" (lazy or guarded: an optional extra would do)" if soft else ""))
    assert undeclared == [], "declare these in pyproject.toml's dependencies:\n" + "\n".join(undeclared)
