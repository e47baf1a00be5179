"""Baseline intrinsic rewards behind :class:`~curiosity.intrinsic.base.IntrinsicReward`: ICM and RND (torch only)."""

from curiosity.baselines.icm import ICM
from curiosity.baselines.rnd import RND

__all__ = ["ICM", "RND"]
