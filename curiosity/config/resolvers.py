"""OmegaConf resolvers used by ``conf/`` (registered at import, idempotently)."""

from __future__ import annotations

import functools
import hashlib
import sys

from hydra.core.global_hydra import GlobalHydra
from omegaconf import OmegaConf

# Config groups that ``--help`` lists: the user's, and the launchers; not the typed schemas (``schema/*``).
HELP_GROUPS = ("hydra/launcher",)


MAX_VARIANT_BYTES = 200  # a directory name may have 255 bytes on common filesystems


def run_variant(override_dirname: str) -> str:
    """The run-directory component naming a run's command-line overrides (``default`` when there are none).

    A name longer than ``MAX_VARIANT_BYTES`` (many overrides) is cut and made unique by a hash of the whole:
    ``<first 180 bytes>~<12 hex digits>``; the run's ``.hydra/overrides.yaml`` keeps the overrides in full.
    """
    name = override_dirname or "default"
    if len(name.encode()) <= MAX_VARIANT_BYTES:
        return name
    digest = hashlib.sha1(name.encode()).hexdigest()[:12]
    return name.encode()[:180].decode(errors="ignore") + "~" + digest


def _listed(group: str) -> bool:
    return group in HELP_GROUPS or not group.startswith(("hydra", "schema"))


HELP_FLAGS = ("--help", "-h")  # Hydra's flags that print the app help (its template holds ${help_groups:})


@functools.cache
def _groups_listing() -> str:
    hydra = GlobalHydra.instance().hydra
    return hydra.format_config_groups(_listed).rstrip("\n") if hydra is not None else ""


def help_groups() -> str:
    """``group: option, option`` lines for ``--help`` (``conf/hydra/help/curiosity.yaml``), Hydra's internals left out.

    Hydra resolves the help template while it composes every run's config (three times per run), and listing the
    groups scans every config file (≈ 1 s each time, measured: a third of a ``budget=smoke`` run's process time). So
    the listing is made only when the command line asks for the help, once per process; otherwise a pointer to it."""
    if not any(flag in sys.argv[1:] for flag in HELP_FLAGS):
        return "(python -m runners.train --help lists them)"
    return _groups_listing()


def one_minus(value: float) -> float:
    """``${one_minus:x}`` = 1 − x (kept for the saved configs of runs made while the hybrid's novelty weight was
    ``${one_minus:${hybrid_alpha}}``)."""
    return 1.0 - float(value)


def _env_actions(env_id: str, distractor: str = "none") -> int:
    from curiosity.envs.adapter import env_actions  # imports gymnasium: only when a config asks

    return env_actions(env_id, distractor)


def power(base: int, exponent: int) -> int:
    """``${power:a,b}`` = a ** b (integers): the MPC planner's default cap, A^5 sequences."""
    return int(base) ** int(exponent)


def by_obs(obs: object, pixels: str, state: str) -> str:
    """``${by_obs:${env.obs},a,b}`` = a for pixel observations, b for state vectors: the default's novelty input,
    random codes of the frames where there are frames (``random_target``), else the latent state (``state``)."""
    return pixels if str(getattr(obs, "value", obs)) == "pixels" else state


def _env_state_dim(env_id: str) -> int:
    from curiosity.envs.adapter import env_state_dim

    return env_state_dim(env_id)


def register_resolvers() -> None:
    """Register ``${run_variant:...}``, ``${help_groups:}``, ``${one_minus:...}``, ``${power:a,b}``,
    ``${env_actions:<id>,<distractor>}``, ``${env_state_dim:<id>}`` and ``${by_obs:<obs>,a,b}``; safe to call more
    than once (jobs share a process)."""
    OmegaConf.register_new_resolver("run_variant", run_variant, replace=True)
    OmegaConf.register_new_resolver("help_groups", help_groups, replace=True)
    OmegaConf.register_new_resolver("one_minus", one_minus, replace=True)
    OmegaConf.register_new_resolver("power", power, replace=True)
    OmegaConf.register_new_resolver("env_actions", _env_actions, replace=True)
    OmegaConf.register_new_resolver("env_state_dim", _env_state_dim, replace=True)
    OmegaConf.register_new_resolver("by_obs", by_obs, replace=True)
