"""Observation encoders E_φ: o_t ↦ s_t ∈ R^d (method.md §2)."""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import torch
from torch import Tensor, nn

from curiosity.nets.activations import FastTanh
from curiosity.nets.preprocess import FrameDifferences, GaussianBlur


def tanh_mlp(sizes: Sequence[int], *, final_activation: bool = False, dropout: float = 0.0) -> nn.Sequential:
    """A stack of Linear layers with tanh (and optional dropout) between them.

    Args:
        sizes: layer widths [in, h_1, ..., out]; at least two entries.
        final_activation: also apply tanh (and dropout) after the last Linear.
        dropout: dropout probability after every activation (0 disables).

    Returns:
        ``nn.Sequential`` mapping (B, sizes[0]) to (B, sizes[-1]).
    """
    layers: list[nn.Module] = []
    n_linear = len(sizes) - 1
    for i, (fan_in, fan_out) in enumerate(itertools.pairwise(sizes)):
        layers.append(nn.Linear(fan_in, fan_out))
        if i < n_linear - 1 or final_activation:
            layers.append(nn.Tanh())
            if dropout > 0:
                layers.append(nn.Dropout(dropout))
    return nn.Sequential(*layers)


class FixedStandardiser(nn.Module):
    """y = (x − shift) / scale per coordinate, with (shift, scale) set once by :meth:`calibrate` (identity before).

    A frozen random encoder's latents keep the scale of its initialisation (on Acrobot's frames a standard deviation
    of ~0.005: ``info/latent_logdet`` at its floor), too small for the transition model and the dispersion term; its
    outputs are standardised with the statistics of the warm-up's observations (as RND normalises its features).
    The two buffers are in the state dict, so a resumed run keeps the calibration.
    """

    def __init__(self, dim: int) -> None:
        super().__init__()
        self.register_buffer("shift", torch.zeros(dim))
        self.register_buffer("scale", torch.ones(dim))

    def forward(self, x: Tensor) -> Tensor:
        """(B, dim) -> (B, dim)."""
        return (x - self.shift) / self.scale

    @torch.no_grad()
    def calibrate(self, raw: Tensor) -> None:
        """Set shift and scale to the mean and standard deviation of ``raw`` (N, dim) (scale floored at 1e-8)."""
        self.shift.copy_(raw.mean(0))
        self.scale.copy_(raw.std(0, correction=0).clamp_min(1e-8))


class ConvEncoder(nn.Module):
    """NSRS's ``ImageEncoder`` for stacked 4×32×32 frames (nsrs-protocol.md §3.2).

    Conv(C→8, 3, pad 1) tanh → Conv(8→16, 3, pad 1) tanh → MaxPool(4, pad 1) → Conv(16→32, 3) tanh → MaxPool(3)
    → flatten (128) → Linear(128→d). No output activation. 6,620 parameters for C = 4, d = 4.

    Memory format: with ``channels_last=True`` (default) weights and inputs use NHWC, which is faster on this
    2-core CPU (torch 2.13, B = 64, median of 200–300 runs, two sessions with other jobs running; NCHW → NHWC):
    forward+backward 35–39 → 25 ms on 1 thread, 20–26 → 16–17 ms on 2 threads; forward under no_grad
    19 → 8–13 ms on 1 thread, 11–16 → 8 ms on 2 threads. The output is the same function of the input either way
    (only strides differ; tested). Each max-pool runs before the tanh it follows in NSRS's order, the same function
    (tanh is increasing) at 1.55× the speed of forward+backward at B = 192 (one thread; ``runners.bench``; tested
    against NSRS's order). The tanh is :class:`~curiosity.nets.activations.FastTanh` (2σ(2x) − 1, the same function
    to float32 rounding; a training iteration ≈ 10 % faster, measured under load).

    Args:
        in_channels: number of stacked frames C.
        latent_dim: d, the latent size.
        channels_last: store weights and run convolutions in channels-last layout.
        frame_size: side of the square frames (32: the flattened features are 128).
        blur_sigma: > 0: a fixed Gaussian blur of every frame first (:class:`~curiosity.nets.preprocess.GaussianBlur`,
            σ in pixels); 0 (NSRS): none.
        differences: feed the newest frame and the successive differences of the (blurred) frames instead of the
            frames (:class:`~curiosity.nets.preprocess.FrameDifferences`); False (NSRS): the frames.
        difference_gain: factor on those differences.
        frozen: keep the initial (random) weights: no parameter takes a gradient, so no loss trains the encoder and
            its latents never move (a fixed random-feature encoder, as in random-feature curiosity); its outputs are
            standardised once :meth:`calibrate` has seen observations (:class:`FixedStandardiser`).
    """

    def __init__(
        self,
        in_channels: int = 4,
        latent_dim: int = 4,
        channels_last: bool = True,
        frame_size: int = 32,
        blur_sigma: float = 0.0,
        differences: bool = False,
        difference_gain: float = 1.0,
        frozen: bool = False,
    ) -> None:
        super().__init__()
        self.channels_last = channels_last
        steps: list[nn.Module] = [GaussianBlur(blur_sigma)] if blur_sigma > 0 else []
        if differences:
            steps.append(FrameDifferences(difference_gain))
        self.preprocess = nn.Sequential(*steps)  # no parameters, no buffers in the state dict: checkpoints unchanged
        # max-pooling before tanh: tanh is increasing, so MaxPool(tanh(x)) = tanh(MaxPool(x)) and the gradient reaches
        # the same element; tanh then runs on 1/16 and 1/9 of the values (module indices, hence checkpoints, unchanged)
        self.features = nn.Sequential(
            nn.Conv2d(in_channels, 8, 3, padding=1),
            FastTanh(),
            nn.Conv2d(8, 16, 3, padding=1),
            nn.MaxPool2d(4, padding=1),
            FastTanh(),
            nn.Conv2d(16, 32, 3),
            nn.MaxPool2d(3),
            FastTanh(),
            nn.Flatten(),
        )
        with torch.no_grad():
            flat = self.features(torch.zeros(1, in_channels, frame_size, frame_size)).shape[1]
        self.head = nn.Linear(flat, latent_dim)
        if channels_last:
            self.features.to(memory_format=torch.channels_last)
        self.requires_grad_(not frozen)
        self.standardise = FixedStandardiser(latent_dim) if frozen else None  # trained encoders: checkpoints unchanged

    def forward(self, obs: Tensor) -> Tensor:
        """Encode observations.

        Args:
            obs: (B, C, 32, 32) float observations.

        Returns:
            (B, d) latents s = E(o).
        """
        z = self._raw(obs)
        return z if self.standardise is None else self.standardise(z)

    def _raw(self, obs: Tensor) -> Tensor:
        obs = self.preprocess(obs)
        if self.channels_last:
            obs = obs.contiguous(memory_format=torch.channels_last)
        return self.head(self.features(obs))

    @torch.no_grad()
    def calibrate(self, obs: Tensor) -> None:
        """A frozen encoder standardises its outputs by their statistics on ``obs`` (N, C, H, W); otherwise nothing."""
        if self.standardise is not None:
            self.standardise.calibrate(self._raw(obs))


class MLPEncoder(nn.Module):
    """Encoder for vector observations: tanh MLP [in, 200, 100, 50, 10] then Linear(10→d), no output activation.

    Args:
        in_dim: flattened observation size.
        latent_dim: d.
        hidden: hidden widths.
        frozen: keep the initial (random) weights, outputs standardised after :meth:`calibrate` (as
            :class:`ConvEncoder`).
    """

    def __init__(self, in_dim: int, latent_dim: int = 4, hidden: Sequence[int] = (200, 100, 50, 10),
                 frozen: bool = False) -> None:  # fmt: skip
        super().__init__()
        self.net = tanh_mlp([in_dim, *hidden, latent_dim])
        self.requires_grad_(not frozen)
        self.standardise = FixedStandardiser(latent_dim) if frozen else None

    def forward(self, obs: Tensor) -> Tensor:
        """Encode observations.

        Args:
            obs: (B, *obs_shape) float observations with prod(obs_shape) = in_dim.

        Returns:
            (B, d) latents.
        """
        z = self.net(obs.flatten(start_dim=1))
        return z if self.standardise is None else self.standardise(z)

    @torch.no_grad()
    def calibrate(self, obs: Tensor) -> None:
        """A frozen encoder standardises its outputs by their statistics on ``obs`` (N, *obs_shape); otherwise nothing."""
        if self.standardise is not None:
            self.standardise.calibrate(self.net(obs.flatten(start_dim=1)))


class ConvWithRandomFeatures(nn.Module):
    """A trained :class:`ConvEncoder` beside a frozen random one: s = [E_φ(o), E_rand(o)] ∈ R^d.

    The first ``latent_dim − random_dim`` coordinates are learned (every loss trains them, as for ``encoder=conv``);
    the last ``random_dim`` come from a second conv encoder that keeps its random initial weights
    (``frozen=True``), by default on blurred frame differences, whose geometry follows the velocity
    (``analysis.encoder_geometry``). Both parts are one latent for the transition model, the novelty and planning.

    Args:
        in_channels: number of stacked frames C.
        latent_dim: d, the whole latent's size (learned + random).
        random_dim: the random part's size, 1 <= random_dim < d.
        frame_size: side of the square frames.
        blur_sigma, differences, difference_gain: the learned part's input (as :class:`ConvEncoder`).
        frozen: also keep the learned part's initial weights (as :class:`ConvEncoder`).
        random_blur_sigma, random_differences: the random part's input.
        channels_last: as :class:`ConvEncoder`.
    """

    def __init__(
        self,
        in_channels: int = 4,
        latent_dim: int = 8,
        random_dim: int = 4,
        frame_size: int = 32,
        blur_sigma: float = 0.0,
        differences: bool = False,
        difference_gain: float = 1.0,
        frozen: bool = False,
        random_blur_sigma: float = 4.0,
        random_differences: bool = True,
        channels_last: bool = True,
    ) -> None:
        super().__init__()
        if not 1 <= random_dim < latent_dim:
            raise ValueError(f"random_dim must be in [1, latent_dim), got {random_dim} with latent_dim={latent_dim}")
        self.learned = ConvEncoder(in_channels, latent_dim - random_dim, channels_last, frame_size, blur_sigma,
                                   differences, difference_gain, frozen)  # fmt: skip
        self.random = ConvEncoder(in_channels, random_dim, channels_last, frame_size, random_blur_sigma,
                                  random_differences, frozen=True)  # fmt: skip

    def forward(self, obs: Tensor) -> Tensor:
        """(B, C, H, W) float observations -> (B, d) latents [learned (B, d − random_dim), random (B, random_dim)]."""
        return torch.cat([self.learned(obs), self.random(obs)], dim=1)

    @torch.no_grad()
    def calibrate(self, obs: Tensor) -> None:
        """Standardise the random part's outputs (and a frozen learned part's) by their statistics on ``obs``."""
        self.learned.calibrate(obs)
        self.random.calibrate(obs)
