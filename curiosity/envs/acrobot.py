"""Acrobot-v1 (docs/protocol.md §1): its adapter, with the directed action and the mechanical energy.

Acrobot cannot be solved without pumping energy into the two links, so "does the agent push with the motion?" (the
directed action) and "does its novelty point towards higher energy?" (``analysis.landscape``) are task-level checks of
an exploration signal. Without torque the energy is conserved (up to the integrator's error).
"""

from __future__ import annotations

import numpy as np

from curiosity.envs.adapter import EnvAdapter, with_sign

G = 9.8


def directed(state: np.ndarray) -> int | None:
    """Torque in the direction of the second joint's velocity: action 2 (+1) if θ̇2 > 0, action 0 (−1) if θ̇2 < 0."""
    return with_sign(float(state[3]))


def energy(state: np.ndarray) -> np.ndarray:
    """Total mechanical energy of gymnasium's Acrobot (its masses, lengths, inertias and g), J.

    state: (..., 4) θ1, θ2, θ̇1, θ̇2 -> (...). E = ½ q̇ᵀ M(θ2) q̇ − (m1 lc1 + m2 l1) g cos θ1 − m2 lc2 g cos(θ1 + θ2);
    −(m1 lc1 + m2 l1 + m2 lc2) g = −14.7 J hanging at rest.
    """
    m1 = m2 = l1 = 1.0
    lc1 = lc2 = 0.5
    i1 = i2 = 1.0
    th1, th2, d1, d2 = np.moveaxis(np.asarray(state, dtype=np.float64), -1, 0)
    m11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * np.cos(th2)) + i1 + i2
    m12 = m2 * (lc2**2 + l1 * lc2 * np.cos(th2)) + i2
    m22 = m2 * lc2**2 + i2
    kinetic = 0.5 * m11 * d1**2 + m12 * d1 * d2 + 0.5 * m22 * d2**2
    potential = -(m1 * lc1 + m2 * l1) * G * np.cos(th1) - m2 * lc2 * G * np.cos(th1 + th2)
    return kinetic + potential


class AcrobotAdapter(EnvAdapter):
    """Acrobot-v1: termination is the goal; physical state (θ1, θ2, θ̇1, θ̇2)."""

    directed_action = staticmethod(directed)
    energy = staticmethod(energy)
    noop_action = 1  # zero torque
