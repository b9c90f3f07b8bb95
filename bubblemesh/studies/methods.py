"""Methods: one small interface over bubblemesh, its peers and any user function.

An *adapter* is ``adapter(case, **params) -> Output``; it raises :class:`Skipped`
when it cannot run here (a package missing) and any exception when it fails.  A
:class:`Method` names an adapter, its fixed ``params`` and a ``grid`` of varied ones.

Adapters (``ADAPTERS``):

* ``bubblemesh.generate``: paper §2, ``bubblemesh.generate(domain, **params)``.
* ``bubblemesh.paper``: §2 then §3, ``bubblemesh.optimize(generate(domain), **params)``;
  with no params the paper's defaults (paper mode); time = generate + optimize.
* ``bubblemesh.mesh``: ``bubblemesh.mesh(domain, **params)``, the library's default.
* ``triangle``, ``gmsh_frontal``, ``gmsh_delaunay``: the peer generators of
  :mod:`bubblemesh.studies.peers` on the case's boundary nodes, tuned to the element count
  of the §2 mesh (or ``target_elements``).
* ``pymeshlab_remesh``, ``pymeshlab_remesh_free``, ``laplacian_pymeshlab``,
  ``laplacian_uniform``: the post-processors, run on the §2 mesh (``steps``: Laplacian steps).
* ``function``: ``function(loops, **params) -> (points, triangles)``, any callable, or a
  ``"module:attribute"`` / ``"path/to/file.py:attribute"`` string resolved where it runs.

The §2 mesh a peer starts from is built inside the peer's cell and not timed, so every
cell stands alone.
"""

from __future__ import annotations

import importlib
import importlib.util
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .case import Case

__all__ = ["ADAPTERS", "Method", "Output", "Skipped", "resolve_function"]


class Skipped(Exception):
    """The method cannot run here (its package is missing, its input could not be made)."""


@dataclass
class Output:
    """What an adapter made: the mesh, its time and how it was run."""

    points: np.ndarray
    triangles: np.ndarray
    seconds: float
    options: str
    input: str = "boundary nodes"
    radii: np.ndarray | None = None
    timings: dict[str, float] = field(default_factory=dict)


def _timed(function: Callable, *args: Any, **kwargs: Any) -> tuple[Any, float]:
    t0 = time.perf_counter()
    result = function(*args, **kwargs)
    return result, time.perf_counter() - t0


def _call(params: Mapping[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in params.items())


def _generate(case: Case, **params: Any) -> Output:
    import bubblemesh as bm

    m, seconds = _timed(bm.generate, case.domain(), **params)
    return Output(m.points, m.triangles, seconds,
                  f"bubblemesh.generate({_call(params)}): {m.insertions} insertions, "
                  f"ΣA_e = {m.bubble_area:.6g} ≥ A_geo = {m.domain_area:.6g}",
                  radii=m.radii, timings={"generate": seconds})


def _paper(case: Case, **params: Any) -> Output:
    import bubblemesh as bm

    m2, t2 = _timed(bm.generate, case.domain())
    m3, t3 = _timed(bm.optimize, m2, **params)
    how = f"({_call(params)})" if params else " (paper defaults)"
    return Output(m3.points, m3.triangles, t2 + t3,
                  f"bubblemesh.optimize{how} after generate: {m3.stats.get('iterations', '?')} "
                  "iterations; seconds = generate + optimize",
                  radii=m3.radii, timings={"generate": t2, "optimize": t3})


def _mesh(case: Case, *, match_elements: bool = False, **params: Any) -> Output:
    """bm.mesh; ``match_elements``: its gradation bisected (on a log scale in
    [0.005, 0.25]) until the count is within 3% of the §2 mesh's, as the peers
    are tuned; the boundary nodes stay the case's, as theirs do (8 runs at
    most, the closest kept and timed)."""
    import bubblemesh as bm

    domain = case.domain()
    m, seconds = _timed(bm.mesh, domain, **params)
    if match_elements:
        target = len(bm.generate(domain).triangles)
        low, high = math.log(0.005), math.log(0.25)  # fewer elements as g grows
        best = (abs(len(m.triangles) - target), m, seconds, 0.25)
        for _ in range(8):
            if best[0] <= 0.03 * target:
                break
            g = math.exp(0.5 * (low + high))
            m, seconds = _timed(bm.mesh, domain, **{**params, "gradation": g})
            if abs(len(m.triangles) - target) < best[0]:
                best = (abs(len(m.triangles) - target), m, seconds, g)
            if len(m.triangles) > target:
                low = math.log(g)
            else:
                high = math.log(g)
        _, m, seconds, g = best
        params = {**params, "gradation": round(g, 4)}
    return Output(m.points, m.triangles, seconds, f"bubblemesh.mesh({_call(params)})",
                  radii=m.radii, timings={"mesh": seconds})


def _peer(name: str) -> Callable[..., Output]:
    def adapter(case: Case, *, target_elements: int | None = None, steps: int | None = None,
                **extra: Any) -> Output:
        import bubblemesh as bm

        from . import peers

        if extra:
            raise TypeError(f"{name} takes target_elements and steps, not {', '.join(extra)}")
        try:
            base = bm.generate(case.domain())
        except Exception as error:  # the peer's input: without it the peer cannot run
            raise Skipped("no bubblemesh §2 mesh to match or post-process "
                          f"({type(error).__name__}: {error})") from None
        target = len(base.triangles) if target_elements is None else int(target_elements)
        options = {} if steps is None else {"laplacian_steps": int(steps)}
        p, t, seconds, info = peers.run_peer(name, case.loops, target,
                                             base=(base.points, base.triangles), **options)
        if info["status"] == "skipped":
            raise Skipped(info["reason"])
        if info["status"] != "ok":
            raise RuntimeError(info["reason"])
        runs = f"; tuning runs (parameter, elements): {info['runs']}" if "runs" in info else ""
        source = "bubblemesh §2 mesh" if name in peers.POSTPROCESSORS else "boundary nodes"
        return Output(p, t, seconds, info["options"] + runs, input=source)

    adapter.__name__ = adapter.__qualname__ = f"peer_{name}"
    return adapter


def resolve_function(ref: Callable | str) -> Callable:
    """A callable, or the one a ``"module:attribute"`` / ``"file.py:attribute"`` names."""
    if callable(ref):
        return ref
    if not isinstance(ref, str) or ":" not in ref:
        raise ValueError(f"function {ref!r}: expected a callable or 'module:attribute'")
    where, _, attribute = ref.rpartition(":")
    if where.endswith(".py"):
        spec = importlib.util.spec_from_file_location(f"_bubblemesh_method_{Path(where).stem}",
                                                      where)
        if spec is None or spec.loader is None or not Path(where).is_file():
            raise ValueError(f"function {ref!r}: no file {where}")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    else:
        module = importlib.import_module(where)
    found = getattr(module, attribute, None)
    if not callable(found):
        raise ValueError(f"function {ref!r}: {where} has no callable {attribute!r}")
    return found


def _function(case: Case, *, function: Callable | str, **params: Any) -> Output:
    f = resolve_function(function)
    result, seconds = _timed(f, [loop.copy() for loop in case.loops], **params)
    try:
        points, triangles = result
    except (TypeError, ValueError):
        raise TypeError(f"{getattr(f, '__name__', f)} returned {type(result).__name__}, "
                        "expected (points, triangles)") from None
    points = np.asarray(points, dtype=np.float64)[:, :2]
    triangles = np.asarray(triangles, dtype=np.int64)
    name = getattr(f, "__qualname__", repr(f))
    return Output(points, triangles, seconds, f"{name}(loops{', ' if params else ''}"
                  f"{_call(params)})")


ADAPTERS: dict[str, Callable[..., Output]] = {
    "bubblemesh.generate": _generate,
    "bubblemesh.paper": _paper,
    "bubblemesh.mesh": _mesh,
    **{name: _peer(name) for name in ("triangle", "gmsh_frontal", "gmsh_delaunay",
                                      "pymeshlab_remesh", "pymeshlab_remesh_free",
                                      "laplacian_pymeshlab", "laplacian_uniform")},
    "function": _function,
}


@dataclass(frozen=True)
class Method:
    """An adapter with its fixed ``params`` and a ``grid`` (name -> values, all combined).

    ``name`` labels the rows (unique in a study), ``label`` the report; ``timed`` cells run
    one at a time on a worker.  ``function`` is the callable (or its reference) of the
    ``function`` adapter.
    """

    name: str
    adapter: str
    params: Mapping[str, Any] = field(default_factory=dict)
    grid: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    label: str = ""
    timed: bool = True
    function: Callable | str | None = None

    def __post_init__(self) -> None:
        if self.adapter not in ADAPTERS:
            raise ValueError(f"method {self.name!r}: unknown adapter {self.adapter!r}; "
                             f"known: {', '.join(ADAPTERS)}")
        if (self.adapter == "function") != (self.function is not None):
            raise ValueError(f"method {self.name!r}: 'function' goes with adapter 'function'")
        for key, values in self.grid.items():
            if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
                raise ValueError(f"method {self.name!r}: grid {key!r} must be a non-empty list")
            if key in self.params:
                raise ValueError(f"method {self.name!r}: {key!r} is both in params and grid")
        object.__setattr__(self, "params", dict(self.params))
        object.__setattr__(self, "grid", {k: list(v) for k, v in self.grid.items()})
        object.__setattr__(self, "label", self.label or self.name)

    @classmethod
    def from_function(cls, name: str, function: Callable | str, *, label: str = "",
                      params: Mapping[str, Any] | None = None,
                      grid: Mapping[str, Sequence[Any]] | None = None,
                      timed: bool = True) -> Method:
        """A user mesher ``function(loops, **params) -> (points, triangles)`` as a method."""
        return cls(name, "function", params or {}, grid or {}, label, timed, function)

    def points(self) -> list[dict[str, Any]]:
        """Every parameter set of the grid (fixed params included), in grid order."""
        keys = list(self.grid)
        return [{**self.params, **dict(zip(keys, values))}
                for values in itertools.product(*(self.grid[k] for k in keys))]

    def reference(self) -> str:
        """What runs, for the cell key: the adapter, and the function's qualified name."""
        if self.function is None:
            return self.adapter
        if isinstance(self.function, str):
            return f"function:{self.function}"
        module = getattr(self.function, "__module__", "?")
        return f"function:{module}:{getattr(self.function, '__qualname__', '?')}"

    def run(self, case: Case, params: Mapping[str, Any]) -> Output:
        if self.function is not None:
            return ADAPTERS["function"](case, function=self.function, **params)
        return ADAPTERS[self.adapter](case, **params)
