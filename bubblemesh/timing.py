"""Wall-clock seconds per phase of a run, reported in ``Mesh.stats`` so that a
user (and the benchmark) can see where the time goes.  Not part of
the paper's method."""

import sys
import time
from collections.abc import Callable

__all__ = ["PhaseClock", "stage_lines"]


class PhaseClock:
    """``lap(phase)`` adds the time since the previous lap (or the start) to
    ``phase``; ``seconds`` maps each phase to its total."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._last = self._start = time.perf_counter()

    def lap(self, phase: str) -> None:
        now = time.perf_counter()
        self.seconds[phase] = self.seconds.get(phase, 0.0) + now - self._last
        self._last = now

    def total(self) -> float:
        return self._last - self._start


def stage_lines(enabled: bool) -> Callable[[str], None]:
    """``say(what)`` for the progress of a run of several stages: one line on
    stderr, ``what`` and the seconds since the previous line (or the start),
    written past any progress bar; nothing unless ``enabled``."""
    if not enabled:
        return lambda what: None
    from tqdm.auto import tqdm

    last = [time.perf_counter()]

    def say(what: str) -> None:
        now = time.perf_counter()
        tqdm.write(f"mesh: {what} ({now - last[0]:.2f} s)", file=sys.stderr)
        last[0] = now

    return say
