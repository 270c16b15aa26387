"""The layer order of ``docs/architecture.md``, enforced on the import graph of every module.

The table between ``<!-- layers:begin -->`` and ``<!-- layers:end -->`` in the architecture page is
the one place the order is written; this test parses it, reads every module of ``src/boustro``
with :mod:`ast` (static: nothing is imported, so modules that load numba, matplotlib or the
network are checked like the others) and asserts that

* every module belongs to exactly one layer;
* no module imports a module of a later layer (``if TYPE_CHECKING:`` imports excepted: they
  exist for type checkers only);
* the module-level import graph has no cycle;
* no function imports a boustro module, except the lazy entries the page declares.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
DOC = ROOT / "docs" / "architecture.md"


def _table() -> tuple[list[tuple[str, list[str]]], set[tuple[str, str]]]:
    """``[(layer, [module prefixes])]`` in order, and the declared lazy ``(importer, imported)``."""
    text = DOC.read_text(encoding="utf-8")
    body = text.split("<!-- layers:begin -->")[1].split("<!-- layers:end -->")[0]
    layers = []
    for line in body.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if (
            len(cells) < 2
            or not cells[0]
            or set(cells[0]) <= {"-", ":", " "}
            or cells[0] == "layer"
        ):
            continue
        layers.append((cells[0], re.findall(r"`(boustro[\w.]*)`", cells[1])))
    lazy_body = text.split("<!-- lazy:begin -->")[1].split("<!-- lazy:end -->")[0]
    lazy = set(re.findall(r"`(boustro[\w.]*)` -> `(boustro[\w.]*)`", lazy_body))
    return layers, lazy


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted((SRC / "boustro").rglob("*.py")):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _resolve(module: str, node: ast.ImportFrom | ast.Import, is_package: bool) -> list[str]:
    """The boustro modules an import statement names (a package or a submodule)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "boustro"]
    if node.level:
        base = module.split(".") if is_package else module.split(".")[:-1]
        base = base[: len(base) - node.level + 1]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    if target.split(".")[0] != "boustro":
        return []
    found = []
    for alias in node.names:  # `from pkg import submodule` names the submodule
        sub = f"{target}.{alias.name}"
        found.append(sub if sub in MODULES else target)
    return found


def _type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(module: str) -> tuple[set[str], set[str]]:
    """``(module-level imports, function-level imports)`` of boustro modules."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(encoding="utf-8"))
    top: set[str] = set()
    inner: set[str] = set()

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _type_checking(child):
                continue
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                names = _resolve(module, child, path.name == "__init__.py")
                (inner if in_function else top).update(names)
            nested = in_function or isinstance(
                child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
            )
            visit(child, nested)

    visit(tree, False)
    return top, inner


def _layer_of(module: str, layers: list[tuple[str, list[str]]]) -> int:
    """Index of the layer whose longest matching prefix names ``module`` (-1: none)."""
    best, best_len = -1, -1
    for i, (_, prefixes) in enumerate(layers):
        for p in prefixes:
            inside = module.startswith(p + ".") and p != "boustro"  # the root names itself only
            if (module == p or inside) and len(p) > best_len:
                best, best_len = i, len(p)
    return best


def test_every_module_has_a_layer():
    layers, _ = _table()
    assert layers, "no layer table in docs/architecture.md"
    missing = [m for m in MODULES if _layer_of(m, layers) < 0]
    assert not missing, f"modules in no layer of docs/architecture.md: {missing}"


def test_no_module_imports_a_later_layer():
    layers, _ = _table()
    bad = []
    for module in MODULES:
        mine = _layer_of(module, layers)
        for target in _imports(module)[0]:
            theirs = _layer_of(target, layers)
            if theirs > mine:
                bad.append(f"{module} ({layers[mine][0]}) -> {target} ({layers[theirs][0]})")
    assert not bad, "imports against the layer order:\n" + "\n".join(sorted(bad))


def test_import_graph_has_no_cycle():
    graph = {m: {t for t in _imports(m)[0] if t in MODULES and t != m} for m in MODULES}
    # A package's __init__ importing its own submodules is how packages are built; a submodule
    # importing its package's __init__ back would close a loop, and is reported.
    state: dict[str, int] = {}
    stack: list[str] = []

    def dfs(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt) :], nxt]
            if nxt not in state:
                found = dfs(nxt)
                if found:
                    return found
        stack.pop()
        state[node] = 2
        return None

    for module in sorted(graph):
        if module not in state:
            cycle = dfs(module)
            assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_function_level_imports_are_declared():
    _, lazy = _table()
    found = {(m, t) for m in MODULES for t in _imports(m)[1]}
    undeclared = sorted(f"{m} -> {t}" for m, t in found - lazy)
    assert not undeclared, (
        "function-level imports of boustro modules not declared lazy in docs/architecture.md:\n"
        + "\n".join(undeclared)
    )
    stale = sorted(f"{m} -> {t}" for m, t in lazy - found)
    assert not stale, "declared lazy imports that no longer exist: " + ", ".join(stale)


def test_no_library_module_imports_a_compatibility_path():
    layers, _ = _table()
    names = [name for name, _ in layers]
    compat = dict(layers)["compat"]
    bad = sorted(
        f"{m} -> {t}"
        for m in MODULES
        if _layer_of(m, layers) != names.index("compat")  # the shims import each other's homes
        for t in _imports(m)[0]
        if any(t == c or t.startswith(c + ".") for c in compat)
    )
    assert not bad, "library modules importing compatibility paths: " + ", ".join(bad)


@pytest.mark.parametrize(
    "statement, absent",
    [
        (
            "import boustro",
            (
                "matplotlib",
                "shapely",
                "pyproj",
                "numba",
                "boustro.cli",
                "boustro.io",
                "boustro.learned",
                "boustro.experiments",
                "boustro.mission",
                "boustro.plot",
                "torch",
            ),
        ),
        ("import boustro.optimize", ("boustro.learned", "numba", "matplotlib", "torch")),
        ("import boustro.learned", ("boustro.io", "boustro.cli", "matplotlib", "shapely", "torch")),
        (
            "import boustro.plan",
            ("boustro.io", "boustro.cli", "matplotlib", "boustro.learned", "torch"),
        ),
        ("import boustro.cli, boustro.batch, boustro.web", ("torch",)),
    ],
)
def test_what_an_import_loads(statement, absent):
    """The static rules above, checked once at run time too: what each entry point pulls in."""
    code = f"import sys; {statement}; print(','.join(m for m in {absent!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "", f"{statement} loaded {out.stdout.strip()}"


#: The modules that may import torch when they are imported: the learned planner's network code
#: (entries of ``boustro.learned._LAZY``) and the paper's experiments; every other module names
#: torch through ``boustro._torch`` (docs/architecture.md, "Which layers may import torch").
TORCH_AT_IMPORT = ("boustro.experiments", "boustro.learned.")


def test_only_the_learned_planner_and_the_experiments_import_torch_at_module_level():
    bad = []
    for module, path in MODULES.items():
        if module.startswith(TORCH_AT_IMPORT) and module != "boustro.learned.config":
            continue
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            names = (
                [a.name for a in node.names]
                if isinstance(node, ast.Import)
                else [node.module or ""]
                if isinstance(node, ast.ImportFrom) and not node.level
                else []
            )
            if any(n == "torch" or n.startswith("torch.") for n in names):
                bad.append(f"{module}:{node.lineno}")
    assert not bad, "torch imported at module level (use boustro._torch): " + ", ".join(bad)


def test_help_and_plans_import_no_torch(tmp_path):
    """``boustro --help``, ``boustro train --help`` and plans of the certified searches (the
    embedded concave field: its hull's Eq. 1, the time and fewest-transects objectives,
    ``--keep-inside``, a decomposition, a vehicle's turns, a camera, every export format) run in
    one fresh process without importing torch; a plan of the smooth model's gradient descent
    then does (so the check itself can fail)."""
    out = str(tmp_path)
    commands = [
        ["plan", "--out", f"{out}/a.geojson"],
        ["plan", "--objective", "time", "--speed", "5", "--out", f"{out}/b.kml"],
        ["plan", "--keep-inside", "--out", f"{out}/c.gpx"],
        ["plan", "--objective", "fewest-transects", "--out", f"{out}/d.csv"],
        ["plan", "--keep-inside", "--objective", "time", "--speed", "5", "--json"],
        ["plan", "--decompose", "--out", f"{out}/e.plan", "--altitude", "30"],
        [
            "plan",
            "--turn-radius",
            "6",
            "--speed",
            "2",
            "--out",
            f"{out}/f.waypoints",
            "--altitude",
            "0",
        ],
        ["plan", "--camera", "dji-phantom-4-pro", "--altitude", "80", "--json"],
    ]
    code = f"""
import contextlib, io, sys
from boustro.cli import build_parser, main
for command in (["--help"], ["train", "--help"]):
    with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):
        build_parser().parse_args(command)
print("help", "torch" in sys.modules)
for argv in {commands!r}:
    with contextlib.redirect_stdout(io.StringIO()):
        status = main(["-q", *argv])
    print(" ".join(argv[:3]), status, "torch" in sys.modules)
with contextlib.redirect_stdout(io.StringIO()):
    main(["-q", "plan", "--method", "gradient", "--json"])
print("gradient", "torch" in sys.modules)
"""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    lines = run.stdout.strip().splitlines()
    assert lines[-1] == "gradient True", run.stdout + run.stderr
    loaded = [line for line in lines[:-1] if not line.endswith(" 0 False") and line != "help False"]
    assert len(lines) == len(commands) + 2 and not loaded, run.stdout + run.stderr
