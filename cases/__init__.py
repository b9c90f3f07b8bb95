"""Case studies reproducing the paper's Figs. 3–6, and the peers they are set against.

A case is one module in this package defining ``NAME``, ``TITLE`` and
``loops()`` (the list of boundary-node arrays, outer loop first).  Cases are
discovered automatically: to add one, copy ``fig3_circle.py`` to a new file and
edit it.  ``ALL`` maps case name to module, sorted by name.
"""

from __future__ import annotations

import importlib
import pkgutil
from types import ModuleType

# Infrastructure modules of this package: never cases, and not imported here
# (some of them pull in matplotlib, gmsh, pymeshlab ...).
_NOT_CASES = {
    "geometry",
    "peers",
    "plots",
    "report",
    "reproduce",
    "benchmark",
    "__main__",
}


def _discover() -> dict[str, ModuleType]:
    found: dict[str, ModuleType] = {}
    for info in pkgutil.iter_modules(__path__):
        if info.name in _NOT_CASES or info.name.startswith("_") or info.ispkg:
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        if callable(getattr(mod, "loops", None)) and isinstance(getattr(mod, "NAME", None), str):
            if mod.NAME in found:
                raise ValueError(f"two case modules use NAME {mod.NAME!r}")
            found[mod.NAME] = mod
    return dict(sorted(found.items(), key=lambda kv: _natural(kv[0])))


def _natural(name: str) -> list:
    # fig10 after fig9, not after fig1
    import re

    return [int(p) if p.isdigit() else p for p in re.split(r"(\d+)", name)]


ALL: dict[str, ModuleType] = _discover()


def get(name: str) -> ModuleType:
    """The case module called ``name`` (KeyError listing the known names)."""
    try:
        return ALL[name]
    except KeyError:
        raise KeyError(f"unknown case {name!r}; known: {', '.join(ALL)}") from None
