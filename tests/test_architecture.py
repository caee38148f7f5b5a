"""Import direction and isolation: the floors of blockid/floors.py, data flowing one way."""

import ast
import importlib
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import blockid
from blockid.floors import FLOORS

SRC = Path(blockid.__file__).parent

# Layer of each subpackage (blockid/floors.py, the one statement of them); a module may
# import only from its own or lower layers.
LAYERS = FLOORS


def _layer(module: str) -> int | None:
    parts = module.split(".")
    if parts[0] != "blockid" or len(parts) < 2:
        return None
    return LAYERS.get(parts[1])


def _modules():
    return sorted(m.name for m in pkgutil.walk_packages([str(SRC)], prefix="blockid."))


@pytest.mark.parametrize("module", _modules())
def test_imports_only_flow_downwards(module):
    own = _layer(module)
    if own is None:
        return
    path = Path(importlib.util.find_spec(module).origin)
    tree = ast.parse(path.read_text())
    top_level = {id(n) for n in tree.body}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            target = _layer(node.module)
            if target is None or target <= own:
                continue
            # the one allowed upward step: .plot() methods hand off to blockid.plotting
            # through an import inside the method (matplotlib stays lazy)
            lazy_plot = id(node) not in top_level and node.module.startswith("blockid.plotting")
            assert lazy_plot, f"{module} (layer {own}) imports {node.module} (layer {target})"


def test_every_module_imports_in_isolation_without_matplotlib():
    code = (
        "import sys, importlib, pkgutil, blockid\n"
        "for m in pkgutil.walk_packages(blockid.__path__, 'blockid.'):\n"
        "    importlib.import_module(m.name)\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'matplotlib imported eagerly'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_every_module_declares_all():
    for module in _modules():
        mod = importlib.import_module(module)
        if module.endswith("__main__"):
            continue
        assert hasattr(mod, "__all__"), f"{module} has no __all__"


@pytest.mark.parametrize(
    "package", ["blockid", "blockid.data", "blockid.design", "blockid.fitting", "blockid.workflows"]
)
def test_every_lazily_exported_name_resolves(package):
    """Each lazily exported name imports from the module its table names (a module
    moved without its entry broke ``blockid.identify``)."""
    module = importlib.import_module(package)
    for name in module.__all__:
        assert getattr(module, name) is not None, f"{package}.{name}"
    assert set(module.__all__) <= set(dir(module))


def test_the_command_line_starts_without_the_heavy_libraries():
    """``blockid --help`` must not pay for pandas, SciPy, numba or matplotlib: commands
    import them when they run (issue: every command used to spend ~1.7 s starting)."""
    code = (
        "import sys, blockid, blockid.cli.main\n"
        "heavy = [m for m in ('pandas', 'scipy', 'numba', 'matplotlib', 'numpy')\n"
        "         if m in sys.modules]\n"
        "assert not heavy, heavy\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_structure_names_are_interpreted_in_the_registry_only():
    """No module compares a structure name against a literal outside the registry
    (one structure name, one interpreter)."""
    pattern = __import__("re").compile(r"structure\s*(==|!=|in)\s*[(\"']")
    offenders = []
    for path in SRC.rglob("*.py"):
        if path.name == "registry.py":
            continue
        for number, line in enumerate(path.read_text().splitlines(), start=1):
            if pattern.search(line):
                offenders.append(f"{path.relative_to(SRC)}:{number}: {line.strip()}")
    assert not offenders, offenders


def test_no_isinstance_ladder_over_block_types_outside_blocks():
    """Per-block knowledge lives in the blocks: outside ``blocks/`` no function tests a
    value against a block class (blocks say what they are by ``role`` and ``kind``, and
    answer for themselves through their methods)."""
    import ast

    names = {
        "Backlash",
        "DeadZone",
        "Saturation",
        "PiecewiseLinear",
        "Polynomial",
        "TwoSegmentPolynomial",
        "LinearBlock",
        "StaticBlock",
        "DynamicBlock",
    }
    offenders = []
    for path in SRC.rglob("*.py"):
        if "blocks" in path.parts:
            continue
        tree = ast.parse(path.read_text())
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef):
                continue
            seen = set()
            for node in ast.walk(fn):
                if (
                    isinstance(node, ast.Call)
                    and getattr(node.func, "id", "") == "isinstance"
                    and len(node.args) == 2
                ):
                    seen |= {
                        n.id for n in ast.walk(node.args[1]) if isinstance(n, ast.Name)
                    } & names
            if seen:
                offenders.append(f"{path.relative_to(SRC)}::{fn.name} tests {sorted(seen)}")
    assert not offenders, offenders


def _import_graph() -> dict[str, set[str]]:
    """Every import of a blockid module by another, at the top of a module or inside a
    function, less the two kinds that cannot close a circle at run time: imports only for
    type checking (``if TYPE_CHECKING:``) and the allowed hand-off of ``.plot()`` methods
    to ``blockid.plotting`` from the floors below it."""
    modules = set(_modules())
    graph: dict[str, set[str]] = {}
    for module in modules:
        tree = ast.parse(Path(importlib.util.find_spec(module).origin).read_text())
        typing_only = {
            id(n)
            for node in ast.walk(tree)
            if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
            for n in ast.walk(node)
        }
        deps = set()
        for node in ast.walk(tree):
            if id(node) in typing_only or not isinstance(node, ast.ImportFrom):
                continue
            if not (node.module or "").startswith("blockid") or node.level:
                continue
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                deps.add(sub if sub in modules else node.module)
        plot_floor = LAYERS["plotting"]
        graph[module] = {
            d for d in deps & modules
            if d != module
            and not (d.startswith("blockid.plotting") and (_layer(module) or 0) < plot_floor)
        }  # fmt: skip
    return graph


def test_no_import_circle():
    """No module imports, even lazily inside a function, one that imports it back (issue
    19: circles hid inside fitting/ through imports within functions)."""
    graph = _import_graph()
    seen: dict[str, int] = {}  # 1: on the current path, 2: done
    circles = []

    def visit(node: str, path: list[str]) -> None:
        seen[node] = 1
        for nxt in sorted(graph[node]):
            if seen.get(nxt) == 1:
                circles.append(path[path.index(nxt) :] + [nxt])
            elif nxt not in seen:
                visit(nxt, [*path, nxt])
        seen[node] = 2

    for module in sorted(graph):
        if module not in seen:
            visit(module, [module])
    assert not circles, [" -> ".join(c) for c in circles]


def _test_file(module: Path) -> Path:
    """Where the tests of ``module`` (a file under ``src/blockid``) go: docs/testing.md,
    *Where a test goes* (a private module's leading underscore dropped; a kernel's tests
    named ``test_<stem>_kernels.py`` in ``tests/kernels``)."""
    rel = module.relative_to(SRC)
    stem = module.stem.lstrip("_")
    tests = SRC.parents[1] / "tests"
    if rel.parts[0] == "_kernels":
        return tests / "kernels" / f"test_{stem}_kernels.py"
    return tests.joinpath(*rel.parts[:-1]) / f"test_{stem}.py"


def test_every_module_has_a_test_file_of_its_own():
    """Tests mirror modules (issue 33 item 6): a reader looking for a module's tests opens
    one file, ``tests/<package>/test_<module>.py``."""
    missing = [
        f"{path.relative_to(SRC)} -> {_test_file(path).relative_to(SRC.parents[1])}"
        for path in sorted(SRC.rglob("*.py"))
        if path.name != "__init__.py" and not _test_file(path).exists()
    ]
    assert not missing, missing
