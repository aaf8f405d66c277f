"""The package's shape: dependencies point one way, no import circles, no private names across packages.

Every import counts, also those inside functions (lazy imports keep ``--help`` fast; they do not make a circle
acceptable). The layers, lowest first, are docs/guides/architecture.md's: physics moves bodies, rules decide what
counts, env speaks PettingZoo, policies learn and play, integrations hand the env to other trainers (BenchMARL),
server speaks Zenoh, web and league sit on the server, the command line on everything.
"""
from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rocketdrl_ma"

#: lowest first; a unit may import its own layer's units only if they are listed together
LAYERS: tuple[tuple[str, ...], ...] = (
    ("validation",), ("physics",), ("rules",), ("config",), ("engine",), ("env", "rlgym"), ("__init__",),
    ("policies", "results"),
    ("integrations",), ("server",), ("web", "league"), ("commands",), ("cli",))


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def unit_of(module: str) -> str:
    """The top-level area a module belongs to: ``rocketdrl_ma.env.actions`` -> ``env``; the package's own
    ``__init__`` -> ``__init__``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


MODULES = {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imported_modules(module: str) -> set[str]:
    """Every package module ``module`` imports (as written: ``from a.b import c`` gives ``a.b.c`` if that is a
    module, else ``a.b``), at the top or inside functions."""
    path = MODULES[module]
    here = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    out = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out |= {alias.name for alias in node.names if alias.name in MODULES}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = here[:len(here) - (node.level - 1)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            for alias in node.names:
                name = f"{base}.{alias.name}"
                out.add(name if name in MODULES else base)
    return {m for m in out if m in MODULES and m != module}


GRAPH = {module: imported_modules(module) for module in MODULES}


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's components with more than one member (each is an import circle)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_walk_sees_the_package():
    assert {"rocketdrl_ma.physics.arena", "rocketdrl_ma.env.parallel_env", "rocketdrl_ma.cli"} <= set(MODULES)
    assert "rocketdrl_ma.physics.world" in GRAPH["rocketdrl_ma.physics.arena"]
    assert "rocketdrl_ma.policies.ppo.checkpoint" in GRAPH["rocketdrl_ma.policies.registry"]  # a lazy import


def test_no_module_imports_in_a_circle():
    assert strongly_connected(GRAPH) == []


def test_no_subpackages_import_in_a_circle():
    """``a.b`` and ``a.c`` must not import each other through any of their modules (a parent's ``__init__``
    re-exporting its children is not a dependency of the children on their parent)."""
    def package_of(module: str) -> str:
        return module if MODULES[module].name == "__init__.py" else module.rsplit(".", 1)[0]

    packages: dict[str, set[str]] = defaultdict(set)
    for module, targets in GRAPH.items():
        for target in targets:
            a, b = package_of(module), package_of(target)
            if a != b and not a.startswith(b + "."):
                packages[a].add(b)
    assert strongly_connected(packages) == []


@pytest.mark.parametrize("unit", sorted({unit_of(m) for m in MODULES}))
def test_dependencies_point_down_the_layers(unit):
    rank = {name: i for i, layer in enumerate(LAYERS) for name in layer}
    assert unit in rank, f"{unit}: not in LAYERS; place it there"
    upward = sorted({f"{m} -> {t}" for m, targets in GRAPH.items() if unit_of(m) == unit for t in targets
                     if rank[unit_of(t)] > rank[unit]})
    assert upward == []


def test_no_private_name_of_another_package():
    """``from rocketdrl_ma.x import _name`` and ``module._name`` across top-level areas."""
    offences = []
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text(), str(path))
        aliases = {}  # local name -> package module it stands for
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                for alias in node.names:
                    full = f"{base}.{alias.name}"
                    if full in MODULES:
                        aliases[alias.asname or alias.name] = full
                    elif base in MODULES and unit_of(base) != unit_of(module) and alias.name.startswith("_"):
                        offences.append(f"{module}: from {base} import {alias.name}")
            elif isinstance(node, ast.Import):
                aliases.update({a.asname or a.name: a.name for a in node.names if a.name in MODULES})
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.attr.startswith("_")
                    and not node.attr.startswith("__") and node.value.id in aliases
                    and unit_of(aliases[node.value.id]) != unit_of(module)):
                offences.append(f"{module}: {node.value.id}.{node.attr}")
    assert offences == []


def test_the_league_configs_live_in_leagues():
    root = PACKAGE.parent
    assert not (root / "league.yaml").exists()
    assert (root / "leagues" / "main.yaml").exists()
