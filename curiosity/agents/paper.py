"""The paper's agent (``baseline=none``): an IB-shaped latent world model, latent curiosity, and planning.

Both readings of the paper (method.md §0) are this one class with different config: ``planner=mpc`` plans with the
world model's reward model and the hybrid curiosity reward (paper text); ``planner=qtree`` searches NSRS's tree of
edge novelties with a double-DQN Q at the leaves, trained on extrinsic + intrinsic reward (precursor code).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import torch
from omegaconf import DictConfig

from curiosity.agents.base import Agent
from curiosity.agents.curiosity import CURIOSITY_KEYS, LatentCuriosity
from curiosity.agents.q_learning import QLearner
from curiosity.agents.representation import LOSS_KEYS, LossWeights, check_finite, encode_segments, representation_loss
from curiosity.agents.schedule import TrainSchedule
from curiosity.agents.world_model import WorldModel
from curiosity.config.build import build, choice
from curiosity.nets.backward import BackwardPredictor
from curiosity.nets.reward import RewardModel
from curiosity.nets.transition import ResidualTransition
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.replay import ReplayBuffer

AGENT_KEYS = ("intrinsic/reward", "losses/q", "train/iterations", "planner/score", "planner/entropy",
              "timing/train_ms", "timing/refresh_ms", "timing/plan_ms")  # fmt: skip


def obs_shape_of(env_cfg: DictConfig) -> tuple[int, ...]:
    """Observation shape an ``env`` node produces: (frame_stack, size, size) for pixels, (state_dim,) for states."""
    if choice(env_cfg.obs) == "pixels":
        return (env_cfg.frame_stack, env_cfg.frame_size, env_cfg.frame_size)
    return (env_cfg.state_dim,)


def build_world_model(cfg: DictConfig) -> WorldModel:
    """Encoder (``encoder`` group), residual transition, reward model (if λ_R > 0), backward predictor (if on)."""
    d, n_actions = cfg.internal_dim, cfg.env.n_actions
    reward = RewardModel(d, n_actions) if cfg.reward_coef > 0 else None
    b = cfg.backward
    backward = BackwardPredictor(d, n_actions, n_candidates=b.n_candidates, noise_dim=b.noise_dim,
                                 hidden=b.hidden) if b.coef > 0 else None  # fmt: skip
    transition = ResidualTransition(d, n_actions, hidden=cfg.transition_hidden, dropout=cfg.transition_dropout)
    return WorldModel(build(cfg.encoder), transition, n_actions, reward, backward)


class PaperAgent(Agent):
    """IB latent world model + hybrid latent curiosity + MPC (or Q-tree) planning, trained on a schedule."""

    def __init__(self, cfg: DictConfig) -> None:
        self.cfg, self.label = cfg, str(cfg.method_label)
        self.n_actions = int(cfg.env.n_actions)
        self.obs_pixels = choice(cfg.env.obs) == "pixels"
        self.model = build_world_model(cfg)
        self.regulariser = build(cfg.entropy)
        self.weights = LossWeights(transition=cfg.transition_coef, reward=cfg.reward_coef, backward=cfg.backward.coef,
                                   sigma_b=cfg.backward.sigma_b, normalised_transition=cfg.normalised_transition,
                                   detach_targets=cfg.detach_targets)  # fmt: skip
        self.planner = build(cfg.planner)
        self.q = (QLearner(self.model.encoder, cfg.internal_dim, self.n_actions, gamma=cfg.planner.gamma,
                           target_every=cfg.q_target_every, huber=cfg.q_huber)
                  if getattr(self.planner, "uses_q", False) else None)  # fmt: skip
        params = list(self.model.parameters()) + (list(self.q.q.parameters()) if self.q else [])
        self.optimizer = build(cfg.optimizer, params=params)
        self.replay = ReplayBuffer(cfg.replay_capacity, obs_shape_of(cfg.env), pixel_uint8=self.obs_pixels)
        memory = EmbeddingMemory(mode=choice(cfg.memory_mode), reservoir_size=cfg.memory_size, seed=cfg.seed)
        self.curiosity = LatentCuriosity(
            self.model, build(cfg.estimator), self.replay, memory, n_actions=self.n_actions,
            novelty_input=choice(cfg.novelty_input), action_scale=cfg.action_scale, alpha=cfg.hybrid_alpha,
            pe_average=choice(cfg.pe_average), pe_eps=cfg.pe_eps, dropout_samples=cfg.pe_dropout_samples,
            warmup_steps=cfg.budget.warmup_steps, standardise=cfg.standardise_latents,
        )  # fmt: skip
        b = cfg.budget
        self.schedule = TrainSchedule(b.warmup_steps, b.train_every, b.iters_per_train, b.ramp, b.early_stop_every,
                                      b.early_stop_threshold)  # fmt: skip
        self.rng = np.random.default_rng([int(cfg.seed), 2])
        self.generator = torch.Generator().manual_seed(int(cfg.seed))
        self.metric_keys = (*LOSS_KEYS, *CURIOSITY_KEYS, *AGENT_KEYS, *getattr(self.curiosity.estimator, "log_keys", ()))
        self._plan_logs: dict[str, float] = {}

    # ------------------------------------------------------------------ acting
    def _plan(self, z0: torch.Tensor) -> tuple[int, dict[str, float]]:
        cur, model = self.curiosity, self.model
        if self.q is not None:
            return self.planner.plan(z0, model.next, cur.imagined, self.q.values)
        reward_fn = model.reward if model.reward_model is not None else None
        return self.planner.plan(z0, model.next, reward_fn, cur.imagined, self.generator)

    def act(self, obs: np.ndarray, step: int) -> int:
        start = time.perf_counter()
        with self.model.evaluating():
            z0 = self.model.encode(torch.as_tensor(obs).unsqueeze(0))[0]
            check_finite("latent", z0)
            action, info = self._plan(z0)
        score = info.get("chosen_score", info.get("best_value", 0.0))
        self._plan_logs = {"planner/score": score, "planner/entropy": info.get("entropy", 0.0),
                           "timing/plan_ms": 1e3 * (time.perf_counter() - start)}  # fmt: skip
        return action

    # ------------------------------------------------------------------ learning
    def observe(self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool,
                step: int) -> dict[str, float]:  # fmt: skip
        self.replay.add(obs, action, reward, next_obs, terminated)
        with self.model.evaluating():
            z = self.model.encode(torch.as_tensor(np.stack([obs, next_obs])))
        check_finite("latent", z)
        cur, a = self.curiosity, torch.tensor([action])
        cur.add(z[0], action, self.replay.total_added - 1)
        logs: dict[str, float] = dict(self._plan_logs)
        self._plan_logs = {}
        if cur.ready:
            r_int, parts = cur.from_latents(z[:1], a, z[1:])
            cur.observe_latents(z[:1], a, z[1:])
            logs.update(parts, **{"intrinsic/reward": float(r_int[0])})
        if self._refresh_due(step):
            start = time.perf_counter()
            cur.refresh()
            logs.update(getattr(cur.estimator, "logs", {}), **{"timing/refresh_ms": 1e3 * (time.perf_counter() - start)})
        iterations = self.schedule.iterations(step)
        if iterations:
            logs.update(self._train(iterations))
        return logs

    def _refresh_due(self, step: int) -> bool:
        since = step + 1 - self.cfg.budget.warmup_steps
        return since >= 0 and since % self.cfg.memory_refresh_every == 0

    def _train(self, iterations: int) -> dict[str, float]:
        start = time.perf_counter()
        sums: dict[str, float] = {}
        window: list[float] = []
        done = 0
        self.model.train()
        for done in range(1, iterations + 1):
            logs, eval_error = self._iteration()
            for k, v in logs.items():
                sums[k] = sums.get(k, 0.0) + v
            window.append(eval_error)
            if self.schedule.stop_early(done, window):
                break
            if self.schedule.early_stop_every and done % self.schedule.early_stop_every == 0:
                window = []
        out = {k: v / done for k, v in sums.items()}
        out.update({"train/iterations": float(done), "timing/train_ms": 1e3 * (time.perf_counter() - start)})
        return out

    def _iteration(self) -> tuple[dict[str, float], float]:
        seg = self.replay.sample_segments(self.cfg.batch_size, self.cfg.n_step, self.rng)
        enc = encode_segments(self.model, seg)
        loss, logs = representation_loss(self.model, seg, enc, self.regulariser, self.weights)
        if self.q is not None:
            z, z_next, act = enc.z[:, 0], enc.z[:, 1], seg.act[:, 0]
            r_int, _ = self.curiosity.from_latents(z.detach(), act, z_next.detach())
            q_loss = self.q.loss(z, act, seg.rewards[:, 0] + r_int, z_next, seg.obs[:, 1], seg.terminateds[:, 0])
            check_finite("losses/q", q_loss)
            loss = loss + self.cfg.q_coef * q_loss
            logs["losses/q"] = q_loss.item()
        check_finite("losses/total", loss)
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        self.optimizer.step()
        if self.q is not None:
            self.q.after_update()
        eval_error = 0.0
        if self.schedule.early_stop_every:
            with self.model.evaluating():
                eval_error = float((self.model.next(enc.z[:, 0], seg.act[:, 0]) - enc.z[:, 1]).square().sum(1).mean())
        return logs, eval_error

    # ------------------------------------------------------------------ checkpointing
    def state_dict(self) -> dict[str, Any]:
        return {
            "model": self.model.state_dict(), "q": self.q.state_dict() if self.q else None,
            "optimizer": self.optimizer.state_dict(), "replay": self.replay.state_dict(),
            "curiosity": self.curiosity.state_dict(), "schedule": self.schedule.state_dict(),
            "rng": self.rng.bit_generator.state, "generator": self.generator.get_state(),
        }  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.model.load_state_dict(state["model"])
        if self.q is not None:
            self.q.load_state_dict(state["q"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.replay.load_state_dict(state["replay"])
        self.curiosity.load_state_dict(state["curiosity"])
        self.schedule.load_state_dict(state["schedule"])
        self.rng.bit_generator.state = state["rng"]
        self.generator.set_state(state["generator"])
