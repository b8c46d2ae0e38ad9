"""The median wall time of repeated calls, shared by the bench scripts (run from bench/ or the repository)."""
from __future__ import annotations

import time

import numpy as np


def median_time(call, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        call()
        times.append(time.perf_counter() - t)
    return float(np.median(times))
