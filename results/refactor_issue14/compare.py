"""Compare metrics.csv of reference runs before/after the refactor, column by column (shared columns)."""
import sys, pandas as pd, numpy as np, json, pathlib
before, after = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
for d in sorted(after.iterdir()):
    if not d.is_dir(): continue
    b = before / d.name
    if not (b / "metrics.csv").exists() or not (d/"metrics.csv").exists(): print(d.name, "missing"); continue
    x, y = pd.read_csv(b / "metrics.csv"), pd.read_csv(d / "metrics.csv")
    shared = [c for c in x.columns if c in y.columns and not c.startswith("timing/") and c not in ("wall_seconds","time")]
    diff = []
    for c in shared:
        u, v = x[c].to_numpy(), y[c].to_numpy()
        if len(u) != len(v): diff.append(f"{c}:len"); continue
        if u.dtype.kind in "fi" and v.dtype.kind in "fi":
            same = np.array_equal(np.nan_to_num(u, nan=1e300), np.nan_to_num(v, nan=1e300))
        else:
            same = (x[c].astype(str) == y[c].astype(str)).all()
        if not same: diff.append(c)
    only = sorted(set(x.columns) ^ set(y.columns))
    print(d.name, "rows", len(x), len(y), "DIFF:", diff, "| columns only in one:", only)
