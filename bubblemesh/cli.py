"""The ``bubblemesh`` command.

``bubblemesh mesh`` runs the paper's two stages on a ``.poly`` boundary:
Delaunay generation with node and element bubbles (§2) and the
physically-based optimisation (§3), then reports the radius ratio of eq. 10.
``bubblemesh reproduce`` rebuilds the paper's Figs. 3-6 and the comparison
with other meshers, ``bubblemesh bench`` times them; both live in the
repository's ``cases`` package, imported only when asked for.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from bubblemesh.errors import GeometryError, MeshingError

__all__ = ["main"]


class CommandError(Exception):
    """Something the command needs is missing (an optional package, the cases)."""


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.run(args)
    except (GeometryError, MeshingError, CommandError, OSError) as error:
        print(f"bubblemesh {args.command}: error: {error}", file=sys.stderr)
        return 1


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bubblemesh",
        description="Delaunay meshing with node/element bubbles and bubble-force optimisation.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    mesh = commands.add_parser("mesh", help="mesh a Triangle .poly boundary")
    mesh.add_argument("input", type=Path, metavar="INPUT", help="boundary as a .poly file")
    mesh.add_argument(
        "-o", "--output", type=Path, required=True, metavar="OUT",
        help="mesh file; the suffix picks the format (.vtu, .msh, .xdmf, ...)",
    )  # fmt: skip
    mesh.add_argument("--no-optimize", action="store_true", help="stop after generation (paper §2)")
    mesh.add_argument("--plot", type=Path, metavar="PNG", help="also draw the mesh to PNG")
    mesh.add_argument(
        "--max-insertions", type=int, metavar="K", help="stop generation after K node insertions"
    )
    mesh.set_defaults(run=_run_mesh)

    reproduce = commands.add_parser("reproduce", help="rebuild the paper's cases and the report")
    reproduce.add_argument(
        "--case", action="append", dest="cases", metavar="NAME",
        help="only this case (repeatable); default all",
    )  # fmt: skip
    reproduce.add_argument("--out", type=Path, default=Path("reports"), help="report folder")
    reproduce.set_defaults(run=_run_reproduce)

    bench = commands.add_parser("bench", help="time bubblemesh against the peer meshers")
    bench.add_argument("--max-elements", type=int, metavar="N", help="largest mesh size")
    bench.add_argument("--repeats", type=int, metavar="R", help="timings per size")
    bench.add_argument("--quick", action="store_true", help="a short run (smoke test)")
    bench.add_argument("--out", type=Path, default=Path("reports"), help="report folder")
    bench.set_defaults(run=_run_bench)
    return parser


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("bubblemesh")
    except PackageNotFoundError:
        return "(not installed)"


def _run_mesh(args: argparse.Namespace) -> int:
    from bubblemesh.domain import Domain

    domain = Domain.from_poly(args.input)
    try:
        from bubblemesh import generate, optimize
        from bubblemesh.quality import summary
    except ImportError as error:
        raise CommandError(f"the meshing kernel is not available: {error}") from None

    mesh = generate(domain, max_insertions=args.max_insertions)
    if not args.no_optimize:
        mesh = optimize(mesh)
    mesh.write(args.output)
    print(f"nodes: {len(mesh.points)} ({mesh.n_boundary} on the boundary)")
    print(f"elements: {len(mesh.triangles)}")
    print(_summary_line(summary(mesh.points, mesh.triangles)))
    print(f"wrote {args.output}")
    if args.plot is not None:
        _plot(mesh.points, mesh.triangles, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _summary_line(stats: dict) -> str:
    """One line of the radius-ratio summary (eq. 10)."""
    return (
        f"radius ratio: min {stats['min']:.3f}, mean {stats['mean']:.3f}, "
        f"median {stats['median']:.3f}; "
        f"below 0.5: {stats['count_below_0_5']} ({100 * stats['frac_below_0_5']:.1f}%), "
        f"below 0.7: {stats['count_below_0_7']} ({100 * stats['frac_below_0_7']:.1f}%); "
        f"angles {stats['min_angle_deg']:.1f}-{stats['max_angle_deg']:.1f} deg"
    )


def _plot(points, triangles, path: Path) -> None:
    try:
        import matplotlib
    except ImportError:
        raise CommandError("--plot needs matplotlib: pip install 'bubblemesh[plot]'") from None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 6))
    axes.triplot(points[:, 0], points[:, 1], triangles, linewidth=0.4, color="0.2")
    axes.set_aspect("equal")
    axes.set_axis_off()
    figure.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(figure)


def _import_cases_module(name: str):
    import importlib

    try:
        return importlib.import_module(f"cases.{name}")
    except ModuleNotFoundError as error:
        if error.name not in ("cases", f"cases.{name}"):
            raise
        raise CommandError(
            f"'bubblemesh {name}' needs the repository's cases package (cases/{name}.py): "
            "run it from a checkout installed with pip install -e ."
        ) from None


def _exit_status(result) -> int:
    return result if isinstance(result, int) else 0


def _run_reproduce(args: argparse.Namespace) -> int:
    reproduce = _import_cases_module("reproduce")
    return _exit_status(reproduce.main(cases=args.cases, out=args.out))


def _run_bench(args: argparse.Namespace) -> int:
    benchmark = _import_cases_module("benchmark")
    options = {"quick": args.quick, "out": args.out}
    if args.max_elements is not None:
        options["max_elements"] = args.max_elements
    if args.repeats is not None:
        options["repeats"] = args.repeats
    return _exit_status(benchmark.main(**options))


if __name__ == "__main__":
    sys.exit(main())
