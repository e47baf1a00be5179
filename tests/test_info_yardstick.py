"""The common yardstick of latent spread: log det(Cov(z) + ridge·I) of a batch of next latents."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from curiosity.info import latent_logdet


def test_logdet_of_a_known_covariance() -> None:
    z = torch.tensor([[1.0, 0.0], [-1.0, 0.0], [0.0, 2.0], [0.0, -2.0]])  # Cov = diag(2/3, 8/3), ddof = 1
    assert latent_logdet(z, ridge=0.0) == pytest.approx(math.log(2 / 3) + math.log(8 / 3), rel=1e-12)
    assert latent_logdet(z, ridge=0.5) == pytest.approx(math.log(2 / 3 + 0.5) + math.log(8 / 3 + 0.5), rel=1e-12)


def test_logdet_agrees_with_numpy_and_grows_with_spread() -> None:
    z = torch.randn(64, 4, generator=torch.Generator().manual_seed(0))
    expected = np.linalg.slogdet(np.cov(z.numpy().astype(np.float64), rowvar=False) + 1e-3 * np.eye(4))[1]
    assert latent_logdet(z) == pytest.approx(expected, rel=1e-9)
    assert latent_logdet(3 * z) > latent_logdet(z)  # spreading the batch raises it by about 4 log 9


def test_a_collapsed_batch_is_bounded_below_by_the_ridge_and_a_single_point_is_refused() -> None:
    assert latent_logdet(torch.ones(8, 3), ridge=1e-3) == pytest.approx(3 * math.log(1e-3), rel=1e-12)
    with pytest.raises(ValueError, match="B >= 2"):
        latent_logdet(torch.ones(1, 3))
