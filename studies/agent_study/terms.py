"""Extra representation-loss terms of the agent study's offline prototypes, as plug-ins of the paper agent's loss.

Each is a :class:`~curiosity.agents.representation.LossTerm`: a study adds it with a config override, e.g.
``+agent.extra_terms.inverse={_target_: studies.agent_study.terms.InverseDynamics, coef: 1.0}``; it is built with
``latent_dim`` and ``n_actions`` when the agent is built, its head is trained with the world model and saved in the
agent's checkpoints, and L gains ``coef × term`` (logged as ``losses/<name>``). None is an option of the package.

Each head is initialised under its own seed (``init_seed``, 1234 as in the prototypes) inside
:func:`torch.random.fork_rng`, so adding a term leaves the agent's own draws from the global generator as they were.
The prototypes before these plug-ins (commits up to 67346ae2) patched the package instead and built their heads after
the agent; ``results/agent_study/*/README.md`` says which numbers they made.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable

import torch
from torch import Tensor, nn
from torch.nn import functional as F

from curiosity.agents.representation import Encoded, LossTerm
from curiosity.intrinsic.icm import inverse_loss
from curiosity.nets.preprocess import GaussianBlur
from curiosity.nets.world_model import WorldModel
from curiosity.types import SegmentBatch


def extra_term(name: str, term: type[LossTerm], coef: float, **options: object) -> str:
    """The config override that adds ``term`` to the agent's loss under ``name`` with weight ``coef`` (and ``options``,
    its own keys): ``+agent.extra_terms.<name>={_target_: <module.Class>, coef: <coef>, ...}``."""
    keys = ", ".join(f"{k}: {v}" for k, v in {"_target_": f"{term.__module__}.{term.__qualname__}", "coef": float(coef),
                                               **options}.items())  # fmt: skip
    return f"+agent.extra_terms.{name}={{{keys}}}"


def seeded(init_seed: int, make: Callable[[], nn.Module], uniform: bool = False) -> nn.Module:
    """``make()`` built with the global generator seeded ``init_seed`` and restored afterwards. ``uniform``: then every
    parameter p drawn anew from U(−1, 1) / √(p.shape[−1]) by a generator seeded ``init_seed`` (the arrow-of-time and
    motion-decoder prototypes' initialisation)."""
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(init_seed)
        module = make()
    if uniform:
        g = torch.Generator().manual_seed(init_seed)
        with torch.no_grad():
            for p in module.parameters():
                p.copy_(torch.empty_like(p).uniform_(-1, 1, generator=g) / math.sqrt(p.shape[-1]))
    return module


class InverseDynamics(LossTerm):
    """Which action led from z_t to z_{t+1}: an ICM/NGU-style head Linear(2d, hidden) → ReLU → Linear(hidden, A) on
    [z_t, z_{t+1}] of each segment's first transition, cross-entropy with a_t (the ICM baseline's L_inv)."""

    def __init__(self, latent_dim: int, n_actions: int, coef: float = 1.0, hidden: int = 64, init_seed: int = 1234) -> None:
        super().__init__(coef)
        self.head = seeded(init_seed, lambda: nn.Sequential(nn.Linear(2 * latent_dim, hidden), nn.ReLU(),
                                                            nn.Linear(hidden, n_actions)))  # fmt: skip

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:
        logits = self.head(torch.cat([enc.z[:, 0], enc.z[:, 1]], dim=1))
        return inverse_loss(logits, seg.act[:, 0])


class ArrowOfTime(LossTerm):
    """Tell the future from the past: from each segment's latents (z_t, z_{t+1}, z_{t+2}), a head Linear(2d, hidden) →
    ReLU → Linear(hidden, 1) on [z_{t+1}, z_x − z_{t+1}] classifies x = t+2 (label 1) against x = t (label 0) by
    binary cross-entropy. Acrobot without friction is time-reversible, so a latent of the pose alone meets the chance
    loss (ln 2); only a z_{t+1} that knows which way the links move lowers it. Segments with a terminal transition are
    left out; needs ``agent.n_step`` ≥ 2. ``recent`` holds (loss, accuracy) of the last 50 batches."""

    def __init__(self, latent_dim: int, n_actions: int, coef: float = 1.0, hidden: int = 64, init_seed: int = 1234) -> None:
        super().__init__(coef)
        self.head = seeded(init_seed, lambda: nn.Sequential(nn.Linear(2 * latent_dim, hidden), nn.ReLU(),
                                                            nn.Linear(hidden, 1)), uniform=True)  # fmt: skip
        self.recent: deque[tuple[float, float]] = deque(maxlen=50)

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:
        if enc.z.shape[1] < 3:
            raise ValueError(f"the arrow-of-time term needs segments of 2 transitions or more (agent.n_step >= 2), "
                             f"got {enc.z.shape[1] - 1}")  # fmt: skip
        z = enc.z[seg.terminateds.sum(1) == 0]
        mid = z[:, 1]
        future = self.head(torch.cat([mid, z[:, 2] - mid], 1)).squeeze(1)
        past = self.head(torch.cat([mid, z[:, 0] - mid], 1)).squeeze(1)
        logits = torch.cat([future, past])
        labels = torch.cat([torch.ones_like(future), torch.zeros_like(past)])
        loss = F.binary_cross_entropy_with_logits(logits, labels)
        self.recent.append((loss.item(), float(((logits > 0) == (labels > 0)).float().mean())))
        return loss

    def summary(self) -> str:
        """The term's mean loss and accuracy over its last (up to) 50 batches, one line."""
        if not self.recent:
            return "arrow: no iteration yet"
        loss, accuracy = (sum(x) / len(self.recent) for x in zip(*self.recent, strict=True))
        return f"arrow: last {len(self.recent)} iterations: loss {loss:.3f} accuracy {accuracy:.3f}"


class MotionDecoder(LossTerm):
    """Decode the motion from z_t: a head Linear(d, hidden) → ReLU → Linear(hidden, cells) predicts the motion image of
    o_t, the difference of its newest two frames after a Gaussian blur (σ = ``blur_sigma``, the encoder's
    ``GaussianBlur``), average-pooled by ``pool`` (32 × 32 frames, pool 4: 8 × 8 = 64 cells), by mean squared error,
    the target divided by a fixed ``scale``: its standard deviation over the first batch (a buffer, checkpointed)."""

    def __init__(self, latent_dim: int, n_actions: int, coef: float = 1.0, hidden: int = 64, cells: int = 64,
                 blur_sigma: float = 4.0, pool: int = 4, init_seed: int = 1234) -> None:  # fmt: skip
        super().__init__(coef)
        self.head = seeded(init_seed, lambda: nn.Sequential(nn.Linear(latent_dim, hidden), nn.ReLU(),
                                                            nn.Linear(hidden, cells)), uniform=True)  # fmt: skip
        self.blur, self.pool, self.cells = GaussianBlur(blur_sigma), int(pool), int(cells)
        self.register_buffer("scale", torch.zeros(()))  # 0: not yet fixed

    def target(self, obs: Tensor) -> Tensor:
        """(B, C, H, W) stacked frames, oldest first → (B, H/pool × W/pool): the newest two frames' blurred difference."""
        last2 = self.blur(obs[:, -2:])
        return F.avg_pool2d(last2[:, 1:] - last2[:, :1], self.pool).flatten(1)

    def forward(self, model: WorldModel, seg: SegmentBatch, enc: Encoded) -> Tensor:
        if seg.obs.dim() != 5 or seg.obs.shape[2] < 2:
            raise ValueError(f"the motion decoder needs stacked frames (B, n + 1, C >= 2, H, W), got {tuple(seg.obs.shape)}")
        target = self.target(seg.obs[:, 0])
        if target.shape[1] != self.cells:
            raise ValueError(f"the motion image has {target.shape[1]} cells, the head {self.cells}: set cells")
        if float(self.scale) == 0.0:
            self.scale.fill_(float(target.std()) + 1e-8)
        return F.mse_loss(self.head(enc.z[:, 0]), target / self.scale)
