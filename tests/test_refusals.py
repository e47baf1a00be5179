"""Every refusal of the command line is one line naming the key, exits non-zero, prints no traceback, and leaves an
existing finished run's directory byte for byte as it was.

One finished ``budget=smoke`` run is made per module; each bad invocation is aimed at its directory (or at an altered
copy of it) in a subprocess of ``python -m runners.train``.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

import pytest

from curiosity.config.validate import RULES
from tests.conftest import holding_lock, run_cli

BASE = ["budget=smoke", "env.renderer=fast"]


@dataclass(frozen=True)
class Case:
    """A bad invocation: its arguments (``{run}``: the run directory aimed at), the key its message must name, and
    how the finished run's directory is altered first (in a copy; "" aims at the finished run itself)."""

    args: tuple[str, ...]
    key: str
    alter: str = ""


def _out_of_range(key: str, value: str, *context: str) -> tuple[str, Case]:
    return f"{key}={value}", Case((*context, f"{key}={value}"), key)


# An out-of-range value of every key that curiosity/config/validate.py checks (the options that have the key first).
ICM, RND, MLP = ("baseline=icm",), ("baseline=rnd",), ("env.obs=state", "encoder=mlp")
SWEEP_INTO_RUN = ("hydra.sweep.dir={run}/..", "hydra.sweep.subdir={name}")  # a sweep whose jobs all aim at the run
OUT_OF_RANGE = dict([
    _out_of_range("seed", "-1"), _out_of_range("threads", "0"), _out_of_range("log_every", "0"),
    _out_of_range("checkpoint_every", "0"), _out_of_range("agent.internal_dim", "0"), _out_of_range("agent.n_step", "0"),
    _out_of_range("agent.batch_size", "1"), _out_of_range("agent.optimizer.lr", "0"),
    _out_of_range("agent.transition_coef", "-1"),
    _out_of_range("agent.reward_coef", "-0.5"), _out_of_range("agent.transition_hidden", "0"),
    _out_of_range("agent.transition_dropout", "1.0"), _out_of_range("agent.replay_capacity", "0"),
    _out_of_range("intrinsic.terms.novelty.action_scale", "-1"), _out_of_range("intrinsic.alpha", "1.5"),
    _out_of_range("intrinsic.terms.pe.eps", "0"),
    _out_of_range("intrinsic.terms.pe.dropout_samples", "0"), _out_of_range("intrinsic.terms.novelty.memory_size", "0"),
    _out_of_range("intrinsic.terms.novelty.refresh_every", "0"), _out_of_range("agent.q_coef", "-1"),
    _out_of_range("agent.q_target_every", "0"), _out_of_range("agent.first_call_min_iterations", "-1"),
    _out_of_range("env.frame_size", "4"), _out_of_range("encoder.blur_sigma", "-1"),
    _out_of_range("encoder.downsample", "0"), _out_of_range("encoder.channels", "[8,0,32]"),
    _out_of_range("encoder.strides", "[1,1]"), _out_of_range("encoder.pools", "[4,3,2]"),
    _out_of_range("env.frame_stack", "0"), _out_of_range("env.state_dim", "0"),
    _out_of_range("env.n_actions", "1"), _out_of_range("env.coverage_bins", "[10,10,0,10]"),
    _out_of_range("budget.max_steps", "0"), _out_of_range("budget.warmup_steps", "-1"),
    _out_of_range("budget.train_every", "0"), _out_of_range("budget.iters_per_train", "-1"),
    _out_of_range("budget.ramp", "[2,0]"), _out_of_range("budget.early_stop_every", "-1"),
    _out_of_range("budget.plateau_every", "-1"), _out_of_range("budget.plateau_tol", "1.0"),
    _out_of_range("budget.early_stop_threshold", "0"), _out_of_range("estimator.bandwidth", "0"),
    _out_of_range("estimator.k", "0", "estimator=knn"), _out_of_range("entropy.coef", "-1"),
    _out_of_range("entropy.t", "0"), _out_of_range("entropy.alpha", "0", "entropy=renyi"),
    _out_of_range("entropy.sigma", "-2", "entropy=renyi_mi"), _out_of_range("entropy.base", "1", "entropy=renyi"),
    _out_of_range("backward.coef", "-1"), _out_of_range("backward.sigma_b", "0", "backward=on"),
    _out_of_range("backward.n_candidates", "0"), _out_of_range("backward.noise_dim", "0"),
    _out_of_range("backward.hidden", "0"), _out_of_range("planner.horizon", "0"), _out_of_range("planner.gamma", "1.5"),
    _out_of_range("planner.temperature", "-1"), _out_of_range("planner.eta", "-1"),
    _out_of_range("planner.max_candidates", "0"), _out_of_range("planner.commit", "0"),
    _out_of_range("planner.hold", "0"), _out_of_range("planner.value_coef", "-1"),
    _out_of_range("encoder.hidden", "[64,0]", *MLP),
    _out_of_range("baseline.epsilon", "2", *ICM), _out_of_range("baseline.gamma", "-0.5", *RND),
    _out_of_range("intrinsic.terms.icm.lr", "0", *ICM), _out_of_range("intrinsic.terms.icm.eta", "-1", *ICM),
    _out_of_range("intrinsic.terms.icm.beta", "2", *ICM), _out_of_range("intrinsic.terms.icm.loss_weight", "-1", *ICM),
    _out_of_range("intrinsic.terms.icm.feature_dim", "0", *ICM), _out_of_range("intrinsic.terms.rnd.out_dim", "0", *RND),
    _out_of_range("intrinsic.terms.rnd.gamma_int", "1.5", *RND), _out_of_range("intrinsic.terms.rnd.obs_clip", "0", *RND),
    _out_of_range("agent.transition_ensemble", "0"), _out_of_range("agent.target_tau", "1.5"),
    _out_of_range("agent.code_coef", "-1"),
    _out_of_range("intrinsic.terms.novelty.refresh_drift", "-0.1"),
    _out_of_range("agent.probe_every", "-1"), _out_of_range("intrinsic.scale", "-1"),
    _out_of_range("intrinsic.terms.rnd.lr", "0", *RND),
    _out_of_range("intrinsic.terms.novelty.target_dim", "0"), _out_of_range("intrinsic.terms.novelty.target_hidden", "0"),
    _out_of_range("intrinsic.terms.novelty.target_lr", "0"), _out_of_range("intrinsic.terms.novelty.target_blur", "-1"),
])  # fmt: skip

OTHER = {
    # values that only fail together with others
    "estimator.k=64 (the first memory)": Case(("estimator=knn", "estimator.k=64"), "estimator.k"),
    "budget.warmup_steps=1 (< n_step)": Case(("budget.warmup_steps=1",), "budget.warmup_steps"),
    "budget.max_steps=64 (= warm-up)": Case(("budget.max_steps=64",), "budget.max_steps"),
    "encoder.downsample=2 without a blur": Case(("encoder=conv", "encoder.downsample=2"), "encoder.downsample=2"),
    "encoder.downsample=4 (8 x 8 frames through pools 4, 3)": Case(("encoder.downsample=4",), "encoder.pools"),
    "encoder.random_dim=4 (= internal_dim)": Case(("encoder=conv_with_random", "encoder.random_dim=4"), "encoder.random_dim"),
    "nsrs preset": Case(("baseline=nsrs", "planner.horizon=0"), "planner.horizon=0"),
    # keys and values the schema does not have
    "+foo=1": Case(("+foo=1",), "foo"),
    "++foo=1": Case(("++foo=1",), "foo"),
    "foo=1": Case(("foo=1",), "foo"),
    "batch_size=16 (moved)": Case(("batch_size=16",), "moved to agent.batch_size"),
    "+sweep=fig7 without -m": Case(("+sweep=fig7",), "+sweep=fig7"),
    "+encoder.foo=1": Case(("+encoder.foo=1",), "encoder.foo"),
    "~seed": Case(("~seed",), "seed"),
    "estimator=kdee": Case(("estimator=kdee",), "estimator"),
    "budget.max_steps=abc": Case(("budget.max_steps=abc",), "budget.max_steps"),
    "env.obs=rgb": Case(("env.obs=rgb",), "env.obs"),
    "seed=[": Case(("seed=[",), "seed"),
    "seed=0,1 without -m": Case(("seed=0,1",), "seed"),
    "-m seed=3-1": Case(("-m", "seed=3-1"), "seed"),
    # groups that do not fit together, and a planner that cannot enumerate its candidates
    "encoder=mlp with pixels": Case(("encoder=mlp",), "encoder"),
    "encoder=conv_blur16 (the default) with env.obs=state": Case(("env.obs=state",), "encoder"),
    "env=chain as listed": Case(("env=chain",), "encoder"),
    "env=chain with pixels": Case(("env=chain", "encoder=mlp", "env.obs=pixels"), "env.obs"),
    "planner.horizon=20": Case(("planner.horizon=20",), "planner.horizon"),
    "qtree horizon 11": Case(("planner=qtree", "planner.horizon=11"), "planner.horizon"),
    "pe imagined by an ensemble of one": Case(("intrinsic.terms.pe.imagined=ensemble",), "intrinsic.terms.pe.imagined"),
    "planner.model=simulated": Case(("planner.model=simulated",), "planner.model"),
    "planner.temperature_scale=relative": Case(("planner.temperature_scale=relative",), "planner.temperature_scale"),
    # the run directory
    "another configuration": Case(("seed=1",), "seed"),
    "resume=false": Case(("resume=false",), "resume=false"),
    "a live lock": Case((), "run.lock", alter="lock"),
    "truncated checkpoint": Case((), "checkpoint.pt", alter="truncated"),
    "empty checkpoint": Case((), "checkpoint.pt", alter="empty"),
    "unfinished, no checkpoint": Case((), "hydra.run.dir", alter="unfinished_no_checkpoint"),
    "finished, no checkpoint, another configuration": Case(("seed=1",), "seed", alter="no_checkpoint"),
    "run directory is a file": Case(("hydra.run.dir={run}/summary.json",), "hydra.run.dir"),
    "read-only run directory": Case(("hydra.run.dir={read_only}/run",), "hydra.run.dir"),
    "sweep directory is a file": Case(("-m", "seed=0,1", "hydra.sweep.dir={run}/metrics.csv"), "hydra.sweep.dir"),
    "sweep job, resume=false": Case(("-m", "seed=0", "resume=false", *SWEEP_INTO_RUN), "resume=false"),
    "sweep jobs, another configuration": Case(("-m", "seed=2,3", *SWEEP_INTO_RUN), "seed"),
}
CASES = {**OUT_OF_RANGE, **OTHER}


def snapshot(run_dir: Path) -> dict[str, bytes]:
    """Every file below ``run_dir`` (its path relative to it) and its bytes."""
    return {str(p.relative_to(run_dir)): p.read_bytes() for p in sorted(run_dir.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished ``baseline=random budget=smoke env.renderer=fast`` run."""
    run_dir = tmp_path_factory.mktemp("refusals") / "finished"
    res = run_cli([*BASE, "baseline=random", f"hydra.run.dir={run_dir}"], cwd=run_dir.parent)
    assert res.returncode == 0, res.stderr[-2000:]
    assert (run_dir / "summary.json").is_file() and (run_dir / "train.log").read_text()
    return run_dir


def _read_only_dir(tmp_path: Path) -> Path:
    if os.geteuid() != 0:  # permissions bind everyone but root
        (tmp_path / "read_only").mkdir(mode=0o555)
        return tmp_path / "read_only"
    if Path("/proc/sys").is_dir() and not os.access("/proc/sys", os.W_OK):
        return Path("/proc/sys")  # a read-only file system, even for root
    pytest.skip("no read-only directory to aim at")


def _altered(finished: Path, tmp_path: Path, alter: str, request: pytest.FixtureRequest) -> Path:
    """A copy of the finished run, altered: locked by a live process, its checkpoints damaged or gone (and, for an
    unfinished run, its summary)."""
    run_dir = tmp_path / "altered"
    shutil.copytree(finished, run_dir)
    checkpoints = [run_dir / "checkpoint.pt", run_dir / "checkpoint.prev.pt"]
    if alter == "lock":  # a live process holds the run's lock until the test ends
        held = holding_lock(run_dir)
        held.__enter__()
        request.addfinalizer(lambda: held.__exit__(None, None, None))
    for path in checkpoints:
        if alter == "truncated":
            path.write_bytes(path.read_bytes()[:1000])
        elif alter == "empty":
            path.write_bytes(b"")
        elif alter in ("no_checkpoint", "unfinished_no_checkpoint"):
            path.unlink()
    if alter == "unfinished_no_checkpoint":  # a run stopped before its end whose checkpoints were lost
        (run_dir / "summary.json").unlink()
    return run_dir


def test_every_checked_numeric_key_has_an_out_of_range_invocation() -> None:
    assert {key for key, _, _ in RULES} <= {case.key for case in OUT_OF_RANGE.values()}
    assert len(CASES) >= 30


@pytest.mark.parametrize("name", list(CASES))
def test_a_refusal_is_one_line_and_changes_nothing(
    name: str, finished: Path, tmp_path: Path, request: pytest.FixtureRequest
) -> None:
    case = CASES[name]
    run_dir = _altered(finished, tmp_path, case.alter, request) if case.alter else finished
    before, finished_before = snapshot(run_dir), snapshot(finished)
    places = {"run": str(run_dir), "name": run_dir.name}
    if any("{read_only}" in a for a in case.args):
        places["read_only"] = str(_read_only_dir(tmp_path))
    args = [a.format(**places) for a in case.args]
    if not any(a.startswith("baseline=") for a in args):
        args.append("baseline=random")
    if not any(a.startswith("hydra.run.dir=") for a in args):
        args.append(f"hydra.run.dir={run_dir}")
    res = run_cli([*BASE, *args], cwd=tmp_path, timeout=120)
    assert res.returncode != 0, res.stdout[-1000:]
    last = res.stderr.strip().splitlines()[-1]
    assert case.key in last, res.stderr[-2000:]
    assert "Traceback" not in res.stdout + res.stderr, res.stderr[-3000:]
    assert snapshot(run_dir) == before  # every file, byte for byte; nothing added
    assert snapshot(finished) == finished_before
