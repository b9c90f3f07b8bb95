"""A finite-element solve on a bubblemesh mesh through the scikit-fem bridge:
named boundary markers carry Dirichlet and Neumann conditions, and the P1
error against a manufactured solution falls at the expected order (the
oracle is the closed-form solution, not the mesher)."""

import numpy as np
import pytest

import bubblemesh as bm
from bubblemesh.interop import to_skfem

skfem = pytest.importorskip("skfem")
from skfem import Basis, ElementTriP1, FacetBasis, LinearForm, solve  # noqa: E402
from skfem.models.poisson import laplace  # noqa: E402

DIRICHLET, NEUMANN, HOLE = 1, 2, 3


def exact(x, y):
    return np.sin(np.pi * x) * np.exp(y)


def grad_exact(x, y):
    return np.pi * np.cos(np.pi * x) * np.exp(y), np.sin(np.pi * x) * np.exp(y)


def source(x, y):  # -Δu for u = sin(pi x) e^y
    return (np.pi**2 - 1.0) * np.sin(np.pi * x) * np.exp(y)


def plate() -> bm.Domain:
    """An L-shaped plate [0,2]^2 minus [1,2]^2 with a circular hole: the left
    side x = 0 'clamped' (Dirichlet), the other outer sides 'loaded' and the
    hole 'hole' (both Neumann)."""
    from dataclasses import replace

    outer = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)
    t = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    hole = np.column_stack([0.5 + 0.2 * np.cos(t), 0.5 + 0.2 * np.sin(t)])
    domain = bm.Domain.from_pslg(loops=[outer, hole], markers=[NEUMANN, HOLE],
                                 names={"clamped": DIRICHLET, "loaded": NEUMANN, "hole": HOLE})
    ends = domain.points[domain.segments]
    marks = np.array(domain.markers)
    marks[(ends[:, 0, 0] == 0.0) & (ends[:, 1, 0] == 0.0)] = DIRICHLET
    return replace(domain, segment_markers=marks)


def solve_on(mesh):
    m, facets = to_skfem(mesh)
    assert set(facets) == {"clamped", "loaded", "hole"}
    e = ElementTriP1()
    basis = Basis(m, e)

    @LinearForm
    def rhs(v, w):
        return source(w.x[0], w.x[1]) * v

    @LinearForm
    def flux(v, w):
        gx, gy = grad_exact(w.x[0], w.x[1])
        return (gx * w.n[0] + gy * w.n[1]) * v

    A = laplace.assemble(basis)
    b = rhs.assemble(basis)
    for name in ("loaded", "hole"):
        b = b + flux.assemble(FacetBasis(m, e, facets=facets[name]))
    dofs = basis.get_dofs(facets["clamped"])
    x = np.zeros(basis.N)
    x[dofs.all()] = exact(*m.p[:, dofs.all()])
    u = solve(*skfem.condense(A, b, x=x, D=dofs))
    return basis, u, len(dofs.all())


def l2_error(basis, u):
    from skfem import Functional

    @Functional
    def err(w):
        return (w["u"] - exact(w.x[0], w.x[1])) ** 2

    return float(np.sqrt(err.assemble(basis, u=basis.interpolate(u))))


def test_markers_reach_skfem_as_named_facets():
    mesh = bm.mesh(plate(), size=0.2)
    m, facets = to_skfem(mesh)
    left = m.p[:, m.facets[:, facets["clamped"]]]
    assert np.all(left[0] == 0.0)  # every clamped facet lies on x = 0
    on_left = np.all(m.p[0, m.facets] == 0.0, axis=0) & (m.f2t[1] < 0)
    assert set(np.flatnonzero(on_left)) == set(facets["clamped"])  # and every one on x = 0
    boundary = set(m.boundary_facets())
    assert set(np.concatenate(list(facets.values()))) == boundary


def test_p1_error_falls_at_order_two():
    errors, sizes = [], []
    for h in (0.1, 0.05, 0.025):
        mesh = bm.mesh(plate(), size=h)
        basis, u, n_dirichlet = solve_on(mesh)
        assert n_dirichlet > 0
        errors.append(l2_error(basis, u))
        sizes.append(np.sqrt(mesh.domain.area / len(mesh.triangles)))  # mean element size
    rates = np.log(np.array(errors[:-1]) / errors[1:]) / np.log(np.array(sizes[:-1]) / sizes[1:])
    assert np.all(rates > 1.7), (errors, rates)
    assert np.all(rates < 2.5), (errors, rates)
