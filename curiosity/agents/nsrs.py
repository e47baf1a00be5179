"""The NSRS baseline (Tao et al. 2020) as nsrs-protocol.md §3–§5 describes its code, with the subtree fix.

NSRS is the paper's agent with NSRS's own parts: kNN novelty of latent states (squared distances, nearest dropped),
Gaussian-potential dispersion, a 1-step transition loss, double DQN on extrinsic + intrinsic reward with TD into the
encoder, and the exhaustive depth-5 tree planner with Q at the leaves. Those settings (``baseline.settings``) are
applied over the run config before it is resolved, so the ``entropy``/``estimator``/``planner`` groups do not change
the baseline, and the ``intrinsic`` group's novelty term (which follows ``estimator``, ``novelty_input``, ...) takes
NSRS's values.
"""

from __future__ import annotations

from typing import Any

from omegaconf import DictConfig, OmegaConf

from curiosity.agents.paper import PaperAgent


class NSRSAgent(PaperAgent):
    """:class:`PaperAgent` built from the run config with ``settings`` merged over it."""

    def __init__(self, cfg: DictConfig, settings: DictConfig | dict[str, Any]) -> None:
        merged = OmegaConf.create(OmegaConf.to_container(cfg, resolve=False, enum_to_str=True))
        for key, value in OmegaConf.to_container(OmegaConf.create(settings), resolve=False).items():
            merged[key] = value  # whole nodes are replaced, not merged: NSRS's parts are not the groups' options
        resolved = OmegaConf.create(OmegaConf.to_container(merged, resolve=True))
        super().__init__(resolved)
