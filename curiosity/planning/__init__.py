"""Planners: sampling MPC (paper text) and the NSRS novelty + Q tree (precursor code)."""

from curiosity.planning.mpc import MPCPlanner
from curiosity.planning.qtree import QTreePlanner

__all__ = ["MPCPlanner", "QTreePlanner"]
