"""Fixed (parameter-free) transforms of stacked frames applied inside an encoder, before its first convolution.

Why they exist (``results/agent_study/pixel_encoder/``): at 32 × 32 the Acrobot links are ~1.5 px wide, so two poses a
few degrees apart share few dark pixels and the distance between their frames saturates; and the velocity is only in
how successive frames differ. A random NSRS conv encoder's latent distances then rank-correlate 0.03 with velocity
distances (a random MLP of the state vector: 0.61). A Gaussian blur makes frame distances grow smoothly with the
displacement; successive differences of the blurred frames carry the velocity.
"""

from __future__ import annotations

import math

import torch
from torch import Tensor, nn
from torch.nn import functional as F


class GaussianBlur(nn.Module):
    """Separable Gaussian blur of each channel, zero padding around the frame's background level, contrast kept.

    The frames of this project are (x − 128)/128 gray levels with a white (1.0) background: the blur runs on
    ``x − background`` so the padding is background, and adds it back. A kernel normalised to sum 1 would divide the
    contrast of a one-pixel line by √(2π)σ (σ = 4: by 10), and the untrained encoder's latents with it, which kept
    the trained agent's latent collapsed (log det −27.6) for twice as long as without the blur; ``keep_contrast``
    multiplies the blurred deviation from the background by √(2π)σ, so a straight line one pixel wide keeps its peak.

    The blur along an axis of length n is one (n, n) banded matrix (row i holds the kernel centred on i, cut where
    the zero padding would be), so a frame is blurred as ``B_h @ x @ B_wᵀ``: the same sums as two zero-padded 1-D
    convolutions (:meth:`reference`, to float rounding), as two matrix products, about 10× faster on a CPU than the
    convolutions at 32 × 32 (they were about a third of the default's training iteration).

    With ``stride`` s > 1 the blurred frame is sampled at every s-th pixel along both axes (rows 0, s, 2s, … of each
    band matrix): a (H, W) frame becomes (⌈H/s⌉, ⌈W/s⌉) for the price of the smaller products. A blur of σ = 4 px
    leaves little detail at periods under ~2σ, so s = 2 loses little of what the encoder sees.

    Args:
        sigma: standard deviation in pixels; the kernel has radius ⌈3σ⌉.
        background: the level of the frame's background.
        keep_contrast: scale the result so a one-pixel line keeps its peak contrast (False: the kernel sums to 1).
        stride: keep every ``stride``-th blurred pixel along each axis (1: the full frame).
    """

    def __init__(self, sigma: float, background: float = 1.0, keep_contrast: bool = True, stride: int = 1) -> None:
        super().__init__()
        if sigma <= 0:
            raise ValueError(f"sigma must be > 0, got {sigma}")
        if stride < 1:
            raise ValueError(f"stride must be >= 1, got {stride}")
        self.stride = int(stride)
        radius = math.ceil(3 * sigma)
        x = torch.arange(-radius, radius + 1, dtype=torch.float32)
        kernel = torch.exp(-(x**2) / (2 * sigma**2))
        self.register_buffer("kernel", kernel / kernel.sum(), persistent=False)
        self.radius = radius
        self.background = background
        self.gain = math.sqrt(2 * math.pi) * sigma if keep_contrast else 1.0
        self._bands: dict[tuple[int, torch.dtype, torch.device], Tensor] = {}

    def band(self, n: int, dtype: torch.dtype, device: torch.device) -> Tensor:
        """The (⌈n/stride⌉, n) matrix of the blur along an axis of length n: ``[i, j] = kernel[j − i·stride + radius]``
        where ``|j − i·stride| ≤ radius``, else 0 (the zero padding)."""
        key = (n, dtype, device)
        if key not in self._bands:
            offset = torch.arange(n).view(1, n) - torch.arange(n).view(n, 1) + self.radius  # j − i + radius
            inside = (offset >= 0) & (offset <= 2 * self.radius)
            taps = self.kernel.to("cpu", torch.float64)[offset.clamp(0, 2 * self.radius)]
            self._bands[key] = torch.where(inside, taps, 0.0)[:: self.stride].contiguous().to(device, dtype)
        return self._bands[key]

    def forward(self, frames: Tensor) -> Tensor:
        """Blur ``frames`` (B, C, H, W) per channel; returns (B, C, ⌈H/stride⌉, ⌈W/stride⌉)."""
        h, w = frames.shape[-2:]
        x = frames - self.background
        x = self.band(h, x.dtype, x.device) @ x @ self.band(w, x.dtype, x.device).T
        return x * self.gain + self.background

    def reference(self, frames: Tensor) -> Tensor:
        """The same blur as two zero-padded 1-D convolutions with the same stride (how it was first written; kept to
        test the matrices against)."""
        b, c, h, w = frames.shape
        x = (frames - self.background).reshape(b * c, 1, h, w)
        k = self.kernel.to(x.dtype)
        x = F.conv2d(x, k.view(1, 1, 1, -1), padding=(0, self.radius), stride=(1, self.stride))
        x = F.conv2d(x, k.view(1, 1, -1, 1), padding=(self.radius, 0), stride=(self.stride, 1))
        return x.reshape(b, c, *x.shape[-2:]) * self.gain + self.background


class FrameDifferences(nn.Module):
    """Replace a stack of frames, oldest first, by the newest frame followed by the successive differences.

    (B, C, H, W) → (B, C, H, W): channel 0 is frame C−1 (the newest), channel k ≥ 1 is
    ``gain · (frame C−k − frame C−k−1)``. A linear, invertible map of the stack: nothing is lost, the motion is
    put where a random first layer weighs it as much as the pose.

    Args:
        gain: factor on the differences.
    """

    def __init__(self, gain: float = 1.0) -> None:
        super().__init__()
        self.gain = gain

    def forward(self, frames: Tensor) -> Tensor:
        """(B, C, H, W) stacked frames, oldest first → (B, C, H, W) newest frame and differences (newest first)."""
        diffs = (frames[:, 1:] - frames[:, :-1]).flip(1) * self.gain
        return torch.cat([frames[:, -1:], diffs], dim=1)
