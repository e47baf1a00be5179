"""ICM: shapes, the ln 3 inverse loss at init, the summed bonus formula, learning, purity of compute, checkpoints."""

from __future__ import annotations

import math

import pytest
import torch
from torch import nn

from curiosity.intrinsic.icm import ICM
from curiosity.intrinsic.nets import make_feature_net
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.types import TransitionBatch
from tests.conftest import random_batch

PIXELS, VECTOR = (4, 32, 32), (6,)
N_ACTIONS = 3


pytestmark = pytest.mark.usefixtures("one_thread")


def make_batch(batch_size: int, obs_shape: tuple[int, ...], seed: int) -> TransitionBatch:
    return random_batch(batch_size, obs_shape, seed)


def make_icm(obs_shape: tuple[int, ...], seed: int = 0, **kwargs: float) -> ICM:
    torch.manual_seed(seed)
    return ICM.from_obs_shape(obs_shape=obs_shape, n_actions=N_ACTIONS, feature_dim=16, **kwargs)


def snapshot(module: nn.Module) -> list[torch.Tensor]:
    return [p.detach().clone() for p in module.parameters()]


def same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return len(a) == len(b) and all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


def test_feature_net_shapes() -> None:
    conv = make_feature_net(PIXELS, 5)
    assert conv.head.in_features == 128  # the NSRS conv stack flattens 4×32×32 to 128
    assert conv(torch.zeros(2, *PIXELS)).shape == (2, 5)
    assert make_feature_net(VECTOR, 5)(torch.zeros(2, 6)).shape == (2, 5)
    with pytest.raises(ValueError):
        make_feature_net((3, 4), 5)


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
@pytest.mark.parametrize("batch_size", [1, 7])
def test_compute_shape(obs_shape: tuple[int, ...], batch_size: int) -> None:
    icm = make_icm(obs_shape)
    assert isinstance(icm, IntrinsicReward)
    bonus = icm.compute(make_batch(batch_size, obs_shape, seed=1))
    assert bonus.shape == (batch_size,)
    assert not bonus.requires_grad
    assert torch.isfinite(bonus).all() and (bonus >= 0).all()


def test_call_applies_scale() -> None:
    icm = make_icm(VECTOR, scale=2.5)
    batch = make_batch(7, VECTOR, seed=1)
    torch.testing.assert_close(icm(batch), 2.5 * icm.compute(batch))


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_inverse_loss_at_init_is_ln3(obs_shape: tuple[int, ...]) -> None:
    icm = make_icm(obs_shape)
    with torch.no_grad():
        icm.inverse_head[-1].weight.zero_()
        icm.inverse_head[-1].bias.zero_()
    info = icm.update(make_batch(7, obs_shape, seed=1))
    assert set(info) == {"losses/icm_inverse", "losses/icm_forward"}
    assert info["losses/icm_inverse"] == pytest.approx(math.log(3), abs=1e-6)
    assert math.log(3) == pytest.approx(1.0986122887, abs=1e-10)


def test_bonus_is_half_eta_squared_norm_summed_over_features() -> None:
    icm = make_icm(VECTOR, eta=3.0)
    with torch.no_grad():  # a zero forward head predicts φ̂ = 0, so the bonus is η/2 ‖φ_{t+1}‖²
        icm.forward_head[-1].weight.zero_()
        icm.forward_head[-1].bias.zero_()
    batch = make_batch(7, VECTOR, seed=1)
    with torch.no_grad():
        next_feat = icm.encoder(batch.next_obs)
    expected = 1.5 * next_feat.square().sum(dim=1)
    torch.testing.assert_close(icm.compute(batch), expected)
    assert not torch.allclose(icm.compute(batch), 1.5 * next_feat.square().mean(dim=1))


@pytest.mark.parametrize(("beta", "frozen"), [(0.0, "forward_head"), (1.0, "inverse_head")])
def test_beta_weights_the_two_losses(beta: float, frozen: str) -> None:
    icm = make_icm(VECTOR, beta=beta)
    before = snapshot(getattr(icm, frozen))
    icm.update(make_batch(7, VECTOR, seed=1))
    assert same(before, snapshot(getattr(icm, frozen)))  # weight 0 → zero gradient → Adam leaves it unchanged
    other = "inverse_head" if frozen == "forward_head" else "forward_head"
    assert not same(snapshot(make_icm(VECTOR, beta=beta).nets[other]), snapshot(getattr(icm, other)))


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_bonus_falls_on_a_repeated_transition_only(obs_shape: tuple[int, ...]) -> None:
    icm = make_icm(obs_shape)
    seen, new = make_batch(1, obs_shape, seed=1), make_batch(1, obs_shape, seed=2)
    start = icm.compute(seen).item()
    for _ in range(200):
        icm.update(seen)
    end = icm.compute(seen).item()
    assert end < start / 100.0
    assert icm.compute(new).item() > 10.0 * end


def test_compute_changes_no_state() -> None:
    icm = make_icm(VECTOR)
    batch = make_batch(7, VECTOR, seed=1)
    icm.update(batch)
    params, optim = snapshot(icm.nets), icm.state_dict()["optimiser"]
    first = icm.compute(batch)
    for _ in range(3):
        assert torch.equal(icm.compute(make_batch(5, VECTOR, seed=2)), icm.compute(make_batch(5, VECTOR, seed=2)))
    assert torch.equal(first, icm.compute(batch))
    assert same(params, snapshot(icm.nets))
    after = icm.state_dict()["optimiser"]
    assert all(torch.equal(optim["state"][k]["exp_avg"], after["state"][k]["exp_avg"]) for k in optim["state"])


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_state_dict_round_trip(obs_shape: tuple[int, ...]) -> None:
    icm = make_icm(obs_shape, seed=0)
    batch, probe = make_batch(7, obs_shape, seed=1), make_batch(5, obs_shape, seed=2)
    for _ in range(3):
        icm.update(batch)
    clone = make_icm(obs_shape, seed=1)
    assert not torch.equal(clone.compute(probe), icm.compute(probe))
    clone.load_state_dict(icm.state_dict())
    assert torch.equal(clone.compute(probe), icm.compute(probe))  # exact: a restored copy, same input, one process
    assert clone.update(batch) == icm.update(batch)  # the Adam state came along, and is not shared
    assert torch.equal(clone.compute(probe), icm.compute(probe))
