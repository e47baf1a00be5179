"""RND: shapes, frozen target, the mean-over-outputs bonus, clipping, learning, the statistics contract, checkpoints."""

from __future__ import annotations

from typing import Any

import pytest
import torch

from curiosity.intrinsic.rnd import RND
from curiosity.intrinsic.base import IntrinsicReward
from curiosity.types import TransitionBatch
from tests.conftest import random_batch

PIXELS, VECTOR = (4, 32, 32), (6,)


pytestmark = pytest.mark.usefixtures("one_thread")


def make_batch(batch_size: int, obs_shape: tuple[int, ...], seed: int) -> TransitionBatch:
    return random_batch(batch_size, obs_shape, seed)


def make_rnd(obs_shape: tuple[int, ...], seed: int = 0, **kwargs: Any) -> RND:
    torch.manual_seed(seed)
    return RND.from_obs_shape(obs_shape=obs_shape, out_dim=16, **kwargs)


def statistics(rnd: RND) -> list[torch.Tensor]:
    rms, ret = rnd.obs_rms, rnd.return_normaliser
    acc = ret.running_return if ret.running_return is not None else torch.empty(0)
    counts = torch.tensor([rms.count, ret.rms.count])
    return [t.clone() for t in (rms.mean, rms.var, ret.rms.mean, ret.rms.var, counts, acc)]


def same(a: list[torch.Tensor], b: list[torch.Tensor]) -> bool:
    return len(a) == len(b) and all(torch.equal(x, y) for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
@pytest.mark.parametrize("batch_size", [1, 7])
def test_compute_shape(obs_shape: tuple[int, ...], batch_size: int) -> None:
    rnd = make_rnd(obs_shape)
    assert isinstance(rnd, IntrinsicReward)
    rnd.update(make_batch(7, obs_shape, seed=3))
    bonus = rnd.compute(make_batch(batch_size, obs_shape, seed=1))
    assert bonus.shape == (batch_size,)
    assert not bonus.requires_grad
    assert torch.isfinite(bonus).all() and (bonus >= 0).all()


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_target_never_changes(obs_shape: tuple[int, ...]) -> None:
    rnd = make_rnd(obs_shape)
    before = {k: v.clone() for k, v in rnd.target.state_dict().items()}
    predictor_before = [p.detach().clone() for p in rnd.predictor.parameters()]
    for seed in range(5):
        info = rnd.update(make_batch(7, obs_shape, seed=seed))
    assert set(info) == {"losses/rnd"}
    assert all(not p.requires_grad for p in rnd.target.parameters())
    after = rnd.target.state_dict()
    assert before.keys() == after.keys() and all(torch.equal(before[k], after[k]) for k in before)
    assert not same(predictor_before, [p.detach() for p in rnd.predictor.parameters()])


def test_raw_bonus_is_mean_over_outputs_of_normalised_clipped_next_obs() -> None:
    rnd = make_rnd(VECTOR)
    rnd.observe(make_batch(64, VECTOR, seed=3))
    with torch.no_grad():  # a zero last layer makes f̂ = 0, so the raw bonus is mean_k f(x)_k²
        rnd.predictor[-1].weight.zero_()
        rnd.predictor[-1].bias.zero_()
    batch = make_batch(7, VECTOR, seed=1)
    x = rnd.obs_rms.normalise(batch.next_obs, clip=5.0)
    with torch.no_grad():
        expected = rnd.target(x).square().mean(dim=1)
    torch.testing.assert_close(rnd.raw_bonus(batch.next_obs), expected)
    torch.testing.assert_close(rnd.compute(batch), expected / rnd.return_normaliser.std.float())


def test_normalised_observations_are_clipped() -> None:
    rnd = make_rnd(VECTOR)
    rnd.observe(make_batch(64, VECTOR, seed=3))  # statistics of obs in [0, 1]
    far, farther = torch.full((1, 6), 1e3), torch.full((1, 6), 1e6)
    assert torch.equal(rnd.raw_bonus(far), rnd.raw_bonus(farther))  # both clip to x = +5 everywhere


def test_observe_updates_both_statistics() -> None:
    rnd = make_rnd(VECTOR, gamma_int=0.5)
    batch = make_batch(3, VECTOR, seed=1)
    rnd.observe(batch)
    torch.testing.assert_close(rnd.obs_rms.mean.float(), batch.next_obs.mean(0), rtol=1e-3, atol=1e-5)
    assert rnd.obs_rms.count == pytest.approx(3 + 1e-4)
    raw = rnd.raw_bonus(batch.next_obs).double()  # bonus under the updated observation statistics
    expected_return = 0.25 * raw[0] + 0.5 * raw[1] + raw[2]  # the batch is one time-ordered stream
    torch.testing.assert_close(rnd.return_normaliser.running_return, expected_return)


@pytest.mark.parametrize("observe_in_update", [True, False])
def test_update_observes_only_when_asked(observe_in_update: bool) -> None:
    rnd = make_rnd(VECTOR, observe_in_update=observe_in_update)
    before = statistics(rnd)
    rnd.update(make_batch(7, VECTOR, seed=1))
    assert same(before, statistics(rnd)) is not observe_in_update


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_compute_changes_no_state(obs_shape: tuple[int, ...]) -> None:
    rnd = make_rnd(obs_shape)
    batch = make_batch(7, obs_shape, seed=1)
    rnd.update(batch)
    stats, params = statistics(rnd), [p.detach().clone() for p in rnd.nets.parameters()]
    first = rnd.compute(batch)
    for seed in range(5):
        rnd.compute(make_batch(5, obs_shape, seed=seed))
        rnd.raw_bonus(make_batch(5, obs_shape, seed=seed).next_obs)
    assert torch.equal(first, rnd.compute(batch))
    assert same(stats, statistics(rnd))
    assert same(params, [p.detach() for p in rnd.nets.parameters()])


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_bonus_falls_on_a_repeated_transition_only(obs_shape: tuple[int, ...]) -> None:
    rnd = make_rnd(obs_shape)  # default lr 1e-4
    rnd.observe(make_batch(256, obs_shape, seed=3))  # warm-up observations initialise the statistics
    seen, new = make_batch(1, obs_shape, seed=1), make_batch(1, obs_shape, seed=2)
    start = rnd.raw_bonus(seen.next_obs).item()
    for _ in range(200):
        rnd.update(seen)
    assert rnd.raw_bonus(seen.next_obs).item() < start / 100.0
    assert rnd.compute(new).item() > 10.0 * rnd.compute(seen).item()


@pytest.mark.parametrize("obs_shape", [PIXELS, VECTOR])
def test_state_dict_round_trip(obs_shape: tuple[int, ...]) -> None:
    rnd = make_rnd(obs_shape, seed=0)
    batch, probe = make_batch(7, obs_shape, seed=1), make_batch(5, obs_shape, seed=2)
    for _ in range(3):
        rnd.update(batch)
    clone = make_rnd(obs_shape, seed=1)
    assert not torch.equal(clone.compute(probe), rnd.compute(probe))
    clone.load_state_dict(rnd.state_dict())
    assert torch.equal(clone.compute(probe), rnd.compute(probe))
    assert same(statistics(clone), statistics(rnd))
    assert clone.update(batch) == rnd.update(batch)  # Adam state and statistics came along, and are not shared
    assert torch.equal(clone.compute(probe), rnd.compute(probe))
