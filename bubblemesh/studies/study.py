"""Studies: cases x methods x parameter grids, each cell one tidy row.

A :class:`Study` lists cases and :class:`~bubblemesh.studies.methods.Method` s; every
(case, method, grid point) is a :class:`Cell` whose ``key`` hashes the case (name and
loops), the method (name, adapter, function), the parameters and the bubblemesh version.
:func:`run_cell` meshes one cell and returns its row (never raises: a failure is a row
with ``status`` "failed" and the error in ``reason``).

A study definition is a TOML (or JSON) file; see ``load_study`` and the repository's
``cases/README.md``.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .case import Case, bundled_folder, load_cases
from .checks import basic_check, exact_check
from .methods import Method, Skipped, resolve_function

__all__ = ["Cell", "Study", "load_study", "run_cell", "bubblemesh_version", "versions"]

Verify = Callable[[Case, np.ndarray, np.ndarray], str]
REPORTS = ("study", "paper")
#: Packages whose versions each row records.
PACKAGES = ("bubblemesh", "numpy", "scipy", "numba", "pandas", "meshio", "triangle", "gmsh",
            "pymeshlab", "dask", "distributed")
# One timed cell at a time in a worker process, whatever its thread count.
_TIMING_LOCK = threading.Lock()


def bubblemesh_version() -> str:
    """The package version and a digest of its source: a cell's key changes with
    the code that computes it, so a study never reuses rows of older code."""
    if not _SOURCE:
        import bubblemesh

        root = Path(bubblemesh.__file__).parent
        digest = hashlib.sha256()
        for path in sorted(root.rglob("*.py")):
            if path.relative_to(root).parts[:2] == ("studies", "data"):
                continue  # the case files, installed beside the code but not code
            digest.update(path.relative_to(root).as_posix().encode() + b"\0")
            digest.update(path.read_bytes())
        _SOURCE.append(f"{bubblemesh.__version__}+{digest.hexdigest()[:12]}")
    return _SOURCE[0]


_SOURCE: list[str] = []


_VERSIONS: dict[str, str] = {}


def versions() -> dict[str, str]:
    """Python's and the installed packages' versions in this process (cached)."""
    if not _VERSIONS:
        from importlib import metadata

        _VERSIONS["python"] = platform.python_version()
        for package in PACKAGES:
            try:
                _VERSIONS[package] = metadata.version(package)
            except metadata.PackageNotFoundError:
                _VERSIONS[package] = "not installed"
        _VERSIONS["bubblemesh"] = bubblemesh_version()
    return dict(_VERSIONS)


@dataclass(frozen=True, eq=False)
class Cell:
    """One (case, method, parameters) of a study; ``index`` is its place in the study."""

    study: str
    case: Case
    method: Method
    params: Mapping[str, Any]
    index: int
    key: str


def cell_key(case: Case, method: Method, params: Mapping[str, Any], version: str) -> str:
    text = json.dumps({"case": case.name, "loops": case.digest, "method": method.name,
                       "runs": method.reference(), "params": dict(params), "bubblemesh": version},
                      sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


@dataclass(frozen=True, eq=False)
class Study:
    """Cases x methods x each method's grid.

    ``verify(case, points, triangles) -> str`` fills the ``verify`` column (default
    :func:`~bubblemesh.studies.checks.basic_check`; None: not run).  ``report`` is
    "study" (tables and quality against the ``x`` parameters) or "paper" (the paper's
    figures, for the Figs. 3-6 reproduction); ``keep_meshes`` writes every mesh as VTU.
    """

    name: str
    cases: Sequence[Case]
    methods: Sequence[Method]
    title: str = ""
    description: str = ""
    report: str = "study"
    x: Sequence[str] = ()
    keep_meshes: bool = False
    verify: Verify | None = basic_check
    source: str | None = None
    command: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "cases", tuple(self.cases))
        object.__setattr__(self, "methods", tuple(self.methods))
        object.__setattr__(self, "x", tuple(self.x))
        if not self.cases or not self.methods:
            raise ValueError(f"study {self.name!r} needs at least one case and one method")
        for kind, names in (("case", [c.name for c in self.cases]),
                            ("method", [m.name for m in self.methods])):
            twice = {n for n in names if names.count(n) > 1}
            if twice:
                raise ValueError(f"study {self.name!r}: {kind} {sorted(twice)[0]!r} given twice")
        if self.report not in REPORTS:
            raise ValueError(f"study {self.name!r}: report must be one of {REPORTS}")
        object.__setattr__(self, "title", self.title or self.name)

    def cells(self, version: str | None = None) -> list[Cell]:
        """Every cell, case-major (case, then method, then grid point)."""
        version = version or bubblemesh_version()
        cells: list[Cell] = []
        for case in self.cases:
            for method in self.methods:
                for params in method.points():
                    key = cell_key(case, method, params, version)
                    cells.append(Cell(self.name, case, method, params, len(cells), key))
        return cells

    @property
    def labels(self) -> dict[str, str]:
        return {m.name: m.label for m in self.methods}


# --------------------------------------------------------------------------- one cell

def _worker_name() -> str:
    try:
        from distributed import get_worker

        return str(get_worker().address)
    except (ImportError, ValueError):
        return f"local:{os.getpid()}"


def _mesh_columns(case: Case, points: np.ndarray, triangles: np.ndarray) -> dict[str, Any]:
    from bubblemesh.quality import summary

    from . import peers

    s = summary(points, triangles)
    shift, n_boundary = peers.boundary_shift(case.boundary, points, triangles)
    return dict(
        elements=int(s["count"]), nodes=int(len(points)), rho_min=s["min"], rho_mean=s["mean"],
        rho_median=s["median"], n_below_0_5=int(s["count_below_0_5"]),
        pct_below_0_5=100.0 * s["frac_below_0_5"], n_below_0_7=int(s["count_below_0_7"]),
        pct_below_0_7=100.0 * s["frac_below_0_7"], min_angle=s["min_angle_deg"],
        max_angle=s["max_angle_deg"], boundary_shift=shift, boundary_nodes=n_boundary,
        inverted=peers._inverted(points, triangles),
    )


def run_cell(cell: Cell, verify: Verify | None = basic_check, keep_mesh: bool = False
             ) -> dict[str, Any]:
    """Mesh one cell: ``{"row": {...}, "mesh": (points, triangles, radii) or None}``.

    Timed cells hold a per-process lock, so two never run at once in one worker."""
    row: dict[str, Any] = dict(
        study=cell.study, key=cell.key, case=cell.case.name, method=cell.method.name,
        adapter=cell.method.reference(), params=json.dumps(dict(cell.params), sort_keys=True,
                                                           default=repr),
        **{f"param_{k}": v for k, v in cell.params.items()},
        bubblemesh_version=bubblemesh_version(), case_digest=cell.case.digest,
        status="ok", reason="", timed=cell.method.timed, worker=_worker_name(),
        started=None, versions=json.dumps(versions(), sort_keys=True),
    )
    mesh = None
    lock = _TIMING_LOCK if cell.method.timed else threading.Lock()
    with lock:
        row["started"] = time.time()
        t0 = time.perf_counter()
        try:
            out = cell.method.run(cell.case, cell.params)
            points = np.asarray(out.points, dtype=np.float64)[:, :2]
            triangles = np.asarray(out.triangles, dtype=np.int64)
            row.update(_mesh_columns(cell.case, points, triangles), seconds=float(out.seconds),
                       timings=json.dumps(out.timings), options=out.options, input=out.input)
            if verify is not None:
                row["verify"] = _verified(verify, cell.case, points, triangles)
            if keep_mesh:
                radii = None if out.radii is None else np.asarray(out.radii, dtype=np.float64)
                mesh = (points, triangles, radii)
        except Skipped as why:
            row.update(status="skipped", reason=str(why))
        except Exception as error:  # a failing cell is a row; the study goes on
            row.update(status="failed", reason=f"{type(error).__name__}: {error}")
        row["cell_seconds"] = time.perf_counter() - t0
    return {"row": row, "mesh": mesh}


def _verified(verify: Verify, case: Case, points: np.ndarray, triangles: np.ndarray) -> str:
    try:
        return str(verify(case, points, triangles))
    except Exception as error:  # the checker's own failure is an outcome, not a lost row
        return f"failed: the checker raised {type(error).__name__}: {error}"


# --------------------------------------------------------------------------- definitions

def _read_definition(path: Path) -> dict[str, Any]:
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise ValueError(f"study definition {path}: {error}") from None
    try:
        if path.suffix == ".json":
            data = json.loads(text)
        else:
            try:
                import tomllib
            except ImportError:  # Python 3.10
                import tomli as tomllib  # type: ignore[no-redef]
            data = tomllib.loads(text)
    except ValueError as error:  # JSONDecodeError, TOMLDecodeError
        raise ValueError(f"study definition {path}: {error}") from None
    if not isinstance(data, dict):
        raise ValueError(f"study definition {path}: expected a table of settings")
    return data


def find_definition(name_or_path: str | Path) -> Path:
    """A definition file; a bare name ("paper", "iterations") is one shipped with the package."""
    path = Path(name_or_path)
    if path.exists():
        return path
    if path.suffix == "" and path.parent == Path("."):
        for suffix in (".toml", ".json"):
            shipped = bundled_folder() / f"{path.name}{suffix}"
            if shipped.exists():
                return shipped
    raise ValueError(f"no study definition {str(name_or_path)!r} (a .toml/.json file, or one "
                     f"of the shipped: {', '.join(shipped_studies())})")


def shipped_studies() -> list[str]:
    return sorted(p.stem for p in bundled_folder().glob("*.toml"))


def _verify_from(setting: Any, path: Path) -> Verify | None:
    if setting in (None, "basic"):
        return basic_check
    if setting == "exact":
        return exact_check
    if setting in ("none", False):
        return None
    if isinstance(setting, str):
        return resolve_function(setting)
    raise ValueError(f"study definition {path}: verify must be 'basic', 'exact', 'none' or "
                     "'module:function'")


_METHOD_KEYS = {"name", "adapter", "params", "grid", "label", "timed", "function"}
_STUDY_KEYS = {"name", "title", "description", "cases", "cases_dir", "methods", "report", "x",
               "keep_meshes", "verify"}


def load_study(path: str | Path, cases_dir: str | Path | None = None,
               only_cases: Sequence[str] | None = None) -> Study:
    """A study from its definition file.  Keys (TOML shown; JSON takes the same):

    ``name``, ``title``, ``description``; ``cases`` ("all" or a list of names) read from
    ``cases_dir`` (relative to the file; default its own folder when it holds case files,
    else the paper's cases; the ``cases_dir`` argument wins); ``[[methods]]`` tables with
    ``name``, ``adapter``, ``label``, ``params`` (fixed), ``grid`` (name -> list of values),
    ``timed`` (default true) and ``function`` ("module:attr" or "file.py:attr", adapter
    "function"); ``report`` ("study" or "paper"), ``x`` (grid parameters on the report's
    x axis), ``keep_meshes``, ``verify`` ("basic", "none" or "module:function").
    ``only_cases`` narrows the cases to those names.
    """
    path = find_definition(path)
    data = _read_definition(path)
    unknown = set(data) - _STUDY_KEYS
    if unknown:
        raise ValueError(f"study definition {path}: unknown setting {sorted(unknown)[0]!r}")
    folder = Path(cases_dir) if cases_dir is not None else _cases_folder(data, path)
    known = load_cases(folder)
    wanted = data.get("cases", "all")
    names = list(known) if wanted == "all" else list(wanted)
    if only_cases:
        names = [n for n in names if n in only_cases] + [n for n in only_cases if n not in names]
    missing = [n for n in names if n not in known]
    if missing:
        raise ValueError(f"unknown case {missing[0]!r}; known: {', '.join(known)}")
    methods = []
    for k, spec in enumerate(data.get("methods", [])):
        if not isinstance(spec, dict) or not {"name", "adapter"} <= set(spec):
            raise ValueError(f"study definition {path}: method {k} needs a name and an adapter")
        bad = set(spec) - _METHOD_KEYS
        if bad:
            raise ValueError(f"study definition {path}: method {spec['name']!r}: unknown "
                             f"setting {sorted(bad)[0]!r}")
        function = spec.get("function")
        if isinstance(function, str) and function.partition(":")[0].endswith(".py"):
            file, _, attribute = function.rpartition(":")
            function = f"{(path.parent / file).resolve()}:{attribute}"
        methods.append(Method(spec["name"], spec["adapter"], spec.get("params", {}),
                              spec.get("grid", {}), spec.get("label", ""),
                              bool(spec.get("timed", True)), function))
    return Study(
        name=str(data.get("name", path.stem)), cases=[known[n] for n in names], methods=methods,
        title=str(data.get("title", "")), description=str(data.get("description", "")),
        report=str(data.get("report", "study")), x=data.get("x", ()),
        keep_meshes=bool(data.get("keep_meshes", False)),
        verify=_verify_from(data.get("verify"), path), source=str(path),
    )


def _cases_folder(data: Mapping[str, Any], path: Path) -> Path:
    if "cases_dir" in data:
        return path.parent / str(data["cases_dir"])
    if any(p.suffix in (".json", ".poly", ".py") and not p.name.startswith("_")
           and p.name != path.name for p in path.parent.iterdir()):
        return path.parent
    return bundled_folder()
