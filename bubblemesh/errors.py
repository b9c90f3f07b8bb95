"""Exceptions raised by bubblemesh.

``GeometryError`` is raised for invalid input geometry (paper §2.1 needs a
valid refined boundary); the message names the offending loop/segment.
``MeshingError`` is raised when an internal bound is hit (a loop that could run
away) or an internal invariant fails; it is never silently ignored.
"""

__all__ = ["GeometryError", "MeshingError"]


class GeometryError(ValueError):
    """Invalid input geometry: the message says what is wrong and where."""


class MeshingError(RuntimeError):
    """An internal bound or invariant failed while meshing."""
