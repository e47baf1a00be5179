"""OmegaConf resolvers used by ``conf/config.yaml`` (registered at import, idempotently)."""

from __future__ import annotations

from omegaconf import OmegaConf


def run_variant(override_dirname: str) -> str:
    """The run-directory component naming a run's command-line overrides (``default`` when there are none)."""
    return override_dirname or "default"


def register_resolvers() -> None:
    """Register ``${run_variant:...}``; safe to call more than once (Hydra jobs share one process)."""
    OmegaConf.register_new_resolver("run_variant", run_variant, replace=True)
