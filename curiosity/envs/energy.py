"""Mechanical energy of the classic-control tasks: what an exploring agent must build up to reach their goals.

Neither Acrobot nor MountainCar can be solved without pumping energy into the system, so "does the agent's novelty
point towards higher energy?" is a task-level check of an exploration signal (``analysis.landscape``). Only the
agent's actions change these energies: without torque or push they are conserved (up to the integrator's error).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

G = 9.8


def acrobot(state: np.ndarray) -> np.ndarray:
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


def mountaincar(state: np.ndarray) -> np.ndarray:
    """Energy per unit mass of gymnasium's MountainCar: ½ v² + (0.0025 / 3) sin(3x) (its gravity term is
    −0.0025 cos(3x) per step). state: (..., 2) position, velocity -> (...)."""
    x, v = np.moveaxis(np.asarray(state, dtype=np.float64), -1, 0)
    return 0.5 * v**2 + 0.0025 / 3 * np.sin(3 * x)


ENERGY: dict[str, Callable[[np.ndarray], np.ndarray]] = {"Acrobot-v1": acrobot, "MountainCar-v0": mountaincar}


def energy_fn(env_id: str) -> Callable[[np.ndarray], np.ndarray] | None:
    """The energy function of env ``env_id``, or None for an env without one (e.g. the chain)."""
    return ENERGY.get(env_id)
