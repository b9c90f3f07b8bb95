"""The result of a check: violations with their location, and the facts measured."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

# every kind a checker may report, with the one-line meaning the summary prints
KINDS = {
    "bad_index": "a triangle names a node that does not exist",
    "empty": "no triangles",
    "repeated_vertex": "a triangle uses one node twice",
    "degenerate": "a triangle has zero area (collinear vertices)",
    "orientation": "a triangle is clockwise",
    "duplicate_triangle": "two triangles have the same three nodes",
    "non_manifold_edge": "an edge used by more than two triangles, or twice in one direction",
    "non_manifold_vertex": "the mesh boundary touches itself at a node",
    "neighbors": "the neighbour array disagrees with the triangles",
    "euler": "V - E + F differs from (components - holes) of the domain",
    "unused_node": "a node used by no triangle",
    "duplicate_node": "two nodes at the same position",
    "boundary_moved": "an input boundary node is not a mesh node (moved or missing)",
    "missing_segment": "an input segment is neither a mesh edge nor a chain of mesh edges",
    "split_segment": "an input segment is a chain of mesh edges, not one edge",
    "interior_segment": "a segment (piece) has triangles on both sides",
    "one_sided_constraint": "an interior constraint (piece) has triangles on one side only",
    "segment_orientation": "a segment has the mesh on its right (domain must be on the left)",
    "extra_boundary_edge": "a mesh boundary edge that is no segment (a gap or a missing triangle)",
    "outside_domain": "a triangle's centroid lies outside the domain, in a hole or on a loop",
    "area": "the triangle areas do not sum to the domain area",
    "vertex_in_triangle": "a node lies in a triangle it is not a vertex of (overlap)",
    "not_delaunay": "a node strictly inside a triangle's circumcircle and visible from it",
    "population": "eq. 6 fails: sum of element bubble areas < domain area",
}


@dataclass(frozen=True)
class Violation:
    """One failed property: ``kind`` (a key of ``KINDS``), where, and why."""

    kind: str
    message: str
    triangle: int | None = None
    edge: tuple[int, int] | None = None
    node: int | None = None
    segment: int | None = None

    def as_row(self) -> dict[str, Any]:
        u, v = self.edge if self.edge is not None else (None, None)
        return dict(kind=self.kind, triangle=self.triangle, edge_u=u, edge_v=v,
                    node=self.node, segment=self.segment, message=self.message)


@dataclass
class Report:
    """Violations found, segment splits, measured facts and the quality summary.

    ``limit`` caps the violations kept per kind; ``omitted[kind]`` counts the
    ones dropped beyond it (they still make ``ok`` false).
    """

    violations: list[Violation] = field(default_factory=list)
    splits: dict[int, tuple[int, ...]] = field(default_factory=dict)
    facts: dict[str, Any] = field(default_factory=dict)
    quality: dict[str, Any] = field(default_factory=dict)
    checks: dict[str, str] = field(default_factory=dict)
    omitted: dict[str, int] = field(default_factory=dict)
    limit: int = 1000
    _kept: dict[str, int] = field(default_factory=dict, repr=False)

    @property
    def ok(self) -> bool:
        return not self.violations and not self.omitted

    def add(self, kind: str, message: str, **where: Any) -> None:
        if kind not in KINDS:
            raise ValueError(f"unknown violation kind {kind!r}")
        kept = self._kept.get(kind, 0)
        if kept >= self.limit:
            self.omitted[kind] = self.omitted.get(kind, 0) + 1
            return
        self._kept[kind] = kept + 1
        self.violations.append(Violation(kind, message, **where))

    def full(self, kind: str) -> bool:
        """True once ``limit`` violations of this kind are kept (callers may stop)."""
        return self._kept.get(kind, 0) >= self.limit

    def count(self, kind: str) -> int:
        """Violations of this kind, including the omitted ones."""
        return self._kept.get(kind, 0) + self.omitted.get(kind, 0)

    def of_kind(self, kind: str) -> list[Violation]:
        return [v for v in self.violations if v.kind == kind]

    def to_frame(self):
        """A pandas DataFrame, one row per violation kept."""
        import pandas as pd

        columns = ["kind", "triangle", "edge_u", "edge_v", "node", "segment", "message"]
        frame = pd.DataFrame([v.as_row() for v in self.violations], columns=columns)
        for name in ("triangle", "edge_u", "edge_v", "node", "segment"):
            frame[name] = frame[name].astype("Int64")
        return frame

    def summary(self, examples: int = 3) -> str:
        """One screen of text: verdict, checks run, counts per kind, quality."""
        lines = [f"mesh check: {'OK' if self.ok else 'VIOLATIONS FOUND'}"]
        facts = ", ".join(f"{k} {v:.10g}" if isinstance(v, float) else f"{k} {v}"
                          for k, v in self.facts.items())
        if facts:
            lines.append(f"  {facts}")
        for name, state in self.checks.items():
            lines.append(f"  {name:<13} {state}")
        if self.splits:
            n = sum(len(c) - 1 for c in self.splits.values())
            lines.append(f"  {len(self.splits)} input segments split into {n} mesh edges")
        for kind in dict.fromkeys(v.kind for v in self.violations) | dict.fromkeys(self.omitted):
            lines.append(f"  {kind}: {self.count(kind)} ({KINDS[kind]})")
            for v in self.of_kind(kind)[:examples]:
                lines.append(f"    - {v.message}")
        if self.quality:
            q = self.quality
            lines.append(
                "  quality: 2r/R min {min_radius_ratio:.4f} mean {mean_radius_ratio:.4f}; "
                "angles {min_angle:.2f}..{max_angle:.2f} deg; ".format(**q)
                + f"{q['below_0.5']} below 0.5, {q['below_0.7']} below 0.7"
            )
        return "\n".join(lines)

    def raise_if_failed(self, title: str = "mesh check failed", kinds=None) -> None:
        """AssertionError listing the violations (of ``kinds`` if given)."""
        found = [v for v in self.violations if kinds is None or v.kind in kinds]
        extra = sum(n for k, n in self.omitted.items() if kinds is None or k in kinds)
        if found or extra:
            shown = "\n  ".join(v.message for v in found[:5])
            more = len(found) - 5 + extra
            tail = f"\n  ... and {more} more" if more > 0 else ""
            raise AssertionError(f"{title}:\n  {shown}{tail}")
