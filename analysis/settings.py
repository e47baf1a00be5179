"""``RUNS_DIR/analysis.yaml``: how a results directory's committed tables are made, so that the bare command
(``python -m analysis.tables RUNS_DIR``) makes them again.

Keys: ``pool`` (a list of ``LABEL=GLOB``), ``group_by`` (a list of config keys), ``reference`` (a row glob),
``include`` (a list of globs, relative to RUNS_DIR, of run directories another preset made with the same config:
:mod:`analysis.include`) and ``labels`` (a list of ``SHORT=GLOB``: a short name for the row matching the glob, shown
by the cost table and every figure, :mod:`analysis.cost`, :mod:`analysis.plotting`, in the order listed; the other
tables keep the rows' own labels) and ``margin`` (a number > 0: the cost table's rule, a row passes when the bound of
its ratio of means to the reference's is at most this; :mod:`analysis.cost`, default 1.10).
"""

from __future__ import annotations

from pathlib import Path

import yaml

SETTINGS = "analysis.yaml"  # in RUNS_DIR
DEFAULT_REFERENCE = "nsrs*"  # the reference row of a directory whose analysis.yaml names none
SETTING_KEYS = ("pool", "group_by", "reference", "include", "labels", "margin")


def settings(root: Path) -> dict[str, object]:
    """``RUNS_DIR/analysis.yaml`` as a dict; {} without the file. Raises ValueError naming an unknown key."""
    path = Path(root) / SETTINGS
    if not path.is_file():
        return {}
    found = yaml.safe_load(path.read_text()) or {}
    if not isinstance(found, dict) or set(found) - set(SETTING_KEYS):
        extra = sorted(set(found) - set(SETTING_KEYS)) if isinstance(found, dict) else found
        raise ValueError(f"{path}: {extra} is not a setting; allowed: {', '.join(SETTING_KEYS)}")
    return found


def margin_setting(root: Path) -> float | None:
    """``analysis.yaml``'s ``margin`` (a number > 0), or None when it names none. Raises ValueError otherwise."""
    found = settings(root).get("margin")
    if found is None:
        return None
    if isinstance(found, bool) or not isinstance(found, (int, float)) or not found > 0:
        raise ValueError(f"{Path(root) / SETTINGS}: margin: {found!r} is not allowed; allowed: a number > 0")
    return float(found)
