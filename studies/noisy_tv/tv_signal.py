"""Why does (or doesn't) an agent press the noisy TV? What its final model makes of the TV, on its own replay.

    python -m studies.noisy_tv.tv_signal OUT.csv RUN_DIR [RUN_DIR ...]

Each RUN_DIR with its ``checkpoint.pt`` (not committed), restored by the package it runs with: run it from a worktree
of the runs' commit as ``PYTHONPATH=<this checkout> python -m studies.noisy_tv.tv_signal ...`` (``python -m`` puts the
worktree, and its package, first on the path; ``studies`` comes from this checkout). Writes OUT.csv, one row per run
(in the order given), and beside it OUT.md: per method, mean ± SE over its runs of the TV rate and of the ratios below.

For each run, over the transitions after the random warm-up (the agent's own steps), with the final encoder E and
latent transition model T in eval mode:
- ``tv_rate``: the fraction of those steps that pressed the TV (the remote, the last action).
- ``pe_tv``, ``pe_other``: the mean true latent prediction error e = ‖T(E(o), a) − E(o')‖² of real transitions that
  pressed the TV, and of the others. Their ratio is what the prediction-error bonus of a *real* step rewards the TV
  with (r_pe = log1p(e / ē) is monotone in e).
- ``dis_tv``, ``dis_other``: the ensemble disagreement ê(s, a) (what the planner scores an *imagined* step's
  prediction error with) of the TV action and, averaged, of the env's own actions, at the same states (every state
  the agent acted in).
- ``patch_shift``: mean ‖E(o with the newest frame's patch redrawn) − E(o)‖² (how far a fresh patch alone moves the
  latent), and ``step_shift``: mean ‖E(o') − E(o)‖² of the steps with the env's own actions (how far a physical step
  moves it). Their ratio says whether the encoder sees the TV at all.
- ``pixel_patch_shift``, ``pixel_step_shift``: the same two shifts in the frames themselves (sum of squares over the
  observation), and ``blur_patch_shift``, ``blur_step_shift`` in the frames after the encoder's fixed Gaussian blur
  (``encoder.blur_sigma``; equal to the raw ones without a blur): what the blur alone does to the TV, before learning.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
import torch

from curiosity.envs.distractor import find_tv
from curiosity.envs.wrappers import normalise_pixels
from curiosity.nets.preprocess import GaussianBlur
from curiosity.runtime.restore import restore_run

FIELDS = ("method", "seed", "steps", "tv_rate", "pe_tv", "pe_other", "dis_tv", "dis_other", "patch_shift",
          "step_shift", "pixel_patch_shift", "pixel_step_shift", "blur_patch_shift", "blur_step_shift")  # fmt: skip


def encode(model, obs: torch.Tensor) -> torch.Tensor:
    return torch.cat([model.encode(obs[i : i + 256]) for i in range(0, len(obs), 256)])


def measure(run_dir: Path) -> dict:
    run = restore_run(run_dir)
    cfg, agent = run.cfg, run.agent
    model, replay = agent.model, agent.replay
    tv_env = find_tv(run.env)  # the restored env's TV: its action and patch, as the run had them
    assert tv_env is not None and tv_env.tv_action is not None, f"{run_dir}: no remote-control TV in this run"
    tv_action, size = tv_env.tv_action, tv_env.size
    first = replay.total_added - len(replay)
    index = np.arange(max(first, int(cfg.budget.warmup_steps)), replay.total_added)
    rng = np.random.default_rng(0)
    with model.evaluating(), torch.no_grad():
        batch = replay.transitions_at(index)
        z, z_next = encode(model, batch.obs), encode(model, batch.next_obs)
        act = batch.act
        pe = (model.next(z, act) - z_next).square().sum(1)
        tv = act == tv_action
        dis = torch.stack([model.ensemble_disagreement(z, torch.full_like(act, a))
                           for a in range(tv_action + 1)], dim=1)  # fmt: skip
        redrawn = batch.obs.clone()
        noise = normalise_pixels(rng.integers(0, 256, size=(len(index), size, size), dtype=np.uint8))
        redrawn = redrawn.unsqueeze(1) if redrawn.dim() == 3 else redrawn  # (B, frames, H, W); the newest is last
        redrawn[:, -1, tv_env.rows, tv_env.cols] = torch.as_tensor(noise)
        redrawn = redrawn.reshape(batch.obs.shape)
        patch_shift = (encode(model, redrawn) - z).square().sum(1)
        step_shift = (z_next - z).square().sum(1)[~tv]
        sigma = float(cfg.encoder.get("blur_sigma", 0.0) or 0.0)
        blur = GaussianBlur(sigma) if sigma > 0 else torch.nn.Identity()
        frames = {"pixel": (batch.obs, redrawn, batch.next_obs)}
        frames["blur"] = tuple(blur(x.reshape(-1, *x.shape[-2:])).reshape(x.shape) for x in frames["pixel"])
        pixel = {}
        for name, (o, o_tv, o_next) in frames.items():
            pixel[f"{name}_patch_shift"] = float((o_tv - o).square().flatten(1).sum(1).mean())
            pixel[f"{name}_step_shift"] = float((o_next - o).square().flatten(1).sum(1)[~tv].mean())
    return {
        "method": str(cfg.method_label),
        "seed": int(cfg.seed),
        "steps": len(index),
        "tv_rate": float(tv.float().mean()),
        "pe_tv": float(pe[tv].mean()) if tv.any() else float("nan"),
        "pe_other": float(pe[~tv].mean()),
        "dis_tv": float(dis[:, tv_action].mean()),
        "dis_other": float(dis[:, :tv_action].mean()),
        "patch_shift": float(patch_shift.mean()),
        "step_shift": float(step_shift.mean()),
        **pixel,
    }


RATIOS = {  # column of OUT.md: (numerator, denominator)
    "real PE, TV / other": ("pe_tv", "pe_other"),
    "imagined PE (disagreement), TV / own actions": ("dis_tv", "dis_other"),
    "latent shift, fresh patch / physical step": ("patch_shift", "step_shift"),
    "blurred-frame shift, patch / step": ("blur_patch_shift", "blur_step_shift"),
    "frame shift, patch / step": ("pixel_patch_shift", "pixel_step_shift"),
}


def summary(rows: list[dict]) -> str:
    """Per method, mean ± SE (sample SD / sqrt(n)) over runs of the TV rate and each ratio in ``RATIOS``."""
    head = ["method", "runs (seeds)", "TV rate", *RATIOS]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for method in sorted({r["method"] for r in rows}):
        mine = [r for r in rows if r["method"] == method]
        cols = [np.array([r["tv_rate"] for r in mine])]
        cols += [np.array([r[a] / r[b] for r in mine]) for a, b in RATIOS.values()]
        cells = [f"{c.mean():.3f} ± {c.std(ddof=1) / np.sqrt(len(c)):.3f}" if len(c) > 1 else f"{c[0]:.3f}" for c in cols]
        seeds = " ".join(str(r["seed"]) for r in sorted(mine, key=lambda r: r["seed"]))
        lines.append(f"| {method} | {len(mine)} ({seeds}) | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.noisy_tv.tv_signal", description=__doc__.splitlines()[0])
    parser.add_argument("out", help="CSV file, one row per run (OUT.md beside it: the per-method summary)")
    parser.add_argument("runs", nargs="+", help="run directories with their checkpoint.pt, with the noisy TV")
    args = parser.parse_args(argv)
    out, runs = args.out, args.runs
    torch.set_num_threads(1)
    rows = []
    with Path(out).open("w", newline="") as f:
        writer = csv.DictWriter(f, FIELDS)
        writer.writeheader()
        for run in runs:
            row = measure(Path(run))
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
            print(row, flush=True)
            rows.append(row)
    Path(out).with_suffix(".md").write_text(summary(rows))


if __name__ == "__main__":
    main()
