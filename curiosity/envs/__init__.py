"""Environments: gymnasium classic control as one continuing episode, from pixels or from the state vector, each
described by its adapter (:mod:`curiosity.envs.adapter`)."""

from curiosity.envs import chain as _chain  # noqa: F401  (registers curiosity/Chain-v0)
from curiosity.envs.adapter import EnvAdapter, adapter_of
from curiosity.envs.coverage import GridCoverage
from curiosity.envs.make import make_env

__all__ = ["EnvAdapter", "GridCoverage", "adapter_of", "make_env"]
