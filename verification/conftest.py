"""pytest configuration for the verification suite.

Hypothesis profiles (select with HYPOTHESIS_PROFILE=<name>; default ``ci``):

- ``ci``: reproducible (derandomize=True, no example database writes), no
  deadline (numba compiles on first call), enough examples to find real bugs
  within a few minutes for the whole suite.
- ``dev``: quick local iteration, random seeds, uses the example database so a
  failure found once is replayed first.
- ``thorough``: ten times the ``ci`` budget, random seeds; for nightly or
  pre-release runs.
- ``quick``: a fifth of ``ci``, still derandomized; the default when
  NUMBA_DISABLE_JIT is set (kernels run as plain Python), and tox's ``oldest``
  (which checks that the lower bounds work, not hunting bugs).

Tests with their own expensive bodies scale their budget with
``strategies.budget(n)`` so that ``thorough`` also runs them harder.

Markers: ``peers`` (needs triangle / scipy / trimesh; those tests call
``pytest.importorskip`` so they skip with a reason where a peer is missing),
``slow`` (deselect with ``-m "not slow"``), and ``heavy``: whole meshes (many
random domains, fine or awkward inputs, campaigns in worker processes) that
take a minute or more each when the kernels run as plain Python; tox's nojit
and oldest deselect them, the jitted environments run them.
"""

from __future__ import annotations

import os
import sys

from hypothesis import HealthCheck, settings

# the helpers live next to the tests; make them importable under any
# pytest import mode (prepend, append or importlib)
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

_common = dict(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    print_blob=True,
)
settings.register_profile("ci", max_examples=100, derandomize=True, database=None, **_common)
settings.register_profile("dev", max_examples=30, **_common)
settings.register_profile("thorough", max_examples=1000, **_common)
settings.register_profile("quick", max_examples=20, derandomize=True, database=None, **_common)
_NOJIT = os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0")
PROFILE = os.environ.get("HYPOTHESIS_PROFILE") or ("quick" if _NOJIT else "ci")
settings.load_profile(PROFILE)


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "peers: needs a peer library (triangle, scipy, trimesh); skipped if missing"
    )
    config.addinivalue_line("markers", "slow: expensive; deselect with -m 'not slow'")
    config.addinivalue_line(
        "markers", "heavy: minutes as plain Python; deselected by tox -e nojit and -e oldest"
    )


def pytest_report_header(config):
    return f"hypothesis profile: {PROFILE} (max_examples={settings.default.max_examples})"
