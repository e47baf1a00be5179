"""Where a trained agent finds its states novel: intrinsic reward and novelty over a grid of the physical plane, beside
the cells the run visited.

``python -m analysis.heatmap RUN_DIR [--out DIR] [--grid N]`` restores the run from its checkpoint
(``curiosity.runtime.restore.restore_run``) and writes ``heatmap.{png,pdf}`` to DIR (default RUN_DIR). MountainCar:
an N × N grid of (position, velocity); each state is rendered as the frame stack a car at that state would have shown,
its earlier positions integrated backwards at constant velocity (x_{t−j} = x_t − j·v, clipped to the track). Acrobot:
(θ1, θ2) at zero velocity, so every frame of the stack is the same. Observations come from the run's own observation
wrappers (``curiosity.envs.make.observe_state``), are encoded with the trained encoder and scored with the trained
curiosity module: ``novelty`` is the novelty of arriving at the state, ``intrinsic`` the imagined r_int terms (novelty
and, with α > 0, the prediction-error bonus) averaged over the actions. The visited cells are the run's coverage grid
(from the checkpoint) projected onto the plane.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from analysis.plotting import DOUBLE, panels, save
from curiosity.agents.paper import PaperAgent
from curiosity.envs.make import observe_state
from curiosity.envs.simulator import Simulator
from curiosity.errors import CheckpointError
from curiosity.runtime.checkpoint import load_checkpoint
from curiosity.runtime.restore import RestoreError, restore_run

PLANES = {  # env name -> (axis names, low, high, physical state of a grid point (x, y))
    "mountaincar": (("position", "velocity"), (-1.2, -0.07), (0.6, 0.07)),
    "acrobot": (("θ1", "θ2"), (-np.pi, -np.pi), (np.pi, np.pi)),
}


@dataclass
class Plane:
    """An N × N grid: axis names, the axes' values xs (N,), ys (N,), and the physical states (N·N, P), y-major."""

    names: tuple[str, str]
    xs: np.ndarray
    ys: np.ndarray
    physical: np.ndarray


def plane(env: str, n: int) -> Plane:
    """The grid of ``env``'s plane (MountainCar (x, v); Acrobot (θ1, θ2, 0, 0))."""
    if env not in PLANES:
        raise ValueError(f"env={env}: no heatmap plane; allowed: {', '.join(PLANES)}")
    names, low, high = PLANES[env]
    xs, ys = np.linspace(low[0], high[0], n), np.linspace(low[1], high[1], n)
    gx, gy = np.meshgrid(xs, ys)
    cols = [gx.ravel(), gy.ravel()] + ([np.zeros(n * n)] * 2 if env == "acrobot" else [])
    return Plane(names, xs, ys, np.stack(cols, axis=1))


def history(env: str, state: np.ndarray, k: int) -> list[np.ndarray]:
    """The k physical states shown by a frame stack ending at ``state`` (P,), oldest first."""
    if env != "mountaincar":
        return [state] * k  # zero velocity: the earlier frames are the same
    x, v = state
    return [np.array([np.clip(x - j * v, -1.2, 0.6), v]) for j in range(k - 1, -1, -1)]


def render(sim: Simulator, state: np.ndarray) -> np.ndarray:
    """The run's observation of one physical state (one frame, or the state vector)."""
    sim.adapter.set_physical_state(sim.core, state)
    raw = sim.core._get_ob() if hasattr(sim.core, "_get_ob") else np.array(state, dtype=np.float32)
    return observe_state(sim.env, raw).astype(np.float32)


def observations(cfg: Any, grid: Plane) -> np.ndarray:
    """Observations (N·N, *obs_shape) of the grid states: frame stacks for pixels, state vectors otherwise."""
    sim = Simulator(cfg.env)
    if not sim.pixels:
        return np.stack([render(sim, s) for s in grid.physical])
    k = int(cfg.env.frame_stack)
    return np.stack([np.stack([render(sim, h) for h in history(str(cfg.env.name), s, k)]) for s in grid.physical])


@torch.no_grad()
def scores(agent: Any, obs: np.ndarray) -> dict[str, np.ndarray]:
    """``novelty`` (N,) and ``intrinsic`` (N,) of the observations under the trained agent."""
    with agent.model.evaluating():
        z = agent.model.encode(torch.as_tensor(obs))
        n, actions = z.shape[0], range(agent.model.n_actions)
        novelty = agent.novelty.novelty(z, torch.zeros(n, dtype=torch.long), z)
        terms = [agent.intrinsic.imagined_terms(z, torch.full((n,), a, dtype=torch.long), z) for a in actions]
        intrinsic = torch.stack([torch.stack(list(t.values())).sum(0) for t in terms]).mean(0)
    return {"novelty": novelty.numpy(), "intrinsic": intrinsic.numpy()}


def visited(cfg: Any, coverage: dict[str, np.ndarray]) -> np.ndarray:
    """The run's visited coverage cells projected onto the plane's two first dimensions: (bins_y, bins_x) bool."""
    bins = tuple(int(b) for b in cfg.env.coverage_bins)
    cells = np.asarray(coverage["visited"], dtype=bool).reshape(bins)
    return cells.any(axis=tuple(range(2, len(bins)))).T


def draw(run_dir: Path, out: Path, n: int) -> list[Path]:
    """Restore the run, score the grid and write ``heatmap.{png,pdf}``; returns the two paths."""
    run = restore_run(run_dir)
    if not isinstance(run.agent, PaperAgent) or run.agent.novelty is None:
        raise RestoreError(f"{run_dir}: method {run.cfg.method_label} has no latent curiosity module to map; "
                           "allowed: runs of the paper's agent (baseline=none) with a novelty term")  # fmt: skip
    grid = plane(str(run.cfg.env.name), n)
    torch.manual_seed(0)  # the imagined prediction-error bonus samples dropout masks: the same map on every re-run
    values = scores(run.agent, observations(run.cfg, grid))
    ckpt = load_checkpoint(run_dir)
    fig, axes = panels(3, width=DOUBLE / 3, height=2.2)  # two columns wide: every text 8 pt or more
    extent = (grid.xs[0], grid.xs[-1], grid.ys[0], grid.ys[-1])
    for ax, (name, v) in zip(axes, values.items(), strict=False):
        im = ax.imshow(v.reshape(n, n), origin="lower", extent=extent, aspect="auto", cmap="viridis")
        fig.colorbar(im, ax=ax, fraction=0.05)
        ax.set(xlabel=grid.names[0], ylabel=grid.names[1], title=f"{name} at step {run.step}")
    axes[2].imshow(visited(run.cfg, ckpt["coverage"]) if ckpt else np.zeros((2, 2)), origin="lower", extent=extent,
                   aspect="auto", cmap="Greys", vmin=0, vmax=1)  # fmt: skip
    axes[2].set(xlabel=grid.names[0], ylabel=grid.names[1], title="visited (coverage grid)")
    return save(fig, out, "heatmap")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run_dir", help="a run directory holding checkpoint.pt")
    p.add_argument("--out", help="where to write heatmap.{png,pdf} (default: RUN_DIR)")
    p.add_argument("--grid", type=int, default=40, help="grid points per axis (default 40)")
    args = p.parse_args()
    run_dir = Path(args.run_dir)
    try:
        if not run_dir.is_dir():
            raise RestoreError(f"{run_dir}: no such directory; allowed: a run directory holding checkpoint.pt")
        files = draw(run_dir, Path(args.out) if args.out else run_dir, args.grid)
    except (RestoreError, CheckpointError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        raise SystemExit(1) from None
    print(f"written: {' '.join(map(str, files))}")


if __name__ == "__main__":
    main()
