"""Compare the metrics.csv of reference runs made before and after a change, column by column, exactly.

    python -m studies.refactor.compare BEFORE_DIR AFTER_DIR

For every configuration's metrics.csv in AFTER_DIR (saved as <name>.csv, so the analysis commands do not take these
copies for runs; ``studies.refactor.reference_runs --collect`` saves them so), the shared columns that differ (timings
always do; the timing/* columns are left out) and the columns present on one side only
(``results/refactor_issue14/``).
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np
import pandas as pd


def differing(x: pd.DataFrame, y: pd.DataFrame) -> list[str]:
    out = []
    for column in (c for c in x.columns if c in y.columns and not c.startswith("timing/")):
        u, v = x[column].to_numpy(), y[column].to_numpy()
        if len(u) != len(v):
            out.append(f"{column}:len")
        elif u.dtype.kind in "fi" and v.dtype.kind in "fi":
            if not np.array_equal(np.nan_to_num(u, nan=1e300), np.nan_to_num(v, nan=1e300)):
                out.append(column)
        elif not (x[column].astype(str) == y[column].astype(str)).all():
            out.append(column)
    return out


def compare(before: pathlib.Path, after: pathlib.Path) -> None:
    for new in sorted(after.glob("*.csv")):
        old = before / new.name
        if not old.exists():
            print(new.stem, "missing")
            continue
        x, y = pd.read_csv(old), pd.read_csv(new)
        only = sorted(set(x.columns) ^ set(y.columns))
        print(new.stem, "rows", len(x), len(y), "DIFF:", differing(x, y), "| columns only in one:", only)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.refactor.compare", description=__doc__.splitlines()[0])
    parser.add_argument("before", type=pathlib.Path, help="directory of <configuration>.csv before the change")
    parser.add_argument("after", type=pathlib.Path, help="directory of <configuration>.csv after it")
    args = parser.parse_args(argv)
    compare(args.before, args.after)


if __name__ == "__main__":
    main()
