"""Shapes, parameter counts and train/eval behaviour of the networks."""

from __future__ import annotations

import pytest
import torch

from curiosity.nets import BackwardPredictor, ConvEncoder, MLPEncoder, QNetwork, ResidualTransition, RewardModel, one_hot
from curiosity.nets.encoders import conv_feature_side
from curiosity.nets.activations import FastTanh


def n_params(module: torch.nn.Module) -> int:
    return sum(p.numel() for p in module.parameters())


def test_one_hot():
    out = one_hot(torch.tensor([2, 0, 1]), 3)
    assert out.dtype == torch.float32
    assert torch.equal(out, torch.tensor([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]))


def test_conv_encoder_shape_and_parameter_count():
    enc = ConvEncoder(in_channels=4, latent_dim=4)
    assert n_params(enc) == 6620
    assert enc(torch.randn(5, 4, 32, 32)).shape == (5, 4)
    assert ConvEncoder(latent_dim=2)(torch.randn(3, 4, 32, 32)).shape == (3, 2)


def test_conv_encoder_layout_does_not_change_the_function():
    torch.manual_seed(0)
    nhwc = ConvEncoder(channels_last=True)
    nchw = ConvEncoder(channels_last=False)
    nchw.load_state_dict(nhwc.state_dict())
    x = torch.randn(6, 4, 32, 32)
    torch.testing.assert_close(nhwc(x), nchw(x), rtol=1e-5, atol=1e-6)
    nhwc(x).sum().backward()
    assert all(p.grad is not None for p in nhwc.parameters())


def nsrs_order(enc: ConvEncoder) -> torch.nn.Module:
    """The same layers in NSRS's order with torch's own tanh: conv tanh conv tanh pool conv tanh pool flatten, head."""
    f, tanh = enc.features, torch.nn.Tanh
    return torch.nn.Sequential(f[0], tanh(), f[2], tanh(), f[3], f[5], tanh(), f[6], f[8], enc.head)


def test_conv_encoder_pooling_before_tanh_is_nsrs_function_and_gradient():
    # our encoder max-pools before each tanh for speed, and computes tanh as 2σ(2x) − 1 (FastTanh); tanh is increasing,
    # so the function and the gradient are NSRS's (tolerances: float ops in another order, any BLAS, tanh to ~2e-7)
    torch.manual_seed(0)
    for channels_last in (True, False):
        enc = ConvEncoder(channels_last=channels_last)
        ref = nsrs_order(enc)
        assert [type(m).__name__ for m in ref] == ["Conv2d", "Tanh", "Conv2d", "Tanh", "MaxPool2d", "Conv2d", "Tanh",
                                                   "MaxPool2d", "Flatten", "Linear"]  # fmt: skip
        x = torch.randn(16, 4, 32, 32)
        ours = enc(x)
        theirs = ref(x.contiguous(memory_format=torch.channels_last) if channels_last else x)
        torch.testing.assert_close(ours, theirs, rtol=1e-5, atol=1e-6)
        g_ours = torch.autograd.grad(ours.square().sum(), list(enc.parameters()))
        g_theirs = torch.autograd.grad(theirs.square().sum(), list(enc.parameters()))
        for a, b in zip(g_ours, g_theirs, strict=True):
            torch.testing.assert_close(a, b, rtol=1e-4, atol=1e-6)


def test_fast_tanh_is_tanh_to_float32_rounding_in_value_and_gradient():
    x = torch.cat([torch.linspace(-30, 30, 4001), torch.tensor([0.0, 1e-8, -1e-8, 88.0, -88.0, 1e4, -1e4])])
    x = x.requires_grad_()
    ours, ref = FastTanh()(x), torch.tanh(x)
    torch.testing.assert_close(ours, ref, rtol=0, atol=3e-7)  # absolute: 2σ(2x) − 1 cancels near 0
    assert ours.abs().max() <= 1.0 and torch.isfinite(ours).all()
    (g_ours,) = torch.autograd.grad(ours.square().sum(), x)
    (g_ref,) = torch.autograd.grad(ref.square().sum(), x)
    torch.testing.assert_close(g_ours, g_ref, rtol=0, atol=1e-6)
    image = torch.randn(2, 8, 5, 5).contiguous(memory_format=torch.channels_last)
    assert FastTanh()(image).is_contiguous(memory_format=torch.channels_last)


def test_mlp_encoder_shape_and_layers():
    enc = MLPEncoder(in_dim=6, latent_dim=2)
    widths = [m.out_features for m in enc.modules() if isinstance(m, torch.nn.Linear)]
    assert widths == [200, 100, 50, 10, 2]
    assert enc(torch.randn(7, 6)).shape == (7, 2)
    assert enc(torch.randn(7, 2, 3)).shape == (7, 2)


def test_transition_shape_residual_and_widths():
    torch.manual_seed(0)
    model = ResidualTransition(latent_dim=4, n_actions=3).eval()
    widths = [(m.in_features, m.out_features) for m in model.modules() if isinstance(m, torch.nn.Linear)]
    assert widths == [(7, 10), (10, 30), (30, 30), (30, 10), (10, 4)]
    z, a = torch.randn(8, 4), one_hot(torch.randint(3, (8,)), 3)
    out = model(z, a)
    assert out.shape == (8, 4)
    torch.testing.assert_close(out - z, model.net(torch.cat([z, a], -1)))


def test_transition_dropout_active_only_in_train_mode():
    torch.manual_seed(0)
    model = ResidualTransition(latent_dim=4, n_actions=3, dropout=0.5)
    z, a = torch.randn(16, 4), one_hot(torch.randint(3, (16,)), 3)
    model.train()
    assert not torch.equal(model(z, a), model(z, a))
    model.eval()
    assert torch.equal(model(z, a), model(z, a))  # exact: one input through one eval-mode net, in one process


def test_reward_model_shape_and_widths():
    model = RewardModel(latent_dim=4, n_actions=3)
    widths = [m.out_features for m in model.modules() if isinstance(m, torch.nn.Linear)]
    assert widths == [10, 50, 20, 1]
    assert model(torch.randn(9, 7)).shape == (9,)


def test_backward_predictor_shape_and_fresh_noise():
    model = BackwardPredictor(latent_dim=4, n_actions=3, n_candidates=5)
    z = torch.randn(6, 4)
    out = model(z)
    assert out.shape == (6, 5, 7)
    assert not torch.equal(out, model(z))
    assert not torch.equal(out[:, 0], out[:, 1])
    g1, g2 = torch.Generator().manual_seed(3), torch.Generator().manual_seed(3)
    assert torch.equal(model(z, generator=g1), model(z, generator=g2))  # exact: equal seeds, one process


def test_q_network_shape_and_widths():
    model = QNetwork(latent_dim=4, n_actions=3)
    widths = [(m.in_features, m.out_features) for m in model.modules() if isinstance(m, torch.nn.Linear)]
    assert widths == [(4, 20), (20, 50), (50, 20), (20, 3)]
    assert sum(isinstance(m, torch.nn.ReLU) for m in model.modules()) == 3
    assert model(torch.randn(2, 4)).shape == (2, 3)


@pytest.mark.parametrize("module", [RewardModel(2, 3), QNetwork(2, 3), MLPEncoder(5, 2)])
def test_gradients_reach_every_parameter(module):
    x = torch.randn(4, next(module.parameters()).shape[1])
    module(x).sum().backward()
    assert all(p.grad is not None and torch.isfinite(p.grad).all() for p in module.parameters())


def test_conv_encoder_flattens_any_frame_size() -> None:
    enc = ConvEncoder(in_channels=2, latent_dim=3, frame_size=48)
    assert enc(torch.zeros(5, 2, 48, 48)).shape == (5, 3)
    assert ConvEncoder().head.in_features == 128


@pytest.mark.parametrize(("kwargs", "flat"), [
    ({"downsample": 2, "pools": (2, 3)}, 128),  # 16 x 16 after the blur: conv 16 -> pool 8 -> conv 6 -> pool 2
    ({"strides": (2, 2, 1), "pools": (1, 3)}, 128),  # strided: 32 -> 16 -> 8 -> conv 6 -> pool 2
    ({"downsample": 2, "pools": (2, 3), "channels": (8, 8, 16)}, 64),  # narrower
])
def test_cheaper_conv_encoders_keep_nsrs_structure_and_encode_32px_observations(kwargs: dict, flat: int) -> None:
    enc = ConvEncoder(in_channels=4, latent_dim=4, blur_sigma=4.0, **kwargs)
    assert enc.head.in_features == flat
    assert len(enc.features) == len(ConvEncoder().features)  # module indices as NSRS's (a pool of 1: Identity)
    obs = torch.rand(6, 4, 32, 32) * 2 - 1
    z = enc(obs)
    assert z.shape == (6, 4)
    z.sum().backward()
    assert all(p.grad is not None and torch.isfinite(p.grad).all() for p in enc.parameters())


def test_default_conv_encoder_keeps_its_parameter_names() -> None:
    # the options' defaults build NSRS's encoder module for module: checkpoints of earlier runs load unchanged
    names = [n for n, _ in ConvEncoder(blur_sigma=4.0).named_parameters()]
    assert names == ["features.0.weight", "features.0.bias", "features.2.weight", "features.2.bias",
                     "features.5.weight", "features.5.bias", "head.weight", "head.bias"]  # fmt: skip


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"downsample": 2}, "needs a blur"),
    ({"blur_sigma": 4.0, "downsample": 4}, "leave no features"),  # 8 x 8 frames through a pool of 4 and of 3
    ({"strides": (2, 2, 2)}, "leave no features"),
    ({"channels": (8, 16)}, "take 3 values"),
])
def test_conv_encoder_options_that_cannot_build_are_refused_in_one_line(kwargs: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match) as info:
        ConvEncoder(**kwargs)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("frame_size", [16, 32])
@pytest.mark.parametrize("downsample", [1, 2])
@pytest.mark.parametrize("strides", [(1, 1, 1), (2, 1, 1), (2, 2, 1), (1, 2, 2)])
@pytest.mark.parametrize("pools", [(1, 1), (2, 3), (4, 3), (4, 2)])
def test_conv_feature_side_is_the_side_torch_computes(frame_size: int, downsample: int, strides: tuple, pools: tuple) -> None:
    # the arithmetic that config validation refuses a layout by, against the layers themselves
    side = conv_feature_side(frame_size, downsample, strides, pools)
    if side < 1:
        with pytest.raises(ValueError, match="leave no features"):
            ConvEncoder(frame_size=frame_size, blur_sigma=4.0, downsample=downsample, strides=strides, pools=pools)
        return
    enc = ConvEncoder(frame_size=frame_size, blur_sigma=4.0, downsample=downsample, strides=strides, pools=pools)
    n = -(-frame_size // downsample)
    assert enc.features[:-1](torch.zeros(1, 4, n, n)).shape[-2:] == (side, side)
