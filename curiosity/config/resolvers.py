"""OmegaConf resolvers used by ``conf/`` (registered at import, idempotently)."""

from __future__ import annotations

from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

# Config groups that ``--help`` lists: the user's, and the launchers; not the typed schemas (``schema/*``).
HELP_GROUPS = ("hydra/launcher",)


def run_variant(override_dirname: str) -> str:
    """The run-directory component naming a run's command-line overrides (``default`` when there are none)."""
    return override_dirname or "default"


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
