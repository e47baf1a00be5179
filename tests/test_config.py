"""Config groups compose, typed schemas reject bad input, seed ranges expand."""

from __future__ import annotations

import re

import pytest
from hydra.errors import ConfigCompositionException
from omegaconf import OmegaConf
from omegaconf.errors import ConfigAttributeError, ValidationError

from curiosity.config import ConfigError, sampled_candidates, validate
from curiosity.config.ranges import RangeError, expand_ranges
from tests.conftest import compose_cfg, group_options

PUBLIC_GROUPS = {
    "env": {"acrobot", "mountaincar"},
    "encoder": {"conv", "mlp"},
    "entropy": {"gaussian_potential", "renyi", "renyi_mi", "none"},
    "estimator": {"kde", "knn"},
    "backward": {"off", "on"},
    "intrinsic": {"hybrid", "novelty", "pe", "icm", "rnd"},
    "baseline": {"none", "icm", "rnd", "nsrs", "random"},
    "planner": {"mpc", "qtree"},
    "budget": {"smoke", "quick", "paper"},
}


def test_public_groups_and_options_exist() -> None:
    found: dict[str, set[str]] = {}
    for group, option in group_options():
        found.setdefault(group, set()).add(option)
    for group, options in PUBLIC_GROUPS.items():
        assert options <= found[group], f"{group}: missing {options - found[group]}"


@pytest.mark.parametrize(("group", "option"), group_options())
def test_every_option_composes_and_validates(group: str, option: str) -> None:
    extra = {
        ("encoder", "mlp"): ["env.obs=state"],
        ("env", "chain"): ["encoder=mlp"],
        ("env", "cartpole"): ["encoder=mlp"],
        ("intrinsic", "pe"): ["intrinsic.terms.pe.imagined=ensemble", "agent.transition_ensemble=2"],
        ("intrinsic", "icm"): ["intrinsic.terms.icm.input=latent"],
        ("intrinsic", "rnd"): ["intrinsic.terms.rnd.input=latent"],
        ("intrinsic", "re3"): ["intrinsic.terms.re3.input=latent"],
    }.get((group, option), [])  # the planner imagines
    cfg = compose_cfg([f"{group}={option}", *extra])
    resolved = OmegaConf.to_container(cfg, resolve=True)
    assert isinstance(resolved, dict)
    if group in {"env", "entropy", "estimator", "backward", "planner", "budget", "baseline", "encoder", "intrinsic"}:
        assert cfg[group].name == option
    validate(cfg)


def test_defaults_are_the_paper_agent_on_acrobot_pixels() -> None:
    cfg = compose_cfg()
    assert (cfg.env.id, cfg.env.obs.value, cfg.baseline.name, cfg.budget.name) == ("Acrobot-v1", "pixels", "none", "per_plan")
    assert cfg.budget.max_steps == 3000 and cfg.planner.name == "mpc" and cfg.estimator.name == "kde"
    assert (cfg.encoder.blur_sigma, cfg.planner.hold) == (4.0, 4)  # the agent study's
    # the cheap seed's (issue 50): training once per plan, 16 x 16 frames, random-code novelty, a wider model
    assert (cfg.budget.train_every, cfg.budget.iters_per_train) == (20, 64)
    assert (cfg.encoder.name, cfg.encoder.downsample, list(cfg.encoder.pools)) == ("conv_blur16", 2, [2, 3])
    assert cfg.intrinsic.terms.novelty.input.value == "random_target" and cfg.agent.transition_hidden == 64
    # on state vectors the novelty falls back to the latent state (random codes need frames)
    state = compose_cfg(["env.obs=state", "encoder=mlp"])
    assert state.intrinsic.terms.novelty.input.value == "state"
    validate(state)


@pytest.mark.parametrize("preset", ["+experiment=paper_text", "+experiment=paper_code", "baseline=nsrs"])
def test_the_papers_presets_and_nsrs_keep_their_schedule_and_model_whatever_the_default(preset: str) -> None:
    """Issue 50 moved the default to budget=per_plan and a transition model 64 wide; the presets that claim a reading
    keep 16 iterations at every env step and the paper's 10 hidden units."""
    cfg = compose_cfg([preset])
    assert (cfg.budget.name, cfg.budget.train_every, cfg.budget.iters_per_train) == ("quick", 1, 16)
    assert cfg.agent.transition_hidden == 10
    assert compose_cfg([preset, "budget=faithful"]).budget.name == "faithful"  # the command line still wins


@pytest.mark.parametrize("preset", ["baseline=nsrs", "baseline=icm", "baseline=rnd", "+experiment=paper_text",
                                    "+experiment=paper_code"])  # fmt: skip
def test_the_papers_and_the_baselines_presets_keep_the_frames_as_they_are(preset: str) -> None:
    cfg = compose_cfg([preset])
    assert (cfg.encoder.name, cfg.encoder.blur_sigma) == ("conv", 0.0)
    if preset == "+experiment=paper_text":
        assert cfg.planner.hold == 1  # one action per env step, as the text plans
    # a state encoder given on the command line still replaces the preset's
    assert compose_cfg([preset, "env.obs=state", "encoder=mlp"]).encoder.name == "mlp"


@pytest.mark.parametrize(
    "key", ["seed", "budget.max_steps", "budget.warmup_steps", "planner.horizon", "env.renderer", "env.obs"]
)
def test_canonical_keys_exist(key: str) -> None:
    assert OmegaConf.select(compose_cfg(), key) is not None


def test_canonical_estimator_keys() -> None:
    assert compose_cfg(["estimator=kde"]).estimator.bandwidth > 0
    assert compose_cfg(["estimator=knn"]).estimator.k >= 1


@pytest.mark.parametrize(
    ("override", "error"),
    [
        ("seed=1.5", ValidationError),
        ("seed=abc", ValidationError),
        ("budget.max_steps=abc", ValidationError),
        ("env.renderer=slow", ValidationError),
        ("env.obs=rgb", ValidationError),
        ("estimator.k=3", ConfigAttributeError),  # kde has no k
        ("planner.bogus=1", ConfigAttributeError),
    ],
)
def test_typed_schema_rejects_bad_values(override: str, error: type[Exception]) -> None:
    with pytest.raises(ConfigCompositionException) as info:
        compose_cfg([override])
    key = override.split("=")[0]
    # Hydra's message names the key; the OmegaConf error behind it says what is wrong.
    assert key in str(info.value), str(info.value)
    cause = info.value.__cause__ or info.value.__context__
    assert isinstance(cause, error), repr(cause)


@pytest.mark.parametrize(
    ("overrides", "key"),
    [
        (["budget.max_steps=-5"], "budget.max_steps"),
        (["budget.max_steps=64"], "budget.max_steps"),  # not more than the 64 warm-up steps
        (["budget.warmup_steps=-1"], "budget.warmup_steps"),
        (["seed=-3"], "seed"),
        (["log_every=0"], "log_every"),
        (["estimator.bandwidth=0"], "estimator.bandwidth"),
        (["estimator=knn", "estimator.k=0"], "estimator.k"),
        (["planner.horizon=0"], "planner.horizon"),
        (["entropy=renyi", "entropy.alpha=-1"], "entropy.alpha"),
        (["entropy=renyi", "entropy.sigma=0"], "entropy.sigma"),
        (["env.coverage_bins=[10,0,10,10]"], "env.coverage_bins"),
    ],
)
def test_validation_names_key_value_and_rule(overrides: list[str], key: str) -> None:
    with pytest.raises(ConfigError) as info:
        validate(compose_cfg(overrides))
    assert key in str(info.value) and "must be" in str(info.value)


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["seed=0-3"], ["seed=range(0,4)"]),
        (["seed=5-5"], ["seed=range(5,6)"]),
        (["seed=0-2,7"], ["seed=0,1,2,7"]),
        (["seed=0,1,2"], ["seed=0,1,2"]),
        (["seed=range(0,4)"], ["seed=range(0,4)"]),
        (["seed=4"], ["seed=4"]),
        (["name=1-2", "estimator=kde,knn"], ["name=1-2", "estimator=kde,knn"]),
        (["-m", "seed=10-12", "budget=smoke"], ["-m", "seed=range(10,13)", "budget=smoke"]),
    ],
)
def test_expand_ranges(argv: list[str], expected: list[str]) -> None:
    assert expand_ranges(argv) == expected


@pytest.mark.parametrize("arg", ["seed=3-1", "seed=a-b", "seed=1-b", "seed=0-3-5", "seed=0,3-1"])
def test_bad_ranges_name_seed(arg: str) -> None:
    with pytest.raises(RangeError, match="seed="):
        expand_ranges([arg])


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["encoder=mlp"], "encoder=mlp: takes state observations, but env=acrobot has env.obs=pixels"),
        (["env.obs=state"], "encoder=conv_blur16: takes pixel observations"),
        (["env=chain"], "allowed: encoder=mlp with env.obs=state"),
        (["env=chain", "encoder=mlp", "env.obs=pixels"], "env.obs=pixels: env=chain has no pixel observations"),
        (["planner.horizon=20"], "planner.horizon=20: 3^20 = 3486784401 candidate sequences exceed planner.max_candidates"),
        (["planner.horizon=6", "planner.max_candidates=700"], "allowed: planner.horizon <= 5"),
        (["planner=qtree", "planner.horizon=11"], "planner.horizon=11: a depth-11 tree has 3^11 = 177147 leaves"),
        (["baseline=nsrs", "planner.horizon=0"], "planner.horizon=0: must be"),
        (["baseline=icm", "intrinsic.terms.icm.lr=-1"], "intrinsic.terms.icm.lr=-1.0: must be a learning rate > 0"),
        (["baseline=rnd", "baseline.gamma=1.5"], "baseline.gamma=1.5: must be a discount in [0, 1]"),
        (["env.obs=state", "encoder=mlp", "encoder.hidden=[64,0]"], "encoder.hidden=[64, 0]: must be"),
        (["intrinsic=rnd"], "intrinsic=rnd: no term scores the planner's imagined latent steps; allowed:"),
        (["intrinsic=pe"], "intrinsic=pe: no term scores the planner's imagined latent steps"),
        (["baseline=icm", "intrinsic=hybrid"], "intrinsic=hybrid: the pe term needs the paper agent's latent world model"),
    ],
)
def test_pairings_and_planner_sizes_are_checked(overrides: list[str], message: str) -> None:
    with pytest.raises(ConfigError, match=re.escape(message)) as info:
        validate(compose_cfg(overrides))
    assert "\n" not in str(info.value)  # one line


def test_mpc_samples_only_when_asked_and_says_how_many() -> None:
    assert sampled_candidates(compose_cfg()) is None  # 3^3 = 27 sequences, all scored
    cfg = compose_cfg(["planner.horizon=20", "planner.sample_candidates=true"])
    validate(cfg)
    assert sampled_candidates(cfg) == 243
    assert sampled_candidates(compose_cfg(["planner=qtree"])) is None


def test_a_long_override_list_gets_a_short_unique_directory_name() -> None:
    from curiosity.config.resolvers import MAX_VARIANT_BYTES, run_variant

    assert run_variant("") == "default" and run_variant("seed=3") == "seed=3"
    long_a = ",".join(f"key{i}=value{i}" for i in range(40))
    long_b = long_a.replace("value39", "value40")
    a, b = run_variant(long_a), run_variant(long_b)
    assert len(a.encode()) <= MAX_VARIANT_BYTES and a != b and a.startswith(long_a[:100])


def test_a_run_made_before_a_key_existed_reads_back_as_it_ran(tmp_path) -> None:
    """``saved_config`` fills a key the run's config lacks with the value that reproduces the run (``LEGACY``), not
    with today's default: runs made before the imagined prediction-error option existed planned with MC dropout,
    today's default is off."""
    from curiosity.config.compose import LEGACY, saved_config

    cfg = compose_cfg(["seed=3"])
    now = OmegaConf.to_container(cfg)
    del now["intrinsic"]["terms"]["pe"]["imagined"], now["planner"]["model"], now["agent"]["probe_every"]
    del now["planner"]["hold"]
    (tmp_path / ".hydra").mkdir()
    OmegaConf.save(OmegaConf.create(now), tmp_path / ".hydra" / "config.yaml")
    old = saved_config(tmp_path)
    assert cfg.intrinsic.terms.pe.imagined.name == "off" and LEGACY["intrinsic.terms.pe.imagined"] == "dropout"
    assert str(old.intrinsic.terms.pe.imagined) in ("dropout", "PEImagined.dropout")
    assert str(old.planner.model) in ("learned", "PlannerModel.learned") and old.agent.probe_every == 0
    assert cfg.planner.hold == 4 and old.planner.hold == 1  # runs before planner.hold held no action
    assert old.seed == 3 and old.agent.transition_dropout == cfg.agent.transition_dropout  # saved keys are kept as saved
    now["intrinsic"]["terms"]["pe"]["imagined"] = "off"
    OmegaConf.save(OmegaConf.create(now), tmp_path / ".hydra" / "config.yaml")
    assert str(saved_config(tmp_path).intrinsic.terms.pe.imagined) in ("off", "PEImagined.off")  # saved wins


def test_keys_of_runs_made_before_the_intrinsic_group_held_them_are_read_from_their_old_place(tmp_path) -> None:
    """A run saved with top-level ``hybrid_alpha``, ``pe_imagined``, ``novelty_input`` (no ``intrinsic`` node) reads
    back with those values in the intrinsic group (``MOVED``); an old run without ``pe_imagined`` gets ``LEGACY``'s."""
    from curiosity.config.compose import MOVED, saved_config

    now = OmegaConf.to_container(compose_cfg(["seed=3"]))
    del now["intrinsic"]
    old_keys = {"hybrid_alpha": 0.0, "novelty_input": "state_action", "memory_refresh_drift": 0.1,
                "pe_imagined": "ensemble"}  # fmt: skip
    (tmp_path / ".hydra").mkdir()
    OmegaConf.save(OmegaConf.create({**now, **old_keys}), tmp_path / ".hydra" / "config.yaml")
    old = saved_config(tmp_path)
    assert old.intrinsic.alpha == 0.0 and old.intrinsic.terms.novelty.refresh_drift == 0.1
    assert str(old.intrinsic.terms.novelty.input) in ("state_action", "NoveltyInput.state_action")
    assert str(old.intrinsic.terms.pe.imagined) in ("ensemble", "PEImagined.ensemble")
    assert set(old_keys) <= set(MOVED)
    del old_keys["pe_imagined"]
    OmegaConf.save(OmegaConf.create({**now, **old_keys}), tmp_path / ".hydra" / "config.yaml")
    assert str(saved_config(tmp_path).intrinsic.terms.pe.imagined) in ("dropout", "PEImagined.dropout")


def test_agent_keys_of_runs_made_before_the_agent_node_are_read_from_their_old_place(tmp_path) -> None:
    """A run saved with the agent's keys at the top level (``batch_size``, ``optimizer``, ... before the ``agent`` node)
    and its encoder's ``latent_dim: ${internal_dim}`` reads back with them under ``agent`` and the interpolation
    following the key, each value in one place only."""
    from curiosity.config.compose import AGENT_KEYS, MOVED, saved_config

    now = OmegaConf.to_container(compose_cfg(["seed=3"]), resolve=False)
    agent = {key: now["agent"].pop(key) for key in AGENT_KEYS}  # the keys that were top-level then
    del now["agent"]
    old = {**now, **agent, "batch_size": 16, "internal_dim": 6, "optimizer": {"_target_": "torch.optim.SGD", "lr": 0.1}}
    old["encoder"]["latent_dim"] = "${internal_dim}"
    (tmp_path / ".hydra").mkdir()
    OmegaConf.save(OmegaConf.create(old), tmp_path / ".hydra" / "config.yaml")
    cfg = saved_config(tmp_path)
    assert cfg.agent.batch_size == 16 and cfg.agent.internal_dim == 6 and cfg.encoder.latent_dim == 6
    assert cfg.agent.optimizer == {"_target_": "torch.optim.SGD", "lr": 0.1}  # replaced, not merged with Adam's keys
    assert not set(agent) & set(cfg) and all(f"agent.{key}" == MOVED[key] for key in agent)
