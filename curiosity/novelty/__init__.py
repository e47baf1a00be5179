"""Novelty scores and intrinsic rewards of the paper (§3.3), as pure torch functions (imports torch and numpy only).

- Densities and distances over a memory: :func:`kde_log_density`, :func:`knn_distance`, :func:`nsrs_knn_score`,
  :func:`k_smallest_sq_dists` (all exact, chunked over the memory).
- Rewards: :class:`KDENoveltyReward` (random-phase baselines ``scalar`` / ``pointwise`` / ``printed`` / ``zscore`` /
  ``none``), :class:`PredictionErrorBonus` (log1p(e / (ē + ε)), running mean), :func:`hybrid_intrinsic_reward`, and
  the named reward functions they use.
- :class:`EmbeddingMemory`: exact or fixed-size reservoir memory with re-embedding.
"""

from curiosity.novelty.kde import kde_log_density
from curiosity.novelty.knn import k_smallest_sq_dists, knn_distance, nsrs_knn_score
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.novelty.rewards import (
    BASELINES,
    KDENoveltyReward,
    PredictionErrorBonus,
    hybrid_intrinsic_reward,
    kde_reward_none,
    kde_reward_pointwise,
    kde_reward_printed,
    kde_reward_scalar,
    kde_reward_zscore,
    prediction_error_bonus,
    squared_prediction_error,
)

__all__ = [
    "BASELINES",
    "EmbeddingMemory",
    "KDENoveltyReward",
    "PredictionErrorBonus",
    "hybrid_intrinsic_reward",
    "k_smallest_sq_dists",
    "kde_log_density",
    "kde_reward_none",
    "kde_reward_pointwise",
    "kde_reward_printed",
    "kde_reward_scalar",
    "kde_reward_zscore",
    "knn_distance",
    "nsrs_knn_score",
    "prediction_error_bonus",
    "squared_prediction_error",
]
