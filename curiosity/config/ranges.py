"""Inclusive integer ranges on the command line: ``seed=0-3`` means seeds 0, 1, 2, 3.

Hydra's override grammar cannot be extended and passes ``seed=0-3`` through as the string ``'0-3'``, so the entry
point rewrites ``sys.argv`` before Hydra parses it (``seed=A-B`` -> ``seed=range(A,B+1)``). Only whitelisted integer
keys are rewritten; a free-text value such as ``name=1-2`` stays a string.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

RANGE_KEYS = ("seed",)
_ARG = re.compile(r"^(?P<key>" + "|".join(RANGE_KEYS) + r")=(?P<value>.*)$")
_RANGE = re.compile(r"^(\d+)-(\d+)$")
_INT = re.compile(r"^\d+$")


class RangeError(ValueError):
    """A malformed range for an integer key."""


def _expand_item(key: str, item: str) -> list[int] | None:
    """[A, ..., B] for an item ``A-B``; None for a plain integer; RangeError for anything else with a dash."""
    item = item.strip()
    if m := _RANGE.match(item):
        lo, hi = int(m[1]), int(m[2])
        if lo > hi:
            raise RangeError(f"{key}={item}: the range's start {lo} is after its end {hi}; write {key}={hi}-{lo}")
        return list(range(lo, hi + 1))
    if "-" in item[1:] or (item.startswith("-") and not _INT.match(item[1:])):
        raise RangeError(f"{key}={item}: expected an integer or an inclusive range A-B of integers with A <= B")
    return None


def expand_ranges(argv: Sequence[str]) -> list[str]:
    """Rewrite ``seed=A-B`` (inclusive) and comma lists holding such ranges into Hydra sweep syntax.

    ``seed=0-3`` -> ``seed=range(0,4)``; ``seed=0-2,7`` -> ``seed=0,1,2,7``. Other arguments, and values already in
    Hydra's syntax (``range(0,4)``, ``choice(...)``), pass through unchanged.

    Raises:
        RangeError: naming the key, for ``seed=3-1``, ``seed=a-b`` and similar.
    """
    out = []
    for arg in argv:
        m = _ARG.match(arg)
        if not m or "(" in m["value"]:
            out.append(arg)
            continue
        key, items = m["key"], m["value"].split(",")
        expanded = [_expand_item(key, item) for item in items]
        if all(e is None for e in expanded):
            out.append(arg)
        elif len(expanded) == 1:
            seq = expanded[0]
            assert seq is not None
            out.append(f"{key}=range({seq[0]},{seq[-1] + 1})")
        else:
            flat = [str(v) for e, item in zip(expanded, items, strict=True) for v in (e if e is not None else [item.strip()])]
            out.append(f"{key}={','.join(flat)}")
    return out
