"""KDE novelty reward baselines (docs/method.md §4 worked example), prediction-error bonus oracle, hybrid, state dicts."""

from __future__ import annotations

import math

import pytest
import torch

from curiosity.intrinsic.mixture import hybrid_intrinsic_reward
from curiosity.intrinsic.prediction_error import PredictionErrorBonus, prediction_error_bonus, squared_prediction_error
from curiosity.novelty import BASELINES, KDENoveltyReward, kde_log_density, kde_reward_none, kde_reward_scalar

F64 = torch.float64
E = math.exp
LOG_RHO = torch.tensor([-0.4398695, -2.5527778, -65.6094379], dtype=F64)  # docs/method.md §4, 7 decimals
LOG_RHO_EXACT = torch.tensor(  # the same, from the squared distances of each query to the five replay points
    [
        math.log((4 * E(-1 / 4) + E(-9 / 4)) / 5),
        math.log((E(-9) + 2 * E(-6.5) + E(-4) + E(-1)) / 5),
        math.log((E(-100) + 2 * E(-90.5) + E(-81) + E(-64)) / 5),
    ],
    dtype=F64,
)


@pytest.fixture
def example() -> dict[str, torch.Tensor]:
    return {
        "replay": torch.tensor([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 2.0]], dtype=F64),
        "random": torch.tensor([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [0.5, 0.5]], dtype=F64),
        "query": torch.tensor([[0.5, 0.5], [3.0, 3.0], [10.0, 10.0]], dtype=F64),
    }


def _reward(example, baseline: str, **kw) -> torch.Tensor:
    obj = KDENoveltyReward(bandwidth=1.0, baseline=baseline, **kw)
    obj.set_reference(example["random"])
    obj.fit(example["replay"])
    return obj(example["query"])


def _replay_log_densities(self_in: bool) -> list[float]:
    """log ρ of each replay point under the replay KDE (h = 1), by hand from its squared distances."""
    d2 = [[0, 1, 1, 2, 8], [1, 0, 2, 1, 5], [1, 2, 0, 1, 5], [2, 1, 1, 0, 2], [8, 5, 5, 2, 0]]
    out = []
    for i, row in enumerate(d2):
        terms = [E(-v / 2) for j, v in enumerate(row) if self_in or j != i]
        out.append(math.log(sum(terms) / len(terms)))
    return out


def test_log_density_matches_worked_example(example):
    obj = KDENoveltyReward(bandwidth=1.0, baseline="none")
    obj.fit(example["replay"])
    torch.testing.assert_close(LOG_RHO_EXACT, LOG_RHO, atol=5e-8, rtol=0)
    torch.testing.assert_close(obj.log_density(example["query"]), LOG_RHO_EXACT, atol=1e-13, rtol=0)
    torch.testing.assert_close(obj(example["query"]), -LOG_RHO, atol=5e-8, rtol=0)


@pytest.mark.parametrize(
    ("self_in", "log_rho0_bar"),
    [(False, math.log((2 * E(-1 / 8) + E(-1 / 4)) / 3)), (True, math.log((1 + 2 * E(-1 / 8) + E(-1 / 4)) / 4))],
)
def test_scalar_baseline(example, self_in, log_rho0_bar):
    r = _reward(example, "scalar", self_in_reference=self_in)
    torch.testing.assert_close(r, log_rho0_bar - LOG_RHO_EXACT, atol=1e-13, rtol=0)
    assert r[0] < r[1] < r[2]  # rarer in replay -> larger reward, never -inf
    assert torch.isfinite(r).all()


def _log_rho0_at_queries() -> torch.Tensor:
    return torch.tensor(
        [
            math.log((1 + 2 * E(-1 / 8) + E(-1 / 4)) / 4),
            math.log((E(-9) + 2 * E(-7.625) + E(-6.25)) / 4),
            math.log((E(-100) + 2 * E(-95.125) + E(-90.25)) / 4),
        ],
        dtype=F64,
    )


def test_pointwise_and_printed_baselines(example):
    log_rho0 = _log_rho0_at_queries()
    pointwise = _reward(example, "pointwise")
    torch.testing.assert_close(pointwise, log_rho0 - LOG_RHO_EXACT, atol=1e-12, rtol=0)
    assert pointwise[2] < pointwise[1]  # the documented flaw: outside the random support the most novel is punished
    torch.testing.assert_close(_reward(example, "printed"), LOG_RHO_EXACT - log_rho0, atol=1e-12, rtol=0)


@pytest.mark.parametrize("self_in", [False, True])
def test_zscore_baseline(example, self_in):
    logs = torch.tensor(_replay_log_densities(self_in), dtype=F64)
    mean = logs.mean()
    std = (logs - mean).pow(2).mean().sqrt()  # population std, as numpy's default
    expected = -(LOG_RHO_EXACT - mean) / std
    torch.testing.assert_close(_reward(example, "zscore", self_in_reference=self_in), expected, atol=1e-12, rtol=0)


def test_state_dict_round_trip_and_errors(example):
    for baseline in BASELINES:
        src = KDENoveltyReward(bandwidth=1.0, baseline=baseline)
        src.set_reference(example["random"])
        src.fit(example["replay"])
        dst = KDENoveltyReward(bandwidth=1.0, baseline=baseline)
        dst.load_state_dict(src.state_dict())
        dst.fit(example["replay"])
        same = dst(example["query"]), src(example["query"])
        torch.testing.assert_close(*same, atol=0, rtol=0)  # exact: one computation on one input, in one process
    with pytest.raises(ValueError, match="baseline"):
        KDENoveltyReward(bandwidth=1.0, baseline="zscore").load_state_dict(src.state_dict())
    with pytest.raises(ValueError, match="baseline"):
        KDENoveltyReward(bandwidth=1.0, baseline="ratio")
    fresh = KDENoveltyReward(bandwidth=1.0)
    with pytest.raises(RuntimeError, match="fit"):
        fresh(example["query"])
    fresh.fit(example["replay"])
    with pytest.raises(RuntimeError, match="set_reference"):
        fresh(example["query"])


@pytest.mark.parametrize("b", [2, 512])
def test_reward_is_the_named_function_without_grad(b):
    g = torch.Generator().manual_seed(b)
    memory, ref = torch.randn(300, 3, generator=g), torch.randn(50, 3, generator=g)
    query = torch.randn(b, 3, generator=g, requires_grad=True)
    obj = KDENoveltyReward(bandwidth=0.6)
    obj.set_reference(ref)
    obj.fit(memory)
    r = obj(query)
    assert r.shape == (b,) and r.dtype == torch.float32 and not r.requires_grad
    log_rho0_bar = kde_log_density(ref, ref, bandwidth=0.6, exclude_self=True).mean()
    expected = kde_reward_scalar(kde_log_density(query, memory, bandwidth=0.6), log_rho0_bar)
    torch.testing.assert_close(r, expected.detach(), atol=1e-5, rtol=0)


def test_hydra_instantiate():
    from hydra.utils import instantiate

    obj = instantiate({"_target_": "curiosity.novelty.KDENoveltyReward", "bandwidth": 0.5, "baseline": "zscore"})
    assert isinstance(obj, KDENoveltyReward) and obj.baseline == "zscore" and obj.bandwidth == 0.5
    target = "curiosity.intrinsic.prediction_error.PredictionErrorBonus"
    pe = instantiate({"_target_": target, "average": "ema", "ema_decay": 0.9})
    assert isinstance(pe, PredictionErrorBonus) and pe.average == "ema"


# --- prediction-error bonus ---

PE_ERRORS = torch.tensor([0.0, 0.5, 1.0, 4.0], dtype=F64)
PE_ORACLE = torch.tensor([0.0, 0.4054651081, 0.6931471806, 1.6094379124], dtype=F64)  # ē = 1, ε = 1e-8 (docs/method.md §4)


def test_pe_bonus_oracle():
    # the printed oracle is log(1 + e) to 10 digits; ε = 1e-8 shifts the values by up to 8e-9
    torch.testing.assert_close(prediction_error_bonus(PE_ERRORS, 1.0, eps=1e-8), PE_ORACLE, atol=1e-8, rtol=0)
    exact = torch.log1p(PE_ERRORS / (1.0 + 1e-8))
    torch.testing.assert_close(prediction_error_bonus(PE_ERRORS, 1.0, eps=1e-8), exact, atol=1e-15, rtol=0)
    bonus = PredictionErrorBonus(eps=1e-8, initial_mean=1.0)
    torch.testing.assert_close(bonus(PE_ERRORS), exact, atol=1e-15, rtol=0)
    assert bonus.mean == pytest.approx(1.375, abs=1e-15) and bonus.count == 4


def test_pe_update_after_use_cumulative():
    bonus = PredictionErrorBonus(initial_mean=1.0)
    first = bonus(torch.tensor([100.0, 100.0]))  # uses ē = 1 from before the batch, not this batch's 100
    assert first[0].item() == pytest.approx(math.log(101.0), abs=1e-5)
    bonus.update(torch.tensor([1.0]))
    assert bonus.mean == pytest.approx(201.0 / 3.0, abs=1e-12)  # mean of every error seen
    r = bonus.compute(torch.tensor([201.0 / 3.0], dtype=F64))
    assert r.item() == pytest.approx(math.log(2.0), abs=1e-9) and bonus.count == 3  # compute() does not update


def test_pe_ema():
    bonus = PredictionErrorBonus(average="ema", ema_decay=0.9, initial_mean=1.0)
    bonus(PE_ERRORS)
    assert bonus.mean == pytest.approx(1.375, abs=1e-15)  # first update: the batch mean
    r = bonus(torch.tensor([3.0, 5.0], dtype=F64))
    torch.testing.assert_close(r, torch.log1p(torch.tensor([3.0, 5.0], dtype=F64) / (1.375 + 1e-8)), atol=1e-12, rtol=0)
    assert bonus.mean == pytest.approx(0.9 * 1.375 + 0.1 * 4.0, abs=1e-12)


def test_pe_state_dict_and_validation():
    src = PredictionErrorBonus(average="ema", ema_decay=0.5)
    src(torch.tensor([2.0, 4.0]))
    src(torch.tensor([9.0]))
    dst = PredictionErrorBonus(average="ema", ema_decay=0.5)
    dst.load_state_dict(src.state_dict())
    assert (dst.mean, dst.count) == (src.mean, src.count) == (0.5 * 3.0 + 0.5 * 9.0, 3)
    with pytest.raises(ValueError, match="average"):
        PredictionErrorBonus(average="median")
    with pytest.raises(ValueError, match="ema_decay"):
        PredictionErrorBonus(ema_decay=1.0)


def test_squared_prediction_error_sums_features():
    pred = torch.tensor([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0]], requires_grad=True)
    target = torch.tensor([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    e = squared_prediction_error(pred, target)
    torch.testing.assert_close(e, torch.tensor([13.0, 3.0]), atol=0, rtol=0)  # exact: sums of small integers
    assert not e.requires_grad


def test_hybrid():
    # Small integers and binary fractions: every operation below is exact in IEEE 754 arithmetic, on any CPU.
    r_nov, r_pe = torch.tensor([1.0, -2.0]), torch.tensor([3.0, 0.5])
    mix = hybrid_intrinsic_reward
    torch.testing.assert_close(mix(r_nov, r_pe), torch.tensor([2.0, -0.75]), atol=0, rtol=0)  # exact: binary fractions
    torch.testing.assert_close(mix(r_nov, r_pe, alpha=0.0), r_nov, atol=0, rtol=0)  # exact: binary fractions
    torch.testing.assert_close(mix(r_nov, r_pe, alpha=1.0), r_pe, atol=0, rtol=0)  # exact: binary fractions
    torch.testing.assert_close(mix(r_nov, r_pe, alpha=0.25), 0.75 * r_nov + 0.25 * r_pe, atol=0, rtol=0)  # exact: as above
    with pytest.raises(ValueError, match="alpha"):
        hybrid_intrinsic_reward(r_nov, r_pe, alpha=1.5)
    torch.testing.assert_close(kde_reward_none(torch.tensor([-2.0])), torch.tensor([2.0]), atol=0, rtol=0)  # exact: a negation
