"""RunningMeanStd against numpy, ReturnNormaliser on hand-computed streams."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from curiosity.intrinsic.normalisers import ReturnNormaliser, RunningMeanStd

BATCH_SIZES = (1, 5, 17, 2, 64, 3)


def _stream(shape: tuple[int, ...], seed: int = 0) -> list[torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    return [torch.randn(b, *shape, generator=g, dtype=torch.float64) * 3.0 + 2.0 for b in BATCH_SIZES]


@pytest.mark.parametrize("shape", [(), (3,), (2, 4)])
def test_running_mean_std_matches_numpy_exactly_without_prior(shape: tuple[int, ...]) -> None:
    rms = RunningMeanStd(shape=shape, epsilon=0.0)
    batches = _stream(shape)
    for x in batches:
        rms.update(x)
    data = torch.cat(batches).numpy()
    np.testing.assert_allclose(rms.mean.numpy(), data.mean(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rms.var.numpy(), data.var(axis=0), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rms.std.numpy(), data.std(axis=0), rtol=0, atol=1e-12)
    assert rms.count == sum(BATCH_SIZES)


def test_running_mean_std_default_prior_fades() -> None:
    rms = RunningMeanStd(shape=(3,))
    assert torch.equal(rms.mean, torch.zeros(3, dtype=torch.float64))
    assert torch.equal(rms.var, torch.ones(3, dtype=torch.float64))
    assert rms.count == pytest.approx(1e-4)
    batches = _stream((3,), seed=1)
    for x in batches:
        rms.update(x.float())
    data = torch.cat(batches).numpy()
    np.testing.assert_allclose(rms.mean.numpy(), data.mean(axis=0), rtol=1e-5)
    np.testing.assert_allclose(rms.var.numpy(), data.var(axis=0), rtol=1e-5)
    assert rms.count == pytest.approx(sum(BATCH_SIZES) + 1e-4)


def test_running_mean_std_rejects_bad_input() -> None:
    rms = RunningMeanStd(shape=(3,))
    rms.update(torch.zeros(0, 3))
    assert rms.count == pytest.approx(1e-4)
    with pytest.raises(ValueError):
        rms.update(torch.zeros(4, 2))
    with pytest.raises(ValueError):
        RunningMeanStd(epsilon=-1.0)


def test_normalise_and_clip() -> None:
    rms = RunningMeanStd(shape=(2,), epsilon=0.0)
    rms.update(torch.tensor([[0.0, 10.0], [2.0, 10.0]]))  # mean (1, 10), std (1, 0)
    x = torch.tensor([[4.0, 10.0], [-9.0, 11.0]])
    assert torch.equal(rms.normalise(x), torch.tensor([[3.0, 0.0], [-10.0, 1e8]]))
    assert torch.equal(rms.normalise(x, clip=5.0), torch.tensor([[3.0, 0.0], [-5.0, 5.0]]))
    assert rms.normalise(x).dtype == torch.float32


def test_running_mean_std_state_round_trip_copies() -> None:
    rms = RunningMeanStd(shape=(3,))
    rms.update(torch.randn(10, 3))
    other = RunningMeanStd(shape=(3,))
    other.load_state_dict(rms.state_dict())
    assert torch.equal(other.mean, rms.mean) and torch.equal(other.var, rms.var) and other.count == rms.count
    rms.update(torch.randn(10, 3) + 5.0)
    assert not torch.equal(other.mean, rms.mean)
    with pytest.raises(ValueError):
        RunningMeanStd(shape=(2,)).load_state_dict(rms.state_dict())


def test_return_normaliser_hand_stream() -> None:
    # γ = 0.5, rewards 1, 2 | 3, 4 over two calls: returns R = 1, 2.5 | 4.25, 6.125 (never reset between calls).
    norm = ReturnNormaliser(gamma=0.5, epsilon=0.0)
    first = norm.update_and_normalise(torch.tensor([1.0, 2.0], dtype=torch.float64))
    # statistics of {1, 2.5}: mean 1.75, var 0.5625, std 0.75; update-then-divide, no mean subtraction
    assert norm.rms.var.item() == 0.5625  # exact: binary fractions throughout (IEEE 754, any CPU)
    torch.testing.assert_close(first, torch.tensor([1.0, 2.0], dtype=torch.float64) / 0.75, rtol=1e-15, atol=1e-15)
    second = norm.update_and_normalise(torch.tensor([3.0, 4.0], dtype=torch.float64))
    # statistics of {1, 2.5, 4.25, 6.125}: mean 3.46875, var 3.6748046875
    assert norm.running_return.item() == 6.125  # exact: binary fractions
    assert norm.rms.mean.item() == 3.46875  # exact: binary fractions
    assert norm.rms.var.item() == pytest.approx(3.6748046875, rel=1e-14)
    std = math.sqrt(3.6748046875)
    torch.testing.assert_close(second, torch.tensor([3.0 / std, 4.0 / std], dtype=torch.float64), rtol=1e-12, atol=1e-12)


def test_return_normaliser_parallel_streams() -> None:
    # two streams, time along dim 0: A = 1, 1 → R = 1, 1.5;  B = 0, 2 → R = 0, 2.  Values {1, 0, 1.5, 2}.
    norm = ReturnNormaliser(gamma=0.5, epsilon=0.0)
    norm.update(torch.tensor([[1.0, 0.0], [1.0, 2.0]]))
    assert torch.equal(norm.running_return, torch.tensor([1.5, 2.0], dtype=torch.float64))
    assert norm.rms.mean.item() == 1.125  # exact: binary fractions
    assert norm.rms.var.item() == 0.546875  # exact: binary fractions
    with pytest.raises(ValueError):
        norm.update(torch.ones(2, 3))


def test_return_normaliser_normalise_is_pure_and_keeps_the_mean() -> None:
    norm = ReturnNormaliser(gamma=0.9)
    norm.update(torch.tensor([5.0, 6.0, 7.0]))
    before = norm.state_dict()
    out = norm.normalise(torch.tensor([0.0, 1.0]))
    assert out[0].item() == 0.0  # no mean subtraction: a zero reward stays zero
    assert out[1].item() == pytest.approx(1.0 / norm.std.item(), rel=1e-6)
    after = norm.state_dict()
    assert torch.equal(before["running_return"], after["running_return"])
    assert all(torch.equal(before["rms"][k], after["rms"][k]) for k in ("mean", "var", "count"))


def test_return_normaliser_state_round_trip_continues_the_stream() -> None:
    norm = ReturnNormaliser(gamma=0.9)
    norm.update(torch.tensor([1.0, 3.0, 2.0]))
    clone = ReturnNormaliser(gamma=0.1)
    clone.load_state_dict(norm.state_dict())
    nxt = torch.tensor([0.5, 4.0])
    assert torch.equal(clone.update_and_normalise(nxt), norm.update_and_normalise(nxt))
    assert clone.gamma == 0.9
