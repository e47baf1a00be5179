"""``RUNS_DIR/analysis.yaml``: how a results directory's committed tables are made, so that the bare command
(``python -m analysis.tables RUNS_DIR``) makes them again.

Keys: ``pool`` (a list of ``LABEL=GLOB``), ``group_by`` (a list of config keys), ``reference`` (a row glob),
``include`` (a list of globs, relative to RUNS_DIR, of run directories another preset made with the same config:
:mod:`analysis.include`) and ``labels`` (a list of ``SHORT=GLOB``: a short name for the row matching the glob, shown
by the cost table and every figure, :mod:`analysis.cost`, :mod:`analysis.plotting`, in the order listed; the other
tables keep the rows' own labels).
"""

from __future__ import annotations

from pathlib import Path

import yaml

SETTINGS = "analysis.yaml"  # in RUNS_DIR
DEFAULT_REFERENCE = "nsrs*"  # the reference row of a directory whose analysis.yaml names none
SETTING_KEYS = ("pool", "group_by", "reference", "include", "labels")


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
