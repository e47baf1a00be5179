"""Typed schemas for every config group, registered with Hydra's ConfigStore.

Each group option's YAML (``conf/<group>/<option>.yaml``) starts from its schema here through
``defaults: [/schema/<group>/<option>@_here_, _self_]``, so an unknown key or a value of the wrong type fails while
Hydra composes the config, before anything runs. Group options that build an object name it with ``_target_``;
``name`` (and ``label``) are metadata that :func:`curiosity.build` drops before instantiation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING


class ObsKind(Enum):
    pixels = "pixels"
    state = "state"


class Renderer(Enum):
    gym = "gym"
    fast = "fast"


class Distractor(Enum):
    none = "none"
    noisy_tv = "noisy_tv"
    noisy_tv_background = "noisy_tv_background"


class Kernel(Enum):
    gaussian = "gaussian"
    yu = "yu"


class Device(Enum):
    auto = "auto"
    cpu = "cpu"
    cuda = "cuda"


class NoveltyInput(Enum):
    state_action = "state_action"
    state = "state"
    state_motion = "state_motion"
    random_target = "random_target"


class PEImagined(Enum):
    dropout = "dropout"
    ensemble = "ensemble"
    off = "off"


class TemperatureScale(Enum):
    absolute = "absolute"
    spread = "spread"


class PlannerModel(Enum):
    learned = "learned"
    oracle = "oracle"


class MemoryMode(Enum):
    exact = "exact"
    reservoir = "reservoir"


class Average(Enum):
    cumulative = "cumulative"
    ema = "ema"


class UpdateRule(Enum):
    joint = "joint"
    nsrs = "nsrs"


class QIntrinsic(Enum):
    batch = "batch"
    relabel = "relabel"


class BandwidthRule(Enum):
    fixed = "fixed"
    median_nn = "median_nn"
    scott = "scott"


# ---------------------------------------------------------------- env
@dataclass
class TVConfig:
    """The noisy TV's patch (curiosity/envs/distractor.py): side and top-left pixel in the frame."""

    size: int = 5
    row: int = 0
    col: int = 0


@dataclass
class EnvConfig:
    """An environment (curiosity/envs/adapter.py): its adapter, gymnasium id, observations and coverage grid."""

    name: str = MISSING
    _target_: str = "curiosity.envs.adapter.EnvAdapter"  # the env's adapter: physical state, goal, directed action
    id: str = MISSING
    obs: ObsKind = ObsKind.pixels
    renderer: Renderer = Renderer.gym
    frame_size: int = 32
    frame_stack: int = 4
    state_dim: int = "${env_state_dim:${.id}}"  # type: ignore[assignment]  # the env's own observation vector's length
    distractor: Distractor = Distractor.none  # none | noisy_tv (remote control: one added action) | noisy_tv_background
    tv: TVConfig = field(default_factory=TVConfig)
    n_actions: int = "${env_actions:${.id},${.distractor}}"  # type: ignore[assignment]  # the env's actions (+ the TV's)
    pixels_available: bool = True  # whether env.obs=pixels is possible (a renderer exists)
    coverage_low: list[float] = MISSING
    coverage_high: list[float] = MISSING
    coverage_bins: list[int] = MISSING
    fast_renderer: Any = None  # env.renderer=fast: draws 32x32 frames from the physical state (None: not available)


# ---------------------------------------------------------------- encoder
@dataclass
class ConvEncoderConfig:
    name: str = "conv"
    _target_: str = "curiosity.nets.encoders.ConvEncoder"
    in_channels: int = "${env.frame_stack}"  # type: ignore[assignment]
    latent_dim: int = "${agent.internal_dim}"  # type: ignore[assignment]
    frame_size: int = "${env.frame_size}"  # type: ignore[assignment]
    blur_sigma: float = 0.0  # > 0: blur each frame first (σ in pixels); 0: NSRS's encoder as it is
    differences: bool = False  # newest frame + successive frame differences instead of the frames
    difference_gain: float = 1.0
    frozen: bool = False  # true: the encoder keeps its random initial weights (no loss trains it)
    downsample: int = 1  # with a blur: keep every downsample-th blurred pixel per axis (2: 16x16 frames); 1: all
    channels: list[int] = field(default_factory=lambda: [8, 16, 32])  # the three convolutions' output channels
    strides: list[int] = field(default_factory=lambda: [1, 1, 1])  # the three convolutions' strides
    pools: list[int] = field(default_factory=lambda: [4, 3])  # max-pools after conv 2 and conv 3 (>= 4 pads 1; 1: none)


@dataclass
class ConvWithRandomConfig(ConvEncoderConfig):
    """The conv encoder's keys (for its trained part) and the frozen random part's."""

    name: str = "conv_with_random"
    _target_: str = "curiosity.nets.encoders.ConvWithRandomFeatures"
    random_dim: int = 2  # the frozen random part's size (the learned part has agent.internal_dim - random_dim)
    random_blur_sigma: float = 4.0
    random_differences: bool = True


@dataclass
class MLPEncoderConfig:
    name: str = "mlp"
    _target_: str = "curiosity.nets.encoders.MLPEncoder"
    in_dim: int = "${env.state_dim}"  # type: ignore[assignment]
    latent_dim: int = "${agent.internal_dim}"  # type: ignore[assignment]
    hidden: list[int] = field(default_factory=lambda: [200, 100, 50, 10])
    frozen: bool = False  # true: the encoder keeps its random initial weights (no loss trains it)


# ---------------------------------------------------------------- entropy (the IB regulariser)
@dataclass
class GaussianPotentialConfig:
    name: str = "gaussian_potential"
    _target_: str = "curiosity.info.regularisers.GaussianPotentialRegulariser"
    coef: float = 1.0
    t: float = 2.0


@dataclass
class RenyiConfig:
    name: str = "renyi"
    _target_: str = "curiosity.info.regularisers.RenyiEntropyRegulariser"
    coef: float = 1.0
    alpha: float = 0.99
    sigma: float = 2.0
    kernel: Kernel = Kernel.gaussian
    base: float = 2.0


@dataclass
class RenyiMIConfig(RenyiConfig):
    name: str = "renyi_mi"
    _target_: str = "curiosity.info.regularisers.RenyiMIRegulariser"


@dataclass
class NoEntropyConfig:
    name: str = "none"
    _target_: str = "curiosity.info.regularisers.NoRegulariser"


# ---------------------------------------------------------------- estimator (novelty)
class KDEBaseline(Enum):
    scalar = "scalar"
    pointwise = "pointwise"
    zscore = "zscore"
    none = "none"
    printed = "printed"


class KDEPrecision(Enum):
    float64 = "float64"
    float32 = "float32"


@dataclass
class KDEConfig:
    name: str = "kde"
    _target_: str = "curiosity.novelty.estimators.KDENovelty"
    bandwidth: float = 2.0
    bandwidth_rule: BandwidthRule = BandwidthRule.median_nn
    baseline: KDEBaseline = KDEBaseline.scalar
    standardise: bool = False
    self_in_reference: bool = False
    precision: KDEPrecision = KDEPrecision.float64  # float32: about 1.6x faster, ~1e-4 nats off (big or sampled memories)


@dataclass
class NSRSKNNConfig:
    name: str = "nsrs_knn"
    _target_: str = "curiosity.novelty.estimators.NSRSKNNNovelty"
    k: int = 5


@dataclass
class KNNConfig:
    name: str = "knn"
    _target_: str = "curiosity.novelty.estimators.KNNNovelty"
    k: int = 5
    normalise: bool = True


# ---------------------------------------------------------------- backward predictor
@dataclass
class BackwardConfig:
    name: str = MISSING
    coef: float = 0.0
    sigma_b: float = 1.0
    n_candidates: int = 8
    noise_dim: int = 4
    hidden: int = 32


# ---------------------------------------------------------------- planner
@dataclass
class MPCConfig:
    name: str = "mpc"
    _target_: str = "curiosity.planning.mpc.MPCPlanner"
    horizon: int = 5  # all 243 sequences (the text does not give H; +experiment=paper_text: 3)
    gamma: float = 0.9
    temperature: float = 0.0  # argmax (the text does not give tau; 0.02 sampled on noise, issue 11 audit)
    eta: float = 1.0
    max_candidates: int = "${power:${.n_actions},5}"  # type: ignore[assignment]  # A^5: 243 (3 actions), 1024 (a TV remote)
    sample_candidates: bool = False  # above max_candidates sequences: sample that many (true) or refuse (false)
    n_actions: int = "${env.n_actions}"  # type: ignore[assignment]
    # absolute: softmax(G / tau) | spread: G standardised across the candidates first
    temperature_scale: TemperatureScale = TemperatureScale.absolute
    # learned: imagined futures from the world model | oracle: the real simulator (an upper bound)
    model: PlannerModel = PlannerModel.learned
    # actions of the chosen sequence executed before planning again (1 <= commit <= horizon; 1: receding horizon, the
    # text's reading; the default: the whole sequence, agent study)
    commit: int = "${.horizon}"  # type: ignore[assignment]
    # env steps each planned action is held for: H actions look H x hold steps ahead, A^H candidates; commit counts
    # held actions (1: one action per step, the text's reading; 4: the agent study's, with encoder=conv_blur)
    hold: int = 4
    # > 0: a terminal value, value_coef x gamma^H x max_a Q(leaf, a), with a Q trained on r_ext + r_int of replayed
    # transitions (NSRS's, TD-MPC's value beyond the horizon; not the paper's); Q discounts gamma^(1/hold) per env step
    value_coef: float = 0.0


@dataclass
class QTreeConfig:
    name: str = "qtree"
    _target_: str = "curiosity.planning.qtree.QTreePlanner"
    horizon: int = 5  # tree depth
    gamma: float = 0.8
    n_actions: int = "${env.n_actions}"  # type: ignore[assignment]


# ---------------------------------------------------------------- intrinsic (the reward every agent explores with)
class RewardInput(Enum):
    obs = "obs"
    latent = "latent"


@dataclass
class MixtureConfig:
    """r_int = Σ_k weights[k] · terms[k]; each term a node below (its ``_target_`` takes the agent's ``context``)."""

    name: str = MISSING
    _target_: str = "curiosity.intrinsic.mixture.Mixture.from_config"
    _recursive_: bool = False  # the mixture builds its terms, each with the agent's context
    terms: Any = MISSING
    weights: Any = MISSING
    scale: float = 1.0


@dataclass
class HybridConfig(MixtureConfig):
    """The paper's hybrid: weights {novelty: 1 − alpha, pe: alpha} (Eq. 11)."""

    _target_: str = "curiosity.intrinsic.mixture.Mixture.hybrid"
    weights: Any = None  # from alpha
    alpha: float = 0.5  # α (paper: 0.5)


@dataclass
class LatentNoveltyTermConfig:
    """Latent novelty (curiosity/intrinsic/latent_novelty/): ``intrinsic.terms.novelty.<key>``."""

    _target_: str = "curiosity.intrinsic.latent_novelty.LatentNovelty.from_context"
    estimator: Any = "${estimator}"  # the estimator group
    input: NoveltyInput = NoveltyInput.state  # state: the state reached (measured better here) | state_action (the text)
    # | state_motion: the state reached and the latent's one-step motion into it
    # | random_target: a frozen random conv encoder's codes of the frame reached; imagined: a head's from the latent
    action_scale: float = 1.0  # c, length of the action part of y (state_action), in latent standard deviations
    motion_scale: float = 1.0  # m, weight of the motion part of state_motion, in motion standard deviations
    target_dim: int = 4  # random_target: size of the random encoder's codes
    target_hidden: int = 64  # random_target: width of the head's two hidden layers (latent -> code)
    target_lr: float = 1e-3  # random_target: the head's Adam learning rate
    target_blur: float = 4.0  # random_target: the random encoder's Gaussian blur of each frame, pixels (0: none)
    standardise: bool = True  # standardise latents per dimension by the memory's statistics at each refresh
    memory_mode: MemoryMode = MemoryMode.exact  # exact (every pair) | reservoir (a uniform sample of memory_size)
    memory_size: int = 100_000
    refresh_every: int = 10  # env steps between re-embedding the memory with the current encoder
    refresh_drift: float = 0.0  # also refresh whenever the memory's median drift exceeds this (standardised units)
    scale: float = 1.0


@dataclass
class PredictionErrorTermConfig:
    """The prediction-error bonus (curiosity/intrinsic/prediction_error.py): ``intrinsic.terms.pe.<key>``."""

    _target_: str = "curiosity.intrinsic.prediction_error.PredictionError.from_context"
    imagined: PEImagined = PEImagined.off  # imagined steps: dropout (MC-dropout disagreement) | ensemble | off
    dropout_samples: int = 8  # MC-dropout samples per imagined step (imagined=dropout)
    average: Average = Average.cumulative  # running mean of the error: cumulative | ema
    eps: float = 1e-8  # epsilon of r_pe = log1p(e / (mean_e + epsilon))
    log_every: int = "${log_every}"  # type: ignore[assignment]
    scale: float = 1.0


@dataclass
class ICMTermConfig:
    """Pathak's ICM (curiosity/intrinsic/icm.py)."""

    _target_: str = "curiosity.intrinsic.icm.ICM.from_context"
    input: RewardInput = RewardInput.obs
    feature_dim: int = 32
    eta: float = 1.0
    beta: float = 0.2
    loss_weight: float = 10.0
    lr: float = 1e-3
    scale: float = 1.0


@dataclass
class RNDTermConfig:
    """Burda's RND (curiosity/intrinsic/rnd.py)."""

    _target_: str = "curiosity.intrinsic.rnd.RND.from_context"
    input: RewardInput = RewardInput.obs
    out_dim: int = 64
    lr: float = 1e-4
    gamma_int: float = 0.99
    obs_clip: float = 5.0
    observe_in_update: bool = False  # running statistics follow the env stream (the agent observes once per step)
    scale: float = 1.0


@dataclass
class RE3TermConfig:
    """RE3 (Seo et al. 2021, curiosity/intrinsic/re3.py): log(1 + distance to the k-th nearest neighbour) in a fixed
    random encoder's space."""

    _target_: str = "curiosity.intrinsic.re3.RE3.from_context"
    input: RewardInput = RewardInput.obs  # latent: the agent's latents (then a planner can score imagined steps)
    k: int = 3
    capacity: int = 10000  # the first-in-first-out memory of random embeddings
    out_dim: int = 32


# ---------------------------------------------------------------- baseline (which agent runs)
@dataclass
class AgentConfig:
    name: str = MISSING
    label: str = MISSING  # method label: run directory and summary.json
    _target_: str = MISSING


@dataclass
class QAgentConfig(AgentConfig):
    """ICM / RND: greedy double DQN on r_ext + r_int from the ``intrinsic`` group."""

    epsilon: float = 0.0
    gamma: float = 0.8


# ---------------------------------------------------------------- budget
@dataclass
class BudgetConfig:
    name: str = MISSING
    max_steps: int = 3000  # env-step cap of the one continuing episode
    stop_at_goal: bool = True  # false: the goal resets the env and the run goes on to max_steps (Figure 7's curves)
    warmup_steps: int = 64  # uniformly random steps first (they count towards steps-to-goal)
    train_every: int = 1  # env steps between training calls
    iters_per_train: int = 16  # gradient iterations per training call
    ramp: list[int] = field(default_factory=list)  # multipliers of iters_per_train for the first calls
    early_stop_every: int = 0  # check the early-stop rule every this many iterations (0: never)
    early_stop_threshold: float = 0.00390625
    # the adaptive schedule: iters_per_train is a call's most; every plateau_every iterations the model's error on the
    # transitions since the previous call (held out so far) is measured, and the call stops once it fell by less than
    # plateau_tol (a fraction) since the previous measurement. 0: off (every call runs iters_per_train)
    plateau_every: int = 0
    plateau_tol: float = 0.02


# ---------------------------------------------------------------- agent (the learning agents' own keys)
@dataclass
class AgentKeysConfig:
    """``agent.<key>``: what the learning agents train with (the paper's agent and NSRS read every key; the Q agent of
    ICM/RND reads ``internal_dim``, ``batch_size``, ``optimizer``, ``replay_capacity`` and ``q_*``; random reads none)."""

    # representation learning (paper §3.4-§3.8, §4.1); +experiment=paper_text sets the values the paper prints
    internal_dim: int = 4  # latent dimension d (the paper: 2 or 4)
    n_step: int = 2  # n of the n-step transition/reward/backward losses (not printed; our choice, for speed)
    batch_size: int = 64  # segments per iteration (paper: 32; the agent study: 64)
    # one optimiser over every trained module (paper: lr 5e-3, the optimiser not named; the agent study: 1e-3, since
    # 5e-3 moves the memory's latents more between refreshes)
    optimizer: Any = field(default_factory=lambda: {"_target_": "torch.optim.Adam", "lr": 0.001})
    transition_coef: float = 1.0  # weight of L_trans(n)
    reward_coef: float = 1.0  # lambda_R of the reward model loss (0 removes the reward model)
    transition_hidden: int = 10  # residual transition MLP width (paper: 10)
    # paper: 0.5; precursor code: 0.1; with 0.5 the model ignored the action (issue 11 audit)
    transition_dropout: float = 0.0
    normalised_transition: bool = False  # the normalised variant of L_trans (paper Eq. 20)
    # encoded targets E(o_{t+i+1}) keep their gradient, as in the precursor; detached, the latent collapsed here
    detach_targets: bool = False
    # > 0: those targets come from a copy of the encoder that follows it by Polyak averaging at this rate per
    # iteration, without gradient (TD-MPC's target encoder: 0.01; not the paper's); 0: the trained encoder's own
    target_tau: float = 0.0
    # > 0 (with intrinsic.terms.novelty.input=random_target): L gains code_coef x the n-step loss of the random codes
    # the model predicts, ||g(T^i(E(o_t))) - R(o_{t+i})||^2, g held (curiosity/agents/code_term.py; not the paper's)
    code_coef: float = 0.0
    replay_capacity: int = 1_000_000  # paper: 10^6
    # plug-in terms of the representation loss: name -> {_target_: a curiosity.agents.representation.LossTerm, coef}
    extra_terms: dict[str, Any] = field(default_factory=dict)
    # diagnostics and the agent study (issue 11)
    # transition models in a deep ensemble (>= 2 for intrinsic.terms.pe.imagined=ensemble; the mean predicts)
    transition_ensemble: int = 1
    probe_every: int = 100  # agent steps between model-quality probes against the real simulator (probe/*); 0: off
    # Q learning (planner=qtree: the precursor code and NSRS; the Q agent of ICM / RND)
    q_coef: float = 1.0  # weight of the TD loss (TD gradients reach the encoder, as in NSRS)
    q_target_every: int = 1000  # Q updates between target-network refreshes
    q_huber: bool = True  # Huber TD loss (NSRS: SmoothL1)
    # how an iteration steps the parameters, and the intrinsic rewards of Q targets (curiosity/agents/updates.py,
    # curiosity/agents/relabel.py): ours, or NSRS's code's
    updates: UpdateRule = UpdateRule.joint  # joint: one optimiser, one step on L | nsrs: representation step, then Q step
    q_intrinsic: QIntrinsic = QIntrinsic.batch  # batch: score each sampled batch | relabel: the buffer, after training
    first_call_min_iterations: int = 0  # the first training call runs at least this many iterations (NSRS: 2001)


# ---------------------------------------------------------------- top level
@dataclass
class Config:
    env: EnvConfig = MISSING
    encoder: Any = MISSING
    entropy: Any = MISSING
    estimator: Any = MISSING
    backward: BackwardConfig = MISSING
    intrinsic: MixtureConfig = MISSING
    baseline: AgentConfig = MISSING
    planner: Any = MISSING
    budget: BudgetConfig = MISSING
    # run
    seed: int = 0
    deterministic: bool = False  # true: one thread and torch deterministic algorithms
    threads: int = 1  # torch intra-op threads per run
    # cpu | cuda | auto (cuda when available): networks, batches, novelty memory, planning (CUDA untested here)
    device: Device = Device.cpu
    log_every: int = 10  # env steps per metrics.csv row / TensorBoard point (per-step values are averaged)
    progress: bool = True  # tqdm bar
    resume: bool = True  # re-running the same command on an existing run directory resumes its checkpoint
    checkpoint_every: int = 500  # env steps between checkpoints (also written at the end and on SIGTERM/SIGINT)
    checkpoint_keep: bool = False  # true: also keep each periodic checkpoint as checkpoints/step=<n>.pt
    method_label: str = "${baseline.label}"
    agent: AgentKeysConfig = field(default_factory=AgentKeysConfig)


_GROUP_SCHEMAS: dict[str, dict[str, type]] = {
    "env": {"env": EnvConfig},
    "encoder": {"conv": ConvEncoderConfig, "conv_with_random": ConvWithRandomConfig, "mlp": MLPEncoderConfig},
    "entropy": {
        "gaussian_potential": GaussianPotentialConfig,
        "renyi": RenyiConfig,
        "renyi_mi": RenyiMIConfig,
        "none": NoEntropyConfig,
    },
    "estimator": {"kde": KDEConfig, "knn": KNNConfig, "nsrs_knn": NSRSKNNConfig},
    "backward": {"backward": BackwardConfig},
    "planner": {"mpc": MPCConfig, "qtree": QTreeConfig},
    "intrinsic": {
        "mixture": MixtureConfig,
        "hybrid": HybridConfig,
        "novelty": LatentNoveltyTermConfig,
        "pe": PredictionErrorTermConfig,
        "icm": ICMTermConfig,
        "rnd": RNDTermConfig,
        "re3": RE3TermConfig,
    },
    "baseline": {"agent": AgentConfig, "q_agent": QAgentConfig},
    "budget": {"budget": BudgetConfig},
}


def _stored(cs: ConfigStore) -> bool:
    """Whether every schema is in the store already (the analysis composes a config per run directory: registering
    the ~40 schemas again each time took 0.1 s a call)."""
    schema = cs.repo.get("schema", {})
    return "base_config.yaml" in cs.repo and all(
        f"{name}.yaml" in schema.get(group, {}) for group, schemas in _GROUP_SCHEMAS.items() for name in schemas
    )


def register_schemas() -> None:
    """Register the top-level schema as ``base_config`` and each option schema as ``schema/<group>/<name>`` (once:
    a call that finds them all stored does nothing)."""
    cs = ConfigStore.instance()
    if _stored(cs):
        return
    cs.store(name="base_config", node=Config)
    for group, schemas in _GROUP_SCHEMAS.items():
        for name, node in schemas.items():
            cs.store(group=f"schema/{group}", name=name, node=node)
