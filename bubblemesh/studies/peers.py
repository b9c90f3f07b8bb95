"""The meshers and smoothers bubblemesh is set against, behind one small interface.

    run_peer(name, loops, target_elements, *, base=None) -> (points, triangles, seconds, info)

``loops`` are the case's boundary-node arrays (outer first); every peer meshes
the region they bound *on exactly those boundary nodes*.  ``target_elements``
is the element count of the bubblemesh §2 mesh, which the mesh generators are
tuned to match.  ``base=(points, triangles)`` is that §2 mesh, the input of the
post-processors (remeshing, Laplacian smoothing); its first ``sum(len(loop))``
nodes are the boundary nodes in loop order (the ``bubblemesh.Mesh`` layout).

``info`` always has ``status`` ("ok", "skipped" when the peer's package is not
installed, "failed" when it raised) and ``reason``; a missing or failing peer
never raises.  On "ok" it also has ``options`` (what was run, in words),
``runs`` (every tuning run: parameter and element count), ``boundary_shift``
(largest distance from a given boundary node to the nearest boundary node of
the result; 0 when the boundary is kept) and ``boundary_nodes``.

``seconds`` is the wall time of the run whose mesh is returned (the tuning
run closest to the target), excluding package start-up; for the
post-processors it excludes building the §2 input mesh.

How each peer is tuned to the same boundary and element count:

* ``triangle``: Triangle's ``pq30a<A>Y`` (quality, min angle 30°, maximum
  area ``A``; ``Y`` forbids Steiner points on the boundary, so the boundary
  nodes are exactly the given ones).  ``A`` starts at domain area / target and
  is corrected ``A *= count / target`` for up to ``TUNING_RUNS`` runs; the run
  closest to the target is kept.
* ``gmsh_frontal`` / ``gmsh_delaunay``: Gmsh ``Mesh.Algorithm`` 6 / 5 on a
  geometry whose points are the boundary nodes and whose curves are the
  boundary segments, each a transfinite curve of 2 nodes (so Gmsh adds no
  boundary node).  Each node's size h_i is the mean length of its two
  segments.  Gmsh's own ``Mesh.MeshSizeFactor`` and boundary extension do not
  reach the interior once the boundary is transfinite (measured: the count did
  not change with the factor), so the interior size comes from a size
  callback: f × the reciprocal-distance mean, over the loops, of h at each
  loop's nearest node (the paper's eq. 3 weighting, one term per loop so a
  densely noded hole does not outweigh the outer loop), with
  ``f *= sqrt(count / target)`` corrected over the tuning runs.  One thread,
  no terminal output, initialised and finalised around each call.
* ``pymeshlab_remesh``: ``meshing_isotropic_explicit_remeshing`` of the §2 mesh
  with an absolute target edge length ``L`` (start: the equilateral edge for
  domain area / target; corrected ``L *= sqrt(count / target)``).  The filter
  has no boundary-lock switch, and on the whole mesh it splits and collapses
  boundary edges like any other (measured: the boundary-node count changes).
  So the faces owning a boundary edge are left unselected and the filter runs
  with ``selectedonly=True``: the boundary nodes, and that strip of §2 faces,
  are kept exactly.
* ``pymeshlab_remesh_free``: the same on the whole mesh, boundary not kept
  (``boundary_shift`` and ``boundary_nodes`` say how far it changed): what the
  filter does when left alone, for reference.
* ``laplacian_pymeshlab``: ``apply_coord_laplacian_smoothing`` with
  ``cotangentweight=False`` for ``LAPLACIAN_STEPS`` steps, only the interior
  vertices selected (``selected=True``) so the boundary stays fixed (the
  filter's own ``boundary`` switch smooths the boundary as a polyline instead).
  Its update is x ← (x + 2 Σ neighbours) / (2·deg + 1) (each neighbour counted
  once per shared face, plus the vertex itself).
* ``laplacian_uniform``: a plain uniform Laplacian written here with scipy
  sparse, x ← mean of the neighbours (Jacobi), boundary fixed, same step count:
  the textbook variant and a cross-check of pymeshlab's
  (``laplacian_smooth(..., self_weight=0.5)`` reproduces pymeshlab's update).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

__all__ = [
    "PEERS",
    "GENERATORS",
    "POSTPROCESSORS",
    "LAPLACIAN_STEPS",
    "run_peer",
    "laplacian_smooth",
    "hole_points",
    "triangle_number",
    "boundary_shift",
    "peer_versions",
]

GENERATORS = ("triangle", "gmsh_frontal", "gmsh_delaunay")
POSTPROCESSORS = (
    "pymeshlab_remesh",
    "pymeshlab_remesh_free",
    "laplacian_pymeshlab",
    "laplacian_uniform",
)
PEERS = GENERATORS + POSTPROCESSORS

#: Laplacian smoothing steps for both Laplacian peers: converged, i.e. on every case the
#: mean ρ after 20 steps is within 0.001 of its value after 200 (measured on the §2 meshes).
LAPLACIAN_STEPS = 20
#: Runs spent matching the target element count (the closest is kept).
TUNING_RUNS = 3
#: Triangle's minimum-angle bound in degrees (``q30``).
TRIANGLE_MIN_ANGLE = 30
#: Iterations of pymeshlab's isotropic remeshing (the filter's default).
REMESH_ITERATIONS = 10


# --------------------------------------------------------------------------- helpers


def _segments(loops: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    pts = np.vstack([np.asarray(lp, dtype=np.float64)[:, :2] for lp in loops])
    segs, off = [], 0
    for lp in loops:
        n = len(lp)
        i = np.arange(n)
        segs.append(np.column_stack([off + i, off + (i + 1) % n]))
        off += n
    return pts, np.vstack(segs).astype(np.int64)


def hole_points(loops: Sequence[np.ndarray]) -> np.ndarray:
    """A point strictly inside each hole loop (shapely's representative point)."""
    from shapely.geometry import Polygon

    out = [Polygon(np.asarray(lp)[:, :2]).representative_point().coords[0] for lp in loops[1:]]
    return np.asarray(out, dtype=np.float64).reshape(-1, 2)


def _domain_area(loops: Sequence[np.ndarray]) -> float:
    from .geometry import signed_area

    return abs(signed_area(loops[0])) - sum(abs(signed_area(lp)) for lp in loops[1:])


def _ccw(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    tri = tri.copy()
    flip = area2 < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    return tri


def _inverted(points: np.ndarray, tri: np.ndarray) -> int:
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    area2 = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    return int((area2 <= 0).sum())


def _boundary_nodes(triangles: np.ndarray) -> np.ndarray:
    """Nodes on an edge used by exactly one triangle."""
    t = np.asarray(triangles, dtype=np.int64)
    e = np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    u, cnt = np.unique(e, axis=0, return_counts=True)
    return np.unique(u[cnt == 1])


def boundary_shift(
    boundary: np.ndarray, points: np.ndarray, triangles: np.ndarray
) -> tuple[float, int]:
    """How far the given boundary nodes moved in a mesh, and how many boundary nodes it has.

    Returns ``(shift, n_boundary)``: ``shift`` is the largest distance from a
    given boundary node to the nearest node on the mesh's boundary (0 when every
    boundary node is kept), ``n_boundary`` the mesh's count of boundary nodes
    (equal to ``len(boundary)`` when none were added or removed).
    """
    from scipy.spatial import cKDTree

    p = np.asarray(points, dtype=np.float64)[:, :2]
    bn = _boundary_nodes(triangles)
    if len(bn) == 0:
        return float("inf"), 0
    d, _ = cKDTree(p[bn]).query(np.asarray(boundary, dtype=np.float64)[:, :2])
    return float(d.max()), int(len(bn))


def triangle_number(x: float) -> str:
    """``x`` with 6 significant digits and no exponent: Triangle's switch parser reads only
    digits and '.', so 'a3.1e-05' would mean area bound 3.1 followed by switch 'e'."""
    return np.format_float_positional(
        float(x), precision=6, unique=False, fractional=False, trim="-"
    )


def _skip(reason: str, status: str = "skipped"):
    return None, None, float("nan"), {"status": status, "reason": reason}


def _closest(runs: list[tuple], target: int):
    """The run (param, count, result...) whose count is closest to target (earliest on ties)."""
    return min(runs, key=lambda r: (abs(np.log(max(r[1], 1) / target)), runs.index(r)))


# --------------------------------------------------------------------------- Triangle


def _triangle(loops, target, area=None, tuning_runs=TUNING_RUNS):
    """Triangle tuned to ``target`` elements from the area bound ``area`` (default: domain
    area / target); ``tuning_runs=1`` is one run at ``area``.  ``info["parameter"]`` is the
    area bound of the returned run."""
    import triangle as tr

    pts, segs = _segments(loops)
    data = {"vertices": pts, "segments": segs}
    holes = hole_points(loops)
    if len(holes):
        data["holes"] = holes
    area = _domain_area(loops) / target if area is None else float(area)
    runs = []
    for _ in range(tuning_runs):
        opts = f"pq{TRIANGLE_MIN_ANGLE}a{triangle_number(area)}YQ"
        t0 = time.perf_counter()
        out = tr.triangulate(data, opts)
        sec = time.perf_counter() - t0
        p, t = np.asarray(out["vertices"], np.float64), np.asarray(out["triangles"], np.int64)
        runs.append((opts, len(t), p, t, sec, area))
        if len(t) == target:
            break
        area *= len(t) / target
    opts, _, p, t, sec, area = _closest(runs, target)
    return (
        p,
        _ccw(p, t),
        sec,
        {
            "parameter": area,
            "options": f"triangle.triangulate(..., '{opts}') (p: PSLG, q{TRIANGLE_MIN_ANGLE}: min "
            "angle, "
            f"a: max area, Y: no boundary Steiner points, Q: quiet)",
            "runs": [(r[0], int(r[1])) for r in runs],
        },
    )


# --------------------------------------------------------------------------- Gmsh


def _node_sizes(loop: np.ndarray) -> np.ndarray:
    """Mean length of the two boundary segments at each node of a closed loop."""
    seg_len = np.hypot(*(np.roll(loop, -1, axis=0) - loop).T)
    return 0.5 * (seg_len + np.roll(seg_len, 1))


def _gmsh(loops, target, algorithm, uniform=False, factor=1.0, tuning_runs=TUNING_RUNS):
    """Gmsh on the boundary nodes; sizes interpolated from them (or uniform, for the benchmark),
    times ``factor``, tuned to ``target`` elements over ``tuning_runs`` runs (1: one run at
    ``factor``).  ``info["parameter"]`` is the factor of the returned run."""
    import gmsh
    from scipy.spatial import cKDTree

    loop_sizes = [_node_sizes(lp) for lp in loops]
    sizes = np.concatenate(loop_sizes)
    trees = [cKDTree(lp) for lp in loops]

    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.Algorithm", algorithm)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        factor, runs = float(factor), []
        for _ in range(tuning_runs):
            gmsh.clear()
            gmsh.model.add("case")
            t0 = time.perf_counter()
            curve_loops, off = [], 0
            for loop in loops:
                n = len(loop)
                ptags = [
                    gmsh.model.geo.addPoint(x, y, 0.0, h)
                    for (x, y), h in zip(loop, sizes[off : off + n], strict=True)
                ]
                off += n
                ltags = [gmsh.model.geo.addLine(ptags[i], ptags[(i + 1) % n]) for i in range(n)]
                for lt in ltags:  # exactly the given boundary nodes: no node added on a segment
                    gmsh.model.geo.mesh.setTransfiniteCurve(lt, 2)
                curve_loops.append(gmsh.model.geo.addCurveLoop(ltags))
            surf = gmsh.model.geo.addPlaneSurface(curve_loops)
            gmsh.model.geo.synchronize()
            if uniform:
                h = float(factor * sizes.mean())
                gmsh.option.setNumber("Mesh.MeshSizeMin", h)
                gmsh.option.setNumber("Mesh.MeshSizeMax", h)
            else:

                def size_at(dim, tag, x, y, z, lc, f=factor):
                    num = den = 0.0
                    for tree, h in zip(trees, loop_sizes, strict=True):
                        d, i = tree.query((x, y))
                        if d < 1e-300:
                            return float(f * h[i])
                        num += h[i] / d
                        den += 1.0 / d
                    return float(f * num / den)

                gmsh.model.mesh.setSizeCallback(size_at)
            gmsh.model.mesh.generate(2)
            node_tags, coords, _ = gmsh.model.mesh.getNodes()
            _, elem_nodes = gmsh.model.mesh.getElementsByType(2, surf)
            sec = time.perf_counter() - t0
            p = np.asarray(coords, dtype=np.float64).reshape(-1, 3)[:, :2]
            index = np.zeros(int(np.max(node_tags)) + 1, dtype=np.int64)
            index[np.asarray(node_tags, dtype=np.int64)] = np.arange(len(node_tags))
            t = index[np.asarray(elem_nodes, dtype=np.int64).reshape(-1, 3)]
            runs.append((factor, len(t), p, t, sec))
            if len(t) == target:
                break
            factor *= float(np.sqrt(len(t) / target))
    finally:
        gmsh.finalize()
    factor, _, p, t, sec = _closest(runs, target)
    name = {6: "Frontal-Delaunay", 5: "Delaunay"}[algorithm]
    field = (
        f"uniform size {factor:.4g} x mean boundary spacing"
        if uniform
        else f"size at x = {factor:.4g} x reciprocal-distance mean over the loops of the "
        "size of each loop's nearest node (Python size callback, included in the time)"
    )
    return (
        p,
        _ccw(p, t),
        sec,
        {
            "parameter": factor,
            "options": f"gmsh {gmsh.__version__} Mesh.Algorithm={algorithm} ({name}), boundary "
            "segments "
            f"transfinite with 2 nodes, node size = mean adjacent segment length, "
            f"MeshSizeExtendFromBoundary=0, {field}",
            "runs": [(round(float(r[0]), 6), r[1]) for r in runs],
        },
    )


# --------------------------------------------------------------------------- pymeshlab


def _meshset(points, triangles):
    import pymeshlab as pml

    v = np.zeros((len(points), 3), dtype=np.float64)
    v[:, :2] = points[:, :2]
    ms = pml.MeshSet()
    ms.add_mesh(pml.Mesh(vertex_matrix=v, face_matrix=np.array(triangles, dtype=np.int32)))
    return ms


def _remesh_once(bp, bt, length, lock_strip):
    import pymeshlab as pml

    ms = _meshset(bp, bt)
    t0 = time.perf_counter()
    if lock_strip:
        ms.compute_selection_from_mesh_border()  # faces owning a boundary edge, boundary vertices
        ms.apply_selection_inverse(invfaces=True, invverts=True)
    ms.meshing_isotropic_explicit_remeshing(
        iterations=REMESH_ITERATIONS,
        targetlen=pml.PureValue(float(length)),
        selectedonly=lock_strip,
    )
    m = ms.current_mesh()
    sec = time.perf_counter() - t0
    return (
        np.array(m.vertex_matrix(), dtype=np.float64)[:, :2],
        np.array(m.face_matrix(), dtype=np.int64),
        sec,
    )


def _pymeshlab_remesh(loops, target, base, lock):
    bp, bt = np.asarray(base[0], np.float64), np.asarray(base[1], np.int64)
    length, runs = np.sqrt(4.0 * _domain_area(loops) / (np.sqrt(3.0) * target)), []
    for _ in range(TUNING_RUNS):
        p, t, sec = _remesh_once(bp, bt, length, lock)
        runs.append((length, len(t), p, t, sec))
        if len(t) == target:
            break
        length *= np.sqrt(len(t) / target)
    length, _, p, t, sec = _closest(runs, target)
    how = (
        "with selectedonly=True on the faces that own no boundary edge "
        "(compute_selection_from_mesh_border "
        "+ apply_selection_inverse): boundary nodes and the boundary strip of faces kept"
        if lock
        else "on the whole mesh: boundary edges may be split or collapsed "
        "(see boundary shift / boundary nodes)"
    )
    return (
        p,
        _ccw(p, t),
        sec,
        {
            "options": f"meshing_isotropic_explicit_remeshing(iterations={REMESH_ITERATIONS}, "
            f"targetlen=PureValue({length:.4g})) {how}",
            "runs": [(round(float(r[0]), 6), int(r[1])) for r in runs],
        },
    )


def _laplacian_pymeshlab(base, n_boundary, steps):
    bp, bt = np.asarray(base[0], np.float64), np.asarray(base[1], np.int64)
    ms = _meshset(bp, bt)
    t0 = time.perf_counter()
    ms.compute_selection_from_mesh_border()
    ms.apply_selection_inverse(invfaces=False, invverts=True)  # interior vertices only
    ms.apply_coord_laplacian_smoothing(
        stepsmoothnum=steps, boundary=False, cotangentweight=False, selected=True
    )
    p = np.array(ms.current_mesh().vertex_matrix(), dtype=np.float64)[:, :2]
    sec = time.perf_counter() - t0
    return (
        p,
        bt.copy(),
        sec,
        {
            "options": f"apply_coord_laplacian_smoothing(stepsmoothnum={steps}, "
            "cotangentweight=False, "
            f"selected=True) with only interior vertices selected",
        },
    )


def laplacian_smooth(
    points: np.ndarray,
    triangles: np.ndarray,
    fixed: np.ndarray,
    steps: int,
    self_weight: float = 0.0,
) -> np.ndarray:
    """Jacobi uniform Laplacian smoothing, ``fixed`` (bool mask or indices) never moved.

    Each step moves every free node to (self_weight·x + Σ neighbours) /
    (self_weight + deg).  ``self_weight=0`` is the plain mean of the neighbours;
    ``self_weight=0.5`` is pymeshlab's update.
    """
    import scipy.sparse as sp

    p = np.array(points, dtype=np.float64)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    n = len(p)
    e = np.unique(np.sort(np.vstack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    adj = sp.coo_matrix(
        (np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]], np.r_[e[:, 1], e[:, 0]])), shape=(n, n)
    ).tocsr()
    deg = np.asarray(adj.sum(axis=1)).ravel()
    mask = np.zeros(n, dtype=bool)
    mask[fixed] = True
    free = ~mask & (deg > 0)
    denom = (self_weight + deg[free])[:, None]
    for _ in range(steps):
        q = adj @ p
        p[free] = (self_weight * p[free] + q[free]) / denom
    return p


def _laplacian_uniform(base, n_boundary, steps):
    bp, bt = np.asarray(base[0], np.float64), np.asarray(base[1], np.int64)
    t0 = time.perf_counter()
    p = laplacian_smooth(bp, bt, np.arange(n_boundary), steps)
    sec = time.perf_counter() - t0
    return (
        p,
        bt.copy(),
        sec,
        {
            "options": f"bubblemesh.studies.peers.laplacian_smooth(steps={steps}): "
            "x <- mean of neighbours, boundary fixed",
        },
    )


# --------------------------------------------------------------------------- interface

_PACKAGE = {
    "triangle": "triangle",
    "gmsh_frontal": "gmsh",
    "gmsh_delaunay": "gmsh",
    "pymeshlab_remesh": "pymeshlab",
    "pymeshlab_remesh_free": "pymeshlab",
    "laplacian_pymeshlab": "pymeshlab",
    "laplacian_uniform": "scipy",
}


def run_peer(
    name: str,
    loops: Sequence[np.ndarray],
    target_elements: int,
    *,
    base: tuple[np.ndarray, np.ndarray] | None = None,
    laplacian_steps: int = LAPLACIAN_STEPS,
):
    """Mesh the region bounded by ``loops`` with peer ``name``; see the module docstring."""
    import importlib

    if name not in _PACKAGE:
        raise ValueError(f"unknown peer {name!r}; known: {', '.join(PEERS)}")
    try:
        importlib.import_module(_PACKAGE[name])
    except Exception as exc:  # ImportError, or a broken binary wheel
        return _skip(f"package {_PACKAGE[name]!r} not importable: {exc}")
    loops = [np.asarray(lp, dtype=np.float64)[:, :2] for lp in loops]
    boundary = np.vstack(loops)
    target = max(int(target_elements), 1)
    if name in POSTPROCESSORS and base is None:
        return _skip("needs the bubblemesh §2 mesh as input (base=None)")
    try:
        if name == "triangle":
            p, t, sec, info = _triangle(loops, target)
        elif name == "gmsh_frontal":
            p, t, sec, info = _gmsh(loops, target, 6)
        elif name == "gmsh_delaunay":
            p, t, sec, info = _gmsh(loops, target, 5)
        elif name in ("pymeshlab_remesh", "pymeshlab_remesh_free"):
            p, t, sec, info = _pymeshlab_remesh(
                loops, target, base, lock=name == "pymeshlab_remesh"
            )
        elif name == "laplacian_pymeshlab":
            p, t, sec, info = _laplacian_pymeshlab(base, len(boundary), laplacian_steps)
        else:
            p, t, sec, info = _laplacian_uniform(base, len(boundary), laplacian_steps)
    except Exception as exc:
        return _skip(f"{type(exc).__name__}: {exc}", status="failed")
    shift, nb = boundary_shift(boundary, p, t)
    info.update(
        status="ok", reason="", boundary_shift=shift, boundary_nodes=nb, inverted=_inverted(p, t)
    )
    return p, t, sec, info


def peer_versions() -> dict[str, str]:
    """Installed versions of the peers' packages ('not installed' when missing)."""
    from importlib import metadata

    out = {}
    for pkg in ("triangle", "gmsh", "pymeshlab", "scipy"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out
