"""Shared helpers: the `bounded` binary, small generated clouds, and running `detect`."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]


def bounded_bin() -> Path:
    """The binary under test: $BOUNDED_BIN (relative to the repository root), default the
    debug build."""
    path = Path(os.environ.get("BOUNDED_BIN", "target/debug/bounded"))
    return path if path.is_absolute() else REPO / path


def box_points(n: int = 3000, seed: int = 1) -> np.ndarray:
    """`n` points on the surface of a 2 x 1 x 0.5 box (float64, shape (n, 3)): faces meet
    at sharp edges."""
    rng = np.random.default_rng(seed)
    size = np.array([2.0, 1.0, 0.5])
    faces = rng.integers(0, 6, n)
    p = rng.random((n, 3)) * size
    axis = faces // 2
    p[np.arange(n), axis] = np.where(faces % 2 == 0, 0.0, size[axis])
    return p


def detect(src: Path, out: Path, *extra: str) -> subprocess.CompletedProcess:
    """Runs `bounded detect src -o out`, failing the test with its stderr if it fails."""
    binary = bounded_bin()
    if not binary.exists():
        pytest.fail(f"{binary} does not exist: build it (cargo build) or set BOUNDED_BIN")
    run = subprocess.run(
        [str(binary), "detect", str(src), "-o", str(out), *extra],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    return run
