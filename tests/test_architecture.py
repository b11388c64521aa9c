"""The layers of docs/architecture.md, enforced: every import inside inskit
goes down (or stays inside its own package), never up, and the library never
imports the jobs or the CLI."""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "inskit"

#: the layer of every top-level package or module, lowest first (docs/architecture.md)
LAYERS = {
    "errors": 0, "units": 0, "_numba_cache": 0, "_numba_blas": 0, "_numba_load": 0,
    "earth": 1, "rotations": 1,
    "types": 2, "config_files": 2, "files": 2,
    "filters": 3, "gnss": 3,
    "io": 4, "analysis": 4, "simulation": 4, "strapdown": 4,
    "integration": 5, "gyrofree": 5, "platform": 5,
    "alignment": 6,
    "jobs": 7,
    "cli_output": 8,
    "cli_gyrofree": 9, "cli_platform": 9, "cli_gnss": 9, "cli_report": 9, "cli_reproduce": 9,
    "cli_study": 9, "cli_tune": 9,
    "cli": 10, "api": 10,
    "__init__": 11, "__main__": 11,
}


def _top(module_path: Path) -> str:
    rel = module_path.relative_to(SRC)
    return rel.parts[0].removesuffix(".py")


def _imports(path: Path):
    """Top-level inskit names a file imports (absolute or relative)."""
    tree = ast.parse(path.read_text(), str(path))
    pkg = path.relative_to(SRC).parts[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = list(pkg[: len(pkg) - node.level + 1])
                parts = base + (node.module.split(".") if node.module else [])
                if not parts:  # "from . import x" at the top: x is the top-level name
                    for a in node.names:
                        yield a.name, node.lineno
                    continue
                yield parts[0], node.lineno
            elif node.module and node.module.split(".")[0] == "inskit":
                parts = node.module.split(".")
                if len(parts) > 1:
                    yield parts[1], node.lineno
                else:
                    for a in node.names:
                        yield a.name, node.lineno
        elif isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                if parts[0] == "inskit" and len(parts) > 1:
                    yield parts[1], node.lineno


def test_every_module_has_a_layer():
    tops = {_top(p) for p in SRC.rglob("*.py")}
    assert tops <= set(LAYERS), f"give these a layer in docs/architecture.md and here: {sorted(tops - set(LAYERS))}"


def test_no_import_goes_up():
    bad = []
    for path in sorted(SRC.rglob("*.py")):
        me = _top(path)
        for name, line in _imports(path):
            if name == me or name not in LAYERS:
                continue
            if LAYERS[name] >= LAYERS[me]:
                bad.append(f"{path.relative_to(SRC)}:{line} ({me}, layer {LAYERS[me]}) imports {name} "
                           f"(layer {LAYERS[name]})")
    assert not bad, "\n".join(bad)


def test_no_module_imports_another_packages_private_names():
    bad = []
    for path in sorted(SRC.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        me = _top(path)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level >= 2 and node.module:
                other = node.module.split(".")[0]
                private = [p for p in node.module.split(".") if p.startswith("_")]
                private += [a.name for a in node.names if a.name.startswith("_")]
                if other != me and private:
                    bad.append(f"{path.relative_to(SRC)}:{node.lineno} takes {private} from {node.module}")
    assert not bad, "\n".join(bad)
