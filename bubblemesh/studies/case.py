"""A case: a region's boundary nodes (loops, outer first) with a name, a title and metadata.

A case is data.  A folder of cases holds one file per case:

* ``NAME.json``: ``{"name", "title", "loops": [[[x, y], ...], ...]}`` plus any metadata
  (``label``, ``paper``, ``construction``, ...); or ``"poly": "file.poly"`` instead of
  ``loops`` (a path relative to the JSON file);
* ``NAME.poly``: a Triangle ``.poly`` boundary (name and title from the file name);
* ``NAME.py``: a module defining ``NAME``, ``TITLE`` and ``loops()``, for cases given by
  formulas (the builders of :mod:`bubblemesh.studies.geometry` help).

``load_cases(folder)`` reads them all; ``paper_cases()`` are the paper's Figs. 3-6,
shipped with the package.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Case", "load_case", "load_cases", "paper_cases", "CASE_SUFFIXES"]

CASE_SUFFIXES = (".json", ".poly", ".py")
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]*$")


@dataclass(frozen=True, eq=False)
class Case:
    """Boundary loops (``(n, 2)`` float64, outer first, no closing repeat) and their labels.

    ``metadata`` is free-form (JSON values); the paper report reads ``label`` ("Fig. 3"),
    ``paper`` (``claim``, ``low_elements``: "none" or "few") and ``construction``.
    """

    name: str
    loops: tuple[np.ndarray, ...]
    title: str = ""
    metadata: Mapping[str, Any] = field(default_factory=dict)
    source: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise ValueError(f"case name {self.name!r}: use letters, digits, '_', '.', '-'")
        where = f"case {self.name!r}"
        if isinstance(self.loops, np.ndarray) or not isinstance(self.loops, Sequence):
            raise TypeError(f"{where}: loops must be a list of (n, 2) arrays")
        loops = []
        for k, loop in enumerate(self.loops):
            a = np.array(loop, dtype=np.float64)
            if a.ndim != 2 or a.shape[1] != 2 or len(a) < 3:
                raise ValueError(f"{where}: loop {k} has shape {a.shape}, expected (n >= 3, 2)")
            a.flags.writeable = False
            loops.append(a)
        if not loops:
            raise ValueError(f"{where}: no loops")
        object.__setattr__(self, "loops", tuple(loops))
        object.__setattr__(self, "title", str(self.title or self.name))
        object.__setattr__(self, "metadata", dict(self.metadata))

    def __repr__(self) -> str:
        nodes = sum(len(loop) for loop in self.loops)
        return f"Case({self.name!r}, loops={len(self.loops)}, nodes={nodes})"

    @property
    def label(self) -> str:
        """A short name for tables: ``metadata['label']``, else the title before a colon."""
        return str(self.metadata.get("label") or self.title.split(":")[0])

    @property
    def boundary(self) -> np.ndarray:
        """Every boundary node, loop after loop (the first nodes of a bubblemesh Mesh)."""
        return np.vstack(self.loops)

    @property
    def digest(self) -> str:
        """16 hex digits of SHA-256 over the loops' bytes: the case's identity in cell keys."""
        h = hashlib.sha256()
        for loop in self.loops:
            h.update(np.ascontiguousarray(loop, dtype="<f8").tobytes())
            h.update(b"|")
        return h.hexdigest()[:16]

    def domain(self):
        """The validated :class:`bubblemesh.Domain` (GeometryError names loop and segment)."""
        from bubblemesh.domain import Domain

        return Domain.from_loops(self.loops)

    @classmethod
    def from_poly(cls, path: str | Path, name: str | None = None, title: str = "",
                  metadata: Mapping[str, Any] | None = None) -> Case:
        """The loops of a Triangle ``.poly`` file (read and checked by ``Domain.from_poly``)."""
        from bubblemesh.domain import Domain

        path = Path(path)
        domain = Domain.from_poly(path)
        loops = [np.asarray(domain.points)[index] for index in domain.loops]
        return cls(name or path.stem, tuple(loops), title or path.stem, metadata or {},
                   str(path))

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "title": self.title, **self.metadata,
                "loops": [loop.tolist() for loop in self.loops]}

    def to_json(self, path: str | Path) -> None:
        """Write the case as JSON, one node per line; floats round-trip exactly."""
        head = {k: v for k, v in self.to_dict().items() if k != "loops"}
        text = json.dumps(head, indent=1, ensure_ascii=False)[:-2]
        loops = ",\n".join(
            "  [\n" + ",\n".join(f"   [{x!r}, {y!r}]" for x, y in loop.tolist()) + "\n  ]"
            for loop in self.loops
        )
        Path(path).write_text(f'{text},\n "loops": [\n{loops}\n ]\n}}\n', encoding="utf-8")


def _from_json(path: Path) -> Case:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ValueError(f"case file {path}: {error}") from None
    if not isinstance(data, dict):
        raise ValueError(f"case file {path}: expected a JSON object")
    meta = {k: v for k, v in data.items() if k not in ("name", "title", "loops", "poly")}
    name, title = data.get("name", path.stem), data.get("title", "")
    if "poly" in data:
        return Case.from_poly(path.parent / data["poly"], name, title, meta)
    if "loops" not in data:
        raise ValueError(f"case file {path}: needs 'loops' or 'poly'")
    try:
        return Case(name, tuple(data["loops"]), title, meta, str(path))
    except (TypeError, ValueError) as error:
        raise ValueError(f"case file {path}: {error}") from None


def _from_python(path: Path) -> Case:
    spec = importlib.util.spec_from_file_location(f"_bubblemesh_case_{path.stem}", path)
    if spec is None or spec.loader is None:
        raise ValueError(f"case file {path}: not a Python module")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    if not callable(getattr(module, "loops", None)):
        raise ValueError(f"case file {path}: defines no loops() function")
    return Case(getattr(module, "NAME", path.stem), tuple(module.loops()),
                getattr(module, "TITLE", ""), dict(getattr(module, "METADATA", {})), str(path))


def load_case(path: str | Path) -> Case:
    """One case file (``.json``, ``.poly`` or ``.py``); ValueError names the file."""
    path = Path(path)
    if path.suffix == ".json":
        return _from_json(path)
    if path.suffix == ".poly":
        return Case.from_poly(path)
    if path.suffix == ".py":
        return _from_python(path)
    raise ValueError(f"case file {path}: expected one of {', '.join(CASE_SUFFIXES)}")


def _natural(name: str) -> list:
    # fig10 after fig9, not after fig1
    return [(0, int(p), "") if p.isdigit() else (1, 0, p) for p in re.split(r"(\d+)", name)]


def load_cases(folder: str | Path) -> dict[str, Case]:
    """Every case file in ``folder`` (not recursive; names starting with '_' skipped, JSON
    files without ``loops``/``poly`` skipped), by name in natural order ("fig10" after "fig9")."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"cases folder {folder} does not exist")
    found: dict[str, Case] = {}
    for path in sorted(folder.iterdir()):
        if path.suffix not in CASE_SUFFIXES or path.name.startswith("_"):
            continue
        if path.suffix == ".json" and not _is_case_json(path):
            continue
        case = load_case(path)
        if case.name in found:
            raise ValueError(f"cases folder {folder}: two cases are named {case.name!r}")
        found[case.name] = case
    return dict(sorted(found.items(), key=lambda item: _natural(item[0])))


def _is_case_json(path: Path) -> bool:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return True  # load_case reports it
    return isinstance(data, dict) and ("loops" in data or "poly" in data)


def bundled_folder() -> Path:
    """The folder of case files and study definitions shipped with the package (the
    repository's ``cases/``, installed as ``bubblemesh.studies.data``; read in place when
    the source tree runs uninstalled)."""
    try:
        data = importlib.import_module("bubblemesh.studies.data")
    except ImportError:
        return Path(__file__).resolve().parents[2] / "cases"
    return Path(str(data.__file__)).parent


def paper_cases() -> dict[str, Case]:
    """The paper's Figs. 3-6 (shipped as JSON with the package)."""
    return load_cases(bundled_folder())
