"""A run's resolved ``.hydra/config.yaml``, flattened to dotted keys, and the keys that never tell two rows apart: what
every analysis module that identifies runs by their config reads (``analysis.rows``, ``analysis.include``,
``analysis.cost``, ``analysis.steps_table``)."""

from __future__ import annotations

import functools
from pathlib import Path

from omegaconf import OmegaConf

from curiosity.config.compose import saved_config

# Keys that change neither the agent nor the environment, and keys derived from others (the action count follows
# env.id and env.distractor, which name the row): left out of a row's identity.
IGNORED = (
    "seed",
    "progress",
    "threads",
    "resume",
    "checkpoint_every",
    "checkpoint_keep",
    "env.n_actions",
    "planner.n_actions",
)


def flat_config(run_dir: str | Path) -> dict[str, object]:
    """A run's ``.hydra/config.yaml`` over the current defaults of its group choices (so that a key added after the run
    was made has its default, which keeps the old behaviour, and an oracle run is told apart from the learned-model
    runs made before ``planner.model`` existed), resolved where it can be, flattened to ``{"planner.horizon": 3}``.
    Read once per process and file version (one analysis command reads every run's config three times)."""
    path = Path(run_dir).resolve() / ".hydra" / "config.yaml"
    stat = path.stat()
    return dict(_flat_config(path, stat.st_mtime_ns, stat.st_size))


@functools.lru_cache(maxsize=4096)
def _flat_config(path: Path, mtime_ns: int, size: int) -> dict[str, object]:
    cfg = saved_config(path.parent.parent)
    try:
        tree = OmegaConf.to_container(cfg, resolve=True, enum_to_str=True)
    except Exception:  # an interpolation that needs a resolver of the runner: keep the raw text
        tree = OmegaConf.to_container(cfg, resolve=False, enum_to_str=True)
    flat: dict[str, object] = {}

    def walk(node: object, prefix: str) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                walk(value, f"{prefix}{key}.")
        else:
            flat[prefix[:-1]] = tuple(node) if isinstance(node, list) else node

    walk(tree, "")
    return flat
