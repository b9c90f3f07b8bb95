"""Paper Fig. 3: circular region.  Unit disk, 64 uniformly spaced boundary nodes."""

from cases.geometry import circle

NAME = "fig3_circle"
TITLE = "Fig. 3: circular region (unit disk, 64 boundary nodes)"


def loops():
    return [circle((0.0, 0.0), 1.0, 64)]
