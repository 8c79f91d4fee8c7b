"""The shape of clearcli/io: no import circle of any kind between its modules (at module
level, inside functions or under TYPE_CHECKING: lint-imports sees only the first two),
and telling a file apart imports no format's reader library."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import clearcli.io

IO = Path(clearcli.io.__file__).parent


def _modules() -> dict[str, Path]:
    found = {}
    for path in IO.rglob("*.py"):
        parts = path.relative_to(IO.parent.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        found[name] = path
    return found


def _imports(modules: dict[str, Path]) -> dict[str, set[str]]:
    """Every module of clearcli.io another one imports, wherever the import stands."""
    edges: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
                targets = [base, *(f"{base}.{a.name}" for a in node.names)]
            else:
                continue
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name:
                    edges[name].add(target)
    return edges


def _circle(edges: dict[str, set[str]]) -> list[str] | None:
    """One import circle, as the modules along it, or None."""
    state: dict[str, int] = {}  # 1 on the path, 2 done
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for nxt in sorted(edges[node]):
            if state.get(nxt) == 1:
                return path[path.index(nxt) :] + [nxt]
            if nxt not in state:
                found = visit(nxt)
                if found:
                    return found
        path.pop()
        state[node] = 2
        return None

    for node in sorted(edges):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_no_import_circle_of_any_kind_between_io_modules() -> None:
    edges = _imports(_modules())
    assert "clearcli.io.formats.base" in edges and edges["clearcli.io.walk"]
    # the depth images of logs reach the log through its interface, not a reader
    assert "clearcli.io.mcap" not in edges["clearcli.io.mcap_images"]
    assert "clearcli.io.log_access" in edges["clearcli.io.mcap_images"]
    assert _circle(edges) is None, " -> ".join(_circle(edges) or [])


def test_telling_files_apart_imports_no_reader_library() -> None:
    code = (
        "import sys\n"
        "import clearcli.io.read, clearcli.io.describe, clearcli.io.walk, clearcli.tasks.sources\n"
        "print(' '.join(sorted(m for m in ('mcap', 'rosbags', 'pypcd4', 'PIL', 'clearcli.io.mcap',"
        " 'clearcli.io.rosbag', 'clearcli.io.pcd', 'clearcli.io.images') if m in sys.modules)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == []
