"""The layers of probedyn, checked on the source of this checkout (docs/developing.md).

Folders are stages and import only downward::

    core  <-  meshes  <-  fem  <-  lumped  <-  schemes
                 ^---------^--------^----  probes (composes geometry, FEM, reduction)
    commands, report, cli: on top (the only places that print, plot or write prose)

Every ``import`` of the package is read with :mod:`ast` (module level and inside functions,
relative imports resolved); nothing is imported or executed. Checked: the forbidden arrows,
no loop between folders, ``probedyn/core`` and the plotting leaf import nothing above them,
nothing below the CLI imports ``probedyn.commands``, and no model module imports matplotlib or
pyvista.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: top-level folders served as probedyn.<folder> (pyproject.toml package-dir)
STAGES = ("meshes", "fem", "lumped", "schemes")
#: folders of probedyn/ that are layers of their own
SUBPACKAGES = ("core", "commands", "probes", "diagnose", "report")
#: layers allowed to import probedyn.commands (the command line and the report on top of it)
TOP = {"cli", "commands", "report"}
#: the only places that may import matplotlib or pyvista: the plotting leaf and the renderer (the
#: report and the commands draw through probedyn.plotting)
PLOTTING_ALLOWED = ("fem/render.py", "probedyn/plotting.py")

FORBIDDEN = {
    "meshes": {"fem", "lumped", "schemes", "probes"},
    "fem": {"lumped", "schemes", "probes"},
    "lumped": {"schemes", "probes"},
    "schemes": {"probes"},
}


def layer_of_file(rel: str) -> str | None:
    parts = rel.split("/")
    if parts[0] in STAGES:
        return parts[0]
    if parts[0] != "probedyn":
        return None
    if len(parts) > 2:
        return parts[1] if parts[1] in SUBPACKAGES else "probedyn"
    return {"cli.py": "cli", "plotting.py": "plotting", "report.py": "report"}.get(parts[1], "probedyn")


def layer_of_module(name: str) -> str | None:
    parts = name.split(".")
    if parts[0] != "probedyn":
        return None
    if len(parts) == 1:
        return "probedyn"
    if parts[1] in STAGES or parts[1] in SUBPACKAGES or parts[1] in ("cli", "plotting"):
        return parts[1]
    return "probedyn"


def module_of_file(rel: str) -> list[str]:
    """Dotted package path of a source file (``fem/model.py`` -> ``probedyn.fem.model``)."""
    parts = rel[:-3].split("/")
    if parts[0] in STAGES:
        parts = ["probedyn"] + parts
    if parts[-1] == "__init__":
        parts = parts[:-1] + ["__init__"]
    return parts


def source_files() -> list[str]:
    out = []
    for top in ("probedyn",) + STAGES:
        for p in sorted((ROOT / top).rglob("*.py")):
            rel = p.relative_to(ROOT).as_posix()
            if "/__pycache__/" not in rel:
                out.append(rel)
    return out


def imports_of(rel: str) -> list[tuple[int, str]]:
    """``(line, imported module)`` for every import statement of a file."""
    tree = ast.parse((ROOT / rel).read_text(encoding="utf-8"), filename=rel)
    pkg = module_of_file(rel)[:-1]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg[: len(pkg) - (node.level - 1)] if node.level > 1 else pkg
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            # ``from probedyn import commands``: the imported names are modules
            if layer_of_module(mod) == "probedyn":
                out += [(node.lineno, f"{mod}.{a.name}") for a in node.names]
            else:
                out.append((node.lineno, mod))
    return out


@pytest.fixture(scope="module")
def graph():
    edges: dict[tuple[str, str], list[str]] = defaultdict(list)
    plots: list[str] = []
    for rel in source_files():
        src = layer_of_file(rel)
        for line, mod in imports_of(rel):
            where = f"{rel}:{line} imports {mod}"
            if mod.split(".")[0] in ("matplotlib", "pyvista") and not rel.startswith(PLOTTING_ALLOWED):
                plots.append(where)
            dst = layer_of_module(mod)
            if dst is not None and dst != src:
                edges[(src, dst)].append(where)
    return edges, plots


def test_the_checkout_has_the_layers():
    files = source_files()
    assert {layer_of_file(f) for f in files} >= {"meshes", "fem", "lumped", "schemes", "probes", "core", "commands"}
    assert len(files) > 50


def test_no_forbidden_arrow(graph):
    edges, _ = graph
    bad = [w for (a, b), ws in edges.items() if b in FORBIDDEN.get(a, ()) for w in ws]
    assert not bad, "imports against the layers:\n" + "\n".join(bad)


def test_nothing_below_the_command_line_imports_the_commands(graph):
    edges, _ = graph
    bad = [w for (a, b), ws in edges.items() if b == "commands" and a not in TOP for w in ws]
    assert not bad, "probedyn.commands imported below the CLI:\n" + "\n".join(bad)


def test_core_and_the_plotting_leaf_import_nothing_above_them(graph):
    edges, _ = graph
    bad = [w for (a, b), ws in edges.items() if a == "core" for w in ws]
    bad += [w for (a, b), ws in edges.items() if a == "plotting" and b != "core" for w in ws]
    assert not bad, "probedyn.core / probedyn.plotting import other parts of probedyn:\n" + "\n".join(bad)


def test_no_model_module_imports_matplotlib_or_pyvista(graph):
    _, plots = graph
    assert not plots, "plotting outside fem/render.py, probedyn/plotting.py, the report and the commands:\n" + \
        "\n".join(plots)


def test_no_import_loop_between_folders(graph):
    edges, _ = graph
    succ: dict[str, set[str]] = defaultdict(set)
    for a, b in edges:
        succ[a].add(b)
    # strongly connected components (Tarjan); a component of more than one folder is a loop
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    loops: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in succ[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                loops.append(sorted(comp))

    for v in list(succ):
        if v not in index:
            visit(v)
    # within a loop, name the thinner direction of each two-way pair (usually the wrong one)
    detail = [w for comp in loops for (a, b), ws in edges.items() if a in comp and b in comp
              and len(ws) <= len(edges.get((b, a), ())) for w in ws]
    assert not loops, f"import loops between folders {loops}:\n" + "\n".join(detail)


def test_the_import_parser_resolves_what_the_checks_rely_on():
    """Absolute and relative imports land in the right folder (a check that cannot see an
    arrow would prove nothing)."""
    assert layer_of_module("probedyn.lumped.beam") == "lumped"
    assert layer_of_module("probedyn.commands._common") == "commands"
    assert layer_of_file("schemes/contact/dmt.py") == "schemes"
    assert layer_of_file("probedyn/core/registry.py") == "core"
    assert module_of_file("schemes/contact/dmt.py") == ["probedyn", "schemes", "contact", "dmt"]
    found = dict(imports_of("schemes/contact/dmt.py"))
    assert "probedyn.schemes.contact.base" in found.values()  # ``from .base import ...``
