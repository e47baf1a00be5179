"""Command-line overrides that Hydra accepts but the schema does not: keys appended (``+``, ``++``) or deleted (``~``).

Hydra lets ``+foo=1`` add a key to any node, typed or not; our nodes are typed dataclasses, so an appended key is
one that nothing reads. It is refused like ``foo=1``. Appending stays possible where a node is free-form (the keyword
arguments of ``optimizer``, say ``+optimizer.weight_decay=1e-4``), and ``+group=option`` appends a config group
(``+experiment=paper_code``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Sequence

from hydra.core.override_parser.overrides_parser import OverridesParser
from omegaconf import DictConfig, OmegaConf


def _schema_fields(cfg: DictConfig, parent: str) -> set[str] | None:
    """The field names of the typed node at ``parent`` ("" for the root), or None when it is free-form."""
    node = OmegaConf.select(cfg, parent, default=None) if parent else cfg
    kind = OmegaConf.get_type(node) if isinstance(node, DictConfig) else None
    if kind is None or not dataclasses.is_dataclass(kind):
        return None
    return {f.name for f in dataclasses.fields(kind)}


def appended_key_errors(overrides: Sequence[str], cfg: DictConfig, groups: Collection[str]) -> list[str]:
    """One message per ``+key=value`` / ``++key=value`` adding a key the typed schema does not have, or ``~key``.

    Args:
        overrides: the command line's overrides (Hydra's own ``hydra.*`` ones are left alone).
        cfg: the config composed with them.
        groups: the config groups chosen (``hydra.runtime.choices``): ``+group=option`` appends one of those.
    """
    errors = []
    for override in OverridesParser.create().parse_overrides(list(overrides)):
        key = override.key_or_group.split("@")[0]
        if key in groups or key.split(".")[0] == "hydra":
            continue
        parent, _, name = key.rpartition(".")
        fields = _schema_fields(cfg, parent)
        if override.is_delete() and fields is not None:
            errors.append(f"{override.input_line}: {key} is part of the schema and cannot be deleted; allowed: "
                          f"{key}=<value>")  # fmt: skip
        elif (override.is_add() or override.is_force_add()) and fields is not None and name not in fields:
            errors.append(f"{override.input_line}: {key} is not a key of this configuration; allowed: the keys "
                          "`python -m runners.train --help` lists (+ appends only to free-form nodes such as optimizer, "
                          "or a group such as +experiment=paper_code)")  # fmt: skip
    return errors
