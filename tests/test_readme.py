"""The README's quick start runs as written: its shell commands from an empty folder, and
its Python snippet on the file they create."""

import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_readme_python_snippet_runs_on_the_example_data(tmp_path):
    text = README.read_text()
    snippet = re.search(r"```python\n(.*?)```", text, flags=re.S).group(1)
    assert "arm.csv" in snippet
    from blockid.workflows.examples import example_record

    record = example_record("electrohydraulic", 0)
    assert record.estimation == (0, 1100) and record.validation == (1100, 2200)
    record.frame.to_csv(tmp_path / "arm.csv", index=False)
    run = subprocess.run(
        [sys.executable, "-c", snippet], cwd=tmp_path, capture_output=True, text=True, check=False
    )
    assert run.returncode == 0, run.stderr
    fit = float(re.search(r"'velocity': ([-0-9.e]+)", run.stdout).group(1))
    assert fit > 70.0  # measured 84 % free-run fit on the validation range


def _quick_start_commands() -> list[list[str]]:
    """The ``blockid`` command lines of the README's quick start, as words: every line of
    its fenced shell blocks, continuation lines joined and comments dropped, that starts
    with ``blockid`` (not the ``source``/``make`` lines that set up the environment)."""
    text = README.read_text()
    section = re.search(r"^## Quick start\n(.*?)(?=^## )", text, flags=re.S | re.M).group(1)
    commands = []
    for block in re.findall(r"```(?:bash|sh|shell|console)\n(.*?)```", section, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words and words[0] == "blockid":
                commands.append(words)
    return commands


def _declared_outputs(words: list[str]) -> list[str]:
    """The files and folders a command line says it writes (``-o``/``--out``, ``--plot``)."""
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--out", "--plot")]


@pytest.mark.slow  # about a minute: identify searches for up to --budget 60 s
def test_the_readme_shell_quick_start_runs_as_written(tmp_path):
    """Every ``blockid`` line of the quick start, in order, in an empty folder, with the
    installed entry point: each exits 0 and writes what it says it writes."""
    blockid = Path(sys.executable).with_name("blockid")
    if not blockid.exists():
        pytest.skip(f"no blockid entry point next to {sys.executable}")
    commands = _quick_start_commands()
    assert [w[1] for w in commands[:2]] == ["example-data", "identify"]
    assert len(commands) >= 8
    for words in commands:
        run = subprocess.run(
            [str(blockid), *words[1:]],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            check=False,
            timeout=600,
        )
        line = shlex.join(words)
        assert run.returncode == 0, f"{line}\n{run.stderr}"
        assert "Traceback" not in run.stderr, f"{line}\n{run.stderr}"
        for out in _declared_outputs(words):
            path = tmp_path / out
            assert path.exists(), f"{line}: {out} was not written"
            assert path.is_file() or any(path.iterdir()), f"{line}: {out} is empty"
        if "--json" in words:
            json.loads(run.stdout)
