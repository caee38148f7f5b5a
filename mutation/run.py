"""Mutation benchmark of blockid's core with mutmut, on a snapshot of a commit.

Usage: ``python mutation/run.py [--commit REV] [--workdir DIR] [--only PACKAGE ...]``

The snapshot (``git archive`` of the commit) is unpacked into a scratch folder, so the
working tree is never touched. mutmut's configuration is appended to the snapshot's
``pyproject.toml`` from ``mutation/config.toml``. Mutants are generated for every core
package, sampled uniformly per package with the configured seed, and run; the numbers per
package and the surviving mutants are written to ``<workdir>/summary.json`` and printed.
The numba kernels are left to ``mutation/kernels.py`` (mutmut skips decorated functions).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import random
import subprocess
import sys
import tarfile
import tempfile
import time
import tomllib
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
MUTMUT = Path(sys.executable).with_name("mutmut")

# mutmut's names for the outcome of a mutant, as printed by `mutmut results --all true`.
DETECTED = {"killed": "killed", "timeout": "timeout", "segfault": "killed", "suspicious": "killed"}


def snapshot(commit: str, workdir: Path) -> None:
    """Unpack ``git archive <commit>`` into ``workdir`` (a fresh folder)."""
    workdir.mkdir(parents=True)
    with tempfile.TemporaryFile() as archive:
        subprocess.run(["git", "-C", str(REPO), "archive", commit], stdout=archive, check=True)
        archive.seek(0)
        with tarfile.open(fileobj=archive) as tar:
            tar.extractall(workdir, filter="data")


def mutmut_section(config: dict) -> str:
    """The ``[tool.mutmut]`` table for the snapshot's pyproject.toml."""
    packages = config["packages"].values()
    only = sorted({f for p in packages for f in p["files"]})
    # files a package leaves out are not mutated at all (the export runtime is copied
    # into exported modules as text: mutmut's trampolines must not be in it)
    excluded = sorted({f for p in packages for f in p.get("exclude", [])})
    args = list(config["pytest_args"])
    for test in config.get("deselect", []):
        args += ["--deselect", test]
    table = {
        "source_paths": ["src"],
        "also_copy": ["docs"],  # tests/test_docs_extending.py runs docs/extending.md
        "only_mutate": only,
        "do_not_mutate": excluded,
        "pytest_add_cli_args": args,
        "pytest_add_cli_args_test_selection": config["tests"],
        "timeout_multiplier": config["timeout_multiplier"],
        "use_git_change_detection": False,
    }
    lines = ["", "[tool.mutmut]"] + [f"{key} = {json.dumps(value)}" for key, value in table.items()]
    return "\n".join(lines) + "\n"


def mutmut(workdir: Path, *args: str, check: bool = True) -> str:
    run = subprocess.run(
        ["nice", "-n", "10", str(MUTMUT), *args],
        cwd=workdir,
        capture_output=True,
        text=True,
    )
    if check and run.returncode != 0:
        sys.stderr.write(run.stdout[-3000:] + run.stderr[-3000:])
        raise SystemExit(f"mutmut {args[0]} failed with exit code {run.returncode}")
    return run.stdout


def statuses(workdir: Path) -> dict[str, str]:
    """Every mutant's name and status (``not checked`` before it is run), read from the
    ``.meta`` files mutmut keeps beside each mutated module."""
    from mutmut.stats import status_by_exit_code

    result = {}
    for meta in (workdir / "mutants" / "src").rglob("*.meta"):
        for name, code in json.loads(meta.read_text())["exit_code_by_key"].items():
            result[name] = status_by_exit_code[code]
    return result


def source_file(name: str) -> str:
    """``blockid.blocks.static.xǁPolynomialǁ__call____mutmut_3`` -> its source file."""
    module = name.split(".x\u01c1")[0].split(".x_")[0]
    return "src/" + module.replace(".", "/") + ".py"


def package_of(name: str, packages: dict) -> str | None:
    path = source_file(name)
    for package, spec in packages.items():
        if any(fnmatch.fnmatch(path, f) for f in spec["files"]) and not any(
            fnmatch.fnmatch(path, f) for f in spec.get("exclude", [])
        ):
            return package
    return None


def wilson(k: int, n: int, population: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson interval of a proportion, with the finite-population correction."""
    if n == 0:
        return (0.0, 1.0)
    fpc = math.sqrt((population - n) / (population - 1)) if population > 1 else 0.0
    p = k / n
    zz = z * fpc
    centre = (p + zz**2 / (2 * n)) / (1 + zz**2 / n)
    half = zz * math.sqrt(p * (1 - p) / n + zz**2 / (4 * n**2)) / (1 + zz**2 / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def summarise(chosen: dict[str, list[str]], all_names: dict, status: dict) -> dict:
    summary = {}
    for package, names in chosen.items():
        counts = {"killed": 0, "timeout": 0, "survived": 0, "no tests": 0, "not run": 0}
        survivors = []
        for name in names:
            s = status.get(name, "not checked")
            if s in DETECTED:
                counts[DETECTED[s]] += 1
            elif s == "survived":
                counts["survived"] += 1
                survivors.append(name)
            elif s == "no tests":
                counts["no tests"] += 1
                survivors.append(name)
            else:
                counts["not run"] += 1
        detected = counts["killed"] + counts["timeout"]
        run = len(names) - counts["not run"]
        # Unrun mutants bound the score: all survive (low) or all are killed (high).
        low, _ = wilson(detected, len(names), len(all_names[package]))
        _, high = wilson(detected + counts["not run"], len(names), len(all_names[package]))
        summary[package] = {
            "mutants": len(all_names[package]),
            "sampled": len(names),
            **counts,
            "score": detected / run if run else None,
            "score_bounds": [detected / len(names), (detected + counts["not run"]) / len(names)]
            if names
            else None,
            "interval95": [low, high],
            "survivors": survivors,
        }
    return summary


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--commit", default="HEAD")
    parser.add_argument("--workdir", type=Path)
    parser.add_argument("--only", nargs="*", help="packages to run (default: all)")
    parser.add_argument("--names", nargs="*", help="run exactly these mutants (re-check)")
    parser.add_argument("--report", action="store_true", help="only summarise the last run")
    parser.add_argument(
        "--sample-of",
        type=Path,
        help="run the sample kept in an earlier run's summary (like for like when a "
        "package's mutants changed, which makes the seed draw a new sample)",
    )
    args = parser.parse_args(argv)

    config = tomllib.loads((HERE / "config.toml").read_text())
    section = config["mutmut"]
    commit = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", args.commit], capture_output=True, text=True
    ).stdout.strip()
    workdir = args.workdir or Path(tempfile.gettempdir()) / f"blockid-mutation-{commit[:10]}"
    started = time.monotonic()
    if not workdir.exists():
        snapshot(commit, workdir)
        with open(workdir / "pyproject.toml", "a") as pyproject:
            pyproject.write(mutmut_section(section))
    print(f"commit {commit}, snapshot in {workdir}", flush=True)

    # Generate every mutant and record which tests reach which function; a name that
    # matches nothing stops mutmut right after that step.
    if not args.report:
        mutmut(
            workdir, "run", "--max-children", str(config["workers"]), "no-such-mutant", check=False
        )
    status = statuses(workdir)
    packages = section["packages"]
    all_names: dict[str, list[str]] = {p: [] for p in packages}
    for name in sorted(status):
        package = package_of(name, packages)
        if package is not None:
            all_names[package].append(name)

    rng = random.Random(config["seed"])
    chosen = {}
    for package, spec in packages.items():
        names = all_names[package]
        n = spec["sample"]
        chosen[package] = sorted(rng.sample(names, n)) if 0 < n < len(names) else names
    if args.sample_of:
        earlier = json.loads(args.sample_of.read_text())["sample"]
        for package, names in earlier.items():
            kept = [name for name in names if name in status]
            print(f"{package}: {len(kept)} of the earlier sample's {len(names)} mutants exist now")
            chosen[package] = kept
    selected = [p for p in packages if not args.only or p in args.only]
    to_run = args.names or [name for p in selected for name in chosen[p]]
    if not args.report:
        print(f"running {len(to_run)} mutants of {sum(map(len, all_names.values()))}", flush=True)
    if not args.report:
        mutmut(workdir, "run", "--max-children", str(config["workers"]), *to_run)

    summary = {
        "commit": commit,
        "tool": "mutmut " + mutmut(workdir, "--version").split()[-1],
        "seed": config["seed"],
        "wall_time_s": None if args.report else round(time.monotonic() - started),
        "packages": summarise({p: chosen[p] for p in selected}, all_names, statuses(workdir)),
        "sample": {p: chosen[p] for p in selected},
    }
    (workdir / "summary.json").write_text(json.dumps(summary, indent=1))
    print(
        f"{'package':<12} {'mutants':>7} {'sampled':>7} {'killed':>6} {'timeout':>7} "
        f"{'survived':>8} {'no tests':>8} {'not run':>7} {'score':>6}  95 % interval"
    )
    for package, row in summary["packages"].items():
        low, high = row["interval95"]
        score = f"{100 * row['score']:.1f}" if row["score"] is not None else "-"
        print(
            f"{package:<12} {row['mutants']:>7} {row['sampled']:>7} {row['killed']:>6} "
            f"{row['timeout']:>7} {row['survived']:>8} {row['no tests']:>8} "
            f"{row['not run']:>7} {score:>6}  "
            f"{100 * low:.0f}-{100 * high:.0f} %"
        )
    for package, row in summary["packages"].items():
        for name in row["survivors"]:
            print(f"survived  {package:<12} {name}")
    print(f"wall time {summary['wall_time_s']} s; details: mutmut show <name> in {workdir}")


if __name__ == "__main__":
    main()
