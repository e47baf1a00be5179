"""A double-DQN agent driven by a pluggable intrinsic reward: how the ICM and RND baselines act.

The Q-function sits on a learned latent of the same size as the paper's agent (``agent.internal_dim``), from the same
encoder architecture (``encoder`` group), trained by TD only; targets are r_ext + r_int with r_int from the
intrinsic-reward module; actions are greedy in Q (ε = ``epsilon``, 0 as in NSRS's baselines), after the same random
warm-up and with the same training schedule (``budget``) as every other agent, so only the exploration method differs.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig

from curiosity.agents.base import Agent
from curiosity.agents.paper import obs_shape_of
from curiosity.agents.q_learning import QLearner
from curiosity.agents.representation import check_finite
from curiosity.agents.schedule import TrainSchedule
from curiosity.build import build, choice
from curiosity.intrinsic.base import IntrinsicContext
from curiosity.intrinsic.mixture import Mixture
from curiosity.replay import ReplayBuffer
from curiosity.types import TransitionBatch

Q_AGENT_KEYS = ("intrinsic/reward", "losses/q", "train/iterations", "timing/train_ms", "q/max")


class IntrinsicQAgent(Agent):
    """Greedy double-DQN on r_ext + r_int.

    Args:
        cfg: the run config (``agent.*``, ``encoder``, ``budget``, ``intrinsic``
            (the reward, built with this agent's encoder and replay; no world model, so no prediction-error term), ...).
        epsilon: probability of a uniformly random action after the warm-up.
        gamma: discount of the Q-learning.
    """

    model_free_intrinsic = True

    def __init__(self, cfg: DictConfig, epsilon: float = 0.0, gamma: float = 0.8) -> None:
        self.cfg, self.label = cfg, str(cfg.method_label)
        self.n_actions, self.epsilon = int(cfg.env.n_actions), float(epsilon)
        obs_shape = obs_shape_of(cfg.env)
        self.encoder = build(cfg.encoder)
        own = cfg.agent  # internal_dim, q_target_every, q_huber, optimizer, replay_capacity, batch_size
        self.q = QLearner(self.encoder, own.internal_dim, self.n_actions, gamma=gamma, target_every=own.q_target_every,
                          huber=own.q_huber)  # fmt: skip
        self.optimizer = build(own.optimizer, params=[*self.encoder.parameters(), *self.q.q.parameters()])
        self.replay = ReplayBuffer(own.replay_capacity, obs_shape, pixel_uint8=choice(cfg.env.obs) == "pixels")
        context = IntrinsicContext(n_actions=self.n_actions, obs_shape=obs_shape, latent_dim=own.internal_dim,
                                   warmup_steps=cfg.budget.warmup_steps, seed=int(cfg.seed), replay=self.replay,
                                   encode=self._encode_eval)  # fmt: skip
        self.intrinsic: Mixture = build(cfg.intrinsic, context=context)
        b = cfg.budget
        self.schedule = TrainSchedule(b.warmup_steps, b.train_every, b.iters_per_train, b.ramp)
        self.rng = np.random.default_rng([int(cfg.seed), 3])
        self.metric_keys = Q_AGENT_KEYS + self.intrinsic.log_keys
        self._q_max = 0.0

    @torch.no_grad()
    def _encode_eval(self, obs: torch.Tensor) -> torch.Tensor:
        """The Q encoder's latents, (B, *obs_shape) -> (B, internal_dim), in eval mode without gradient."""
        was_training = self.encoder.training
        self.encoder.eval()
        try:
            return self.encoder(obs)
        finally:
            self.encoder.train(was_training)

    def _with_latents(self, batch: TransitionBatch) -> TransitionBatch:
        """The batch with the encoder's latents of o_t and o_{t+1} when the reward reads latents."""
        if not self.intrinsic.needs_latents:
            return batch
        return batch.with_latents(self._encode_eval(batch.obs), self._encode_eval(batch.next_obs))

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
                                torch.tensor([float(terminated)]),
                                index=torch.tensor([self.replay.total_added - 1]))  # fmt: skip
        fresh = self._with_latents(fresh)
        logs = {"q/max": self._q_max}
        logs.update(self.intrinsic.transition_logs(fresh))
        logs.update(self.intrinsic.observe(fresh))
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
        batch = self._with_latents(self.replay.sample_transitions(self.cfg.agent.batch_size, self.rng))
        with torch.no_grad():
            r_int = self.intrinsic(batch) if self.intrinsic.ready else torch.zeros_like(batch.rewards)
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
        saved = state["intrinsic"]
        if "nets" in saved:  # saved before rewards were mixtures: the one reward's own state
            saved = {next(iter(self.intrinsic.terms)): saved}
        self.intrinsic.load_state_dict(saved)
        self.replay.load_state_dict(state["replay"])
        self.schedule.load_state_dict(state["schedule"])
        self.rng.bit_generator.state = state["rng"]
