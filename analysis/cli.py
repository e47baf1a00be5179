"""The command line every analysis command shares: ``RUNS_DIR [--out DIR] [--group-by KEYS] [--pool LABEL=GLOB]``,
and one clear error line (no traceback) for a missing directory, no runs or a malformed option. A results directory
may hold ``analysis.yaml`` with the ``pool``, ``group_by``, ``reference``, ``include`` and ``labels`` its tables were
made with (:mod:`analysis.settings`): the bare command then makes them again (an option on the command line wins)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from analysis.collect import existing_roots
from analysis.settings import settings


@dataclass
class Options:
    """What a command was asked: the runs' root, where to write, the row keys and the pools."""

    root: Path
    out: Path
    group_by: list[str]
    pools: list[str]
    args: argparse.Namespace


def comma_ints(text: str) -> list[int]:
    """``"0,300,1000"`` -> [0, 300, 1000]; [] when an item is not an integer (the caller prints its error line)."""
    try:
        return [int(v) for v in text.split(",")]
    except ValueError:
        return []


def parser(description: str) -> argparse.ArgumentParser:
    """The options every analysis command shares: RUNS_DIR, --out, --group-by, --pool."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("root", help="a directory holding run directories (searched recursively)")
    p.add_argument("--out", help="where to write (default: RUNS_DIR/report)")
    p.add_argument("--group-by", default="", help="comma-separated config keys that define a row, e.g. "
                   "env.name,entropy.name (default: method label + the keys that differ between its runs)")  # fmt: skip
    p.add_argument("--pool", action="append", default=[], metavar="LABEL=GLOB",
                   help="merge the rows whose label matches GLOB into one row LABEL (repeatable); LABEL+=GLOB adds "
                        "the pooled row beside the rows it pools")  # fmt: skip
    return p


def _apply(args: argparse.Namespace, found: dict[str, object]) -> None:
    """Settings from the directory's file where the command line left an option at its default."""
    if not args.pool and "pool" in found:
        args.pool = [str(v) for v in found["pool"]]  # type: ignore[union-attr]
    if not args.group_by and "group_by" in found:
        args.group_by = ",".join(str(v) for v in found["group_by"])  # type: ignore[union-attr]
    if hasattr(args, "reference") and args.reference is None and "reference" in found:
        args.reference = str(found["reference"])
    if hasattr(args, "labels") and args.labels is None and "labels" in found:
        if not isinstance(found["labels"], list):
            raise ValueError(f"labels: {found['labels']!r} is not allowed; allowed: a list of SHORT=GLOB")
        args.labels = [str(v) for v in found["labels"]]


def label_option(p: argparse.ArgumentParser) -> None:
    """``--label SHORT=GLOB`` (repeatable): a short name for the row matching GLOB in the cost table and every figure
    (:mod:`analysis.cost`, :mod:`analysis.plotting`); ``args.labels`` is None when not given, so ``analysis.yaml``'s
    ``labels`` apply."""
    p.add_argument("--label", dest="labels", action="append", default=None, metavar="SHORT=GLOB",
                   help="short name for the row matching GLOB in the cost table and the figures (repeatable)")  # fmt: skip


def run(p: argparse.ArgumentParser, command: Callable[[Options], str]) -> None:
    """Parse the command line, run ``command`` and print its one-line result; a bad input exits 1 with one line."""
    args = p.parse_args()
    root = existing_roots([args.root])[0]
    out = Path(args.out) if args.out else root / "report"
    try:
        _apply(args, settings(root))
        print(command(Options(root, out, [k for k in args.group_by.split(",") if k], list(args.pool), args)))
    except (FileNotFoundError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(1) from None
