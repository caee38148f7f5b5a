"""The README's Python quick start runs as written (on the file its commands create)."""

import re
import subprocess
import sys
from pathlib import Path

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
