"""Build objects from config nodes with ``hydra.utils.instantiate``."""

from __future__ import annotations

from enum import Enum
from typing import Any

from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

# Keys of a group node that describe the option (for labels and run directories) rather than the object.
METADATA_KEYS = ("name", "label")


def build(node: DictConfig, **runtime: Any) -> Any:
    """Instantiate a group node's ``_target_``, without its metadata keys, passing ``runtime`` keyword arguments."""
    cfg = OmegaConf.to_container(node, resolve=True, enum_to_str=True)
    assert isinstance(cfg, dict)
    for key in METADATA_KEYS:
        cfg.pop(key, None)
    # Runtime objects (a whole DictConfig, tensors) are passed to the built partial, not merged into the config.
    return instantiate(cfg, _partial_=True)(**runtime)


def choice(value: Any) -> str:
    """The string of a config choice, whether stored as an Enum or as a plain string."""
    return value.value if isinstance(value, Enum) else str(value)
