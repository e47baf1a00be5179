"""Offline check (not part of the package): is the velocity in the trained pixel latent but too small for its distances?

``analysis.encoder_geometry``'s metrics, plus, per encoder: ``rho_velocity_white`` (the same Spearman correlation with
the latents whitened by their own covariance instead of standardised per coordinate, so every direction of the latent
weighs alike) and ``r2_velocity_linear`` (the share of the variance of θ̇1, θ̇2 a least-squares linear map of the
latent explains, fitted on half the states and scored on the other half).

    python whitened.py COEF [ENCODER_GEOMETRY ARGS...]

COEF 0: the default representation loss; COEF > 0: with ``../arrow_of_time/``'s term at that weight.
"""

import runpy
import sys
from pathlib import Path

import numpy as np

import analysis.encoder_geometry as geo

plain = geo.geometry


def whitened(z: np.ndarray) -> np.ndarray:
    z = z - z.mean(0)
    evals, evecs = np.linalg.eigh(np.cov(z, rowvar=False))
    return z @ evecs / np.sqrt(np.maximum(evals, 1e-12 * evals.max()))


def linear_r2(z: np.ndarray, y: np.ndarray) -> float:
    half = len(z) // 2
    x = np.c_[z, np.ones(len(z))]
    w, *_ = np.linalg.lstsq(x[:half], y[:half], rcond=None)
    resid = y[half:] - x[half:] @ w
    return float(1 - (resid**2).sum() / ((y[half:] - y[half:].mean(0)) ** 2).sum())


def geometry(latents: np.ndarray, vectors: np.ndarray, n_velocity: int) -> dict[str, float]:
    row = plain(latents, vectors, n_velocity)
    white = plain(whitened(latents), vectors, n_velocity)
    row["rho_velocity_white"] = white["rho_velocity"]
    row["rho_pose_white"] = white["rho_pose"]
    row["r2_velocity_linear"] = linear_r2(latents, vectors[:, -n_velocity:])
    return row


geo.geometry = geometry
here = Path(__file__).resolve().parent
sys.argv = [str(here.parent / "arrow_of_time" / "arrow_of_time.py"), *sys.argv[1:]]
runpy.run_path(sys.argv[0], run_name="__main__")
