"""Build objects from config nodes with ``hydra.utils.instantiate``."""

from __future__ import annotations

from enum import Enum
from typing import Any

from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

# Keys of a group node that describe the option (for labels and run directories) rather than the object.
METADATA_KEYS = ("name", "label")


def _strip_metadata(cfg: Any) -> Any:
    """The config without the metadata keys of every node that builds an object (has a ``_target_``)."""
    if isinstance(cfg, dict):
        return {k: _strip_metadata(v) for k, v in cfg.items() if not ("_target_" in cfg and k in METADATA_KEYS)}
    if isinstance(cfg, list):
        return [_strip_metadata(v) for v in cfg]
    return cfg


def build(node: DictConfig | dict[str, Any], **runtime: Any) -> Any:
    """Instantiate a group node's ``_target_``, without its metadata keys (at every level, so a node may hold another
    group's node, e.g. a novelty term its ``estimator``), passing ``runtime`` keyword arguments."""
    cfg = OmegaConf.to_container(node, resolve=True, enum_to_str=True) if isinstance(node, DictConfig) else node
    assert isinstance(cfg, dict)
    cfg = {k: v for k, v in _strip_metadata(cfg).items() if k not in METADATA_KEYS}
    # Runtime objects (a whole DictConfig, tensors) are passed to the built partial, not merged into the config.
    return instantiate(cfg, _partial_=True)(**runtime)


def choice(value: Any) -> str:
    """The string of a config choice, whether stored as an Enum or as a plain string."""
    return value.value if isinstance(value, Enum) else str(value)
