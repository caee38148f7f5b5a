"""Check surviving mutants against new tests by writing each one into the source.

Usage: ``python mutation/confirm.py WORKDIR TEST [TEST ...] -- MUTANT [MUTANT ...]``

``WORKDIR`` is the snapshot ``mutation/run.py`` left behind. The tests given are copied
from this checkout into it; then, one mutant at a time, ``mutmut apply`` writes the mutant
into the snapshot's ``src`` (no trampoline, so code that runs at import time, such as the
registry's declarations, is mutated too), the tests run, and the file is put back. Methods
(``module.xǁClassǁmethod__mutmut_N``) go through mutmut's own trampoline instead, with
``MUTANT_UNDER_TEST`` set, because ``mutmut apply`` 3.8.1 writes a method's mutant over the
first method of that name in the file. A mutant is killed when a test fails.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
MUTMUT = Path(sys.executable).with_name("mutmut")


def source_file(workdir: Path, name: str) -> Path:
    module = name.split(".x\u01c1")[0].split(".x_")[0]
    return workdir / "src" / (module.replace(".", "/") + ".py")


def main(argv: list[str]) -> None:
    split = argv.index("--")
    workdir, tests, names = Path(argv[0]), argv[1:split], argv[split + 1 :]
    for test in tests:
        target = workdir / test
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(REPO / test, target)
    env = dict(os.environ, PYTHONPATH="src", NUMBA_CACHE_DIR=str(workdir / ".numba"))
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    pytest = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *tests]
    if subprocess.run(pytest, cwd=workdir, env=env, capture_output=True).returncode != 0:
        raise SystemExit("the tests fail on the unmutated snapshot")
    for test in tests:  # the trampolined copy runs from mutants/
        shutil.copy(REPO / test, workdir / "mutants" / test)
    killed = 0
    for name in names:
        if "\u01c1" in name:  # a method: switch it on in the trampolined copy
            run = subprocess.run(
                pytest,
                cwd=workdir / "mutants",
                env=dict(env, MUTANT_UNDER_TEST=name),
                capture_output=True,
            )
        else:
            path = source_file(workdir, name)
            original = path.read_bytes()
            try:
                subprocess.run(
                    [str(MUTMUT), "apply", name], cwd=workdir, check=True, capture_output=True
                )
                run = subprocess.run(pytest, cwd=workdir, env=env, capture_output=True)
            finally:
                path.write_bytes(original)
        outcome = "survived" if run.returncode == 0 else "killed"
        killed += outcome == "killed"
        print(f"{outcome:<9}{name}", flush=True)
    print(f"{killed} of {len(names)} killed")


if __name__ == "__main__":
    main(sys.argv[1:])
