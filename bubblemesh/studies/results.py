"""Results tables: one row per cell, written as Parquet (with pyarrow) and CSV.

``results.parquet`` is read back when present (exact types), else ``results.csv``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["COLUMNS", "TIMING_COLUMNS", "read_results", "write_results", "parquet_available"]

#: The columns every row has, in this order (``param_<name>`` columns follow ``params``).
COLUMNS = [
    "study", "key", "case", "method", "adapter", "params", "bubblemesh_version",
    "case_digest", "status", "reason", "verify", "elements", "nodes", "rho_min", "rho_mean",
    "rho_median", "n_below_0_5", "pct_below_0_5", "n_below_0_7", "pct_below_0_7",
    "min_angle", "max_angle", "boundary_shift", "boundary_nodes", "inverted", "seconds",
    "timings", "cell_seconds", "timed", "worker", "started", "input", "options", "mesh_file",
    "versions",
]  # fmt: skip
#: Columns that differ between two runs of the same cell (when and where it ran, how long).
TIMING_COLUMNS = ("seconds", "timings", "cell_seconds", "worker", "started")


def parquet_available() -> bool:
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return False
    return True


def frame(rows: list[dict[str, Any]]):
    """The rows as a DataFrame with ``COLUMNS`` first, then the parameter columns."""
    import pandas as pd

    df = pd.DataFrame(rows)
    for column in COLUMNS:
        if column not in df:
            df[column] = None
    params = sorted(c for c in df.columns if c.startswith("param_"))
    rest = [c for c in df.columns if c not in COLUMNS and c not in params]
    at = COLUMNS.index("params") + 1
    return df[COLUMNS[:at] + params + COLUMNS[at:] + rest]


def write_results(df, out: str | Path) -> list[Path]:
    """``out/results.csv`` and, with pyarrow, ``out/results.parquet``; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    if parquet_available():
        parquet = out / "results.parquet"
        tmp = parquet.with_suffix(".parquet.tmp")
        df.to_parquet(tmp, index=False)
        tmp.replace(parquet)
        written.append(parquet)
    csv = out / "results.csv"
    tmp = csv.with_suffix(".csv.tmp")
    df.to_csv(tmp, index=False, float_format="%.6g")
    tmp.replace(csv)
    return [csv, *written]


def read_results(out: str | Path):
    """The results table in ``out`` (Parquet if it can, else CSV); None when there is none."""
    import pandas as pd

    out = Path(out)
    if (out / "results.parquet").exists() and parquet_available():
        return pd.read_parquet(out / "results.parquet")
    if (out / "results.csv").exists():
        return pd.read_csv(out / "results.csv", keep_default_na=False,
                           na_values={c: [""] for c in COLUMNS
                                      if c not in ("reason", "verify", "options")})
    return None
