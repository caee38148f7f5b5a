"""Operator mutations inside blockid's numba kernels, checked against their tests.

Usage: ``python mutation/kernels.py [--commit REV] [--workdir DIR]``

mutmut leaves decorated functions alone, and an ``@njit`` function cannot call mutmut's
trampoline anyway, so this script mutates the kernels itself: in every function decorated
with ``njit`` it swaps one operator at a time (``+``/``-``, ``*``/``/``, ``**`` to ``*``,
``<``/``<=``, ``>``/``>=``, ``==``/``!=``, ``and``/``or``), drops a unary minus or a
``not``, or adds one to a numeric constant. Each mutant is written into a snapshot of the
commit, compiled by numba for real (the other kernel files load from a warm cache) and
checked with the tests listed for its file in ``mutation/config.toml``; a failing test
kills it. Mutants are sampled uniformly per file with the configured seed.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import random
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
PYTEST_ARGS: list[str] = []  # from the [mutmut] table of config.toml

SWAP = {
    ast.Add: ast.Sub,
    ast.Sub: ast.Add,
    ast.Mult: ast.Div,
    ast.Div: ast.Mult,
    ast.Pow: ast.Mult,
    ast.Lt: ast.LtE,
    ast.LtE: ast.Lt,
    ast.Gt: ast.GtE,
    ast.GtE: ast.Gt,
    ast.Eq: ast.NotEq,
    ast.NotEq: ast.Eq,
    ast.And: ast.Or,
    ast.Or: ast.And,
}
SYMBOL = {
    ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**",
    ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!=",
    ast.And: "and", ast.Or: "or",
}  # fmt: skip


def is_kernel(node: ast.AST) -> bool:
    return isinstance(node, ast.FunctionDef) and any(
        "njit" in ast.unparse(d) for d in node.decorator_list
    )


class Mutator(ast.NodeTransformer):
    """Number every mutation site in kernel bodies; apply the one numbered ``target``."""

    def __init__(self, target: int = -1) -> None:
        self.target = target
        self.sites: list[str] = []
        self.inside = False

    def _site(self, node: ast.AST, what: str) -> bool:
        self.sites.append(f"line {node.lineno}: {what}")
        return len(self.sites) - 1 == self.target

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.AST:
        if not is_kernel(node):
            return node
        self.inside = True
        node.body = [self.visit(stmt) for stmt in node.body]
        self.inside = False
        return node

    def _op(self, node: ast.AST, holder: ast.AST, attr: str) -> None:
        op = getattr(holder, attr)
        if type(op) in SWAP:
            new = SWAP[type(op)]
            if self._site(node, f"{SYMBOL[type(op)]} -> {SYMBOL[new]}"):
                setattr(holder, attr, new())

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        self.generic_visit(node)
        self._op(node, node, "op")
        return node

    def visit_AugAssign(self, node: ast.AugAssign) -> ast.AST:
        self.generic_visit(node)
        self._op(node, node, "op")
        return node

    def visit_BoolOp(self, node: ast.BoolOp) -> ast.AST:
        self.generic_visit(node)
        self._op(node, node, "op")
        return node

    def visit_Compare(self, node: ast.Compare) -> ast.AST:
        self.generic_visit(node)
        for i, op in enumerate(node.ops):
            if type(op) in SWAP:
                new = SWAP[type(op)]
                if self._site(node, f"{SYMBOL[type(op)]} -> {SYMBOL[new]}"):
                    node.ops[i] = new()
        return node

    def visit_UnaryOp(self, node: ast.UnaryOp) -> ast.AST:
        self.generic_visit(node)
        if isinstance(node.op, ast.USub | ast.Not):
            sign = "-" if isinstance(node.op, ast.USub) else "not "
            if self._site(node, f"{sign}{ast.unparse(node.operand)} -> drop {sign.strip()}"):
                return node.operand
        return node

    def visit_Constant(self, node: ast.Constant) -> ast.AST:
        value = node.value
        if isinstance(value, int | float) and not isinstance(value, bool):
            if self._site(node, f"{value!r} -> {value + 1!r}"):
                return ast.copy_location(ast.Constant(value + 1), node)
        return node


def sites(source: str) -> list[str]:
    mutator = Mutator()
    mutator.visit(ast.parse(source))
    return mutator.sites


def mutate(source: str, target: int) -> str:
    tree = Mutator(target).visit(ast.parse(source))
    return ast.unparse(ast.fix_missing_locations(tree)) + "\n"


def pytest(workdir: Path, tests: list[str], cache: Path, timeout: float) -> str:
    env = dict(os.environ, PYTHONPATH="src", NUMBA_CACHE_DIR=str(cache))
    command = [sys.executable, "-m", "pytest", "-x", "-q", *PYTEST_ARGS, *tests]
    try:
        run = subprocess.run(
            ["nice", "-n", "10", *command], cwd=workdir, env=env, capture_output=True,
            timeout=timeout,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return "timeout"
    return "survived" if run.returncode == 0 else "killed"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commit", default="HEAD")
    parser.add_argument("--workdir", type=Path)
    parser.add_argument("--sites", nargs="*", help="re-check only these file:index mutants")
    args = parser.parse_args(argv)

    config = tomllib.loads((HERE / "config.toml").read_text())
    kernels = config["kernels"]
    PYTEST_ARGS[:] = config["mutmut"]["pytest_args"]
    for test in config["mutmut"].get("deselect", []):
        PYTEST_ARGS.extend(["--deselect", test])
    commit = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", args.commit], capture_output=True, text=True
    ).stdout.strip()
    workdir = args.workdir or Path(tempfile.gettempdir()) / f"blockid-kernels-{commit[:10]}"
    started = time.monotonic()
    if not workdir.exists():
        workdir.mkdir(parents=True)
        with tempfile.TemporaryFile() as archive:
            subprocess.run(["git", "-C", str(REPO), "archive", commit], stdout=archive, check=True)
            archive.seek(0)
            with tarfile.open(fileobj=archive) as tar:
                tar.extractall(workdir, filter="data")
    print(f"commit {commit}, snapshot in {workdir}", flush=True)

    # Warm cache and clean baseline: every file's tests pass on the unmutated kernels.
    warm = workdir / ".numba-warm"
    clean_time = {}
    for path, tests in kernels["files"].items():
        t0 = time.monotonic()
        if pytest(workdir, tests, warm, timeout=900) != "survived":
            raise SystemExit(f"the tests of {path} fail on the clean snapshot")
        clean_time[path] = time.monotonic() - t0

    rng = random.Random(config["seed"])
    wanted = set(args.sites or [])
    summary = {"commit": commit, "seed": config["seed"], "files": {}}
    for path, tests in kernels["files"].items():
        original = (workdir / path).read_text()
        stat = os.stat(workdir / path)
        every = sites(original)
        n = kernels["sample_per_file"]
        chosen = sorted(rng.sample(range(len(every)), n)) if n < len(every) else range(len(every))
        if wanted:
            chosen = [i for i in range(len(every)) if f"{path}:{i}" in wanted]
        results = {}
        for index in chosen:
            (workdir / path).write_text(mutate(original, index))
            with tempfile.TemporaryDirectory() as cache:
                shutil.copytree(warm, cache, dirs_exist_ok=True)
                # compiling the mutated file is part of the clean time's worth of slack
                outcome = pytest(workdir, tests, Path(cache), timeout=60 + 5 * clean_time[path])
            results[index] = outcome
            print(f"{outcome:<9}{path}:{index}  {every[index]}", flush=True)
        (workdir / path).write_text(original)
        os.utime(workdir / path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        counts = {
            s: sum(1 for r in results.values() if r == s) for s in ("killed", "timeout", "survived")
        }
        summary["files"][path] = {
            "mutants": len(every),
            "sampled": len(results),
            **counts,
            "survivors": [f"{path}:{i}  {every[i]}" for i, r in results.items() if r == "survived"],
        }
    summary["wall_time_s"] = round(time.monotonic() - started)
    (workdir / "summary.json").write_text(json.dumps(summary, indent=1))
    for path, row in summary["files"].items():
        print(
            f"{path:<40} {row['mutants']:>4} mutants, {row['sampled']:>3} sampled: "
            f"{row['killed']} killed, {row['timeout']} timeout, {row['survived']} survived"
        )
    print(f"wall time {summary['wall_time_s']} s")


if __name__ == "__main__":
    main()
