"""Novelty scores and intrinsic rewards of the paper (§3.3), as pure torch functions (imports torch and numpy only).

- Densities and distances over a memory: :func:`kde_log_density`, :func:`knn_distance`, :func:`nsrs_knn_score`,
  :func:`k_smallest_sq_dists` (all exact, chunked over the memory).
- Scores: :class:`KDENoveltyReward` (random-phase baselines ``scalar`` / ``pointwise`` / ``printed`` / ``zscore`` /
  ``none``) and the named score functions it uses; the agents' estimators (:mod:`curiosity.novelty.estimators`, the
  ``estimator`` group) build on it: ``KDENovelty`` is a ``KDENoveltyReward`` with a bandwidth rule. (The
  prediction-error bonus and the hybrid are intrinsic rewards: :mod:`curiosity.intrinsic`.)
- :class:`EmbeddingMemory`: exact or fixed-size reservoir memory with re-embedding.
"""

from curiosity.novelty.kde import kde_log_density
from curiosity.novelty.knn import k_smallest_sq_dists, knn_distance, nsrs_knn_score
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.rewards import (
    BASELINES,
    KDENoveltyReward,
    kde_reward_none,
    kde_reward_pointwise,
    kde_reward_printed,
    kde_reward_scalar,
    kde_reward_zscore,
)

__all__ = [
    "BASELINES",
    "EmbeddingMemory",
    "KDENoveltyReward",
    "k_smallest_sq_dists",
    "kde_log_density",
    "kde_reward_none",
    "kde_reward_pointwise",
    "kde_reward_printed",
    "kde_reward_scalar",
    "kde_reward_zscore",
    "knn_distance",
    "nsrs_knn_score",
]
