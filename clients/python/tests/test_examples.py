"""The package's example runs as written."""

from __future__ import annotations

import pathlib
import subprocess
import sys

EXAMPLE = pathlib.Path(__file__).resolve().parents[3] / "examples" / "python" / "client_tour.py"


def test_client_tour_runs(vigil_url: str) -> None:
    done = subprocess.run(
        [sys.executable, str(EXAMPLE), vigil_url, "--steps", "3"], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("sensor a: ")
    assert sum(line.startswith("step ") for line in lines) == 3
    assert lines[-1].startswith("refused: 422 ")
