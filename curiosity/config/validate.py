"""Range checks for every numeric field, and the pairings between groups, run before any environment is built."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from omegaconf import DictConfig, OmegaConf

from curiosity.build import choice
from curiosity.errors import RunError


class ConfigError(ValueError, RunError):
    """An invalid configuration; the one-line message names each key, its value and what is allowed."""

    def __init__(self, errors: list[str]) -> None:
        self.errors = errors
        super().__init__("; ".join(errors))


_ABSENT = object()

Rule = tuple[str, Callable[[Any], bool], str]

RULES: list[Rule] = [
    ("seed", lambda v: v >= 0, "an integer >= 0"),
    ("threads", lambda v: v >= 1, "an integer >= 1"),
    ("log_every", lambda v: v >= 1, "an integer >= 1"),
    ("checkpoint_every", lambda v: v >= 1, "an integer >= 1"),
    ("agent.internal_dim", lambda v: v >= 1, "an integer >= 1"),
    ("agent.n_step", lambda v: v >= 1, "an integer >= 1"),
    ("agent.batch_size", lambda v: v >= 2, "an integer >= 2"),
    ("agent.optimizer.lr", lambda v: isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0, "a learning rate > 0"),
    ("agent.transition_coef", lambda v: v >= 0, "a number >= 0"),
    ("agent.reward_coef", lambda v: v >= 0, "a number >= 0"),
    ("agent.transition_hidden", lambda v: v >= 1, "an integer >= 1"),
    ("agent.transition_dropout", lambda v: 0 <= v < 1, "a probability in [0, 1)"),
    ("agent.replay_capacity", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.novelty.action_scale", lambda v: v >= 0, "a number >= 0"),
    ("intrinsic.alpha", lambda v: 0 <= v <= 1, "a weight in [0, 1]"),
    ("intrinsic.terms.pe.eps", lambda v: v > 0, "a number > 0"),
    ("intrinsic.terms.pe.dropout_samples", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.novelty.memory_size", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.novelty.refresh_every", lambda v: v >= 1, "an integer >= 1"),
    ("agent.q_coef", lambda v: v >= 0, "a number >= 0"),
    ("agent.first_call_min_iterations", lambda v: v >= 0, "an integer >= 0 (0: the budget's first call)"),
    ("agent.q_target_every", lambda v: v >= 1, "an integer >= 1"),
    ("env.frame_size", lambda v: v >= 8, "an integer >= 8"),
    ("encoder.blur_sigma", lambda v: v >= 0, "a number >= 0 (0: no blur)"),
    ("env.frame_stack", lambda v: v >= 1, "an integer >= 1"),
    ("env.state_dim", lambda v: v >= 1, "an integer >= 1"),
    ("env.n_actions", lambda v: v >= 2, "an integer >= 2"),
    ("env.coverage_bins", lambda v: len(v) > 0 and all(b >= 1 for b in v), "a non-empty list of integers >= 1"),
    ("budget.max_steps", lambda v: v >= 1, "an integer >= 1 (the env-step cap)"),
    ("budget.warmup_steps", lambda v: v >= 0, "an integer >= 0"),
    ("budget.train_every", lambda v: v >= 1, "an integer >= 1"),
    ("budget.iters_per_train", lambda v: v >= 0, "an integer >= 0"),
    ("budget.ramp", lambda v: all(r >= 1 for r in v), "a list of integers >= 1"),
    ("budget.early_stop_every", lambda v: v >= 0, "an integer >= 0 (0 disables the early stop)"),
    ("budget.early_stop_threshold", lambda v: v > 0, "a number > 0"),
    ("budget.plateau_every", lambda v: v >= 0, "an integer >= 0 (0: every call runs budget.iters_per_train)"),
    ("budget.plateau_tol", lambda v: 0 <= v < 1, "a fraction in [0, 1)"),
    ("estimator.bandwidth", lambda v: v > 0, "a number > 0"),
    ("estimator.k", lambda v: v >= 1, "an integer >= 1"),
    ("entropy.coef", lambda v: v >= 0, "a number >= 0"),
    ("entropy.t", lambda v: v > 0, "a number > 0"),
    ("entropy.alpha", lambda v: v > 0, "a Renyi order > 0"),
    ("entropy.sigma", lambda v: v > 0, "a kernel width > 0"),
    ("entropy.base", lambda v: v > 0 and v != 1, "a logarithm base > 0 and != 1"),
    ("backward.coef", lambda v: v >= 0, "a number >= 0"),
    ("backward.sigma_b", lambda v: v > 0, "a number > 0"),
    ("backward.n_candidates", lambda v: v >= 1, "an integer >= 1"),
    ("backward.noise_dim", lambda v: v >= 1, "an integer >= 1"),
    ("backward.hidden", lambda v: v >= 1, "an integer >= 1"),
    ("planner.horizon", lambda v: v >= 1, "an integer >= 1"),
    ("planner.gamma", lambda v: 0 <= v <= 1, "a discount in [0, 1]"),
    ("planner.temperature", lambda v: v >= 0, "a number >= 0 (0 = argmax)"),
    ("planner.eta", lambda v: v >= 0, "a number >= 0"),
    ("planner.max_candidates", lambda v: v >= 1, "an integer >= 1"),
    ("planner.commit", lambda v: v >= 1, "an integer >= 1 (1: plan at every step)"),
    ("planner.hold", lambda v: v >= 1, "an integer >= 1 (1: every env step its own action)"),
    ("planner.value_coef", lambda v: v >= 0, "a number >= 0 (0: no terminal value)"),
    ("agent.transition_ensemble", lambda v: v >= 1, "an integer >= 1 (1: one transition model)"),
    ("agent.target_tau", lambda v: 0 <= v <= 1, "a rate in [0, 1] (0: no target encoder)"),
    ("agent.code_coef", lambda v: v >= 0, "a number >= 0 (0: no code-prediction term)"),
    ("intrinsic.terms.novelty.refresh_drift", lambda v: v >= 0, "a number >= 0 (0: refresh on the schedule only)"),
    ("intrinsic.terms.novelty.target_dim", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.novelty.target_hidden", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.novelty.target_lr", lambda v: v > 0, "a learning rate > 0"),
    ("intrinsic.terms.novelty.target_blur", lambda v: v >= 0, "a number >= 0 (0: no blur)"),
    ("agent.probe_every", lambda v: v >= 0, "an integer >= 0 (0: no model probe)"),
    ("encoder.hidden", lambda v: all(w >= 1 for w in v), "a list of layer widths >= 1"),
    ("encoder.downsample", lambda v: v >= 1, "an integer >= 1 (1: the full frame)"),
    ("encoder.channels", lambda v: len(v) == 3 and all(c >= 1 for c in v), "3 channel counts >= 1"),
    ("encoder.strides", lambda v: len(v) == 3 and all(c >= 1 for c in v), "3 strides >= 1"),
    ("encoder.pools", lambda v: len(v) == 2 and all(c >= 1 for c in v), "2 max-pool sizes >= 1 (1: no pool)"),
    ("baseline.epsilon", lambda v: 0 <= v <= 1, "an exploration probability in [0, 1]"),
    ("baseline.gamma", lambda v: 0 <= v <= 1, "a discount in [0, 1]"),
    ("intrinsic.terms.icm.lr", lambda v: v > 0, "a learning rate > 0"),
    ("intrinsic.terms.icm.eta", lambda v: v >= 0, "a number >= 0"),
    ("intrinsic.terms.icm.beta", lambda v: 0 <= v <= 1, "a weight in [0, 1]"),
    ("intrinsic.terms.icm.loss_weight", lambda v: v >= 0, "a number >= 0"),
    ("intrinsic.terms.icm.feature_dim", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.rnd.lr", lambda v: v > 0, "a learning rate > 0"),
    ("intrinsic.terms.rnd.out_dim", lambda v: v >= 1, "an integer >= 1"),
    ("intrinsic.terms.rnd.gamma_int", lambda v: 0 <= v <= 1, "a discount in [0, 1]"),
    ("intrinsic.terms.rnd.obs_clip", lambda v: v > 0, "a number > 0"),
    ("intrinsic.scale", lambda v: v >= 0, "a number >= 0"),
]

# The observations each encoder takes, and the largest tree a tree planner may expand at every env step.
ENCODER_OBS = {"conv": "pixels", "conv_blur": "pixels", "conv_blur16": "pixels", "conv_with_random": "pixels", "mlp": "state"}
MAX_TREE_LEAVES = 3**10
CPU_ONLY_BASELINES = ("icm", "rnd")  # the Q agent's intrinsic rewards keep their networks on the CPU


def _encoder_layout_errors(cfg: DictConfig) -> list[str]:
    """A conv encoder's downsampling without a blur, and strides and pools that leave its frames no features."""
    errors = []
    downsample = OmegaConf.select(cfg, "encoder.downsample", default=1)
    if downsample > 1 and OmegaConf.select(cfg, "encoder.blur_sigma", default=0.0) <= 0:
        errors.append(f"encoder.downsample={downsample}: samples the blurred frame, and encoder={cfg.encoder.name} does "
                      "not blur; allowed: encoder.downsample=1, or encoder.blur_sigma > 0 (encoder=conv_blur)")  # fmt: skip
    strides, pools = OmegaConf.select(cfg, "encoder.strides"), OmegaConf.select(cfg, "encoder.pools")
    if strides is not None and pools is not None and len(strides) == 3 and len(pools) == 2:
        from curiosity.nets.encoders import conv_layout_error  # imports torch: only once the config is read

        why = conv_layout_error(int(cfg.env.frame_size), int(downsample), list(strides), list(pools))
        if why:
            errors.append(why)
    return errors


def _cross_field_errors(cfg: DictConfig) -> list[str]:
    errors = []
    low, high = list(cfg.env.coverage_low), list(cfg.env.coverage_high)
    if not len(low) == len(high) == len(cfg.env.coverage_bins):
        errors.append("env.coverage_low, env.coverage_high, env.coverage_bins: must have one length")
    elif any(h <= lo for lo, h in zip(low, high, strict=True)):
        errors.append(f"env.coverage_high={high}: must be > env.coverage_low={low} in every dimension")
    k = OmegaConf.select(cfg, "estimator.k", default=None)
    if k is not None and k >= cfg.budget.warmup_steps:
        errors.append(f"estimator.k={k}: must be < budget.warmup_steps={cfg.budget.warmup_steps} (the first memory)")
    imagined = OmegaConf.select(cfg, "intrinsic.terms.pe.imagined", default=None)
    ensemble = cfg.agent.transition_ensemble
    if imagined is not None and choice(imagined) == "ensemble" and ensemble < 2:
        errors.append(f"intrinsic.terms.pe.imagined=ensemble: needs agent.transition_ensemble >= 2, got {ensemble}")
    from curiosity.device import device_error, resolve_device  # imports torch: only once the config is read

    device = choice(cfg.device) if "device" in cfg else "cpu"
    why = device_error(device)
    if why:
        errors.append(why)
    elif resolve_device(device).type != "cpu" and cfg.baseline.name in CPU_ONLY_BASELINES:
        errors.append(f"device={device}: baseline={cfg.baseline.name} runs on the CPU only (its intrinsic-reward "
                      "networks do not move to a device yet); allowed: device=cpu")  # fmt: skip
    if cfg.baseline._target_ != "curiosity.agents.paper.PaperAgent":  # the Q agent (ICM, RND) and random
        for key, ours in (("updates", "joint"), ("q_intrinsic", "batch"), ("first_call_min_iterations", "0")):
            if str(choice(cfg.agent[key])) != ours:
                errors.append(f"agent.{key}={choice(cfg.agent[key])}: only the paper's agent and NSRS read it, not "
                              f"baseline={cfg.baseline.name}; allowed: agent.{key}={ours}")  # fmt: skip
    elif (choice(cfg.agent.q_intrinsic) == "relabel" and cfg.planner.name != "qtree"
          and not OmegaConf.select(cfg, "planner.value_coef", default=0)):  # fmt: skip
        errors.append(f"agent.q_intrinsic=relabel: rescored rewards feed Q targets, and planner={cfg.planner.name} has no "
                      "Q; allowed: agent.q_intrinsic=batch, or planner=qtree, or planner.value_coef > 0")  # fmt: skip
    code_coef = OmegaConf.select(cfg, "agent.code_coef", default=0.0)
    novelty_input = OmegaConf.select(cfg, "intrinsic.terms.novelty.input", default=None)
    if code_coef and code_coef > 0 and choice(novelty_input) != "random_target":
        errors.append(f"agent.code_coef={code_coef}: the model predicts the random codes of random-code novelty, and "
                      f"intrinsic.terms.novelty.input={choice(novelty_input)}; allowed: agent.code_coef=0, or "
                      "intrinsic.terms.novelty.input=random_target")  # fmt: skip
    errors += _encoder_layout_errors(cfg)
    random_dim = OmegaConf.select(cfg, "encoder.random_dim", default=None)
    if random_dim is not None and not 1 <= random_dim < cfg.agent.internal_dim:
        errors.append(f"encoder.random_dim={random_dim}: must be >= 1 and < agent.internal_dim={cfg.agent.internal_dim} "
                      "(the learned part keeps at least one dimension)")  # fmt: skip
    if cfg.budget.warmup_steps < cfg.agent.n_step:
        errors.append(f"budget.warmup_steps={cfg.budget.warmup_steps}: must be >= agent.n_step={cfg.agent.n_step} "
                      "(segments to sample)")  # fmt: skip
    if cfg.budget.max_steps <= cfg.budget.warmup_steps:
        errors.append(f"budget.max_steps={cfg.budget.max_steps}: must be > budget.warmup_steps={cfg.budget.warmup_steps}")
    return errors


def _intrinsic_errors(cfg: DictConfig) -> list[str]:
    """The ``intrinsic`` reward must suit the agent: a planning agent needs a term that scores imagined latent steps;
    the Q agent has no latent world model for the prediction-error term. Checked from the terms' classes."""
    from hydra.utils import get_class, get_method  # imports the agents (torch): only once the config is read

    terms = OmegaConf.to_container(cfg.intrinsic.terms, resolve=True, enum_to_str=True)
    assert isinstance(terms, dict)
    classes: dict[str, type] = {}  # each term's class (curiosity.intrinsic.base.IntrinsicReward)
    for name, node in terms.items():
        target = get_method(node["_target_"])
        classes[name] = getattr(target, "__self__", target)  # a classmethod factory (from_context) or the class
    agent = get_class(str(cfg.baseline._target_))
    label = f"intrinsic={cfg.intrinsic.name}"
    if getattr(agent, "imagines", False) and not any(c.can_imagine(terms[n]) for n, c in classes.items()):
        return [f"{label}: no term scores the planner's imagined latent steps; allowed: a term that does (novelty; pe "
                "with intrinsic.terms.pe.imagined=dropout or ensemble; icm, rnd or re3 with "
                "intrinsic.terms.<name>.input=latent)"]  # fmt: skip
    if getattr(agent, "model_free_intrinsic", False) and (model := [n for n, c in classes.items() if c.needs_model]):
        return [f"{label}: the {', '.join(model)} term needs the paper agent's latent world model, which "
                f"baseline={cfg.baseline.name} has not; allowed: intrinsic=novelty, icm or rnd"]  # fmt: skip
    return []


def _pairing_errors(cfg: DictConfig) -> list[str]:
    """The encoder must take the env's observations, and the env must have them (frames for random-target novelty)."""
    obs, env = choice(cfg.env.obs), cfg.env.name
    novelty_input = OmegaConf.select(cfg, "intrinsic.terms.novelty.input", default=None)
    if novelty_input is not None and choice(novelty_input) == "random_target" and obs != "pixels":
        return [f"intrinsic.terms.novelty.input=random_target: encodes frames, and env.obs={obs} has none; allowed: "
                "env.obs=pixels, or intrinsic.terms.novelty.input=state, state_action or state_motion"]  # fmt: skip
    if obs == "pixels" and not cfg.env.pixels_available:
        return [f"env.obs=pixels: env={env} has no pixel observations; allowed: env.obs=state (with encoder=mlp)"]
    if obs == "pixels" and choice(cfg.env.renderer) == "fast" and cfg.env.get("fast_renderer") is None:
        return [f"env.renderer=fast: env={env} has no fast renderer; allowed: env.renderer=gym"]
    encoder = OmegaConf.select(cfg, "encoder.name", default=None)
    takes = ENCODER_OBS.get(encoder)
    if takes is None or takes == obs:
        return []
    fits = " or ".join(sorted(name for name, kind in ENCODER_OBS.items() if kind == obs))
    other = f", or env.obs={takes} with encoder={encoder}" if takes == "state" or cfg.env.pixels_available else ""
    return [f"encoder={encoder}: takes {takes.removesuffix('s')} observations, but env={env} has env.obs={obs}; "
            f"allowed: encoder={fits} with env.obs={obs}{other}"]  # fmt: skip


def _distractor_errors(cfg: DictConfig) -> list[str]:
    """A noisy TV shows in frames (pixels only), inside the frame; its remote control needs the env's no-op."""
    distractor = choice(cfg.env.get("distractor", "none"))
    if distractor == "none":
        return []
    label = f"env.distractor={distractor}"
    if choice(cfg.env.obs) != "pixels":
        return [f"{label}: the noisy TV is a patch of the frame and env.obs={choice(cfg.env.obs)} has no frames; "
                "allowed: env.obs=pixels, or env.distractor=none"]  # fmt: skip
    size, row, col, side = int(cfg.env.tv.size), int(cfg.env.tv.row), int(cfg.env.tv.col), int(cfg.env.frame_size)
    if not (1 <= size <= side and 0 <= row <= side - size and 0 <= col <= side - size):
        return [f"env.tv.size={size}, env.tv.row={row}, env.tv.col={col}: the patch must lie inside the "
                f"{side}x{side} frame; allowed: 1 <= size <= {side}, 0 <= row, col <= {side} - size"]  # fmt: skip
    from curiosity.envs.adapter import adapter_of  # imports gymnasium: only once the config is read
    from curiosity.envs.distractor import REMOTE

    if distractor == REMOTE and adapter_of(cfg.env).noop_action is None:
        return [f"{label}: the remote control applies the env's no-op and env={cfg.env.name} has none; allowed: "
                "env.distractor=noisy_tv_background or none"]  # fmt: skip
    return []


def _largest_horizon(n_actions: int, limit: int) -> int:
    """The largest H with n_actions^H <= limit (0 when even H = 1 exceeds it)."""
    h = 0
    while n_actions > 1 and n_actions ** (h + 1) <= limit:
        h += 1
    return h


def _planner_errors(cfg: DictConfig) -> list[str]:
    """MPC scores every action sequence unless sampling is asked for; a tree planner expands A^H leaves per step."""
    planner, a = cfg.planner, int(cfg.planner.n_actions)
    h = int(planner.horizon)
    commit = OmegaConf.select(planner, "commit", default=1)
    if commit > h:
        return [f"planner.commit={commit}: must be <= planner.horizon={h} (the plan has {h} actions)"]
    total = a**h
    limit = OmegaConf.select(planner, "max_candidates", default=None)
    if limit is None:
        if total <= MAX_TREE_LEAVES:
            return []
        return [f"planner.horizon={h}: a depth-{h} tree has {a}^{h} = {total} leaves to evaluate at every env step; "
                f"allowed: planner.horizon <= {_largest_horizon(a, MAX_TREE_LEAVES)}"]  # fmt: skip
    if total <= limit or planner.get("sample_candidates", False):
        return []
    return [f"planner.horizon={h}: {a}^{h} = {total} candidate sequences exceed planner.max_candidates={limit}; "
            f"allowed: planner.horizon <= {_largest_horizon(a, limit)} (every sequence scored), a larger "
            f"planner.max_candidates, or planner.sample_candidates=true (score {limit} sampled sequences)"]  # fmt: skip


def sampled_candidates(cfg: DictConfig) -> int | None:
    """How many action sequences the MPC planner samples per step; None when it scores all of them (or is a tree)."""
    limit = OmegaConf.select(cfg, "planner.max_candidates", default=None)
    if limit is None or int(cfg.planner.n_actions) ** int(cfg.planner.horizon) <= limit:
        return None
    return int(limit)


def _rule_errors(cfg: DictConfig, rules: list[Rule], prefix: str = "") -> list[str]:
    errors = []
    for key, ok, allowed in rules:
        value = OmegaConf.select(cfg, key, default=_ABSENT)
        if value is _ABSENT:
            continue
        try:
            good = ok(value)
        except TypeError:  # a string or a list where a number belongs (keys of untyped nodes)
            good = False
        if not good:
            shown = OmegaConf.to_container(value) if OmegaConf.is_config(value) else value
            errors.append(f"{prefix}{key}={shown!r}: must be {allowed}")
    return errors


def validate(cfg: DictConfig, rules: list[Rule] | None = None) -> None:
    """Check every rule whose key is present in ``cfg``, then the keys that depend on each other.

    Raises:
        ConfigError: listing every violated key as ``key=value: must be <allowed>`` (or ``...; allowed: ...``).
    """
    errors = _rule_errors(cfg, RULES if rules is None else rules)
    if not errors:
        errors = _cross_field_errors(cfg) + _pairing_errors(cfg) + _distractor_errors(cfg) + _planner_errors(cfg)
    if not errors:  # imports the agents' code: only for a config that passed everything else
        errors = _intrinsic_errors(cfg)
    if errors:
        raise ConfigError(errors)
