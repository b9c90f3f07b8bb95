"""The ``bubblemesh`` command.

``bubblemesh mesh`` meshes a ``.poly`` boundary with the robust mesher
(:func:`bubblemesh.mesh`: a size field from ``--size`` / ``--max-area`` and
the boundary, §2 and a stable §3), or with ``--paper`` the paper's two stages
as published: Delaunay generation with node and element bubbles (§2) and the
physically-based optimisation (§3); ``--no-optimize`` and ``--max-insertions``
are paper-stage options and imply ``--paper``.  It reports the radius ratio
of eq. 10.
It also reports the boundary markers it wrote.  ``bubblemesh info`` prints the
counts, regions, markers and radius-ratio summary of any mesh file.
``bubblemesh reproduce`` rebuilds the paper's Figs. 3-6 and the comparison
with other meshers, ``bubblemesh study`` runs any study definition (both on
dask), ``bubblemesh bench`` times them; they live in ``bubblemesh.studies``,
imported only when asked for.

The first run after an install compiles the numba kernels (a minute or two)
and says so in one line on stderr; ``mesh --progress`` shows progress bars.
Every error is reported as one line on stderr, ``bubblemesh COMMAND: error:
...``, and the exit status says which kind it was (``EXIT_STATUS`` below, also
in ``--help``).  The output paths of ``mesh`` are checked before meshing
starts, so a bad ``-o`` or ``--plot`` fails at once.  With ``--debug`` an
unexpected exception (a bug) shows its traceback instead of one line.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from bubblemesh.compiling import compile_notice
from bubblemesh.errors import MeshingError

__all__ = ["EXIT_STATUS", "main"]

EXIT_STATUS = """\
exit status:
  0    success
  1    meshing failed (MeshingError), a file could not be written, a package
       the command needs is missing, or an unexpected error (a bug)
  2    usage or bad input: unknown options or values, an input file that is
       not a valid .poly boundary, an output path whose format or folder will
       not do, an unknown case
  130  interrupted"""


DEBUG_HELP = "show the traceback of an unexpected error (a bug) instead of one line"


class CommandError(Exception):
    """Something the command needs is missing (an optional package, the cases)."""

    status = 1


class UsageError(CommandError):
    """An option value the command cannot use (reported with exit status 2)."""

    status = 2


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line: no usage block before them."""

    def error(self, message: str, prog: str | None = None) -> NoReturn:
        prog = prog or self.prog
        self.exit(2, f"{prog}: error: {_one_line(message)} (see {prog} --help)\n")

    def parse_args(self, args=None, namespace=None):
        """As argparse, but an unknown option is blamed on the command it was given to."""
        parsed, extra = self.parse_known_args(args, namespace)
        if extra:
            command = getattr(parsed, "command", None)
            prog = f"{self.prog} {command}" if command else self.prog
            self.error(f"unrecognized arguments: {' '.join(extra)}", prog)
        return parsed


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (see ``EXIT_STATUS``)."""
    try:
        args = _parser().parse_args(argv)
    except SystemExit as done:  # --help, --version, or a usage error already reported
        return done.code if isinstance(done.code, int) else int(done.code is not None)
    prefix = f"bubblemesh {args.command}"
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning(prefix)
        try:
            status = args.run(args)
            sys.stdout.flush()  # a reader that left shows here, not at exit
            return status
        except KeyboardInterrupt:
            _report(prefix, "interrupted")
            return 130
        except BrokenPipeError:  # the reader of stdout left (`| head`): stop quietly
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 1
        except Exception as error:
            status = _status(error)
            if status is None and args.debug:
                raise
            name, message = type(error).__name__, _one_line(str(error))
            if status is None:
                status = 1
                said = f": {message}" if message else ""
                message = f"unexpected {name}{said} (--debug shows where)"
            _report(prefix, message or name)
            return status


def _status(error: Exception) -> int | None:
    """The exit status of an expected error; None for an unexpected one."""
    if isinstance(error, CommandError):
        return error.status
    if isinstance(error, ValueError):  # GeometryError, MeshFileError, parameter checks
        return 2
    if isinstance(error, (MeshingError, OSError, ImportError)):
        return 1
    return None


def _report(prefix: str, message: str) -> None:
    print(f"{prefix}: error: {message}", file=sys.stderr)


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in text.splitlines() if part.strip())


def _one_line_warning(prefix: str):
    def show(message, category, filename, lineno, file=None, line=None):
        where = f"{Path(filename).name}:{lineno}"
        text = _one_line(str(message))
        print(f"{prefix}: warning: {text} ({category.__name__}, {where})", file=sys.stderr)

    return show


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bubblemesh",
        description="Delaunay meshing with node/element bubbles and bubble-force optimisation.",
        epilog=EXIT_STATUS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    # on the commands too; SUPPRESS keeps a top-level --debug from being reset to False
    debug = _Parser(add_help=False)
    debug.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    def command(name: str, help: str) -> argparse.ArgumentParser:
        return commands.add_parser(
            name,
            help=help,
            parents=[debug],
            epilog=EXIT_STATUS,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )

    mesh = command("mesh", "mesh a Triangle .poly boundary")
    mesh.add_argument("input", type=Path, metavar="INPUT", help="boundary as a .poly file")
    mesh.add_argument(
        "-o", "--output", type=Path, required=True, metavar="OUT",
        help="mesh file; the suffix picks the format (.vtu, .msh, .xdmf, ...; meshio's)",
    )  # fmt: skip
    mesh.add_argument("--size", type=_positive, metavar="H", help="element size (edge length)")
    mesh.add_argument("--max-area", type=_positive, metavar="A", help="largest element area")
    mesh.add_argument(
        "--paper", action="store_true", help="the paper's §2 + §3 as published (no size control)"
    )
    mesh.add_argument("--no-optimize", action="store_true", help="stop after generation (paper §2)")
    mesh.add_argument("--plot", type=Path, metavar="PNG", help="also draw the mesh (.png, .pdf)")
    mesh.add_argument(
        "--max-insertions", type=_whole(0), metavar="K", help="stop generation after K insertions"
    )
    mesh.add_argument("--progress", action="store_true", help="show progress bars on stderr")
    mesh.set_defaults(run=_run_mesh)

    reproduce = command("reproduce", "rebuild the paper's cases and the report")
    reproduce.add_argument(
        "--case", action="append", dest="cases", metavar="NAME",
        help="only this case (repeatable); default all",
    )  # fmt: skip
    reproduce.add_argument(
        "--cases-dir", type=Path, metavar="DIR",
        help="folder of case files (.json, .poly, .py); default the paper's four",
    )  # fmt: skip
    _study_options(reproduce, Path("reports"))
    reproduce.set_defaults(run=_run_reproduce)

    study = command("study", "run a study (cases x methods x parameters) and write its report")
    study.add_argument(
        "definition", metavar="DEFINITION",
        help="study definition (.toml or .json), or the name of a shipped one "
             "(paper, iterations)",
    )  # fmt: skip
    study.add_argument("--case", action="append", dest="cases", metavar="NAME",
                       help="only this case (repeatable)")
    study.add_argument("--cases-dir", type=Path, metavar="DIR",
                       help="folder of case files (default: the definition's)")
    _study_options(study, None)
    study.set_defaults(run=_run_study)

    bench = command("bench", "time bubblemesh against the peer meshers")
    bench.add_argument("--max-elements", type=_whole(1), metavar="N", help="largest mesh size")
    bench.add_argument("--repeats", type=_whole(1), metavar="R", help="timings per size")
    bench.add_argument("--quick", action="store_true", help="a short run (smoke test)")
    bench.add_argument("--out", type=Path, default=Path("reports"), help="report folder")
    bench.set_defaults(run=_run_bench)
    info = command("info", "counts, regions, markers and quality of any mesh file")
    info.add_argument("input", type=Path, metavar="MESHFILE", help="any meshio triangle mesh")
    info.set_defaults(run=_run_info)
    from bubblemesh.verify.check import CHECK_DESCRIPTION, add_check_arguments

    check = command("check", "check any mesh file exactly (exit 1 when something is wrong)")
    check.description = CHECK_DESCRIPTION
    add_check_arguments(check)
    check.set_defaults(run=_run_check)
    parser.set_defaults(debug=False)
    return parser


def _whole(least: int):
    """An argparse type: a whole number >= ``least``."""

    def convert(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = least - 1
        if value < least:
            raise argparse.ArgumentTypeError(f"expected a whole number >= {least}, got {text!r}")
        return value

    return convert


def _positive(text: str) -> float:
    """An argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (value > 0 and value != float("inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("bubblemesh")
    except PackageNotFoundError:
        return "(not installed)"


def _run_mesh(args: argparse.Namespace) -> int:
    from bubblemesh import generate, optimize
    from bubblemesh import mesh as robust
    from bubblemesh.domain import Domain
    from bubblemesh.io import check_mesh_path
    from bubblemesh.quality import summary

    domain = Domain.from_poly(args.input)
    check_mesh_path(args.output)  # a bad -o or --plot fails now, not after the meshing
    if args.plot is not None:
        _check_plot_path(args.plot)
    paper = args.paper or args.no_optimize or args.max_insertions is not None
    if paper and (args.size is not None or args.max_area is not None):
        raise UsageError("--size and --max-area apply to the robust mesher, not with --paper, "
                         "--no-optimize or --max-insertions")
    with compile_notice():  # the studies' commands say it their own way
        if paper:
            mesh = generate(domain, max_insertions=args.max_insertions, progress=args.progress)
            if not args.no_optimize:
                mesh = optimize(mesh, progress=args.progress)
        else:
            mesh = robust(domain, size=args.size, max_area=args.max_area,
                          progress=args.progress)
    mesh.write(args.output)
    print(f"nodes: {len(mesh.points)} ({mesh.n_boundary} on the boundary)")
    print(f"elements: {len(mesh.triangles)}")
    print(_summary_line(summary(mesh.points, mesh.triangles)))
    print(_markers_line(mesh))
    print(f"wrote {args.output}")
    if args.plot is not None:
        _plot(mesh.points, mesh.triangles, args.plot)
        print(f"wrote {args.plot}")
    return 0


def _markers_line(mesh) -> str:
    """The markers written: edges per marker, with names."""
    import numpy as np

    _, marks = mesh.boundary_edges()
    names = {marker: name for name, marker in mesh.marker_names.items()}
    values, counts = np.unique(marks, return_counts=True)
    parts = [f"{int(v)}{f' ({names[int(v)]})' if int(v) in names else ''}: {int(c)} edges"
             for v, c in zip(values, counts)]
    return "markers: " + (", ".join(parts) if parts else "none")


def _run_info(args: argparse.Namespace) -> int:
    import numpy as np

    from bubblemesh._mesh import read
    from bubblemesh.quality import summary

    try:
        mesh = read(args.input)
    except BrokenPipeError:
        raise
    except (OSError, ValueError) as error:
        raise UsageError(f"cannot read the input: {error}") from None
    print(f"nodes: {len(mesh.points)} ({mesh.n_boundary} on the boundary)")
    print(f"elements: {len(mesh.triangles)}")
    regions, counts = np.unique(mesh.region_ids(), return_counts=True)
    print("regions: " + ", ".join(f"{int(r) + 1}: {int(c)} triangles"
                                  for r, c in zip(regions, counts)))
    print(_markers_line(mesh))
    print(_summary_line(summary(mesh.points, mesh.triangles)))
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


def _check_plot_path(path: Path) -> None:
    """matplotlib present, a suffix it writes, an existing folder."""
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError:
        raise CommandError("--plot needs matplotlib: pip install 'bubblemesh[plot]'") from None
    if path.is_dir():
        raise UsageError(f"--plot {path} is a folder, not a file name")
    if not path.parent.is_dir():
        raise UsageError(f"--plot {path}: the folder {path.parent} does not exist")
    formats = FigureCanvasBase.get_supported_filetypes()
    if path.suffix.lower().lstrip(".") not in formats:
        raise UsageError(
            f"--plot {path}: matplotlib writes only {', '.join('.' + s for s in formats)} files"
        )


def _plot(points, triangles, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(figsize=(6, 6))
    axes.triplot(points[:, 0], points[:, 1], triangles, linewidth=0.4, color="0.2")
    axes.set_aspect("equal")
    axes.set_axis_off()
    figure.savefig(path, dpi=150, bbox_inches="tight")
    plt.close(figure)


def _study_options(parser: argparse.ArgumentParser, out: Path | None) -> None:
    """The options of the commands that run a study on dask."""
    parser.add_argument(
        "--scheduler", metavar="ADDRESS",
        help="dask scheduler, e.g. tcp://HOST:PORT (default: $BUBBLEMESH_SCHEDULER, else a "
             "local cluster of 2 worker processes); 'inline' runs in this process",
    )  # fmt: skip
    parser.add_argument(
        "--out", type=Path, default=out, metavar="DIR",
        help="results and report folder" + (f" (default {out}/)" if out else
                                             " (default studies/NAME/)"),
    )  # fmt: skip
    parser.add_argument("--retry-failed", action="store_true",
                        help="compute failed and skipped cells again")


def _import_cases_module(name: str):
    """``bubblemesh.studies.<name>``; a missing optional package is a one-line error."""
    import importlib

    try:
        return importlib.import_module(f"bubblemesh.studies.{name}")
    except ModuleNotFoundError as error:
        if error.name is None or error.name.startswith("bubblemesh"):
            raise
        raise CommandError(
            f"'bubblemesh {name}' needs {error.name}: pip install 'bubblemesh[studies]'"
        ) from None


def _exit_status(result) -> int:
    return result if isinstance(result, int) else 0


def _run_check(args: argparse.Namespace) -> int:
    from bubblemesh.verify.check import run_check

    try:
        return run_check(args)
    except BrokenPipeError:
        raise
    except (OSError, ValueError, TypeError) as error:
        raise UsageError(f"cannot read the input: {error}") from None


def _check_scheduler(address: str | None) -> None:
    if address not in (None, "inline") and "://" not in str(address):
        raise UsageError(f"--scheduler {address!r}: expected tcp://HOST:PORT or 'inline'")


def _run_reproduce(args: argparse.Namespace) -> int:
    _check_scheduler(args.scheduler)
    reproduce = _import_cases_module("reproduce")
    reproduce.paper_study(args.cases, args.cases_dir)  # unknown case or folder: fail now
    if args.scheduler != "inline":
        _needs("distributed", "reproduce")
    _needs("matplotlib", "reproduce")
    return _exit_status(reproduce.main(cases=args.cases, out=args.out, cases_dir=args.cases_dir,
                                       scheduler=args.scheduler,
                                       retry_failed=args.retry_failed))


def _needs(module: str, command: str) -> None:
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        raise CommandError(f"'bubblemesh {command}' needs {module}: "
                           "pip install 'bubblemesh[studies]'") from None


def _run_study(args: argparse.Namespace) -> int:
    _check_scheduler(args.scheduler)
    studies = _import_cases_module("study")
    study = studies.load_study(args.definition, cases_dir=args.cases_dir,
                               only_cases=args.cases)
    if args.scheduler != "inline":
        _needs("distributed", "study")
    _needs("matplotlib", "study")
    out = args.out if args.out is not None else Path("studies") / study.name
    run = _import_cases_module("engine").run_study(study, out, scheduler=args.scheduler,
                                                   retry_failed=args.retry_failed)
    given = "".join(f" --case {n}" for n in args.cases or ())
    where = f" --cases-dir {args.cases_dir}" if args.cases_dir is not None else ""
    command = f"bubblemesh study {args.definition}{given}{where} --out {out}/"
    _import_cases_module("report").render(study, run.table, out, run, command)
    failed = int((run.table["status"] != "ok").sum())
    print(f"{study.name}: {len(run.table)} cells, {run.computed} computed, {run.reused} reused"
          + (f", {failed} not ok" if failed else "") + f"; report {out / 'README.md'}")
    return 0


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
