"""Boundary-node builders for case files written as formulas (``NAME.py`` cases).

Every builder returns an ``(n, 2)`` float64 array of boundary nodes, the loop
closed implicitly (the last node is *not* a repeat of the first).  The outer
loop of a case is given counter-clockwise and holes clockwise, the orientation
``bubblemesh.Domain`` uses; ``Domain.from_loops`` accepts either.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

__all__ = [
    "circle",
    "rectangle",
    "polygon",
    "resample_curve",
    "ellipse_curve",
    "naca_airfoil",
    "gear",
    "slot",
    "sector",
    "graded_polygon",
    "signed_area",
    "clockwise",
    "counterclockwise",
]


def signed_area(loop: np.ndarray) -> float:
    """Shoelace area: > 0 for a counter-clockwise loop."""
    x, y = np.asarray(loop, dtype=float).T
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def counterclockwise(loop: np.ndarray) -> np.ndarray:
    loop = np.asarray(loop, dtype=np.float64)
    return loop if signed_area(loop) > 0 else loop[::-1].copy()


def clockwise(loop: np.ndarray) -> np.ndarray:
    loop = np.asarray(loop, dtype=np.float64)
    return loop if signed_area(loop) < 0 else loop[::-1].copy()


def circle(center: Sequence[float], radius: float, n: int, phase: float = 0.0) -> np.ndarray:
    """``n`` nodes uniformly spaced on a circle, counter-clockwise from angle
    ``phase``."""
    t = phase + 2.0 * np.pi * np.arange(n) / n
    return np.column_stack([center[0] + radius * np.cos(t), center[1] + radius * np.sin(t)])


def polygon(corners: Sequence[Sequence[float]], spacing: float) -> np.ndarray:
    """Nodes along a closed polygon: every corner kept exactly, each side split
    into ``max(1, round(length / spacing))`` equal segments."""
    c = np.asarray(corners, dtype=np.float64)
    out = []
    for i in range(len(c)):
        a, b = c[i], c[(i + 1) % len(c)]
        n = max(1, int(round(float(np.hypot(*(b - a))) / spacing)))
        s = np.arange(n)[:, None] / n
        out.append(a + s * (b - a))
    return np.vstack(out)


def rectangle(x0: float, y0: float, x1: float, y1: float, spacing: float) -> np.ndarray:
    """Counter-clockwise rectangle from its lower-left corner."""
    return polygon([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], spacing)


def resample_curve(
    curve: Callable[[np.ndarray], np.ndarray], spacing: float, n_dense: int = 20000
) -> np.ndarray:
    """Nodes at (nearly) equal arc length on the closed curve ``curve(t)``,
    ``t`` in [0, 2π).

    The arc length s(t) is tabulated on ``n_dense`` parameter samples; the node
    count is ``round(L / spacing)`` so the real spacing is ``L / n`` (within a
    few percent of ``spacing``); each node's parameter is found by inverting the
    table linearly and the node is evaluated *on the exact curve*.
    """
    t = np.linspace(0.0, 2.0 * np.pi, n_dense + 1)
    p = np.asarray(curve(t), dtype=np.float64)
    seg = np.hypot(*np.diff(p, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(3, int(round(s[-1] / spacing)))
    ti = np.interp(np.arange(n) * (s[-1] / n), s, t)
    return np.asarray(curve(ti), dtype=np.float64)


def ellipse_curve(
    center: Sequence[float], a: float, b: float, angle_deg: float = 0.0
) -> Callable[[np.ndarray], np.ndarray]:
    """Parametric ellipse with semi-axes ``a``, ``b`` rotated by ``angle_deg``."""
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))

    def f(t: np.ndarray) -> np.ndarray:
        x, y = a * np.cos(t), b * np.sin(t)
        return np.column_stack([center[0] + c * x - s * y, center[1] + s * x + c * y])

    return f


def naca_airfoil(thickness: float, panels: int, chord: float = 1.0,
                 origin: Sequence[float] = (0.0, 0.0), sharp: bool = False) -> np.ndarray:
    """A symmetric NACA 00xx section (``thickness`` as a fraction of the
    chord), clockwise as a hole, with its blunt trailing edge: the standard
    four-digit polynomial, whose last coefficient 0.1015 leaves the edge open
    by about 2% of the thickness (``sharp``: the closed-edge coefficient
    0.1036, the edge one node); ``panels`` nodes a side, clustered at both
    edges by cosine spacing."""
    x = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, panels + 1)))
    y = 5.0 * thickness * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2
                           + 0.2843 * x**3 - (0.1036 if sharp else 0.1015) * x**4)
    if sharp:
        y[-1] = 0.0
    upper = np.column_stack([x, y])[::-1]  # trailing edge to leading edge
    lower = np.column_stack([x, -y])[1:-1 if sharp else None]  # and back: counter-clockwise
    loop = chord * np.vstack([upper, lower]) + np.asarray(origin, dtype=np.float64)
    return clockwise(loop)


def gear(teeth: int, root: float, tip: float, spacing: float) -> np.ndarray:
    """A spur-gear outline, counter-clockwise about the origin: per tooth
    period, corners on the root circle at 0 and 0.15 of it, straight flanks
    up to corners on the tip circle at 0.3 and 0.55 and down to the root at
    0.7, all joined by straight sides; corners kept, sides split by
    :func:`polygon` at ``spacing``."""
    corners = []
    for k in range(teeth):
        for f, r in ((0.0, root), (0.15, root), (0.3, tip), (0.55, tip), (0.7, root)):
            a = 2.0 * np.pi * (k + f) / teeth
            corners.append((r * np.cos(a), r * np.sin(a)))
    return polygon(corners, spacing)


def slot(center: Sequence[float], length: float, radius: float, spacing: float) -> np.ndarray:
    """A straight slot (two half circles of ``radius`` joined by sides
    ``length`` long, along x), clockwise as a hole."""
    cx, cy = float(center[0]), float(center[1])
    n = max(2, int(round(np.pi * radius / spacing)))
    t = np.linspace(-0.5 * np.pi, 0.5 * np.pi, n + 1)[:-1]
    right = np.column_stack([cx + 0.5 * length + radius * np.cos(t), cy + radius * np.sin(t)])
    left = np.column_stack([cx - 0.5 * length - radius * np.cos(t), cy - radius * np.sin(t)])
    m = max(1, int(round(length / spacing)))
    s = np.arange(m)[:, None] / m
    top = np.array([cx + 0.5 * length, cy + radius]) + s * np.array([-length, 0.0])
    bottom = np.array([cx - 0.5 * length, cy - radius]) + s * np.array([length, 0.0])
    return clockwise(np.vstack([right, top, left, bottom]))


def sector(radius: float, angle: float, spacing: float) -> np.ndarray:
    """A circular sector with its tip at the origin, counter-clockwise: the
    tip, then the arc of ``radius`` from angle 0 to ``angle`` (radians) in
    equal pieces at most ``spacing`` long; the straight sides are not split."""
    if not (0.0 < angle < np.pi and radius > 0.0 and spacing > 0.0):
        raise ValueError(f"sector: need 0 < angle < pi and radius, spacing > 0, got "
                         f"{angle!r}, {radius!r}, {spacing!r}")
    n = max(1, math.ceil(radius * angle / spacing))
    t = np.linspace(0.0, angle, n + 1)
    return np.vstack([[(0.0, 0.0)], radius * np.column_stack([np.cos(t), np.sin(t)])])


def graded_polygon(corners: Sequence[Sequence[float]], focus: Sequence[float], fine: float,
                   coarse: float, growth: float) -> np.ndarray:
    """Nodes along a closed polygon, every corner kept, spaced ``fine`` at
    the point ``focus`` and growing by ``growth`` per unit of distance from
    it, up to ``coarse``: each side walked in steps of the spacing at the
    current node, the last step stretched to end on the corner.  ValueError
    unless 0 < fine <= coarse and growth >= 0 (finite)."""
    if not (0.0 < fine <= coarse < math.inf and 0.0 <= growth < math.inf):
        raise ValueError(f"graded_polygon: need 0 < fine <= coarse and growth >= 0, all "
                         f"finite; got fine={fine!r}, coarse={coarse!r}, growth={growth!r}")
    c = np.asarray(corners, dtype=np.float64)
    f = np.asarray(focus, dtype=np.float64)
    out = []
    for i in range(len(c)):
        a, b = c[i], c[(i + 1) % len(c)]
        length = float(np.hypot(*(b - a)))
        s = [0.0]
        while True:
            h = min(coarse, fine + growth * float(np.hypot(*(a + s[-1] / length * (b - a) - f))))
            if s[-1] + 1.5 * h >= length:
                break
            s.append(s[-1] + h)
        out.append(a + np.asarray(s)[:, None] / length * (b - a))
    return np.vstack(out)
