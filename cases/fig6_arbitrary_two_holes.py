"""Paper Fig. 6: arbitrary curved region with an elliptical and a triangular hole."""

import numpy as np

from cases.geometry import clockwise, ellipse_curve, polygon, resample_curve

NAME = "fig6_arbitrary_two_holes"
TITLE = (
    "Fig. 6: arbitrary region (spacing 0.07) with an elliptical (0.03) "
    "and a triangular (0.035) hole"
)


def outer(t):
    r = 1.0 + 0.25 * np.cos(3 * t) + 0.1 * np.sin(5 * t)
    return np.column_stack([1.3 * r * np.cos(t), r * np.sin(t)])


def loops():
    return [
        resample_curve(outer, spacing=0.07),
        clockwise(resample_curve(ellipse_curve((-0.35, 0.15), 0.28, 0.12, 30.0), spacing=0.03)),
        clockwise(polygon([(0.35, -0.45), (0.65, -0.30), (0.40, -0.10)], spacing=0.035)),
    ]
