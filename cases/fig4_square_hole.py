"""Paper Fig. 4: square region with a circular hole, finer at the hole."""

from cases.geometry import circle, clockwise, rectangle

NAME = "fig4_square_hole"
TITLE = "Fig. 4: square [-1,1]² (16 segments a side) with a circular hole r=0.25 (48 nodes)"


def loops():
    return [
        rectangle(-1.0, -1.0, 1.0, 1.0, spacing=2.0 / 16),
        clockwise(circle((0.0, 0.0), 0.25, 48)),
    ]
