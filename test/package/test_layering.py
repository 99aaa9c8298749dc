"""The layering contract of docs/architecture.md, read from the source: every import (module
level or inside a function) points down the layers, rclpy stays in ros/, the product never
imports the studies, the import graph has no cycle, and no file or function outgrows the
limits the house keeps (600 lines a file, cyclomatic complexity 20 a function, by radon)."""
from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest
from radon.complexity import cc_visit

PACKAGE = Path(__file__).resolve().parents[2] / "youbot_dynamics"
LAYERS = ("model", "dynamics", "integrate", "scene", "sim", "io", "node", "identification",
          "accuracy", "ros", "studies", "cli")
"""The sub-packages from the bottom up: a module may import its own package and those below."""
STUDY_USERS = {"studies", "cli"}
"""The packages that may import youbot_dynamics.studies."""
MAX_LINES = 600
MAX_COMPLEXITY = 20


def module_name(path: Path) -> str:
    """youbot_dynamics.pkg.module of a source file (a package's __init__ names the package)."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


SOURCES = {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def imports(path: Path) -> list[tuple[int, str]]:
    """(line, imported module or name) for every import statement of the file, at any depth."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module))
            found += [(node.lineno, f"{node.module}.{alias.name}") for alias in node.names]
    return found


def layer(module: str) -> str | None:
    """The sub-package of a youbot_dynamics module (None for the top-level modules)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in LAYERS else None


def test_every_sub_package_has_a_layer() -> None:
    packages = {path.parent.name for path in PACKAGE.glob("*/__init__.py")}
    assert packages == set(LAYERS)


def test_imports_point_down_the_layers() -> None:
    upward = []
    for name, path in SOURCES.items():
        own = layer(name)
        for line, target in imports(path):
            if own and target.startswith("youbot_dynamics.") and (other := layer(target)):
                if LAYERS.index(other) > LAYERS.index(own):
                    upward.append(f"{path.relative_to(PACKAGE)}:{line} ({own}) imports {target} ({other})")
    assert not upward, "\n".join(dict.fromkeys(upward))


def test_rclpy_only_in_ros() -> None:
    leaks = [f"{path.relative_to(PACKAGE)}:{line} imports {target}"
             for name, path in SOURCES.items() if layer(name) != "ros"
             for line, target in imports(path) if target.split(".")[0] in {"rclpy", "rosidl_runtime_py"}]
    assert not leaks, "\n".join(leaks)


def test_only_cli_and_the_studies_import_studies() -> None:
    users = [f"{path.relative_to(PACKAGE)}:{line}" for name, path in SOURCES.items()
             if layer(name) not in STUDY_USERS
             for line, target in imports(path) if target.startswith("youbot_dynamics.studies")]
    assert not users, "\n".join(dict.fromkeys(users))


def test_the_import_graph_has_no_cycle() -> None:
    graph = nx.DiGraph()
    for name, path in SOURCES.items():
        graph.add_node(name)
        for _, target in imports(path):
            if target in SOURCES and target not in (name, "youbot_dynamics"):
                graph.add_edge(name, target)
    cycles = [sorted(component) for component in nx.strongly_connected_components(graph)
              if len(component) > 1]
    assert not cycles, cycles


def functions(blocks: list) -> list:
    """radon's functions and methods, closures included, from cc_visit's nested blocks."""
    found = []
    for block in blocks:
        inner = [*getattr(block, "methods", ()), *getattr(block, "closures", ()),
                 *getattr(block, "inner_classes", ())]
        found += ([] if hasattr(block, "methods") else [block]) + functions(inner)
    return found


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_file_and_function_size(name: str) -> None:
    text = SOURCES[name].read_text()
    lines = len(text.splitlines())
    assert lines <= MAX_LINES, f"{name}: {lines} lines"
    complex_blocks = [f"{block.fullname} (line {block.lineno}): {block.complexity}"
                      for block in functions(cc_visit(text)) if block.complexity > MAX_COMPLEXITY]
    assert not complex_blocks, complex_blocks
