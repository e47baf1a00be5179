"""Observation encoders E_φ: o_t ↦ s_t ∈ R^d (docs/method.md §2)."""

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
    """NSRS's ``ImageEncoder`` for stacked 4×32×32 frames (docs/protocol.md §3.2).

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
        downsample: with a blur, keep every ``downsample``-th blurred pixel along each axis (the blur's ``stride``):
            the convolutions see (32/downsample)² frames; 1 (NSRS): the full frame. Needs ``blur_sigma > 0``.
        channels: output channels of the three convolutions (NSRS: 8, 16, 32).
        strides: strides of the three convolutions (NSRS: 1, 1, 1; the first two pad 1, the third none).
        pools: sizes of the two max-pools, after the second and the third convolution (NSRS: 4 with padding 1, and
            3); a pool of 4 or more pads 1, a smaller one none, and 1 is no pool. The pools and strides must leave
            the third convolution a map of at least 3 × 3.

    The cost of an encoder pass is its convolutions: NSRS's 3.3 MFLOP per observation at 32 × 32 (72 % in the second
    convolution), ``downsample=2`` with ``pools=[2, 3]`` 1.1 MFLOP (the same 2 × 2 × 32 = 128 features).
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
        downsample: int = 1,
        channels: Sequence[int] = (8, 16, 32),
        strides: Sequence[int] = (1, 1, 1),
        pools: Sequence[int] = (4, 3),
    ) -> None:
        super().__init__()
        if downsample > 1 and blur_sigma <= 0:
            raise ValueError(f"encoder.downsample={downsample} needs a blur (encoder.blur_sigma > 0, got {blur_sigma})")
        if len(channels) != 3 or len(strides) != 3 or len(pools) != 2:
            raise ValueError(f"encoder.channels and encoder.strides take 3 values, encoder.pools 2; got {list(channels)}, "
                             f"{list(strides)}, {list(pools)}")  # fmt: skip
        self.channels_last = channels_last
        steps: list[nn.Module] = [GaussianBlur(blur_sigma, stride=downsample)] if blur_sigma > 0 else []
        if differences:
            steps.append(FrameDifferences(difference_gain))
        self.preprocess = nn.Sequential(*steps)  # no parameters, no buffers in the state dict: checkpoints unchanged
        # max-pooling before tanh: tanh is increasing, so MaxPool(tanh(x)) = tanh(MaxPool(x)) and the gradient reaches
        # the same element; tanh then runs on 1/16 and 1/9 of the values (module indices, hence checkpoints, unchanged)
        c1, c2, c3 = (int(c) for c in channels)
        s1, s2, s3 = (int(s) for s in strides)
        self.features = nn.Sequential(
            nn.Conv2d(in_channels, c1, 3, stride=s1, padding=1),
            FastTanh(),
            nn.Conv2d(c1, c2, 3, stride=s2, padding=1),
            _max_pool(int(pools[0])),
            FastTanh(),
            nn.Conv2d(c2, c3, 3, stride=s3),
            _max_pool(int(pools[1])),
            FastTanh(),
            nn.Flatten(),
        )
        why = conv_layout_error(frame_size, downsample, strides, pools)
        if why:
            raise ValueError(why)
        side = -(-frame_size // downsample)
        with torch.no_grad():
            flat = self.features(torch.zeros(1, in_channels, side, side)).shape[1]
        self.head = nn.Linear(flat, latent_dim)
        if channels_last:
            self.features.to(memory_format=torch.channels_last)
        self.requires_grad_(not frozen)
        self.standardise = FixedStandardiser(latent_dim) if frozen else None  # trained encoders: checkpoints unchanged

    def forward(self, obs: Tensor) -> Tensor:
        """Encode observations.

        Args:
            obs: (B, C, frame_size, frame_size) float observations.

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


def conv_feature_side(frame_size: int, downsample: int, strides: Sequence[int], pools: Sequence[int]) -> int:
    """Side of the last feature map of :class:`ConvEncoder`'s stack for square frames (< 1: the stack does not fit)."""
    n = -(-frame_size // downsample)
    for i, stride in enumerate(strides):
        pad = 1 if i < 2 else 0
        n = (n + 2 * pad - 3) // stride + 1 if n + 2 * pad >= 3 else 0
        if i >= 1:
            size = int(pools[i - 1])
            pad = 1 if size >= 4 else 0
            n = (n + 2 * pad - size) // size + 1 if size > 1 and n + 2 * pad >= size else (n if size == 1 else 0)
    return n


def conv_layout_error(frame_size: int, downsample: int, strides: Sequence[int], pools: Sequence[int]) -> str:
    """One line saying why these frames leave no features through the stack; "" when they fit."""
    if conv_feature_side(frame_size, downsample, strides, pools) >= 1:
        return ""
    side = -(-frame_size // downsample)
    return (f"encoder.strides={list(strides)}, encoder.pools={list(pools)}: frames of {side} x {side} px (env.frame_size="
            f"{frame_size}, encoder.downsample={downsample}) leave no features; allowed: strides and pools that leave "
            "the last max-pool a map of at least 1 x 1")


def _max_pool(size: int) -> nn.Module:
    """NSRS's max-pool of ``size`` (padding 1 from a size of 4 on, as its pool of 4), or no pool for a size of 1."""
    return nn.MaxPool2d(size, padding=1 if size >= 4 else 0) if size > 1 else nn.Identity()


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
    (``studies.encoder_geometry``). Both parts are one latent for the transition model, the novelty and planning.

    Args:
        in_channels: number of stacked frames C.
        latent_dim: d, the whole latent's size (learned + random).
        random_dim: the random part's size, 1 <= random_dim < d.
        frame_size: side of the square frames.
        blur_sigma, differences, difference_gain: the learned part's input (as :class:`ConvEncoder`).
        frozen: also keep the learned part's initial weights (as :class:`ConvEncoder`).
        random_blur_sigma, random_differences: the random part's input.
        channels_last: as :class:`ConvEncoder`.
        downsample, channels, strides, pools: the learned part's architecture (as :class:`ConvEncoder`; the random
            part keeps NSRS's).
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
        downsample: int = 1,
        channels: Sequence[int] = (8, 16, 32),
        strides: Sequence[int] = (1, 1, 1),
        pools: Sequence[int] = (4, 3),
    ) -> None:
        super().__init__()
        if not 1 <= random_dim < latent_dim:
            raise ValueError(f"random_dim must be in [1, latent_dim), got {random_dim} with latent_dim={latent_dim}")
        self.learned = ConvEncoder(in_channels, latent_dim - random_dim, channels_last, frame_size, blur_sigma,
                                   differences, difference_gain, frozen, downsample, channels, strides,
                                   pools)  # fmt: skip
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
