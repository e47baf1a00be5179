"""A double-DQN agent driven by a pluggable intrinsic reward: how the ICM and RND baselines act.

The Q-function sits on a learned latent of the same size as the paper's agent (``internal_dim``), from the same
encoder architecture (``encoder`` group), trained by TD only; targets are r_ext + r_int with r_int from the
intrinsic-reward module; actions are greedy in Q (ε = ``epsilon``, 0 as in NSRS's baselines), after the same random
warm-up and with the same training schedule (``budget``) as every other agent, so only the exploration method differs.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig

from curiosity.agents.base import Agent
from curiosity.agents.paper import obs_shape_of
from curiosity.agents.q_learning import QLearner
from curiosity.agents.representation import check_finite
from curiosity.agents.schedule import TrainSchedule
from curiosity.config.build import build, choice
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.replay import ReplayBuffer
from curiosity.types import TransitionBatch

Q_AGENT_KEYS = ("intrinsic/reward", "losses/q", "train/iterations", "timing/train_ms", "q/max")


class IntrinsicQAgent(Agent):
    """Greedy double-DQN on r_ext + r_int.

    Args:
        cfg: the run config (``internal_dim``, ``encoder``, ``optimizer``, ``batch_size``, ``budget``, ...).
        intrinsic: a factory ``intrinsic(obs_shape=...) -> IntrinsicReward`` (e.g. ``ICM.from_obs_shape``).
        epsilon: probability of a uniformly random action after the warm-up.
        gamma: discount of the Q-learning.
    """

    def __init__(self, cfg: DictConfig, intrinsic: Callable[..., IntrinsicReward], epsilon: float = 0.0,
                 gamma: float = 0.8) -> None:  # fmt: skip
        self.cfg, self.label = cfg, str(cfg.method_label)
        self.n_actions, self.epsilon = int(cfg.env.n_actions), float(epsilon)
        obs_shape = obs_shape_of(cfg.env)
        self.encoder = build(cfg.encoder)
        self.q = QLearner(self.encoder, cfg.internal_dim, self.n_actions, gamma=gamma, target_every=cfg.q_target_every,
                          huber=cfg.q_huber)  # fmt: skip
        self.optimizer = build(cfg.optimizer, params=[*self.encoder.parameters(), *self.q.q.parameters()])
        self.intrinsic = intrinsic(obs_shape=obs_shape)
        self.replay = ReplayBuffer(cfg.replay_capacity, obs_shape, pixel_uint8=choice(cfg.env.obs) == "pixels")
        b = cfg.budget
        self.schedule = TrainSchedule(b.warmup_steps, b.train_every, b.iters_per_train, b.ramp)
        self.rng = np.random.default_rng([int(cfg.seed), 3])
        self.metric_keys = Q_AGENT_KEYS + self.intrinsic.log_keys
        self._q_max = 0.0

    def act(self, obs: np.ndarray, step: int) -> int:
        if self.epsilon > 0 and self.rng.random() < self.epsilon:
            return int(self.rng.integers(self.n_actions))
        with torch.no_grad():
            q = self.q.values(self.encoder(torch.as_tensor(obs).unsqueeze(0)))[0]
        self._q_max = float(q.max())
        return int(torch.argmax(q))

    def observe(self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool,
                step: int) -> dict[str, float]:  # fmt: skip
        self.replay.add(obs, action, reward, next_obs, terminated)
        fresh = TransitionBatch(torch.as_tensor(obs).unsqueeze(0), torch.tensor([action]),
                                torch.as_tensor(next_obs).unsqueeze(0), torch.tensor([reward], dtype=torch.float32),
                                torch.tensor([float(terminated)]))  # fmt: skip
        logs = {"intrinsic/reward": float(self.intrinsic(fresh)[0]), "q/max": self._q_max}
        self.intrinsic.observe(fresh)
        iterations = self.schedule.iterations(step)
        if iterations:
            start = time.perf_counter()
            sums: dict[str, float] = {}
            for _ in range(iterations):
                for k, v in self._iteration().items():
                    sums[k] = sums.get(k, 0.0) + v
            logs.update({k: v / iterations for k, v in sums.items()})
            logs.update({"train/iterations": float(iterations), "timing/train_ms": 1e3 * (time.perf_counter() - start)})
        return logs

    def _iteration(self) -> dict[str, float]:
        batch = self.replay.sample_transitions(self.cfg.batch_size, self.rng)
        with torch.no_grad():
            r_int = self.intrinsic(batch)
            z_next = self.encoder(batch.next_obs)
        loss = self.q.loss(self.encoder(batch.obs), batch.act, batch.rewards + r_int, z_next, batch.next_obs,
                           batch.terminateds)  # fmt: skip
        check_finite("losses/q", loss)
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        self.optimizer.step()
        self.q.after_update()
        return {"losses/q": loss.item(), **self.intrinsic.update(batch)}

    def state_dict(self) -> dict[str, Any]:
        return {"encoder": self.encoder.state_dict(), "q": self.q.state_dict(), "optimizer": self.optimizer.state_dict(),
                "intrinsic": self.intrinsic.state_dict(), "replay": self.replay.state_dict(),
                "schedule": self.schedule.state_dict(), "rng": self.rng.bit_generator.state}  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.encoder.load_state_dict(state["encoder"])
        self.q.load_state_dict(state["q"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.intrinsic.load_state_dict(state["intrinsic"])
        self.replay.load_state_dict(state["replay"])
        self.schedule.load_state_dict(state["schedule"])
        self.rng.bit_generator.state = state["rng"]
