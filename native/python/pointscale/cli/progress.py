"""One progress bar for a whole command: reading, each step of computing, writing."""
from __future__ import annotations

import sys

from tqdm import tqdm

_RESOLUTION = 1000


class CommandProgress:
    """A tqdm bar split into named stages, each given a share of the bar by its expected cost.

    stage(name) returns a callback taking the stage's own fraction in [0, 1] (what the engine's
    `progress=` calls), so the engine's progress moves the one bar. The bar hides itself when
    stderr is not a terminal (tqdm's disable=None), so logs and pipes get no control codes.
    """

    def __init__(self, stages: dict[str, float]):
        total = float(sum(stages.values()))
        self._start = {}
        self._share = {}
        position = 0.0
        for name, weight in stages.items():
            self._start[name] = position
            self._share[name] = weight / total
            position += weight / total
        self._bar = tqdm(total=_RESOLUTION, file=sys.stderr, disable=None, leave=False, dynamic_ncols=True,
                         bar_format="{desc:<24}{percentage:3.0f}%|{bar}| {elapsed}")
        self._shown = 0

    def stage(self, name: str):
        self._bar.set_description_str(name, refresh=False)
        self._move_to(self._start[name])

        def report(fraction: float) -> bool:
            self._move_to(self._start[name] + min(max(float(fraction), 0.0), 1.0) * self._share[name])
            return True

        return report

    def finish(self, name: str) -> None:
        self._move_to(self._start[name] + self._share[name])

    def _move_to(self, position: float) -> None:
        target = min(_RESOLUTION, int(round(position * _RESOLUTION)))
        if target > self._shown:
            self._bar.update(target - self._shown)
            self._shown = target

    def close(self) -> None:
        self._bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
