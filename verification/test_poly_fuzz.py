"""Mutated .poly files: Domain.from_poly returns a Domain or raises GeometryError, nothing else.

Valid files (comments, attributes and markers, numbering from 0 and 1, a
``.node`` file beside the ``.poly``) are mutated byte by byte and token by
token: bit flips, inserted and deleted bytes, lines deleted, repeated or
swapped, truncation, and numbers replaced by huge, negative, non-finite or
malformed ones.  The oracle is only the exception type, so it does not depend
on the reader.  A larger campaign runs on demand and prints counts:

    PYTHONPATH=. python verification/test_poly_fuzz.py 20000
"""

from __future__ import annotations

import random
import sys
import tempfile
from collections import Counter
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st
from strategies import budget

from bubblemesh.domain import Domain
from bubblemesh.errors import GeometryError

SQUARE_WITH_HOLE = b"""\
# a square with a square hole, numbered from 1 (caf\xc3\xa9), attributes and markers
8 2 1 1
1 0 0   0.5 1
2 4 0   0.5 1
3 4 4   0.5 1  # trailing comment
4 0 4   0.5 1

5 1 1   0.5 2
6 2 1   0.5 2
7 2 2   0.5 2
8 1 2   0.5 2
8 1
1 1 2 1
2 3 2 1
3 3 4 1
4 1 4 1
5 5 6 2
6 7 6 2
7 7 8 2
8 5 8 2
1
1 1.5 1.5
"""
TRIANGLE_ZERO_BASED = b"3 2 0 0\n0 0 0\n1 1 0\n2 0 1\n3 0\n0 0 1\n1 1 2\n2 2 0\n"
FROM_NODE_FILE = b"0 2 0 0\n3 0\n1 1 2\n2 2 3\n3 3 1\n0\n"
NODE_FILE = b"3 2 0 0\n1 0 0\n2 1 0\n3 0 1\n"
SEEDS = [SQUARE_WITH_HOLE, TRIANGLE_ZERO_BASED, FROM_NODE_FILE]

TOKENS = [
    b"0", b"-1", b"-3", b"1", b"2", b"3", b"1000000000000", b"1e14", b"99999999999999999999999",
    b"-99999999999999999999999", b"9223372036854775808", b"1e308", b"1e400", b"-1e-320", b"nan",
    b"inf", b"-inf", b"1.5", b"3.0", b".", b"-", b"+", b"e", b"0x10", b"1_0", b"\xd9\xa1", b"#",
    b"\xe9", b"",
]  # fmt: skip
BYTES = b"0123456789-+.eE# ,\t\r\n\x00\x0c\xe9\xff\xef\xbb\xbf"


def mutate(data: bytes, ops: list[tuple[str, int, int]]) -> bytes:
    """Apply ``(kind, a, b)`` edits in turn; positions are taken modulo the length."""
    for kind, a, b in ops:
        n = len(data)
        if kind == "flip" and n:
            i = a % n
            data = data[:i] + bytes([data[i] ^ (1 << (b % 8))]) + data[i + 1 :]
        elif kind == "insert":
            i = a % (n + 1)
            data = data[:i] + BYTES[b % len(BYTES) : b % len(BYTES) + 1] + data[i:]
        elif kind == "delete" and n:
            i = a % n
            data = data[:i] + data[i + 1 + b % 8 :]
        elif kind == "truncate":
            data = data[: a % (n + 1)]
        elif kind == "token":
            tokens = data.split(b" ")
            tokens[a % len(tokens)] = TOKENS[b % len(TOKENS)]
            data = b" ".join(tokens)
        elif kind in ("drop line", "repeat line", "swap lines"):
            lines = data.split(b"\n")
            i, j = a % len(lines), b % len(lines)
            if kind == "drop line":
                del lines[i]
            elif kind == "repeat line":
                lines.insert(i, lines[i])
            else:
                lines[i], lines[j] = lines[j], lines[i]
            data = b"\n".join(lines)
    return data


KINDS = ["flip", "insert", "delete", "truncate", "token", "drop line", "repeat line", "swap lines"]


def outcome(folder: Path, poly: bytes, node: bytes) -> str:
    """'domain' or 'geometry error'; any other exception propagates."""
    (folder / "f.poly").write_bytes(poly)
    (folder / "f.node").write_bytes(node)
    try:
        Domain.from_poly(folder / "f.poly")
    except GeometryError:
        return "geometry error"
    return "domain"


edits = st.lists(
    st.tuples(st.sampled_from(KINDS), st.integers(0, 10_000), st.integers(0, 10_000)),
    min_size=1,
    max_size=6,
)


@budget(300)
@given(st.sampled_from(SEEDS), edits, st.booleans(), edits)
def test_mutated_poly_gives_a_domain_or_a_geometry_error(
    tmp_path_factory, seed, poly_edits, edit_node, node_edits
):
    node = mutate(NODE_FILE, node_edits) if edit_node else NODE_FILE
    outcome(tmp_path_factory.mktemp("fuzz"), mutate(seed, poly_edits), node)


def test_the_seeds_are_valid(tmp_path):
    # without this the fuzz test could pass by mutating files that never parse
    assert all(outcome(tmp_path, seed, NODE_FILE) == "domain" for seed in SEEDS)


def test_found_by_the_campaign(tmp_path):
    # a vertex at 1e308: the loop areas overflowed to inf - inf in math.fsum (a ValueError)
    poly = SQUARE_WITH_HOLE.replace(b"\n1 0 0 ", b"\n1 1e308 0 ")
    assert outcome(tmp_path, poly, NODE_FILE) == "geometry error"


def campaign(n: int, seed: int = 0) -> Counter:
    """``n`` mutated files; counts outcomes, foreign exceptions by type (and prints them)."""
    rng = random.Random(seed)
    counts: Counter = Counter()
    with tempfile.TemporaryDirectory() as scratch:
        for _ in range(n):
            ops = [
                (rng.choice(KINDS), rng.randrange(10_000), rng.randrange(10_000))
                for _ in range(rng.randint(1, 6))
            ]
            node = NODE_FILE
            if rng.random() < 0.3:
                edit = (rng.choice(KINDS), rng.randrange(99), rng.randrange(99))
                node = mutate(NODE_FILE, [edit])
            poly = mutate(rng.choice(SEEDS), ops)
            try:
                counts[outcome(Path(scratch), poly, node)] += 1
            except Exception as error:
                counts[f"foreign {type(error).__name__}"] += 1
                print(repr(poly), repr(node), repr(error), file=sys.stderr)
    return counts


if __name__ == "__main__":
    print(dict(campaign(int(sys.argv[1]) if len(sys.argv) > 1 else 20_000)))
