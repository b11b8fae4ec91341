"""The package's layers: every module imports only its own layer and the layers below it.

The layers, lowest first (docs/developing.md, "The map"): base, model, core, io,
backends, analysis, bifurcation, cli; the package's ``__init__`` sits on top. An
import of a higher layer, or an import circle between modules, fails here.
Function-level (late) imports count as much as top-level ones.
"""

from __future__ import annotations

import ast
from pathlib import Path

import stickslip_fast

PKG = Path(stickslip_fast.__file__).resolve().parent
LAYERS = ("base", "model", "core", "io", "backends", "analysis", "bifurcation", "cli")


def _module_name(path: Path) -> str:
    parts = ["stickslip_fast", *path.relative_to(PKG).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Every module of the package that ``path`` imports (relative imports resolved)."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("stickslip_fast"):
                continue
            for alias in node.names:  # "from . import x" may name a module
                sub = f"{target}.{alias.name}"
                found.add(sub if _exists(sub) else target)
        elif isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("stickslip_fast")}
    return found


def _exists(module: str) -> bool:
    rel = Path(*module.split(".")[1:])
    return (PKG / rel).with_suffix(".py").exists() or (PKG / rel / "__init__.py").exists()


def _layer(module: str) -> int:
    parts = module.split(".")
    if len(parts) == 1:
        return len(LAYERS)  # the package itself: above everything
    return LAYERS.index(parts[1])


def _graph() -> dict[str, set[str]]:
    return {_module_name(p): _imports(p) for p in sorted(PKG.rglob("*.py"))}


def test_every_module_belongs_to_a_layer():
    for path in PKG.rglob("*.py"):
        rel = path.relative_to(PKG)
        assert len(rel.parts) == 2 and rel.parts[0] in LAYERS or rel == Path("__init__.py"), rel


def test_no_import_from_a_higher_layer():
    bad = [
        f"{mod} (layer {LAYERS[_layer(mod)] if _layer(mod) < len(LAYERS) else 'top'}) imports {dep}"
        for mod, deps in _graph().items()
        for dep in deps
        if _layer(dep) > _layer(mod)
    ]
    assert not bad, "\n".join(bad)


def test_no_import_circle():
    graph = _graph()
    # a module's package __init__ is imported with it; that is not a circle of our making
    edges = {
        m: {d for d in deps if d in graph and not m.startswith(d + ".")}
        for m, deps in graph.items()
    }
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        stack.append(m)
        for d in sorted(edges[m]):
            if state.get(d) == 1:
                return stack[stack.index(d) :] + [d]
            if d not in state and (cycle := visit(d)):
                return cycle
        stack.pop()
        state[m] = 2
        return None

    for m in sorted(edges):
        if m not in state and (cycle := visit(m)):
            raise AssertionError("import circle: " + " -> ".join(cycle))


def test_only_io_opens_hdf5_files():
    # io/ is the one place that knows the file schema (docs/developing.md, "The map"):
    # other layers hand it records or dicts. Until 2026-12-02 the branch file, the basins
    # file's boundary, edge and manifold groups and three CLI reports were read and
    # written outside it
    outside = []
    for path in sorted(PKG.rglob("*.py")):
        if path.relative_to(PKG).parts[0] == "io":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                names = [node.module or ""]
            if any(n == "h5py" or n.startswith("h5py.") for n in names):
                outside.append(f"{path.relative_to(PKG)}:{node.lineno}")
    assert not outside, "h5py imported outside io/: " + ", ".join(outside)
