"""The tables the commands print (cli/_tables.py): a result's summary with its columns
justified and notes kept literal, and the electrohydraulic reproduction's table."""

from types import SimpleNamespace

from blockid.cli._tables import print_electrohydraulic, print_summary


def _lines(capsys):
    return [line for line in capsys.readouterr().out.splitlines() if line.strip()]


def test_a_summary_names_its_rows_on_the_left_numbers_on_the_right_notes_as_typed(capsys):
    summary = ("Bands", ["band", "gain"], [["low", "1.5"], ["highest", "22"]], ["see [1] 0:10"])
    print_summary(summary, label_column=True)
    lines = _lines(capsys)
    assert lines[0].strip() == "Bands" and lines[-1] == "see [1] 0:10"
    low = next(line for line in lines if "low" in line)
    high = next(line for line in lines if "highest" in line)
    assert low.index("low") == high.index("highest")  # left-justified labels
    assert low.index("1.5") + 3 == high.index("22") + 2  # right-justified numbers
    print_summary(summary, label_column=False)
    lines = _lines(capsys)
    low = next(line for line in lines if "low" in line)
    high = next(line for line in lines if "highest" in line)
    assert low.index("low") + 3 == high.index("highest") + 7  # now right-justified too


def _result(rows, best, band=None):
    return SimpleNamespace(
        validation_bandwidth=band,
        table=rows,
        best=best,
        reductions=lambda: {"hammerstein": 0.25, "arx": 0.6},
    )


def test_the_reproduction_marks_the_best_estimator_and_numbers_the_failures(capsys):
    rows = [
        {"model": "hammerstein-wiener", "estimator": "key-term-rls",
         "mse": {"velocity": 0.04}, "fit_percent": {"velocity": 81.25}},
        {"model": "hammerstein-wiener", "estimator": "simulation-error",
         "error": "the estimate diverged at pass 3"},
        {"model": "arx", "estimator": "batch", "error": "did not converge in 60 passes"},
    ]  # fmt: skip
    best = {"hammerstein-wiener": {"estimator": "key-term-rls"}}
    print_electrohydraulic(_result(rows, best, band=2.0))
    out = capsys.readouterr().out
    assert "(command low-passed at 2 Hz)" in out
    first = next(line for line in out.splitlines() if "key-term-rls" in line)
    assert "0.04" in first and "81.2" in first and "*" in first and "0.0321" in first
    assert "diverged [1]" in out and "not converged [2]" in out
    assert "[1] hammerstein-wiener simulation-error: the estimate diverged at pass 3" in out
    assert "[2] arx batch: did not converge in 60 passes" in out
    assert "hammerstein 25 %, arx 60 %" in out
