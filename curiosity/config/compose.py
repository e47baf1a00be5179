"""Compose the run config in Python, as ``python -m runners.train`` would (for notebooks, tests, benchmarks, and the
command line's checks before Hydra starts a job), and say in one line why a command line does not compose."""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hydra import compose, initialize_config_dir
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import HydraException, MissingConfigException, OverrideParseException
from omegaconf import DictConfig, ListConfig, OmegaConf
from omegaconf.errors import ConfigAttributeError, ConfigKeyError, OmegaConfBaseException

from curiosity.config import setup

CONF_DIR = Path(__file__).resolve().parents[2] / "conf"
JOB_NAME = "train"  # as ``python -m runners.train`` names its job (and its log file, train.log)


def compose_config(overrides: Sequence[str] = (), hydra_node: bool = False) -> DictConfig:
    """The run config for command-line style ``overrides`` (``["estimator=knn", "seed=3"]``).

    With ``hydra_node`` it keeps Hydra's own node (``hydra.run.dir``, ``hydra.runtime.choices``, ...) as the command
    line would see it.
    """
    setup()
    with initialize_config_dir(config_dir=str(CONF_DIR), version_base="1.3", job_name=JOB_NAME):
        return compose(config_name="config", overrides=list(overrides), return_hydra_config=hydra_node)


def _override_of(key: str, overrides: Sequence[str]) -> str:
    """The override that sets ``key`` (``key=value``), or ``key`` itself."""
    for override in overrides:
        if re.sub(r"^[+~]+", "", override).split("=")[0].split("@")[0] == key:
            return override
    return key


def _missing_option(err: MissingConfigException) -> str | None:
    """``estimator=kdee: no option kdee in group estimator; allowed: kde, knn`` from Hydra's missing-option error."""
    found = re.search(r"Could not find '([^']+)/([^'/]+)'", str(err))
    if not found:
        return None
    group, option = found.groups()
    options = re.search(r"Available options in '[^']+':\n((?:\t.*\n?)*)", str(err))
    allowed = ", ".join(line.strip() for line in options[1].splitlines() if line.strip()) if options else "see --help"
    return f"{group}={option}: no option {option} in group {group}; allowed: {allowed}"


def _unparsable(overrides: Sequence[str]) -> str | None:
    """``seed=[: cannot be parsed (...)`` for the first override Hydra's grammar rejects."""
    parser = OverridesParser.create()
    for override in overrides:
        try:
            parser.parse_overrides([override])
        except OverrideParseException as err:
            why = str(err).splitlines()[0]
            return f"{override}: cannot be parsed ({why}); allowed: key=value, group=option, +key=value, ~key"
    return None


def describe_compose_error(err: Exception, overrides: Sequence[str]) -> str:
    """One line naming the override, its value and what is allowed, for an error Hydra raised while composing."""
    if isinstance(err, MissingConfigException) and (line := _missing_option(err)):
        return line
    if isinstance(err, OverrideParseException) and (line := _unparsable(overrides)):
        return line
    if found := re.match(r"Ambiguous value for argument '(([^=']+)=[^']*)'", str(err)):
        arg, key = found.groups()
        return (f"{arg}: a comma-separated value is a sweep and needs -m; allowed: -m {arg} (one job per value), "
                f"{key}=[...] (a list) or {key}='...' (a string)")  # fmt: skip
    cause = err.__cause__
    if isinstance(cause, OmegaConfBaseException) and getattr(cause, "full_key", None):
        key = str(cause.full_key)
        if isinstance(cause, (ConfigAttributeError, ConfigKeyError)) and key in MOVED:
            return (f"{_override_of(key, overrides)}: {key} moved to {MOVED[key]}; allowed: {MOVED[key]}=<value> "
                    "(`python -m runners.train --help` lists the keys)")  # fmt: skip
        if isinstance(cause, (ConfigAttributeError, ConfigKeyError)):
            return (f"{_override_of(key, overrides)}: {key} is not a key of this configuration; allowed: the keys "
                    "`python -m runners.train --help` lists")  # fmt: skip
        return f"{_override_of(key, overrides)}: {str(cause.msg).splitlines()[0]}"
    text = str(err).split("\nConfig search path")[0].split("\nSee https")[0]
    return "; ".join(line.strip() for line in text.splitlines() if line.strip())


COMPOSE_ERRORS: tuple[type[Exception], ...] = (HydraException, OmegaConfBaseException)


GROUPS = ("env", "encoder", "entropy", "estimator", "backward", "intrinsic", "baseline", "planner", "budget")


# Keys added after runs were made, with the value that reproduces a run made before the key existed. A key's current
# default may differ (the agent study changed ``pe_imagined``'s default from ``dropout`` to ``off``), so a run without
# the key takes this value, not the default.
LEGACY: dict[str, Any] = {
    "intrinsic.terms.pe.imagined": "dropout",
    "agent.transition_ensemble": 1,
    "intrinsic.terms.novelty.refresh_drift": 0.0,
    "agent.probe_every": 0,
    "planner.model": "learned",
    "planner.temperature_scale": "absolute",
    "planner.sample_candidates": False,
    "planner.commit": 1,
    "planner.hold": 1,
    "agent.updates": "joint",
    "agent.q_intrinsic": "batch",
    "agent.first_call_min_iterations": 0,
    "env.distractor": "none",
    "env.tv.size": 5,
    "env.tv.row": 0,
    "env.tv.col": 0,
    "budget.stop_at_goal": True,
}


# Top-level keys of runs made before the intrinsic group held them (up to a6cf5b2) or before the agent node did (up to
# dfebfdf), and where they are now: a saved run's values move to the new places (and interpolations follow them).
AGENT_KEYS = ("internal_dim", "n_step", "batch_size", "optimizer", "transition_coef", "reward_coef", "transition_hidden",
              "transition_dropout", "normalised_transition", "detach_targets", "replay_capacity", "transition_ensemble",
              "probe_every", "q_coef", "q_target_every", "q_huber")  # fmt: skip
MOVED: dict[str, str] = {
    **{key: f"agent.{key}" for key in AGENT_KEYS},
    "hybrid_alpha": "intrinsic.alpha",
    "novelty_input": "intrinsic.terms.novelty.input",
    "action_scale": "intrinsic.terms.novelty.action_scale",
    "standardise_latents": "intrinsic.terms.novelty.standardise",
    "memory_mode": "intrinsic.terms.novelty.memory_mode",
    "memory_size": "intrinsic.terms.novelty.memory_size",
    "memory_refresh_every": "intrinsic.terms.novelty.refresh_every",
    "memory_refresh_drift": "intrinsic.terms.novelty.refresh_drift",
    "pe_imagined": "intrinsic.terms.pe.imagined",
    "pe_average": "intrinsic.terms.pe.average",
    "pe_eps": "intrinsic.terms.pe.eps",
    "pe_dropout_samples": "intrinsic.terms.pe.dropout_samples",
}

_ABSENT = object()  # OmegaConf.select's default: tells a missing key from a None value
_INTERPOLATED_KEY = re.compile(r"\$\{(\w+)\}")


def _follow_moves(node: DictConfig | ListConfig, moved: dict[str, str]) -> None:
    """Point interpolations of moved keys at their new place (``${internal_dim}`` -> ``${agent.internal_dim}``)."""
    for key in node.keys() if isinstance(node, DictConfig) else range(len(node)):
        child = node._get_node(key)  # the node itself: its interpolation unresolved
        if isinstance(child, (DictConfig, ListConfig)):
            _follow_moves(child, moved)
            continue
        value = child._value() if child is not None else None
        if isinstance(value, str) and "${" in value:
            new = _INTERPOLATED_KEY.sub(lambda found: "${" + moved.get(found[1], found[1]) + "}", value)
            if new != value:
                node[key] = new


@functools.lru_cache(maxsize=64)
def _defaults(choices: tuple[str, ...]) -> DictConfig:
    """The composed default config of these group choices (composed once per process: composing takes ~0.1-1 s)."""
    return compose_config(list(choices))


def saved_config(run_dir: str | Path) -> DictConfig:
    """A run's ``.hydra/config.yaml`` over the current defaults of its group choices: a run made before a key existed
    gets the value that reproduces what it did (``LEGACY``) or, for keys not listed there, the key's default; keys that
    moved since (``MOVED``) are read from their old place. When the
    choices no longer compose (an option removed since), the saved config alone."""
    setup()
    saved = OmegaConf.load(Path(run_dir) / ".hydra" / "config.yaml")
    assert isinstance(saved, DictConfig)
    choices = [f"{g}={saved[g].name}" for g in GROUPS if g in saved and "name" in saved[g]]
    try:
        base = _defaults(tuple(choices)).copy()
        OmegaConf.set_struct(base, False)
        merged = OmegaConf.merge(base, saved)
        moved_from = {new: old for old, new in MOVED.items()}
        for old, new in MOVED.items():
            value = OmegaConf.select(saved, old, default=_ABSENT)
            parent = new.rpartition(".")[0]
            if value is not _ABSENT and OmegaConf.select(merged, parent, default=None) is not None:
                OmegaConf.update(merged, new, value, merge=False)
                del merged[old]  # one place per value (the analysis labels rows by the keys whose values differ)
        _follow_moves(merged, MOVED)
        for key, value in LEGACY.items():
            absent = all(OmegaConf.select(saved, k, default=_ABSENT) is _ABSENT for k in (key, moved_from.get(key, key)))
            if absent and OmegaConf.select(base, key, default=_ABSENT) is not _ABSENT:
                OmegaConf.update(merged, key, value, merge=False)
    except (OmegaConfBaseException, HydraException, ValueError):
        return saved
    assert isinstance(merged, DictConfig)
    return merged
