"""A short run of the fuzz campaign (verification/fuzz.py): user-like domains
(decimal grids, ulp jitter, far offsets, scales, mutated .poly files), each in
a worker process with a time limit.  Any crash, hang, foreign exception or
invalid mesh fails the test; the campaign's own cases are a seed range, so a
failure is reproducible with ``python verification/fuzz.py --seed S --cases 1``."""

from __future__ import annotations

import json

import fuzz
import pytest


@pytest.mark.heavy
def test_a_short_campaign_has_no_failures(tmp_path):
    cases = 150
    log = tmp_path / "failures.jsonl"
    with open(log, "w") as f:
        counts = fuzz.campaign(cases, seed=0, timeout=300, log=f)
    failures = [json.loads(line) for line in log.read_text().splitlines()]
    assert not failures, "\n".join(f"seed {r['case']['seed']} ({r['case']['kind']}): "
                                   f"{r['outcome']}: {r['detail']}" for r in failures[:5])
    assert sum(counts.values()) == cases
    assert counts["mesh"] >= cases // 5, f"too few valid domains to mean much: {counts}"


def test_a_case_is_reproducible_from_its_seed():
    assert fuzz.make_case(123) == fuzz.make_case(123)
    kinds = {fuzz.make_case(s)["kind"] for s in range(len(fuzz.KINDS))}
    assert kinds == set(fuzz.KINDS)
