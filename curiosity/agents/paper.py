"""The paper's agent (``baseline=none``): an IB-shaped latent world model, latent curiosity, and planning.

Both readings of the paper (docs/method.md §0) are this one class with different config: ``planner=mpc`` plans with the
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
from curiosity.agents.code_term import code_term
from curiosity.agents.diagnostics import PlanDiagnostics, PlanView
from curiosity.agents.q_learning import QLearner
from curiosity.agents.relabel import RelabelledRewards
from curiosity.agents.representation import (
    LOSS_KEYS,
    LossWeights,
    check_finite,
    encode_segments,
    representation_terms,
    term_weights,
)
from curiosity.agents.schedule import TrainSchedule
from curiosity.agents.updates import TDTerm, load_optimizers_state, optimizers_state, update_rule
from curiosity.nets.world_model import WorldModel
from curiosity.build import build, choice
from curiosity.envs.simulator import Simulator, SimStates
from curiosity.intrinsic.base import IntrinsicContext
from curiosity.intrinsic.latent_novelty import LatentNovelty
from curiosity.intrinsic.mixture import Mixture
from curiosity.nets.backward import BackwardPredictor
from curiosity.nets.encoders import FixedStandardiser
from curiosity.nets.polyak import PolyakCopy
from curiosity.nets.reward import RewardModel
from curiosity.nets.transition import ResidualTransition, TransitionEnsemble
from curiosity.planning.protocols import Plan, Planner, PlanRequest
from curiosity.planning.rollout import SimulatorRollout
from curiosity.replay import ReplayBuffer
from curiosity.device import resolve_device, to_device
from curiosity.types import SegmentBatch, TransitionBatch

AGENT_KEYS = ("intrinsic/reward", "losses/q", "train/iterations", "planner/score", "planner/entropy",
              "planner/first_action_entropy", "planner/spread/score", "planner/spread/reward", "planner/noise",
              "planner/noise_flip", "timing/train_ms", "timing/plan_ms", "timing/probe_ms")  # fmt: skip
HELD_OUT_MIN = 16  # the adaptive schedule measures its model on at least this many of the newest transitions


def obs_shape_of(env_cfg: DictConfig) -> tuple[int, ...]:
    """Observation shape an ``env`` node produces: (frame_stack, size, size) for pixels, (state_dim,) for states."""
    if choice(env_cfg.obs) == "pixels":
        return (env_cfg.frame_stack, env_cfg.frame_size, env_cfg.frame_size)
    return (env_cfg.state_dim,)


def build_world_model(cfg: DictConfig) -> WorldModel:
    """Encoder (``encoder`` group), residual transition, reward model (if λ_R > 0), backward predictor (if on)."""
    own, n_actions = cfg.agent, cfg.env.n_actions
    d = own.internal_dim
    reward = RewardModel(d, n_actions) if own.reward_coef > 0 else None
    b = cfg.backward
    backward = BackwardPredictor(d, n_actions, n_candidates=b.n_candidates, noise_dim=b.noise_dim,
                                 hidden=b.hidden) if b.coef > 0 else None  # fmt: skip
    if own.transition_ensemble > 1:
        transition: torch.nn.Module = TransitionEnsemble(
            d, n_actions, size=own.transition_ensemble, hidden=own.transition_hidden, dropout=own.transition_dropout
        )
    else:
        transition = ResidualTransition(d, n_actions, hidden=own.transition_hidden, dropout=own.transition_dropout)
    return WorldModel(build(cfg.encoder), transition, n_actions, reward, backward)


class PaperAgent(Agent):
    """IB latent world model + hybrid latent curiosity + MPC (or Q-tree) planning, trained on a schedule."""

    imagines = True

    def __init__(self, cfg: DictConfig) -> None:
        self.cfg, self.label = cfg, str(cfg.method_label)
        self.n_actions = int(cfg.env.n_actions)
        self.obs_pixels = choice(cfg.env.obs) == "pixels"
        self.device = resolve_device(choice(OmegaConf.select(cfg, "device", default="cpu")))
        self.model = build_world_model(cfg).to(self.device)
        self.regulariser = build(cfg.entropy)
        own = cfg.agent
        # agent.target_tau > 0: the transition loss's targets come from a slowly moving copy of the encoder (TD-MPC)
        tau = float(own.target_tau)
        self.target_encoder = PolyakCopy(self.model.encoder, tau).to(self.device) if tau > 0 else None
        self.weights = LossWeights(transition=own.transition_coef, reward=own.reward_coef, backward=cfg.backward.coef,
                                   q=own.q_coef, sigma_b=cfg.backward.sigma_b, normalised_transition=own.normalised_transition,
                                   detach_targets=own.detach_targets)  # fmt: skip
        # plug-in loss terms (agent.extra_terms): their parameters are trained and saved with the world model's
        self.extra_terms = torch.nn.ModuleDict({name: build(node, latent_dim=int(own.internal_dim), n_actions=self.n_actions)
                                                for name, node in own.extra_terms.items()}).to(self.device)  # fmt: skip
        self.planner: Planner = build(cfg.planner)
        self.q = (QLearner(self.model.encoder, own.internal_dim, self.n_actions, gamma=self.planner.step_discount,
                           target_every=own.q_target_every, huber=own.q_huber)
                  if self.planner.needs_q else None)  # fmt: skip
        if self.q is not None:
            self.q.to(self.device)
        self.rule = update_rule(choice(own.updates), own.optimizer, self.model, self.model.encoder,
                                self.q.q if self.q is not None else None, self.extra_terms)  # fmt: skip
        self.optimizers = self.rule.optimizers
        relabel = self.q is not None and choice(own.q_intrinsic) == "relabel"
        self.relabelled = RelabelledRewards() if relabel else None  # NSRS's stored r_int of Q targets
        self.replay = ReplayBuffer(own.replay_capacity, obs_shape_of(cfg.env), pixel_uint8=self.obs_pixels)
        context = IntrinsicContext(n_actions=self.n_actions, obs_shape=obs_shape_of(cfg.env), latent_dim=own.internal_dim,
                                   warmup_steps=cfg.budget.warmup_steps, seed=int(cfg.seed), device=self.device,
                                   replay=self.replay, encode=self._encode_eval, model=self.model)  # fmt: skip
        self.intrinsic: Mixture = build(cfg.intrinsic, context=context)
        if not self.intrinsic.imaginable:
            raise ValueError(f"intrinsic={cfg.intrinsic.name}: no term scores imagined latent steps, which the planner "
                             "needs; allowed: a latent reward (novelty, pe with intrinsic.terms.pe.imagined=dropout|ensemble, "
                             "icm/rnd with input=latent)")  # fmt: skip
        self.novelty: LatentNovelty | None = self.intrinsic.term(LatentNovelty)  # its memory, for analysis
        # agent.code_coef > 0: L also asks the model to predict the random codes the novelty scores (a term without
        # parameters of its own, so the optimisers built above are unchanged)
        self.extra_terms.update(code_term(getattr(self.novelty, "target", None), float(own.code_coef)))
        b = cfg.budget
        self.schedule = TrainSchedule(b.warmup_steps, b.train_every, b.iters_per_train, b.ramp, b.early_stop_every,
                                      b.early_stop_threshold, b.plateau_every, b.plateau_tol)  # fmt: skip
        self.rng = np.random.default_rng([int(cfg.seed), 2])
        self.generator = torch.Generator().manual_seed(int(cfg.seed))
        self.oracle = choice(OmegaConf.select(cfg, "planner.model", default="learned")) == "oracle"
        self.diagnostics = PlanDiagnostics(self.planner, int(own.probe_every), int(cfg.budget.warmup_steps),
                                           learned=not self.oracle)  # fmt: skip
        first = tuple(f"planner/p_first/{a}" for a in range(self.n_actions))
        probe = self.diagnostics.keys
        # each term's spread across candidates (and the leaves' value's, with MPC's terminal value)
        leaf_value = self.planner.needs_q and self.planner.scores_candidates  # MPC with a terminal value Q of the leaf
        spread = tuple(f"planner/spread/{name}" for name in (*self.intrinsic.terms, *(("value",) if leaf_value else ())))
        extra_keys = tuple(f"losses/{name}" for name in self.extra_terms)
        self.metric_keys = (*LOSS_KEYS, *extra_keys, *self.intrinsic.log_keys, *AGENT_KEYS, *spread, *first, *probe)
        self._plan_logs: dict[str, float] = {}
        self.env: Any = None
        self.simulator: Simulator | None = None
        self._latent: tuple[np.ndarray, torch.Tensor] | None = None  # the last observation encoded, until training
        self.queue: list[int] = []  # actions of the last chosen sequence still to execute (planner.commit > 1)

    def attach_env(self, env: Any) -> None:
        """Keep the run's env when the oracle planner or the probe branch its simulator."""
        if self.oracle or self.diagnostics.needs_simulator:
            self.env, self.simulator = env, Simulator(self.cfg.env)
            self.diagnostics.simulator = self.simulator

    def summary(self) -> dict[str, Any]:
        """Run means of the planner, probe and memory columns (``diagnostics.SUMMARY_KEYS``) and how imagined steps
        were made."""
        return {"planner_model": "oracle" if self.oracle else "learned", **self.intrinsic.summary(),
                "means": self.diagnostics.means()}  # fmt: skip

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

    def _encode_eval(self, obs: torch.Tensor) -> torch.Tensor:
        """E(o) in eval mode without gradient: (B, *obs_shape) -> (B, d) (what intrinsic rewards re-encode with)."""
        with self.model.evaluating():
            return self.model.encode(obs)

    def _reward_fn(self) -> Any:
        return self.model.reward if self.model.reward_model is not None else None

    def _root(self, obs: np.ndarray) -> SimStates:
        assert self.simulator is not None, "attach_env() was not called"
        return self.simulator.root(self.env, obs)

    def _plan(self, z0: torch.Tensor, obs: np.ndarray) -> Plan:
        rollout = None
        if self.oracle:
            assert self.simulator is not None, "attach_env() was not called"
            rollout = SimulatorRollout(self.simulator, self._root(obs), z0, self.model.encode)
        return self.planner.plan(
            PlanRequest(
                z0,
                self.model.next,
                self.intrinsic.imagined_terms,
                reward_fn=self._reward_fn(),
                q_fn=self.q.values if self.q is not None else None,
                generator=self.generator,
                rollout=rollout,
            )
        )

    def act(self, obs: np.ndarray, step: int) -> int:
        if self.queue:  # planner.commit > 1: the chosen sequence's next action, without planning
            self._plan_logs = {}
            return self.queue.pop(0)
        start = time.perf_counter()
        z0 = self.encode_obs(obs)
        with self.model.evaluating():
            plan = self._plan(z0, obs)
            plan_ms = 1e3 * (time.perf_counter() - start)
            logs = {"planner/score": plan.score, "planner/entropy": plan.info.get("entropy", 0.0),
                    "timing/plan_ms": plan_ms}  # fmt: skip
            logs.update({f"planner/{k}": v for k, v in plan.info.items()
                         if k.startswith(("spread/", "p_first/")) or k == "first_action_entropy"})  # fmt: skip
            view = PlanView(z0, self.model.next, self._reward_fn(), self.intrinsic.imagined_terms,
                            self.intrinsic.stochastic, lambda: self._root(obs), self.model.encode,
                            self.q.values if self.q is not None else None)  # fmt: skip
            logs.update(self.diagnostics.after_plan(view, step))
        self.diagnostics.tally(logs)
        self._plan_logs = logs
        self.queue = list(plan.sequence[1 : self.planner.commit])
        return plan.action

    # ------------------------------------------------------------------ learning
    def observe(self, obs: np.ndarray, action: int, reward: float, next_obs: np.ndarray, terminated: bool,
                step: int) -> dict[str, float]:  # fmt: skip
        """Store the transition; log its intrinsic reward (each term's, and their mixture) once the reward is ready;
        fold it into the reward's memory and statistics (``observe``: refreshes the novelty memory when due); train."""
        self.replay.add(obs, action, reward, next_obs, terminated)
        if terminated:
            self.queue = []  # the chosen sequence's remaining actions belong to the episode that just ended
        z = torch.stack([self.encode_obs(obs), self.encode_obs(next_obs)])
        dev = self.device
        batch = TransitionBatch(torch.as_tensor(obs, device=dev).unsqueeze(0), torch.tensor([action], device=dev),
                                torch.as_tensor(next_obs, device=dev).unsqueeze(0), torch.tensor([reward], device=dev),
                                torch.tensor([float(terminated)], device=dev), z=z[:1], z_next=z[1:],
                                index=torch.tensor([self.replay.total_added - 1], device="cpu"))  # fmt: skip
        logs: dict[str, float] = dict(self._plan_logs)
        self._plan_logs = {}
        logs.update(self.intrinsic.transition_logs(batch))
        logs.update(self.intrinsic.observe(batch))
        own_logs = {k: v for k, v in logs.items() if not k.startswith(("planner/", "probe/"))}  # act() tallied those
        self.diagnostics.tally(own_logs)
        iterations = self.schedule.iterations(step)
        if iterations and self.schedule.calls == 1:  # NSRS: the first call is never shorter than its early-stop check
            iterations = max(iterations, int(self.cfg.agent.first_call_min_iterations))
        if iterations:
            logs.update(self._train(iterations))
        return logs

    def _train(self, iterations: int) -> dict[str, float]:
        start = time.perf_counter()
        sums: dict[str, float] = {}
        window: list[float] = []
        done = 0
        self._latent = None  # the encoder changes
        if self.schedule.calls == 1:
            self._calibrate()
        held_out = self._held_out() if self.schedule.plateau_every else None
        previous = self._held_out_error(held_out) if held_out is not None else None
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
            if held_out is not None and previous is not None and self.schedule.checks_plateau(done):
                now = self._held_out_error(held_out)  # evaluating() restores train mode after
                if self.schedule.plateaued(previous, now):
                    break
                previous = now
        out = {k: v / done for k, v in sums.items()}
        if self.relabelled is not None:  # NSRS: the buffer's intrinsic rewards as of this training call's end
            self._relabel()
        out.update({"train/iterations": float(done), "timing/train_ms": 1e3 * (time.perf_counter() - start)})
        return out

    def _held_out(self) -> TransitionBatch | None:
        """The newest transitions, for the adaptive schedule: those that arrived since the previous training call (none
        of them trained on yet; at the first call, the warm-up's), at least ``HELD_OUT_MIN``; None when fewer than two."""
        since = self.schedule.train_every if self.schedule.calls > 1 else len(self.replay)
        count = min(max(since, HELD_OUT_MIN), len(self.replay))
        if count < 2:
            return None
        index = np.arange(self.replay.total_added - count, self.replay.total_added)
        return self.replay.transitions_at(index).to(self.device)

    def _held_out_error(self, batch: TransitionBatch) -> float:
        """The model's one-step error on ``batch`` relative to the size of the steps: mean ‖T(z, a) − z′‖² /
        mean ‖z′ − z‖², with the current encoder (eval mode, no gradient); scale-free, as the latent moves."""
        with self.model.evaluating():
            z, z_next = self.model.encode(batch.obs), self.model.encode(batch.next_obs)
            error = (self.model.next(z, batch.act) - z_next).square().sum(1).mean()
            step = (z_next - z).square().sum(1).mean().clamp_min(1e-12)
        return float(error / step)

    def _calibrate(self) -> None:
        """At the first training call a frozen encoder standardises its outputs by the warm-up's observations
        (``encoder.frozen``, the random part of ``encoder=conv_with_random``; trained encoders do nothing) and the
        novelty memory is re-embedded with it."""
        encoder = self.model.encoder
        if not any(isinstance(m, FixedStandardiser) for m in encoder.modules()):
            return
        encoder.calibrate(self.replay.all_obs().to(self.device))
        if self.novelty is not None and self.novelty.ready:
            self.novelty.refresh()

    def _relabel(self) -> None:
        assert self.relabelled is not None
        encoded = None
        if self.novelty is not None:  # NSRS's memory: every stored state under the encoder just trained
            encoded = self.novelty.refresh()  # its latents are the relabel's (exact memory: the same transitions)
        self.relabelled.relabel(self.replay, self._encode_eval, self.intrinsic, self.device, encoded)

    def _td_loss(self, z0: torch.Tensor, z1: torch.Tensor, seg: SegmentBatch, first: TransitionBatch) -> torch.Tensor:
        """The Q-tree agent's TD loss on the segments' first transitions, r_ext + r_int (scored now, or NSRS's stored)."""
        assert self.q is not None
        if self.relabelled is not None:
            assert first.index is not None
            r_int = self.relabelled.lookup(first.index).to(self.device)
        else:
            with torch.no_grad():
                r_int = self.intrinsic.compute(first)
        loss = self.q.loss(z0, first.act, first.rewards + r_int, z1, seg.obs[:, 1], first.terminateds)
        check_finite("losses/q", loss)
        return loss

    def _td_fresh(self, seg: SegmentBatch, first: TransitionBatch) -> torch.Tensor:
        """The TD loss re-encoded with the encoder as stepped so far (NSRS's Q step: z_t with gradient, z_{t+1} without)."""
        z0 = self.model.encode(seg.obs[:, 0])
        with torch.no_grad():
            z1 = self.model.encode(seg.obs[:, 1])
        return self._td_loss(z0, z1, seg, first)

    def _iteration(self) -> tuple[dict[str, float], float]:
        """One gradient iteration: the representation terms (and a Q-tree agent's TD term), stepped by the update rule
        (``agent.updates``, curiosity/agents/updates.py)."""
        seg = self.replay.sample_segments(self.cfg.agent.batch_size, self.cfg.agent.n_step, self.rng).to(self.device)
        enc = encode_segments(self.model, seg, self.target_encoder)
        terms, logs = representation_terms(self.model, seg, enc, self.regulariser, self.weights, self.extra_terms)
        first = seg.first_step().with_latents(enc.z[:, 0].detach(), enc.z[:, 1].detach())
        logs.update(self.intrinsic.update(first))  # rewards that learn (ICM, RND) take their step
        td = None
        if self.q is not None and self.rule.steps_q(self.schedule.calls):
            td = TDTerm(on_latents=lambda: self._td_loss(enc.z[:, 0], enc.z[:, 1], seg, first),
                        fresh=lambda: self._td_fresh(seg, first))  # fmt: skip
        logs.update(self.rule.apply(terms, term_weights(self.weights, self.extra_terms), td))
        if self.target_encoder is not None:
            self.target_encoder.update()
        if td is not None:
            assert self.q is not None
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
            **optimizers_state(self.optimizers), "replay": self.replay.state_dict(),
            "intrinsic": self.intrinsic.state_dict(), "schedule": self.schedule.state_dict(),
            "rng": self.rng.bit_generator.state, "generator": self.generator.get_state(),
            "totals": self.diagnostics.state_dict(),
            "queue": list(self.queue),
            **({"extra_terms": self.extra_terms.state_dict()} if len(self.extra_terms) else {}),
            **({"target_encoder": self.target_encoder.state_dict()} if self.target_encoder is not None else {}),
            **({"relabelled": self.relabelled.state_dict()} if self.relabelled is not None else {}),
        }  # fmt: skip

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self._latent = None
        self.model.load_state_dict(state["model"])
        if len(self.extra_terms):
            self.extra_terms.load_state_dict(state["extra_terms"])
        if self.q is not None:
            self.q.load_state_dict(state["q"])
        if self.target_encoder is not None:
            self.target_encoder.load_state_dict(state["target_encoder"])
        load_optimizers_state(self.optimizers, state)
        if self.relabelled is not None:
            self.relabelled.load_state_dict(state["relabelled"])
        self.replay.load_state_dict(state["replay"])
        saved = state["intrinsic"] if "intrinsic" in state else legacy_intrinsic_state(state["curiosity"])
        self.intrinsic.load_state_dict(to_device({k: v for k, v in saved.items() if k in self.intrinsic.terms}, self.device))
        self.schedule.load_state_dict(state["schedule"])
        self.rng.bit_generator.state = state["rng"]
        self.generator.set_state(state["generator"])
        self.diagnostics.load_state_dict(state.get("totals", {}))
        self.queue = list(state.get("queue", []))  # checkpoints before planner.commit had none


def legacy_intrinsic_state(old: dict[str, Any]) -> dict[str, Any]:
    """A checkpoint's ``curiosity`` state from before the intrinsic rewards were separate terms, as the hybrid's
    ``{novelty, pe}`` states (so a run saved then resumes now)."""
    novelty = {k: old[k] for k in ("memory", "ready", "z_mean", "z_std", "estimator")}
    pe = {"real": old["pe_real"], "imagined": old["pe_imagined"], "pairs": old.get("pe_pairs", [])}
    return {"novelty": novelty, "pe": pe}
