"""Planners behind one interface (:class:`Planner`: ``plan(PlanRequest) -> Plan``): sampling MPC (paper text) and
the NSRS novelty + Q tree (precursor code)."""

from curiosity.planning.mpc import MPCPlanner
from curiosity.planning.protocols import Plan, Planner, PlanRequest
from curiosity.planning.qtree import QTreePlanner

__all__ = ["MPCPlanner", "Plan", "PlanRequest", "Planner", "QTreePlanner"]
