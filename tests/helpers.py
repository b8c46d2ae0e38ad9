"""Helpers shared by the package tests (imported as `helpers`; tests/blender has its own `blender_helpers`)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

SHARED_DATA = Path(os.environ.get("POINTSCALE_DATA", Path(__file__).resolve().parents[1] / ".." / "shared" / "data"))


def diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def shared_model(name: str) -> Path:
    """A scanned model from ../shared/data; skips the test when the folder is absent (a user's clone)."""
    path = SHARED_DATA / name
    if not path.exists():
        pytest.skip(f"{name} not found in {SHARED_DATA} (only CI and developers have ../shared/data)")
    return path


def run_cli(*args, cwd=None) -> subprocess.CompletedProcess:
    """The command line, `python -m pointscale *args`, as a user runs it."""
    return subprocess.run([sys.executable, "-m", "pointscale", *args], capture_output=True, text=True, cwd=cwd)


def one_line_error(done: subprocess.CompletedProcess) -> str:
    """The one line a refused command prints (exit 2, no traceback)."""
    assert done.returncode == 2, (done.returncode, done.stdout, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    return lines[0]
