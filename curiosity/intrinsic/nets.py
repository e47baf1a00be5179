"""Small network factories for the baselines, so ICM and RND can be built from an observation shape alone.

Pixel observations (C, H, W) get the NSRS-style conv stack (docs/method.md §2); for the paper's 4×32×32 frames it is

    Conv(4→8, 3, pad 1) tanh → Conv(8→16, 3, pad 1) tanh → MaxPool(4, pad 1) → Conv(16→32, 3) tanh → MaxPool(3)
    → flatten (128) → Linear(128→out_dim),

with no output activation. Vector observations (D,) get an MLP with ReLU hidden layers and a linear output.
"""

from __future__ import annotations

from collections.abc import Sequence

from torch import nn

from curiosity.nets.encoders import ConvEncoder


def conv_feature_net(obs_shape: Sequence[int], out_dim: int) -> nn.Module:
    """NSRS-style conv encoder (C, H, W) → (out_dim,): the paper agent's :class:`~curiosity.nets.encoders.ConvEncoder`."""
    return ConvEncoder(in_channels=int(obs_shape[0]), latent_dim=out_dim, frame_size=int(obs_shape[-1]))


def mlp(in_dim: int, out_dim: int, hidden: Sequence[int] = (64, 64)) -> nn.Sequential:
    """Linear layers in_dim → hidden… → out_dim with ReLU between them and no output activation."""
    layers: list[nn.Module] = []
    width = in_dim
    for h in hidden:
        layers += [nn.Linear(width, int(h)), nn.ReLU()]
        width = int(h)
    layers.append(nn.Linear(width, out_dim))
    return nn.Sequential(*layers)


def make_feature_net(obs_shape: Sequence[int], out_dim: int, mlp_hidden: Sequence[int] = (64, 64)) -> nn.Module:
    """Encoder for one observation: (B, *obs_shape) → (B, out_dim).

    Args:
        obs_shape: (C, H, W) for pixels (conv stack) or (D,) for vectors (MLP).
        out_dim: Feature width.
        mlp_hidden: Hidden widths of the MLP, used for vector observations only.

    Raises:
        ValueError: For observation shapes of any other rank.
    """
    obs_shape = tuple(int(s) for s in obs_shape)
    if len(obs_shape) == 3:
        return conv_feature_net(obs_shape, out_dim)
    if len(obs_shape) == 1:
        return mlp(obs_shape[0], out_dim, mlp_hidden)
    raise ValueError(f"obs_shape must be (C, H, W) or (D,), got {obs_shape}")


def make_predictor_net(
    obs_shape: Sequence[int], out_dim: int, hidden: int = 128, mlp_hidden: Sequence[int] = (64, 64)
) -> nn.Sequential:
    """RND predictor: the feature net to ``hidden`` units, then ReLU → Linear → ReLU → Linear(→ out_dim).

    It is deeper than the target :func:`make_feature_net` of the same ``obs_shape``, as in Burda et al. (2018), so it
    can fit the target's function on visited states.
    """
    trunk = make_feature_net(obs_shape, hidden, mlp_hidden)
    return nn.Sequential(trunk, nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(), nn.Linear(hidden, out_dim))
