"""Environments: gymnasium classic control as one continuing episode, from pixels or from the state vector."""

from curiosity.envs import chain as _chain  # noqa: F401  (registers curiosity/Chain-v0)
from curiosity.envs.coverage import GridCoverage
from curiosity.envs.make import make_env, physical_state

__all__ = ["GridCoverage", "make_env", "physical_state"]
