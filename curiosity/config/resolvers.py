"""OmegaConf resolvers used by ``conf/`` (registered at import, idempotently)."""

from __future__ import annotations

import hashlib

from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

# Config groups that ``--help`` lists: the user's, and the launchers; not the typed schemas (``schema/*``).
HELP_GROUPS = ("hydra/launcher",)


MAX_VARIANT_BYTES = 200  # a directory name may have 255 bytes on common filesystems


def run_variant(override_dirname: str) -> str:
    """The run-directory component naming a run's command-line overrides (``default`` when there are none).

    A name longer than ``MAX_VARIANT_BYTES`` (many overrides) is cut and made unique by a hash of the whole:
    ``<first 180 bytes>~<12 hex digits>``; the run's ``.hydra/overrides.yaml`` keeps the overrides in full.
    """
    name = override_dirname or "default"
    if len(name.encode()) <= MAX_VARIANT_BYTES:
        return name
    digest = hashlib.sha1(name.encode()).hexdigest()[:12]
    return name.encode()[:180].decode(errors="ignore") + "~" + digest


def _listed(group: str) -> bool:
    return group in HELP_GROUPS or not group.startswith(("hydra", "schema"))


def help_groups() -> str:
    """``group: option, option`` lines for ``--help`` (``conf/hydra/help/curiosity.yaml``), Hydra's internals left out."""
    hydra = GlobalHydra.instance().hydra
    return hydra.format_config_groups(_listed).rstrip("\n") if hydra is not None else ""


def register_resolvers() -> None:
    """Register ``${run_variant:...}`` and ``${help_groups:}``; safe to call more than once (jobs share a process)."""
    OmegaConf.register_new_resolver("run_variant", run_variant, replace=True)
    OmegaConf.register_new_resolver("help_groups", help_groups, replace=True)
