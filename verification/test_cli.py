"""The ``bubblemesh`` command line: mesh a .poly, hand reproduce/bench to the cases package."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from bubblemesh.cli import EXIT_STATUS, main
from bubblemesh.compiling import NOTICE
from bubblemesh.domain import Domain
from bubblemesh.errors import MeshingError

SQUARE_WITH_HOLE = [
    [(0.0, 0.0), (0.25, 0.0), (0.5, 0.0), (0.75, 0.0), (1.0, 0.0), (1.0, 0.5),
     (1.0, 1.0), (0.5, 1.0), (0.0, 1.0), (0.0, 0.5)],
    [(0.4, 0.4), (0.4, 0.6), (0.6, 0.6), (0.6, 0.4)],
]  # fmt: skip


@pytest.fixture
def poly(tmp_path) -> Path:
    path = tmp_path / "square.poly"
    Domain.from_loops(SQUARE_WITH_HOLE).to_poly(path)
    return path


@pytest.mark.parametrize("options", [[], ["--paper"], ["--no-optimize"]])
def test_mesh_writes_the_mesh_and_reports_it(poly, tmp_path, capsys, options):
    meshio = pytest.importorskip("meshio")
    out = tmp_path / "square.vtu"
    assert main(["mesh", str(poly), "-o", str(out), *options]) == 0
    printed = capsys.readouterr().out
    mesh = meshio.read(out)
    triangles = mesh.cells_dict["triangle"]
    n_b = int(re.search(r"nodes: \d+ \((\d+) on the boundary\)", printed).group(1))
    assert f"nodes: {len(mesh.points)} ({n_b} on the boundary)" in printed
    assert f"elements: {len(triangles)}" in printed
    line = re.search(r"radius ratio: min (\S+), mean (\S+), median (\S+);", printed)
    assert line, printed
    low, mean, median = (float(v) for v in line.groups())
    assert 0 < low <= mean <= 1 and 0 < median <= 1
    inputs = np.vstack(SQUARE_WITH_HOLE)
    if options:  # paper mode: the input nodes are the boundary, first and unmoved
        assert n_b == 14
        np.testing.assert_array_equal(mesh.points[:14, :2], inputs)
    else:  # the default refines the boundary: every input node is still a boundary node
        boundary = {tuple(p) for p in mesh.points[:n_b, :2].tolist()}
        assert n_b >= 14 and {tuple(p) for p in inputs.tolist()} <= boundary
        assert low > 0.5, "the default mesher left an element below 0.5"
    # the mesh covers the domain: triangle areas add up to A_geo = 1 - 0.04
    p = mesh.points[:, :2]
    a, b, c = p[triangles[:, 0]], p[triangles[:, 1]], p[triangles[:, 2]]
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (cross > 0).all()
    assert 0.5 * cross.sum() == pytest.approx(0.96, rel=1e-12)


def test_mesh_max_insertions_and_plot(poly, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    png = tmp_path / "square.png"
    out = tmp_path / "square.msh"
    args = ["mesh", str(poly), "-o", str(out), "--no-optimize", "--max-insertions", "3"]
    assert main([*args, "--plot", str(png)]) == 0
    printed = capsys.readouterr().out
    assert "nodes: 17 (14 on the boundary)" in printed
    assert png.read_bytes().startswith(b"\x89PNG")


def error_line(capsys, command: str = "mesh") -> str:
    """The one line on stderr, which must read 'bubblemesh COMMAND: error: ...'."""
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and err.endswith("\n"), err
    assert err.startswith(f"bubblemesh {command}: error: "), err
    return err


@pytest.fixture
def meshing(monkeypatch) -> list:
    """Records calls of bubblemesh.generate (which then fails the test if it was not meant
    to run: a bad option must be caught before the meshing)."""
    import bubblemesh

    calls: list = []
    for name in ("generate", "mesh"):  # the --paper stages and the default mesher
        monkeypatch.setattr(bubblemesh, name, lambda *a, **k: calls.append(a) or 1 / 0)
    return calls


def test_mesh_reports_geometry_errors_on_one_line(tmp_path, capsys):
    path = tmp_path / "bow.poly"
    path.write_text("4 2 0 0\n1 0 0\n2 1 1\n3 1 0\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n")
    assert main(["mesh", str(path), "-o", str(tmp_path / "x.vtu")]) == 2
    assert "loop 0 (outer) segment 2 crosses loop 0 (outer) segment 0" in error_line(capsys)


def test_mesh_missing_input_file(tmp_path, capsys, meshing):
    assert main(["mesh", str(tmp_path / "none.poly"), "-o", str(tmp_path / "x.vtu")]) == 2
    assert f"cannot read {tmp_path / 'none.poly'}" in error_line(capsys)
    assert meshing == []


@pytest.mark.parametrize(
    ("text", "line", "words"),
    [
        ("1000000000000 2 0 0\n", 1, "1000000000000 vertices"),
        ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n-3 0\n", 5, "negative"),
        ("3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n1 0\n1 1 99999999999999999999999\n", 6, "out of range"),
        ("# caf\xe9\n0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n", 2, "bad.node"),
    ],
)  # fmt: skip
def test_mesh_reports_poly_errors_with_file_and_line(tmp_path, capsys, meshing, text, line, words):
    path = tmp_path / "bad.poly"
    path.write_bytes(text.encode("latin-1"))
    assert main(["mesh", str(path), "-o", str(tmp_path / "x.vtu")]) == 2
    message = error_line(capsys)
    assert f"{path} line {line}: " in message and words in message
    assert meshing == []


@pytest.mark.parametrize(
    ("output", "words"),
    [
        ("out.xyz", "cannot tell the mesh format from the suffix '.xyz'"),
        ("out", "cannot tell the mesh format"),
        (".", "is a folder"),
        ("nodir/x.vtu", "nodir does not exist"),
        ("x.node", "no triangles"),
    ],
)
def test_bad_output_fails_before_meshing(poly, tmp_path, capsys, meshing, output, words):
    before = sorted(tmp_path.iterdir())
    assert main(["mesh", str(poly), "-o", str(tmp_path / output)]) == 2
    assert words in error_line(capsys)
    assert meshing == [] and sorted(tmp_path.iterdir()) == before


@pytest.mark.parametrize(
    ("plot", "words"),
    [("nodir/x.png", "nodir does not exist"), ("x.foo", "matplotlib writes only"), (".", "folder")],
)
def test_bad_plot_path_fails_before_meshing(poly, tmp_path, capsys, meshing, plot, words):
    pytest.importorskip("matplotlib")
    out = tmp_path / "x.vtu"
    assert main(["mesh", str(poly), "-o", str(out), "--plot", str(tmp_path / plot)]) == 2
    assert words in error_line(capsys)
    assert meshing == [] and not out.exists()


@pytest.mark.parametrize(
    ("argv", "command", "words"),
    [
        (["mesh", "p.poly", "-o", "x.vtu", "--max-insertions", "-1"], "mesh", "--max-insertions"),
        (["mesh", "p.poly", "-o", "x.vtu", "--max-insertions", "2.5"], "mesh", "'2.5'"),
        (["mesh", "p.poly"], "mesh", "-o/--output"),
        (["mesh", "p.poly", "-o", "x.vtu", "--frobnicate"], "mesh", "--frobnicate"),
        (["bench", "--repeats", "0"], "bench", "--repeats"),
        (["nosuchcommand"], "", "nosuchcommand"),
        ([], "", "COMMAND"),
    ],
)  # fmt: skip
def test_usage_errors_are_one_line_with_status_2(capsys, meshing, argv, command, words):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"bubblemesh {command}: error: ".replace(" :", ":")), err
    assert words in err
    assert meshing == []


def failing_generate(monkeypatch, error: BaseException) -> None:
    import bubblemesh

    def generate(*args, **kwargs):
        raise error

    monkeypatch.setattr(bubblemesh, "generate", generate)  # --paper
    monkeypatch.setattr(bubblemesh, "mesh", generate)  # the default mesher


@pytest.mark.parametrize(
    ("error", "status", "words"),
    [
        (MeshingError("bound hit\nat insertion 7"), 1, "bound hit at insertion 7"),
        (ValueError("max_insertions must be >= 0"), 2, "max_insertions must be >= 0"),
        (OSError(28, "No space left on device"), 1, "No space left on device"),
        (ZeroDivisionError("division by zero"), 1, "unexpected ZeroDivisionError: division by"),
        (KeyError(), 1, "error: unexpected KeyError (--debug shows where)"),
        (MeshingError(), 1, "error: MeshingError"),
        (KeyboardInterrupt(), 130, "interrupted"),
    ],
)
def test_errors_while_meshing_are_one_line(
    poly, tmp_path, capsys, monkeypatch, error, status, words
):
    failing_generate(monkeypatch, error)
    assert main(["mesh", str(poly), "-o", str(tmp_path / "x.vtu")]) == status
    assert words in error_line(capsys)


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_shows_the_traceback_of_unexpected_errors(poly, tmp_path, monkeypatch, where):
    failing_generate(monkeypatch, ZeroDivisionError("division by zero"))
    argv = ["mesh", str(poly), "-o", str(tmp_path / "x.vtu")]
    with pytest.raises(ZeroDivisionError):
        main(["--debug", *argv] if where == "before" else [*argv, "--debug"])


def test_debug_keeps_expected_errors_on_one_line(poly, tmp_path, capsys, monkeypatch):
    failing_generate(monkeypatch, MeshingError("bound hit"))
    assert main(["--debug", "mesh", str(poly), "-o", str(tmp_path / "x.vtu")]) == 1
    assert "bound hit" in error_line(capsys)


def test_warnings_are_one_line_each(poly, tmp_path, capsys, monkeypatch):
    import warnings

    import bubblemesh

    def generate(*args, **kwargs):
        warnings.warn("first\nsecond", RuntimeWarning, stacklevel=1)
        raise MeshingError("stopped")

    monkeypatch.setattr(bubblemesh, "mesh", generate)
    assert main(["mesh", str(poly), "-o", str(tmp_path / "x.vtu")]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert len(lines) == 2, lines
    assert lines[0].startswith("bubblemesh mesh: warning: first second (RuntimeWarning")
    assert lines[1] == "bubblemesh mesh: error: stopped"


def fake_studies_module(monkeypatch, name: str, returns=None) -> list:
    """Replace bubblemesh.studies.<name> by a module whose main records its options."""
    calls: list = []
    module = types.ModuleType(f"bubblemesh.studies.{name}")
    module.main = lambda **kwargs: calls.append(kwargs) or returns  # type: ignore[attr-defined]
    module.paper_study = lambda cases, cases_dir: None  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, f"bubblemesh.studies.{name}", module)
    return calls


def test_reproduce_passes_its_options(monkeypatch, tmp_path):
    pytest.importorskip("matplotlib")  # reproduce checks for it before it starts
    calls = fake_studies_module(monkeypatch, "reproduce")
    argv = ["reproduce", "--case", "fig3", "--case", "fig5", "--out", str(tmp_path),
            "--scheduler", "inline"]
    assert main(argv) == 0
    assert calls == [{"cases": ["fig3", "fig5"], "out": tmp_path, "cases_dir": None,
                      "scheduler": "inline", "retry_failed": False}]


def test_bench_passes_only_the_options_given(monkeypatch, tmp_path):
    calls = fake_studies_module(monkeypatch, "benchmark", returns=3)
    assert main(["bench", "--quick", "--out", str(tmp_path)]) == 3
    assert calls == [{"quick": True, "out": tmp_path}]
    main(["bench", "--max-elements", "5000", "--repeats", "2"])
    assert calls[-1] == {"quick": False, "out": Path("reports"), "max_elements": 5000, "repeats": 2}


def test_unknown_case_is_a_usage_error_before_any_meshing(capsys, meshing):
    assert main(["reproduce", "--case", "fig3_circle", "--case", "nope"]) == 2
    assert "nope" in error_line(capsys, "reproduce")
    assert meshing == []


def test_a_bad_scheduler_address_is_a_usage_error(capsys):
    assert main(["reproduce", "--scheduler", "localhost"]) == 2
    assert "tcp://HOST:PORT" in error_line(capsys, "reproduce")


def test_a_missing_optional_package_is_one_line(monkeypatch, capsys):
    import importlib

    def import_module(name, package=None):
        raise ModuleNotFoundError("No module named 'dask'", name="dask")

    monkeypatch.setattr(importlib, "import_module", import_module)
    assert main(["reproduce"]) == 1
    assert "needs dask: pip install 'bubblemesh[studies]'" in error_line(capsys, "reproduce")


@pytest.mark.parametrize(
    ("args", "status", "words"),
    [
        (["-o", "OUT.xyz"], 2, "cannot tell the mesh format"),
        (["-o", "OUT.vtu", "--max-insertions", "-1"], 2, "--max-insertions"),
        (["-o", "OUT.vtu", "--max-insertions", "2"], 0, None),
    ],
)
def test_the_program_exit_status_and_stderr(poly, tmp_path, args, status, words):
    argv = [a.replace("OUT", str(tmp_path / "out")) for a in args]
    result = subprocess.run(
        [sys.executable, "-m", "bubblemesh.cli", "mesh", str(poly), *argv],
        capture_output=True,
        text=True,
    )
    assert result.returncode == status, result.stderr
    if words is None:
        quiet = result.stderr.replace(NOTICE + "\n", "")  # said if numba's cache was cold
        assert quiet == "" and (tmp_path / "out.vtu").exists()
    else:
        assert len(result.stderr.splitlines()) == 1, result.stderr
        assert result.stderr.startswith("bubblemesh mesh: error: ") and words in result.stderr


@pytest.mark.parametrize("command", ["check", "info"])
def test_a_reader_that_leaves_early_is_no_error(tmp_path, command):
    """``bubblemesh check mesh.vtu | head -0``: the reader of stdout has gone
    before the command writes; the command stops quietly (exit 1, nothing on
    stderr), neither "cannot read the input: Broken pipe" nor Python's
    "Exception ignored" at exit."""
    meshio = pytest.importorskip("meshio")
    path = tmp_path / "one.vtu"
    meshio.Mesh(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), [("triangle", [[0, 1, 2]])]
                ).write(path)
    run = subprocess.Popen([sys.executable, "-m", "bubblemesh.cli", command, str(path)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    run.stdout.close()
    err = run.stderr.read().decode()
    assert run.wait(timeout=120) == 1 and err == ""


def test_help_documents_the_exit_status(capsys):
    for argv in (["--help"], ["mesh", "--help"]):
        assert main(argv) == 0
        printed = capsys.readouterr().out
        assert EXIT_STATUS in printed
        assert "--debug" in printed
    assert all(f"  {status} " in EXIT_STATUS for status in (0, 1, 2, 130))


def test_module_runs_as_a_program():
    result = subprocess.run(
        [sys.executable, "-m", "bubblemesh.cli", "mesh", "--help"],
        capture_output=True,
        text=True,
        check=True,
    )
    for option in ("-o OUT", "--no-optimize", "--plot PNG", "--max-insertions K"):
        assert option in result.stdout


def test_check_judges_a_mesh_file_and_its_boundary(poly, tmp_path, capsys):
    """``bubblemesh check``: a paper mesh of the .poly is clean (0); with one
    triangle removed it is not (1) and the summary names what is wrong; a file
    that is no mesh is a usage error (2)."""
    pytest.importorskip("meshio")
    import bubblemesh as bm

    mesh = bm.optimize(bm.generate(Domain.from_poly(poly)))
    mesh.write(tmp_path / "good.vtu")
    assert main(["check", str(tmp_path / "good.vtu"), "--boundary", str(poly)]) == 0
    assert "ok" in capsys.readouterr().out.lower()
    from bubblemesh.io import write_mesh

    write_mesh(tmp_path / "holed.vtu", mesh.points, mesh.triangles[1:])
    assert main(["check", str(tmp_path / "holed.vtu"), "--boundary", str(poly)]) == 1
    out = capsys.readouterr().out
    assert "area" in out and ("boundary" in out or "segment" in out), out
    (tmp_path / "junk.vtu").write_text("not a mesh")
    assert main(["check", str(tmp_path / "junk.vtu")]) == 2
    assert "cannot read the input" in error_line(capsys, "check")


COMPILE = """
import sys
from numba import njit
from bubblemesh.compiling import compile_notice
from bubblemesh.predicates import incircle, orient2d

@njit(cache=True)
def foreign(x):
    return x + 1

with compile_notice(sys.stdout):
    foreign(1)  # not bubblemesh's: no word
    print("foreign compiled", flush=True)
    orient2d(0.0, 0.0, 1.0, 0.0, 0.0, 1.0)
    orient2d(0.0, 0.0, 1.0, 0.0, 0.0, -1.0)
with compile_notice(sys.stdout):  # as bm.generate then bm.optimize: said once a process
    incircle(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.2, 0.2)
"""


@pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT", "0") != "0", reason="nothing compiles")
def test_a_word_while_numba_compiles_and_none_from_its_cache(tmp_path):
    """In a process whose numba cache is empty (NUMBA_CACHE_DIR a new folder),
    the first bubblemesh kernel compiled says NOTICE, after a foreign kernel
    compiled silently, and a second one in a later block says nothing more; a
    second process on the same cache loads the kernels and says nothing (numba
    reports a compile only on a cache miss)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    script = tmp_path / "compile.py"  # a file: numba caches no kernel of `python -c`
    script.write_text(COMPILE)
    lines = []
    for _ in range(2):
        run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                             env=env, check=True)
        lines.append(run.stdout.splitlines())
    assert lines[0] == ["foreign compiled", NOTICE]
    assert lines[1] == ["foreign compiled"]
