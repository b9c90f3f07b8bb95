"""Paper Fig. 5: rectangular region with two circular holes."""

from cases.geometry import circle, clockwise, rectangle

NAME = "fig5_rect_two_holes"
TITLE = "Fig. 5: rectangle [0,4]×[0,2] (spacing 0.2) with holes r=0.4 and r=0.25 (40 nodes each)"


def loops():
    return [
        rectangle(0.0, 0.0, 4.0, 2.0, spacing=0.2),
        clockwise(circle((1.0, 1.0), 0.4, 40)),
        clockwise(circle((3.0, 1.0), 0.25, 40)),
    ]
