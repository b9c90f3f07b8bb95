"""bubblemesh: bubble-controlled Delaunay mesh generation and physically-based
optimisation of 2D regions with holes (paper §2 and §3), on an exact kernel.

    import bubblemesh as bm
    dom = bm.Domain.from_loops([outer, hole])
    mesh = bm.mesh(dom)                 # generate (§2) + optimize (§3)
    bm.radius_ratio(mesh.points, mesh.triangles)   # eq. 10
"""

from typing import Any

from . import threads  # noqa: F401  (first: configures the thread pool before any kernel runs)
from ._mesh import GenerationStats, Mesh, OptimizationStats, read
from .domain import Domain
from .errors import GeometryError, MeshingError
from .generation import generate
from .optimization import optimize
from .quality import radius_ratio
from .triangulation import constrained_delaunay, delaunay

__all__ = [
    "Domain",
    "GenerationStats",
    "GeometryError",
    "Mesh",
    "MeshingError",
    "constrained_delaunay",
    "delaunay",
    "generate",
    "mesh",
    "OptimizationStats",
    "optimize",
    "radius_ratio",
    "read",
]

try:
    from importlib.metadata import version as _version

    __version__ = _version("bubblemesh")
except Exception:  # not installed (running from a checkout)
    __version__ = "0+unknown"


def mesh(domain: Domain, *, progress: bool = False, **optimize_options: Any) -> Mesh:
    """Paper §2 then §3 with the paper's defaults: the optimised mesh."""
    return optimize(generate(domain, progress=progress), progress=progress, **optimize_options)
