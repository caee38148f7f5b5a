"""A command killed with SIGTERM (a job stopped, a CI step timed out) leaves nothing
behind: identify's worker processes end with it."""

import glob
import os
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path

import numpy as np
import pytest

from reference import squared_state_record


def _marked(marker: str) -> list[int]:
    """Processes whose environment carries the marker (the command and its workers)."""
    out = []
    for path in glob.glob("/proc/[0-9]*/environ"):
        try:
            if f"BLOCKID_TEST_MARKER={marker}".encode() in Path(path).read_bytes():
                out.append(int(path.split("/")[2]))
        except OSError:  # a process that ended, or not ours to read
            pass
    return out


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_terminated_identify_leaves_no_worker_process_behind(tmp_path):
    """Seen failing before the command line turned SIGTERM into an exit: the two loky
    workers and their helpers outlived the command (for hours, in one case)."""
    blockid = Path(sys.executable).with_name("blockid")
    if not blockid.exists():
        pytest.skip(f"no blockid entry point next to {sys.executable}")
    e = squared_state_record(n=6000).experiments[0]
    csv = tmp_path / "d.csv"
    np.savetxt(csv, np.column_stack((e.u[:, 0], e.y[:, 0])), delimiter=",", header="u,y",
               comments="")  # fmt: skip
    marker = uuid.uuid4().hex
    proc = subprocess.Popen(
        [str(blockid), "identify", str(csv), "-u", "u", "-y", "y", "--jobs", "2"],
        env={**os.environ, "BLOCKID_TEST_MARKER": marker},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and len(_marked(marker)) < 3:
            time.sleep(0.1)
        assert len(_marked(marker)) >= 3, "the workers never started"
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=60) == 128 + signal.SIGTERM
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and _marked(marker):
            time.sleep(0.1)
        assert _marked(marker) == []
    finally:
        for pid in _marked(marker):  # whatever the outcome, nothing of ours stays
            os.kill(pid, signal.SIGKILL)
