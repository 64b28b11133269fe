"""The imports between one armctl package's modules, read from their source."""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "armctl"


def package_imports(package: str) -> dict[str, set[str]]:
    """Module name → the modules of ``armctl.<package>`` it imports anywhere in its source (at module level, inside
    a function or under ``TYPE_CHECKING`` alike), for the package's modules other than ``__init__``."""
    folder, dotted = SRC / package, f"armctl.{package}"
    names = {p.stem for p in folder.glob("*.py") if p.stem != "__init__"}
    graph: dict[str, set[str]] = {}
    for name in names:
        found: set[str] = set()
        for node in ast.walk(ast.parse((folder / f"{name}.py").read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module == dotted:
                found |= {a.name for a in node.names if a.name in names}
            elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith(dotted + "."):
                found.add(node.module.split(".")[2])
            elif isinstance(node, ast.Import):
                found |= {a.name.split(".")[2] for a in node.names if a.name.startswith(dotted + ".")}
        graph[name] = found - {name}
    return graph
