"""Wall-clock seconds per phase of a run, reported in ``Mesh.stats`` so that a
user (and the benchmark) can see where the time goes.  Not part of
the paper's method."""

import time

__all__ = ["PhaseClock"]


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
