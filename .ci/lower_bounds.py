"""Write pip constraints pinning every dependency of pyproject.toml to its lower bound.

Used by ``tox -e oldest`` so the oldest supported versions are tested without a
second list of versions to keep in step: ``numpy>=1.24.0`` becomes ``numpy==1.24.0``.
"""

import re
import sys
from pathlib import Path

import tomllib

pyproject = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
project = pyproject["project"]
requirements = list(project["dependencies"])
for extra in project["optional-dependencies"].values():
    requirements += [r for r in extra if not r.startswith(project["name"])]

pins = {}
for requirement in requirements:
    if ";" in requirement:  # an environment marker (e.g. tomli before 3.11): not pinned here
        continue
    match = re.fullmatch(r"\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?\s*>=\s*([^,\s]+)\s*", requirement)
    if match is None:
        sys.exit(f"lower_bounds: no plain '>=' lower bound in {requirement!r}")
    pins[match[1].lower()] = match[3]
Path(sys.argv[1]).write_text(
    "".join(f"{name}=={version}\n" for name, version in sorted(pins.items()))
)
