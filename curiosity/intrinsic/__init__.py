"""Intrinsic rewards behind one interface: ``compute(batch) -> (B,)`` and ``update(batch) -> dict``."""

from curiosity.intrinsic.base import IntrinsicReward

__all__ = ["IntrinsicReward"]
