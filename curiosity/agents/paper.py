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
from omegaconf import DictConfig, OmegaConf

from curiosity.agents.base import Agent
from curiosity.agents.curiosity import CURIOSITY_KEYS, LatentCuriosity
from curiosity.agents.q_learning import QLearner
from curiosity.agents.representation import LOSS_KEYS, LossWeights, check_finite, encode_segments, representation_loss
from curiosity.agents.schedule import TrainSchedule
from curiosity.agents.world_model import WorldModel
from curiosity.config.build import build, choice
from curiosity.envs.simulator import Simulator, SimStates
from curiosity.nets.backward import BackwardPredictor
from curiosity.nets.reward import RewardModel
from curiosity.nets.transition import ResidualTransition, TransitionEnsemble
from curiosity.novelty.memory import EmbeddingMemory
from curiosity.planning.probe import probe_keys, probe_model
from curiosity.planning.rollout import SimulatorRollout
from curiosity.replay import ReplayBuffer
from curiosity.runtime.device import resolve_device, to_device

AGENT_KEYS = ("intrinsic/reward", "losses/q", "train/iterations", "planner/score", "planner/entropy",
              "planner/first_action_entropy", "planner/spread/score", "planner/spread/novelty", "planner/spread/pe",
              "planner/spread/reward", "planner/noise", "planner/noise_flip", "memory/drift", "memory/refreshed",
              "intrinsic/pe_estimate_corr",
              "timing/train_ms", "timing/refresh_ms", "timing/plan_ms", "timing/probe_ms")  # fmt: skip
# run means of these planner/probe columns go to summary.json ("agent")
SUMMARY_KEYS = ("planner/first_action_entropy", "planner/noise", "planner/noise_flip", "probe/effect_ratio/1",
                "probe/effect_ratio/3", "probe/spearman", "probe/agree", "memory/drift", "memory/refreshed",
                "intrinsic/pe_estimate_corr")  # fmt: skip


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
    if cfg.transition_ensemble > 1:
        transition: torch.nn.Module = TransitionEnsemble(
            d, n_actions, size=cfg.transition_ensemble, hidden=cfg.transition_hidden, dropout=cfg.transition_dropout)
    else:
        transition = ResidualTransition(d, n_actions, hidden=cfg.transition_hidden, dropout=cfg.transition_dropout)
    return WorldModel(build(cfg.encoder), transition, n_actions, reward, backward)


class PaperAgent(Agent):
    """IB latent world model + hybrid latent curiosity + MPC (or Q-tree) planning, trained on a schedule."""

    def __init__(self, cfg: DictConfig) -> None:
        self.cfg, self.label = cfg, str(cfg.method_label)
        self.n_actions = int(cfg.env.n_actions)
        self.obs_pixels = choice(cfg.env.obs) == "pixels"
        self.device = resolve_device(choice(OmegaConf.select(cfg, "device", default="cpu")))
        self.model = build_world_model(cfg).to(self.device)
        self.regulariser = build(cfg.entropy)
        self.weights = LossWeights(transition=cfg.transition_coef, reward=cfg.reward_coef, backward=cfg.backward.coef,
                                   sigma_b=cfg.backward.sigma_b, normalised_transition=cfg.normalised_transition,
                                   detach_targets=cfg.detach_targets)  # fmt: skip
        self.planner = build(cfg.planner)
        self.q = (QLearner(self.model.encoder, cfg.internal_dim, self.n_actions, gamma=cfg.planner.gamma,
                           target_every=cfg.q_target_every, huber=cfg.q_huber)
                  if getattr(self.planner, "uses_q", False) else None)  # fmt: skip
        if self.q is not None:
            self.q.to(self.device)
        params = list(self.model.parameters()) + (list(self.q.q.parameters()) if self.q else [])
        self.optimizer = build(cfg.optimizer, params=params)
        self.replay = ReplayBuffer(cfg.replay_capacity, obs_shape_of(cfg.env), pixel_uint8=self.obs_pixels)
        memory = EmbeddingMemory(mode=choice(cfg.memory_mode), reservoir_size=cfg.memory_size, seed=cfg.seed)
        self.curiosity = LatentCuriosity(
            self.model, build(cfg.estimator), self.replay, memory, n_actions=self.n_actions,
            novelty_input=choice(cfg.novelty_input), action_scale=cfg.action_scale, alpha=cfg.hybrid_alpha,
            pe_average=choice(cfg.pe_average), pe_eps=cfg.pe_eps, dropout_samples=cfg.pe_dropout_samples,
            warmup_steps=cfg.budget.warmup_steps, standardise=cfg.standardise_latents,
            pe_imagined=choice(cfg.pe_imagined),
        )  # fmt: skip
        b = cfg.budget
        self.schedule = TrainSchedule(b.warmup_steps, b.train_every, b.iters_per_train, b.ramp, b.early_stop_every,
                                      b.early_stop_threshold)  # fmt: skip
        self.rng = np.random.default_rng([int(cfg.seed), 2])
        self.generator = torch.Generator().manual_seed(int(cfg.seed))
        self.oracle = choice(OmegaConf.select(cfg, "planner.model", default="learned")) == "oracle"
        self.probe_every = int(cfg.probe_every) if self.q is None else 0  # the probe scores with the MPC planner
        first = tuple(f"planner/p_first/{a}" for a in range(self.n_actions))
        probe = probe_keys(cfg.planner.horizon) if self.probe_every else ()
        self.metric_keys = (*LOSS_KEYS, *CURIOSITY_KEYS, *AGENT_KEYS, *first, *probe,
                            *getattr(self.curiosity.estimator, "log_keys", ()))  # fmt: skip
        self._plan_logs: dict[str, float] = {}
        self.env: Any = None
        self.simulator: Simulator | None = None
        self.totals: dict[str, list[float]] = {}  # key -> [sum, count] of SUMMARY_KEYS
        self._latent: tuple[np.ndarray, torch.Tensor] | None = None  # the last observation encoded, until training
        self.queue: list[int] = []  # actions of the last chosen sequence still to execute (planner.commit > 1)

    def attach_env(self, env: Any) -> None:
        """Keep the run's env when the oracle planner or the probe branch its simulator."""
        if self.oracle or self.probe_every:
            self.env, self.simulator = env, Simulator(self.cfg.env)

    def summary(self) -> dict[str, Any]:
        """Run means of the planner, probe and memory columns (``SUMMARY_KEYS``) and how imagined steps were made."""
        means = {k: total / n for k, (total, n) in self.totals.items() if n}
        return {"planner_model": "oracle" if self.oracle else "learned", "pe_imagined": self.curiosity.pe_imagined_kind,
                "means": means}  # fmt: skip

    def _tally(self, logs: dict[str, float]) -> None:
        for key in SUMMARY_KEYS:
            if key in logs:
                total = self.totals.setdefault(key, [0.0, 0])
                total[0] += logs[key]
                total[1] += 1

    # ------------------------------------------------------------------ acting
    def encode_obs(self, obs: np.ndarray) -> torch.Tensor:
        """z = E(o) for one observation (*obs_shape) -> (d,), in eval mode without gradient; ``check_finite``.

        Each observation is encoded once per encoder state: the plan's z_t is the memory's z_t, and o_{t+1}, encoded
        by ``observe`` for the intrinsic reward, is reused by the next ``act`` unless training changed the encoder in
        between. Always a batch of one, so a reused latent equals a recomputed one exactly.
        """
        if self._latent is not None and np.array_equal(self._latent[0], obs):
            return self._latent[1]
        with self.model.evaluating():
            z = self.model.encode(torch.as_tensor(obs, device=self.device).unsqueeze(0))[0]
        check_finite("latent", z)
        self._latent = (np.array(obs, copy=True), z)
        return z

    def _reward_fn(self) -> Any:
        return self.model.reward if self.model.reward_model is not None else None

    def _root(self, obs: np.ndarray) -> SimStates:
        assert self.simulator is not None, "attach_env() was not called"
        return self.simulator.root(self.env, obs)

    def _plan(self, z0: torch.Tensor, obs: np.ndarray) -> tuple[int, dict[str, float]]:
        cur, model = self.curiosity, self.model
        if self.q is not None:
            return self.planner.plan(z0, model.next, cur.imagined, self.q.values)
        rollout = None
        if self.oracle:
            assert self.simulator is not None, "attach_env() was not called"
            rollout = SimulatorRollout(self.simulator, self._root(obs), z0, model.encode)
        return self.planner.plan(z0, model.next, self._reward_fn(), cur.imagined_terms, self.generator, rollout=rollout)

    def _score_noise(self, z0: torch.Tensor, obs: np.ndarray) -> dict[str, float]:
        """Two fresh evaluations of the (stochastic) scores of every candidate: their noise and whether the best first
        action flips between them. Only for learned-model MPC with full enumeration and a stochastic term."""
        planner = self.planner
        if self.q is not None or self.oracle or not self.curiosity.stochastic:
            return {}
        if planner.n_actions**planner.horizon > planner.max_candidates:
            return {}
        seqs = planner.candidates()
        g1, g2 = (planner.scores(z0, seqs, self.model.next, self._reward_fn(), self.curiosity.imagined_terms)
                  for _ in range(2))  # fmt: skip
        flip = int(seqs[int(g1.argmax()), 0]) != int(seqs[int(g2.argmax()), 0])
        return {"planner/noise": float((g1 - g2).std(correction=0)) / 2**0.5, "planner/noise_flip": float(flip)}

    def _probe(self, z0: torch.Tensor, obs: np.ndarray, step: int) -> dict[str, float]:
        if not self.probe_every or (step - self.cfg.budget.warmup_steps) % self.probe_every:
            return {}
        start = time.perf_counter()
        assert self.simulator is not None, "attach_env() was not called"
        out = probe_model(self.planner, z0, self.model.next, self._reward_fn(), self.curiosity.imagined_terms,
                          self.simulator, self._root(obs), self.model.encode)  # fmt: skip
        out["timing/probe_ms"] = 1e3 * (time.perf_counter() - start)
        return out

    def act(self, obs: np.ndarray, step: int) -> int:
        if self.queue:  # planner.commit > 1: the chosen sequence's next action, without planning
            self._plan_logs = {}
            return self.queue.pop(0)
        start = time.perf_counter()
        z0 = self.encode_obs(obs)
        with self.model.evaluating():
            action, info = self._plan(z0, obs)
            plan_ms = 1e3 * (time.perf_counter() - start)
            logs = {"planner/score": info.get("chosen_score", info.get("best_value", 0.0)),
                    "planner/entropy": info.get("entropy", 0.0), "timing/plan_ms": plan_ms}  # fmt: skip
            logs.update({f"planner/{k}": v for k, v in info.items()
                         if k.startswith(("spread/", "p_first/")) or k == "first_action_entropy"})  # fmt: skip
            with torch.random.fork_rng(devices=[]):  # diagnostics draw dropout masks but never change the run's stream
                logs.update(self._score_noise(z0, obs))
                logs.update(self._probe(z0, obs, step))
        self._tally(logs)
        self._plan_logs = logs
        if self.planner.commit > 1:
            self.queue = list(self.planner.last_sequence[1 : self.planner.commit])
        return action

    # ------------------------------------------------------------------ learning
    def observe(self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool,
                step: int) -> dict[str, float]:  # fmt: skip
        self.replay.add(obs, action, reward, next_obs, terminated)
        z_t = self.encode_obs(obs)
        z = torch.stack([z_t, self.encode_obs(next_obs)])
        cur, a = self.curiosity, torch.tensor([action], device=self.device)
        cur.add(z[0], action, self.replay.total_added - 1)
        logs: dict[str, float] = dict(self._plan_logs)
        self._plan_logs = {}
        if cur.ready:
            r_int, parts = cur.from_latents(z[:1], a, z[1:])
            cur.observe_latents(z[:1], a, z[1:])
            logs.update(parts, **{"intrinsic/reward": float(r_int[0])})
            corr = cur.pe_estimate_corr() if (step + 1) % self.cfg.log_every == 0 else None
            if corr is not None:
                logs["intrinsic/pe_estimate_corr"] = corr
        if self._refresh_due(step, logs):
            start = time.perf_counter()
            cur.refresh()
            logs.update(getattr(cur.estimator, "logs", {}), **{"timing/refresh_ms": 1e3 * (time.perf_counter() - start)})
            logs["memory/refreshed"] = 1.0
        elif cur.ready:
            logs["memory/refreshed"] = 0.0
        self._tally({k: v for k, v in logs.items() if not k.startswith(("planner/", "probe/"))})  # act() tallied those
        iterations = self.schedule.iterations(step)
        if iterations:
            logs.update(self._train(iterations))
        return logs

    def _refresh_due(self, step: int, logs: dict[str, float]) -> bool:
        """Every ``memory_refresh_every`` env steps from the end of the warm-up, and in between whenever the memory's
        drift (:meth:`LatentCuriosity.drift`, logged as ``memory/drift``) exceeds ``memory_refresh_drift`` (> 0)."""
        since = step + 1 - self.cfg.budget.warmup_steps
        if since < 0:
            return False
        if since % self.cfg.memory_refresh_every == 0:
            return True
        if self.cfg.memory_refresh_drift > 0 and self.curiosity.ready:
            logs["memory/drift"] = self.curiosity.drift()
            return logs["memory/drift"] > self.cfg.memory_refresh_drift
        return False

    def _train(self, iterations: int) -> dict[str, float]:
        start = time.perf_counter()
        sums: dict[str, float] = {}
        window: list[float] = []
        done = 0
        self._latent = None  # the encoder changes
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
        seg = self.replay.sample_segments(self.cfg.batch_size, self.cfg.n_step, self.rng).to(self.device)
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
            "rng": self.rng.bit_generator.state, "generator": self.generator.get_state(), "totals": self.totals,
            "queue": list(self.queue),
        }  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self._latent = None
        self.model.load_state_dict(state["model"])
        if self.q is not None:
            self.q.load_state_dict(state["q"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.replay.load_state_dict(state["replay"])
        self.curiosity.load_state_dict(to_device(state["curiosity"], self.device))
        self.schedule.load_state_dict(state["schedule"])
        self.rng.bit_generator.state = state["rng"]
        self.generator.set_state(state["generator"])
        self.totals = {k: list(v) for k, v in state.get("totals", {}).items()}
        self.queue = list(state.get("queue", []))  # checkpoints before planner.commit had none
