"""The command line every analysis command shares: ``RUNS_DIR [--out DIR] [--group-by KEYS] [--pool LABEL=GLOB]``,
and one clear error line (no traceback) for a missing directory, no runs or a malformed option."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from analysis.collect import existing_roots


@dataclass
class Options:
    """What a command was asked: the runs' root, where to write, the row keys and the pools."""

    root: Path
    out: Path
    group_by: list[str]
    pools: list[str]
    args: argparse.Namespace


def parser(description: str) -> argparse.ArgumentParser:
    """The options every analysis command shares: RUNS_DIR, --out, --group-by, --pool."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("root", help="a directory holding run directories (searched recursively)")
    p.add_argument("--out", help="where to write (default: RUNS_DIR/report)")
    p.add_argument("--group-by", default="", help="comma-separated config keys that define a row, e.g. "
                   "env.name,entropy.name (default: method label + the keys that differ between its runs)")  # fmt: skip
    p.add_argument("--pool", action="append", default=[], metavar="LABEL=GLOB",
                   help="merge the rows whose label matches GLOB into one row LABEL (repeatable)")  # fmt: skip
    return p


def run(p: argparse.ArgumentParser, command: Callable[[Options], str]) -> None:
    """Parse the command line, run ``command`` and print its one-line result; a bad input exits 1 with one line."""
    args = p.parse_args()
    root = existing_roots([args.root])[0]
    out = Path(args.out) if args.out else root / "report"
    try:
        print(command(Options(root, out, [k for k in args.group_by.split(",") if k], list(args.pool), args)))
    except (FileNotFoundError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(1) from None
