"""Information-theoretic functions of the paper, as pure torch functions (imports torch and numpy only).

- Matrix-based Rényi α-entropy, joint entropy and mutual information (§3.6): :func:`renyi_entropy`,
  :func:`renyi_joint_entropy`, :func:`renyi_mutual_information`, :func:`matrix_renyi_entropy`.
- Gaussian-potential dispersion loss L_unif (§3.4.2): :func:`gaussian_potential`.
- Backward stochastic predictor NLL (§3.5): :func:`backward_predictor_nll`.
- Kernel Gram matrix (float64): :func:`gram_matrix`.
- Log-determinant of a latent batch's covariance, the runs' common yardstick of spread: :func:`latent_logdet`.
"""

from curiosity.info.backward import backward_predictor_nll
from curiosity.info.kernels import gram_matrix
from curiosity.info.potential import gaussian_potential
from curiosity.info.renyi import (
    matrix_renyi_entropy,
    renyi_entropy,
    renyi_joint_entropy,
    renyi_mutual_information,
)
from curiosity.info.yardstick import latent_logdet

__all__ = [
    "backward_predictor_nll",
    "gaussian_potential",
    "gram_matrix",
    "latent_logdet",
    "matrix_renyi_entropy",
    "renyi_entropy",
    "renyi_joint_entropy",
    "renyi_mutual_information",
]
