"""Shared helpers of the Python tests: paths of the repository, its bundled
models and the reference data, and the ``umsim`` binary to compare with."""

from __future__ import annotations

import csv
import os
import subprocess
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
MODELS = REPO / "models"
SCENARIOS = MODELS / "scenarios"
# ../shared/reference beside the checkout (CI has it there, as the Rust tests).
REFERENCE = REPO.parent / "shared" / "reference"


def umsim_path() -> Path:
    """``$RAILMBS_UMSIM``, else the workspace's release build (built here if
    it is missing; ``tools/test`` has built it with ``cargo test``)."""
    env = os.environ.get("RAILMBS_UMSIM")
    if env:
        return Path(env)
    exe = REPO / "target" / "release" / "umsim"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "umsim"], cwd=REPO, check=True)
    return exe


def read_csv(path: Path) -> Tuple[List[str], Dict[str, np.ndarray]]:
    """A ``umsim run`` CSV: its header and each column parsed as floats
    (Python's float() reads Rust's shortest round-trip text back to the same
    double, so equal numbers compare equal bit for bit)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header = rows[0]
    data = np.array([[float(x) for x in r] for r in rows[1:]], dtype=np.float64)
    return header, {name: data[:, k] for k, name in enumerate(header)}


@pytest.fixture(scope="session")
def umsim() -> Path:
    return umsim_path()


@pytest.fixture
def run_cli(umsim, tmp_path):
    """Runs ``umsim run SCENARIO ARGS… -o out.csv`` and returns (stdout,
    header, columns)."""

    def run(scenario: Path, *args: str):
        out = tmp_path / "cli.csv"
        proc = subprocess.run(
            [str(umsim), "run", str(scenario), *args, "-o", str(out)],
            capture_output=True,
            text=True,
            check=True,
        )
        header, cols = read_csv(out)
        return proc.stdout, header, cols

    return run


@pytest.fixture
def python_sigint_handler():
    """Python's own SIGINT handler (KeyboardInterrupt) for the test, then
    the previous one: a process started in the background of a shell
    without job control inherits SIGINT ignored, and Python then keeps it
    ignored, so a Ctrl-C test would test nothing there."""
    import signal

    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
