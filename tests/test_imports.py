"""The package's import graph, as installed (``imc_conformance``, its adapters included): no import circles, and
every module imports only from its own layer or the layers below it.

Every import counts, those inside functions too: a circle or an upward import made lazy is still one. The layers,
from the bottom:

- ``core``: the suite-generic core (results, runner, sessions and suites as contracts); it imports nothing else;
- ``base``: what every layer above may use: bounds, errors, escaping, bounded reading, the cache, schema checks,
  the types of the command line's values, the adapter API, building native programs, the restart command;
- ``capture``, ``kinds``, ``relay``, ``render``, ``sessions`` (with the live options), ``fuzz`` (and the adapter
  check): the machinery, each only on those before it;
- ``suites``: each suite over that machinery (a suite imports no other suite);
- ``tools``: what is built on a suite (the scapy layer, the adapters of real implementations);
- ``files``: opening a suite's corpus, waivers and saved results;
- ``commands``: the command line, one module per command;
- ``programs``: the entry points nothing imports: the CLI, the pytest plugin, the benchmark, the hypothesis
  properties for pytest and HypoFuzz, the worker process of a library adapter, and the DUNE scripts of
  ``make dune-conformance`` and ``make dune-relay``.

A module belongs to the layer of the longest prefix that names it; a module no layer names fails the test, so a new
package is placed on purpose.
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

LAYERS = [
    ("core", ["core"]),
    ("base", ["", "limits", "errors", "escaping", "paths", "inputs", "cache", "schemas", "arguments", "adapter_api",
              "native", "restart"]),
    ("capture", ["capture"]),
    ("kinds", ["kinds"]),
    ("relay", ["relay"]),
    ("render", ["render"]),
    ("sessions", ["sessions", "live"]),
    ("fuzz", ["fuzz", "adaptercheck"]),
    ("suites", ["suites"]),
    ("tools", ["scapy", "adapters"]),
    ("files", ["files"]),
    ("commands", ["commands"]),
    ("programs", ["cli", "pytest_plugin", "benchmark", "fuzz.properties", "sessions.worker",
                  "suites.imc.dune.conformance", "suites.imc.dune.relay", "suites.imc.dune.__main__"]),
]
PACKAGE = "imc_conformance"


def modules() -> dict[str, tuple[Path, bool]]:
    """Every module of the installed package: name -> (file, is a package). Only folders with an ``__init__.py``
    are packages (``adapters/cpp`` holds build scripts, not modules)."""
    found = {}
    for name in (PACKAGE, f"{PACKAGE}.adapters"):
        root = Path(importlib.import_module(name).__file__).parent
        for path in root.rglob("*.py"):
            parts = path.relative_to(root).with_suffix("").parts
            if not all((root.joinpath(*parts[:i]) / "__init__.py").exists() for i in range(len(parts))):
                continue
            package = parts[-1] == "__init__"
            dotted = ".".join((name, *(parts[:-1] if package else parts)))
            found.setdefault(dotted, (path, package))
    return found


def import_graph(found: dict[str, tuple[Path, bool]]) -> dict[str, set[str]]:
    """module -> the package's modules it imports (``from a import b`` imports the module ``a.b`` if there is one,
    else ``a``)."""
    edges = {}
    for name, (path, package) in found.items():
        here = name.split(".") if package else name.split(".")[:-1]
        out = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                out.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = ".".join(here[:len(here) - node.level + 1] + ([node.module] if node.module else [])) \
                    if node.level else node.module
                out.update(f"{base}.{a.name}" if f"{base}.{a.name}" in found else base for a in node.names)
        edges[name] = {m for m in out if m in found and m != name}
    return edges


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def layer_of(module: str) -> int | None:
    rel = module[len(PACKAGE) + 1:] if module != PACKAGE else ""
    best = None
    for i, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if (rel == p or (p and rel.startswith(p + "."))) and (best is None or len(p) > best[1]):
                best = (i, len(p))
    return None if best is None else best[0]


def suite_of(module: str) -> str | None:
    """The suite package a module belongs to, if any (``suites.data_suite`` and ``suites`` itself are shared)."""
    parts = module.split(".")
    return parts[2] if len(parts) > 3 and parts[1] == "suites" else None


def wrong_imports(edges: dict[str, set[str]]) -> list[str]:
    """Every import of a higher layer, and of another suite; every module no layer names."""
    problems = [f"{m}: in no layer" for m in sorted(edges) if layer_of(m) is None]
    for a in sorted(edges):
        for b in sorted(edges[a]):
            la, lb = layer_of(a), layer_of(b)
            if la is not None and lb is not None and lb > la:
                problems.append(f"{a} ({LAYERS[la][0]}) imports {b} ({LAYERS[lb][0]}), a layer above it")
            if suite_of(a) and suite_of(b) and suite_of(a) != suite_of(b):
                problems.append(f"{a} imports {b}: a suite imports no other suite")
    return problems


def test_the_package_has_no_import_circle():
    found = circles(import_graph(modules()))
    assert not found, found


def test_every_module_imports_only_its_own_layer_and_those_below():
    problems = wrong_imports(import_graph(modules()))
    assert not problems, "\n".join(problems)


def test_the_checks_see_a_circle_an_upward_import_a_suite_importing_another_and_a_module_in_no_layer():
    edges = {
        f"{PACKAGE}.core.results": {f"{PACKAGE}.core.runner"},
        f"{PACKAGE}.core.runner": {f"{PACKAGE}.core.results"},
        f"{PACKAGE}.suites.imc.node.serve": {f"{PACKAGE}.commands.options"},
        f"{PACKAGE}.suites.ros_acomms.suite": {f"{PACKAGE}.suites.imc.codec"},
        f"{PACKAGE}.commands.options": set(),
        f"{PACKAGE}.suites.imc.codec": set(),
        f"{PACKAGE}.elsewhere": set(),
    }
    assert circles(edges) == [[f"{PACKAGE}.core.results", f"{PACKAGE}.core.runner"]]
    assert wrong_imports(edges) == [
        f"{PACKAGE}.elsewhere: in no layer",
        f"{PACKAGE}.suites.imc.node.serve (suites) imports {PACKAGE}.commands.options (commands), a layer above it",
        f"{PACKAGE}.suites.ros_acomms.suite imports {PACKAGE}.suites.imc.codec: a suite imports no other suite"]


def test_the_graph_reads_relative_and_lazy_imports_as_installed():
    edges = import_graph(modules())
    assert f"{PACKAGE}.suites.imc.unpackers" in edges[f"{PACKAGE}.suites.imc.codec"]  # from .unpackers import ...
    assert f"{PACKAGE}.suites.imc.xml_folder" in edges[f"{PACKAGE}.suites.imc.suite"]  # inside a method
    assert f"{PACKAGE}.suites" in edges[f"{PACKAGE}.commands.options"]  # a name from a package's __init__
    assert f"{PACKAGE}.suites.imc.whole" in edges[f"{PACKAGE}.adapters.imcpy_adapter"]  # absolute, in adapters/
