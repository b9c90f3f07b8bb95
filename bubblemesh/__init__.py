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
from .compiling import maybe_notice
from .domain import Domain
from .errors import GeometryError, MeshingError
from .generation import generate
from .interop import to_pyvista, to_skfem, write_xdmf
from .optimization import optimize
from .pipeline import QualityWarning
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
    "QualityWarning",
    "optimize",
    "radius_ratio",
    "read",
    "to_pyvista",
    "to_skfem",
    "write_xdmf",
]

try:
    from importlib.metadata import version as _version

    __version__ = _version("bubblemesh")
except Exception:  # not installed (running from a checkout)
    __version__ = "0+unknown"


def mesh(domain: Domain, *, size: Any = None, max_area: Any = None, gradation: float = 0.25,
         paper: bool = False, progress: bool = False, **options: Any) -> Mesh:
    """Mesh ``domain``: by default the robust mesher (``bubblemesh.pipeline``).

    ``size``: the element size (edge length), a positive number or a
    vectorised callable ``h(xy: (n, 2)) -> (n,)``; ``max_area``: largest
    triangle area (as the side of the equilateral triangle of that area,
    combined with ``size`` by min); ``gradation``: the size field's largest
    slope (where graded walls would fill with more than 4% over the field's
    element count, the mesh is made on a slightly steeper one that asks for
    that count).  Without either, the sizes follow the input spacing and feature
    size.  ``options`` go to :func:`bubblemesh.pipeline.robust_mesh`
    (``insertion``: "auto", "frontal" or "centroid", §2's insertion order;
    ``max_iterations``, ``tol``, ``amplification``, ``alpha``, ``momentum``,
    ``rings``, ``smoothing_rounds``, ``smoothing_sweeps``).  Input nodes keep their
    coordinates bit for bit and come first, loop after loop (the outer loop
    counter-clockwise), with the nodes added on their segments between them.
    Corners too sharp for a radius ratio of 0.7, and triangles below it that
    touch no such corner, give a :class:`~bubblemesh.pipeline.QualityWarning`,
    also listed in ``mesh.generation.warnings``.

    ``paper=True``: the paper as published, ``optimize(generate(domain))``
    with ``options`` passed to :func:`optimize` (``size``, ``max_area`` and
    ``gradation`` must then be left at their defaults)."""
    if paper:
        if size is not None or max_area is not None or gradation != 0.25:
            raise ValueError("mesh: size, max_area and gradation do not apply with paper=True "
                             "(the paper's sizes come from the boundary spacing alone)")
        return optimize(generate(domain, progress=progress), progress=progress, **options)
    import inspect

    from .pipeline import robust_mesh

    unknown = sorted(set(options) - set(inspect.signature(robust_mesh).parameters))
    if unknown:  # named as the caller wrote it, not as robust_mesh
        raise TypeError(f"mesh() got an unexpected keyword argument {unknown[0]!r}")
    with maybe_notice(progress):
        return robust_mesh(domain, size=size, max_area=max_area, gradation=gradation,
                           progress=progress, **options)
