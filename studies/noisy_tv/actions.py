"""What the agents do instead: each action's share of the agent's own steps, with and without the noisy TV.

    python -m studies.noisy_tv.actions [RESULTS_DIR]

(default ``results/noisy_tv``). Reads only the committed runs, those below RESULTS_DIR and those its ``analysis.yaml``
includes (``summary.json`` ``behaviour.action_freq`` and ``.hydra/config.yaml``), and writes
``RESULTS_DIR/instrument/actions.md``: per method and distractor, mean ± SE over seeds of each action's share and of
the *zero-push* share, the steps that apply the env's no-op (its adapter's ``noop_action``; the TV's remote applies
it too, so with the TV it is the no-op's share plus the TV's).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from hydra.utils import get_class
from omegaconf import OmegaConf

from analysis.include import included_runs


def runs(root: Path) -> dict[tuple[str, str], list[np.ndarray]]:
    """(method, distractor) -> per seed, the action shares and, last, the zero-push share."""
    out: dict[tuple[str, str], list[np.ndarray]] = {}
    local = sorted(p.parent for p in root.rglob("summary.json"))
    for run in local + included_runs(root, local):
        summary = run / "summary.json"
        cfg = OmegaConf.load(run / ".hydra" / "config.yaml")
        freq = np.array(json.loads(summary.read_text())["behaviour"]["action_freq"], dtype=float)
        noop = get_class(cfg.env._target_).noop_action
        distractor = str(OmegaConf.select(cfg, "env.distractor", default="none"))
        push = freq[noop] + (freq[-1] if distractor == "noisy_tv" else 0.0)
        out.setdefault((str(cfg.method_label), distractor), []).append(np.append(freq, push))
    return out


def table(groups: dict[tuple[str, str], list[np.ndarray]]) -> str:
    width = max(len(v[0]) for v in groups.values()) - 1
    head = ["method", "distractor", "seeds", *(f"action {a}" for a in range(width)), "zero push (no-op + TV)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for (method, distractor), rows in sorted(groups.items()):
        x = np.array(rows)
        mean = x.mean(0)
        se = x.std(0, ddof=1) / np.sqrt(len(x)) if len(x) > 1 else [None] * len(mean)  # no SE from one seed
        cells = [f"{m:.3f} ± {s:.3f}" if s is not None else f"{m:.3f} ± –" for m, s in zip(mean, se, strict=True)]
        cells = cells[:-1] + ["–"] * (width + 1 - len(cells)) + cells[-1:]
        lines.append(f"| {method} | {distractor} | {len(x)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.noisy_tv.actions", description=__doc__.splitlines()[0])
    parser.add_argument("root", nargs="?", type=Path, default=Path("results/noisy_tv"),
                        help="the noisy-TV results directory (default results/noisy_tv)")  # fmt: skip
    root = parser.parse_args(argv).root
    text = table(runs(root))
    (root / "instrument" / "actions.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
