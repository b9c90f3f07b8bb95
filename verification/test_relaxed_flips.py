"""Edge flips judged after relaxing (bubblemesh._relaxed_flips), the last step of
bm.mesh: validity, conformity, fixed boundary nodes, the kept minimum and
area bounds, the summed radius ratio growing with every kept flip, the exact
active set, and a defect put into a perfect lattice taken out again.

Oracles: verification/oracles.py (exact orientation and conformity, the radius
ratio from the classical formulas), numpy areas and valence counts."""

from __future__ import annotations

import math

import numpy as np
import oracles as O
from hypothesis import given
from hypothesis import strategies as st
from test_pipeline import corner_domains

import bubblemesh as bm
from bubblemesh import pipeline
from bubblemesh._flips import ideal_counts, segment_keys
from bubblemesh._relaxed_flips import relaxed_flips
from bubblemesh.generation import generate_sized
from bubblemesh.sizing import SizeField

SWEEPS, HALVINGS, STEPS = 3, 4, 3


def _jittered(loops, size, seed):
    """A §2 mesh of the loops with its interior nodes jittered, re-triangulated:
    valence defects and poor triangles for the flips to work on."""
    domain = bm.Domain.from_loops(loops)
    field = SizeField.from_domain(domain, size=size)
    m = generate_sized(pipeline.refined_domain(domain, field), field)
    X = np.array(m.points)
    rng = np.random.default_rng(seed)
    inner = slice(m.n_boundary, None)
    X[inner] += rng.uniform(-0.2, 0.2, X[inner].shape) * m.radii[inner, None]
    tri, nbr = bm.constrained_delaunay(X, m.segments)
    return m, X, np.array(tri), np.array(nbr)


def _areas(X, tri):
    u, v = X[tri[:, 1]] - X[tri[:, 0]], X[tri[:, 2]] - X[tri[:, 0]]
    return 0.5 * (u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])


def _run(X, tri, nbr, segments, n_b, limit, keep, remember=True, passes=6, changed=None):
    movable = np.arange(len(X)) >= n_b
    movable[np.unique(segments)] = False
    changed = np.zeros(len(X), np.bool_) if changed is None else changed
    return relaxed_flips(X, tri, nbr, segment_keys(np.asarray(segments), len(X)), movable,
                         ideal_counts(X, tri, len(X)), limit, keep, passes, SWEEPS, HALVINGS,
                         STEPS, changed, remember)


@given(corner_domains(max_holes=2), st.sampled_from([0.3, 0.2]), st.floats(0.5, 1.0),
       st.booleans(), st.integers(0, 2**32 - 1))
def test_relaxed_flips_keep_the_mesh_valid_conforming_and_within_its_bounds(loops, size, keep,
                                                                           bounded, seed):
    m, X, tri, nbr = _jittered(loops, size, seed)
    X0, q0, tri0 = X.copy(), O.radius_ratio_reference(X, tri), tri.copy()
    area0 = _areas(X, tri)
    changed = np.zeros(len(X), np.bool_)
    limit = np.full(len(tri), np.inf)
    if bounded:  # some triangles just at their bound: the flips must respect every one
        limit = np.where(np.arange(len(tri)) % 2 == 0, area0 * 1.01, 1.2 * area0.max())
    flips = _run(X, tri, nbr, m.segments, m.n_boundary, limit, keep, changed=changed)
    O.check_valid(X, tri, nbr)
    np.testing.assert_array_equal(X[~changed], X0[~changed])  # the rest stays put
    same = ~changed[tri0].any(axis=1)
    np.testing.assert_array_equal(tri[same], tri0[same])
    assert changed.any() == (flips > 0)
    O.check_conforming(X, tri, m.segments, area=m.domain.area, rel=1e-9)
    np.testing.assert_array_equal(X[: m.n_boundary], X0[: m.n_boundary])
    q = O.radius_ratio_reference(X, tri)
    assert q.min() >= min(q0.min(), keep) * (1 - 1e-12)
    assert len(tri) == len(q0)
    # each kept flip raises the sum over the triangles it changed, the rest stay
    assert (q.sum() > q0.sum()) if flips else (q.sum() == q0.sum())
    assert np.all(_areas(X, tri) <= np.maximum(limit, area0) * (1 + 1e-12))


@given(corner_domains(max_holes=1), st.sampled_from([0.3, 0.2]), st.integers(0, 2**32 - 1))
def test_remembering_failed_trials_changes_no_bit(loops, size, seed):
    m, X, tri, nbr = _jittered(loops, size, seed)
    runs = []
    for remember in (True, False):
        Y, t, n = X.copy(), tri.copy(), nbr.copy()
        flips = _run(Y, t, n, m.segments, m.n_boundary, np.full(len(t), np.inf), 0.8, remember)
        runs.append((flips, Y, t, n))
    assert runs[0][0] == runs[1][0]
    for a, b in zip(runs[0][1:], runs[1][1:]):
        np.testing.assert_array_equal(a, b)


def _lattice_patch(rings):
    """The equilateral lattice inside a regular hexagon of ``rings`` rings (unit
    spacing): points with the hexagon's boundary first, and its triangles."""
    pts = {}
    for i in range(-rings, rings + 1):
        for j in range(-rings, rings + 1):
            if max(abs(i), abs(j), abs(i + j)) <= rings:
                pts[(i, j)] = (i + 0.5 * j, j * math.sqrt(3) / 2)
    ring = [k for k in pts if max(abs(k[0]), abs(k[1]), abs(k[0] + k[1])) == rings]
    ring.sort(key=lambda k: math.atan2(pts[k][1], pts[k][0]))
    order = ring + [k for k in pts if k not in ring]
    index = {k: n for n, k in enumerate(order)}
    tri = []
    for i, j in ((i, j) for i in range(-rings - 1, rings + 1)
                 for j in range(-rings - 1, rings + 1)):
        for a, b, c in (((i, j), (i + 1, j), (i, j + 1)), ((i + 1, j), (i + 1, j + 1), (i, j + 1))):
            if a in index and b in index and c in index:
                tri.append((index[a], index[b], index[c]))
    X = np.array([pts[k] for k in order])
    segments = np.array([(n, (n + 1) % len(ring)) for n in range(len(ring))])
    return X, np.array(tri, np.int64), segments, len(ring)


def test_a_defect_flipped_into_a_perfect_lattice_is_flipped_out():
    """One interior edge of an equilateral lattice flipped makes two valence-5
    and two valence-7 nodes and two triangles with a 120-degree apex (ratio
    8 sin(60) sin^2(15) = 0.464):
    the relaxed flips must give back the lattice, every ratio 1, every interior
    valence 6."""
    X, tri, segments, n_b = _lattice_patch(4)
    nbr = bm.topology.neighbors_of(tri)
    inner = np.arange(len(X)) >= n_b
    t, k = next((t, k) for t in range(len(tri)) for k in range(3)
                if nbr[t, k] > t and inner[tri[t, (k + 1) % 3]] and inner[tri[t, (k + 2) % 3]]
                and inner[tri[t, k]])
    u = nbr[t, k]
    a, b, c = tri[t, (k + 1) % 3], tri[t, (k + 2) % 3], tri[t, k]
    d = next(v for v in tri[u] if v not in (a, b))
    tri[t], tri[u] = (c, a, d), (d, b, c)
    nbr = bm.topology.neighbors_of(tri)
    apex = math.radians(120)
    assert np.isclose(O.radius_ratio_reference(X, tri).min(),
                      8 * math.sin(apex / 2) * math.sin((math.pi - apex) / 4) ** 2)
    flips = _run(X, tri, nbr, segments, n_b, np.full(len(tri), np.inf), 0.8)
    assert flips >= 1
    np.testing.assert_allclose(O.radius_ratio_reference(X, tri), 1.0, atol=1e-9)
    valence = np.bincount(tri.ravel(), minlength=len(X))
    assert np.all(valence[n_b:] == 6)
