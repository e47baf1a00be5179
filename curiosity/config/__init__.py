"""Configuration: typed schemas (registered with Hydra's ConfigStore), validation, seed ranges, object building."""

from curiosity.build import build, choice
from curiosity.config.resolvers import register_resolvers
from curiosity.config.schema import register_schemas
from curiosity.config.validate import ConfigError, sampled_candidates, validate

__all__ = [
    "ConfigError",
    "build",
    "choice",
    "register_resolvers",
    "register_schemas",
    "sampled_candidates",
    "setup",
    "validate",
]


def setup() -> None:
    """Register the schemas and resolvers that ``conf/`` needs; call before composing a config."""
    register_schemas()
    register_resolvers()
