"""Agents: objects that pick actions and learn from the transitions they observe."""

from curiosity.agents.base import Agent

__all__ = ["Agent"]
