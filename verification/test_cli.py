"""The ``bubblemesh`` command line: mesh a .poly, hand reproduce/bench to the cases package."""

from __future__ import annotations

import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from bubblemesh.cli import main
from bubblemesh.domain import Domain

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


def kernel_available() -> bool:
    try:
        from bubblemesh import generate, optimize  # noqa: F401
        from bubblemesh.quality import summary  # noqa: F401
    except ImportError:
        return False
    return True


needs_kernel = pytest.mark.skipif(
    not kernel_available(), reason="bubblemesh.generate not importable yet"
)


@needs_kernel
@pytest.mark.parametrize("optimize", [True, False])
def test_mesh_writes_the_mesh_and_reports_it(poly, tmp_path, capsys, optimize):
    meshio = pytest.importorskip("meshio")
    out = tmp_path / "square.vtu"
    argv = ["mesh", str(poly), "-o", str(out)] + ([] if optimize else ["--no-optimize"])
    assert main(argv) == 0
    printed = capsys.readouterr().out
    mesh = meshio.read(out)
    triangles = mesh.cells_dict["triangle"]
    assert f"nodes: {len(mesh.points)} (14 on the boundary)" in printed
    assert f"elements: {len(triangles)}" in printed
    line = re.search(r"radius ratio: min (\S+), mean (\S+), median (\S+);", printed)
    assert line, printed
    low, mean, median = (float(v) for v in line.groups())
    assert 0 < low <= mean <= 1 and 0 < median <= 1
    # the boundary nodes come first and unmoved
    np.testing.assert_array_equal(mesh.points[:14, :2], np.vstack(SQUARE_WITH_HOLE))
    # the mesh covers the domain: triangle areas add up to A_geo = 1 - 0.04
    p = mesh.points[:, :2]
    a, b, c = p[triangles[:, 0]], p[triangles[:, 1]], p[triangles[:, 2]]
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (cross > 0).all()
    assert 0.5 * cross.sum() == pytest.approx(0.96, rel=1e-12)


@needs_kernel
def test_mesh_max_insertions_and_plot(poly, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    png = tmp_path / "square.png"
    out = tmp_path / "square.msh"
    args = ["mesh", str(poly), "-o", str(out), "--no-optimize", "--max-insertions", "3"]
    assert main([*args, "--plot", str(png)]) == 0
    printed = capsys.readouterr().out
    assert "nodes: 17 (14 on the boundary)" in printed
    assert png.read_bytes().startswith(b"\x89PNG")


def test_mesh_reports_geometry_errors_without_traceback(tmp_path, capsys):
    path = tmp_path / "bow.poly"
    path.write_text("4 2 0 0\n1 0 0\n2 1 1\n3 1 0\n4 0 1\n4 0\n1 1 2\n2 2 3\n3 3 4\n4 4 1\n")
    assert main(["mesh", str(path), "-o", str(tmp_path / "x.vtu")]) == 1
    error = capsys.readouterr().err
    assert "bubblemesh mesh: error:" in error
    assert "loop 0 (outer) segment 2 crosses loop 0 (outer) segment 0" in error
    assert "Traceback" not in error


def test_mesh_missing_input_file(tmp_path, capsys):
    assert main(["mesh", str(tmp_path / "none.poly"), "-o", str(tmp_path / "x.vtu")]) == 1
    assert "none.poly" in capsys.readouterr().err


def fake_cases_module(monkeypatch, name: str, returns=None) -> list:
    calls: list = []
    module = types.ModuleType(f"cases.{name}")
    module.main = lambda **kwargs: calls.append(kwargs) or returns  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, f"cases.{name}", module)
    return calls


def test_reproduce_passes_cases_and_out(monkeypatch, tmp_path):
    calls = fake_cases_module(monkeypatch, "reproduce")
    assert main(["reproduce", "--case", "fig3", "--case", "fig5", "--out", str(tmp_path)]) == 0
    assert calls == [{"cases": ["fig3", "fig5"], "out": tmp_path}]
    assert main(["reproduce"]) == 0
    assert calls[-1] == {"cases": None, "out": Path("reports")}


def test_bench_passes_only_the_options_given(monkeypatch, tmp_path):
    calls = fake_cases_module(monkeypatch, "benchmark", returns=3)
    assert main(["bench", "--quick", "--out", str(tmp_path)]) == 3
    assert calls == [{"quick": True, "out": tmp_path}]
    main(["bench", "--max-elements", "5000", "--repeats", "2"])
    assert calls[-1] == {"quick": False, "out": Path("reports"), "max_elements": 5000, "repeats": 2}


def test_missing_cases_package_is_a_clear_error(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "cases.benchmark", None)  # import fails as if absent
    assert main(["bench", "--quick"]) == 1
    assert "needs the repository's cases package" in capsys.readouterr().err


def test_module_runs_as_a_program():
    result = subprocess.run(
        [sys.executable, "-m", "bubblemesh.cli", "mesh", "--help"],
        capture_output=True,
        text=True,
        check=True,
    )
    for option in ("-o OUT", "--no-optimize", "--plot PNG", "--max-insertions K"):
        assert option in result.stdout
