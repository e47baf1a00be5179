"""A frozen random image encoder whose codes the latent novelty can score, and a head that predicts them from the
agent's latent (``intrinsic.terms.novelty.input=random_target``; issue 11, not in the paper).

With the real simulator for imagined steps, novelty over a never-trained random encoder of blurred frames reaches
the Acrobot goal in fewer steps than novelty over the trained latent (``results/agent_study/hold/README.md``), but a
learned model cannot follow a random latent (``results/agent_study/pixel_encoder/``). So the codes r = R(o) of a
frozen random :class:`~curiosity.nets.encoders.ConvEncoder` hold the memory, the agent's model still plans in its
trained latent, and a small head g(s) ≈ R(o) (trained on replay batches, the latent detached) turns an imagined
latent into the code the planner's novelty scores. R's outputs are standardised once, on the warm-up's frames.
"""

from __future__ import annotations

from typing import Any

import torch
from torch import Tensor, nn

from curiosity.nets.encoders import ConvEncoder, tanh_mlp

SEED_OFFSET = 104_729  # R and g draw their initial weights from seed + this, in a forked RNG (the run's stream is kept)


class RandomTarget(nn.Module):
    """R (frozen, random) and the head g (trained) of ``random_target`` novelty.

    Args:
        obs_shape: one observation's shape (C, H, W), square frames.
        latent_dim: d, the agent's latent size (g's input).
        dim: size of the codes r = R(o).
        hidden: width of g's two hidden tanh layers.
        lr: g's Adam learning rate.
        blur_sigma: R's Gaussian blur of each frame, in pixels (0: none).
        seed: the run's seed.
    """

    def __init__(self, obs_shape: tuple[int, ...], latent_dim: int, *, dim: int = 4, hidden: int = 64,
                 lr: float = 1e-3, blur_sigma: float = 4.0, seed: int = 0) -> None:  # fmt: skip
        super().__init__()
        if len(obs_shape) != 3 or obs_shape[1] != obs_shape[2]:
            raise ValueError(f"novelty input random_target encodes square image frames (env.obs=pixels); got an "
                             f"observation of shape {tuple(obs_shape)}")  # fmt: skip
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(seed + SEED_OFFSET)
            self.encoder = ConvEncoder(in_channels=obs_shape[0], latent_dim=dim, frame_size=obs_shape[1],
                                       blur_sigma=blur_sigma, frozen=True)  # fmt: skip
            self.head = tanh_mlp([latent_dim, hidden, hidden, dim])
        self.encoder.eval()
        self.optimizer = torch.optim.Adam(self.head.parameters(), lr=lr)
        self.register_buffer("calibrated", torch.tensor(False))

    @torch.no_grad()
    def calibrate(self, frames: Tensor) -> None:
        """Standardise R's outputs by their statistics on ``frames`` (N, C, H, W), once (later calls do nothing)."""
        if not bool(self.calibrated):
            self.encoder.calibrate(frames)
            self.calibrated.fill_(True)

    @torch.no_grad()
    def codes(self, frames: Tensor) -> Tensor:
        """r = R(o): (B, C, H, W) -> (B, dim)."""
        return self.encoder(frames)

    @torch.no_grad()
    def predict(self, z: Tensor) -> Tensor:
        """g(s), the code predicted from latents: (B, d) -> (B, dim)."""
        return self.head(z)

    def fit_step(self, z: Tensor, frames: Tensor) -> float:
        """One Adam step of g on ‖g(s) − R(o)‖² (mean over the batch): z (B, d) latents (detached here), frames
        (B, C, H, W) their observations; returns the loss before the step."""
        loss = target_loss(self.head(z.detach()), self.codes(frames))
        self.optimizer.zero_grad(set_to_none=True)
        loss.backward()
        self.optimizer.step()
        return float(loss.detach())

    def checkpoint(self) -> dict[str, Any]:
        return {"modules": self.state_dict(), "optimizer": self.optimizer.state_dict()}

    def restore(self, state: dict[str, Any]) -> None:
        self.load_state_dict(state["modules"])
        self.optimizer.load_state_dict(state["optimizer"])


def target_loss(predicted: Tensor, codes: Tensor) -> Tensor:
    """The head's loss: squared distance of predicted codes (B, dim) from R's codes (B, dim), mean over the batch."""
    return (predicted - codes).square().sum(-1).mean()
