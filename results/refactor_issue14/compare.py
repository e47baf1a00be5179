"""Compare the metrics.csv of reference runs made before and after a change, column by column, exactly.

python compare.py BEFORE_DIR AFTER_DIR: for every configuration's metrics.csv in AFTER_DIR (saved as <name>.csv, so the
analysis commands do not take these copies for runs), the shared columns that differ
(timings always do; the timing/* columns are left out) and the columns present on one side only.
"""

import pathlib
import sys

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


def main(before: pathlib.Path, after: pathlib.Path) -> None:
    for new in sorted(after.glob("*.csv")):
        old = before / new.name
        if not old.exists():
            print(new.stem, "missing")
            continue
        x, y = pd.read_csv(old), pd.read_csv(new)
        only = sorted(set(x.columns) ^ set(y.columns))
        print(new.stem, "rows", len(x), len(y), "DIFF:", differing(x, y), "| columns only in one:", only)


if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]))
