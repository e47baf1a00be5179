"""Offline check (not part of the package): is the velocity in the trained pixel latent but too small for its distances?

    python -m studies.agent_study.pixel_encoder.whitened COEF [OVERRIDES...] --seeds 0,1 [--train-iters 1000] --json OUT.json

``studies.encoder_geometry``'s check with the arrow-of-time term at weight COEF
(``studies.agent_study.pixel_encoder.arrow_of_time``; COEF 0: the default representation loss) and these metrics per
encoder: ``studies.encoder_geometry.geometry``'s, with ``rho_velocity_white`` and ``rho_pose_white`` the check's
``rho_velocity`` and ``rho_pose`` of the latents whitened by their own covariance (then standardised per coordinate,
as the check does: every direction of the latent weighs alike), and ``r2_velocity_linear`` (the share of the variance
of θ̇1, θ̇2 a least-squares linear map of the latent explains, fitted on half the states and scored on the other half).
"""

from __future__ import annotations

import numpy as np

from studies import encoder_geometry
from studies.agent_study.pixel_encoder.arrow_of_time import parse, run


def geometry(latents: np.ndarray, vectors: np.ndarray, n_velocity: int) -> dict[str, float]:
    """The metrics of the module docstring: latents (n, d), state vectors (n, S), the last ``n_velocity`` velocities."""
    row = encoder_geometry.geometry(latents, vectors, n_velocity)
    white = encoder_geometry.geometry(encoder_geometry.whitened(latents), vectors, n_velocity)
    return {**{k: row[k] for k in ("rho_all", "rho_pose", "rho_velocity", "knn")},
            "rho_velocity_white": white["rho_velocity"], "rho_pose_white": white["rho_pose"],
            "r2_velocity_linear": row["r2_velocity_linear"]}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    coef, rest = parse("python -m studies.agent_study.pixel_encoder.whitened", __doc__.splitlines()[0], argv)
    return run(coef, rest, geometry)


if __name__ == "__main__":
    raise SystemExit(main())
