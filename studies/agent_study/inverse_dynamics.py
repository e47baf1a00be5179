"""Offline prototype (not part of the package): the representation check with an inverse-dynamics head added.

The question: does an ICM/NGU-style inverse-dynamics loss (which action led from s_t to s_{t+1}?, cross-entropy of an
MLP head on [s_t, s_{t+1}]) added to the paper agent's representation loss make the latent's novelty tell the
frontier (pumping states) from random play, i.e. raise ``python -m studies.representation``'s AUC?

    python -m studies.agent_study.inverse_dynamics COEF [OVERRIDES...] [--data-seed D] [--out-dir DIR]

COEF is the weight of the inverse loss (0: the check unchanged); the head is the plug-in
``studies.agent_study.terms.InverseDynamics`` (Linear(2d, 64) -> ReLU -> Linear(64, A), ``agent.extra_terms.inverse``),
trained with the world model. Runs the check with ``env.renderer=fast`` at 0, 300 and 1000 iterations, prints its
table and writes ``ds<D>_c<COEF>_<overrides or default>.json`` into DIR (default: the current directory). Results:
``results/agent_study/representation/inverse/README.md``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from studies import representation as rep
from studies.agent_study.terms import InverseDynamics, extra_term

ITERS = (0, 300, 1000)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.inverse_dynamics",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("coef", type=float, help="the inverse-dynamics term's weight (0: none)")
    parser.add_argument("overrides", nargs="*", help="config overrides, as for runners.train")
    parser.add_argument("--data-seed", type=int, default=1, help="env seed of the training data (probe sets: +1, +2)")
    parser.add_argument("--out-dir", default=".", help="where the JSON goes (default: the current directory)")
    args = parser.parse_intermixed_args(argv)
    term = [extra_term("inverse", InverseDynamics, args.coef)] if args.coef > 0 else []
    rows = rep.study([*args.overrides, "env.renderer=fast", *term], list(ITERS), data_seed=args.data_seed)
    print(args.coef, args.overrides)
    print(rep._table(rows))
    name = f"ds{args.data_seed}_c{args.coef}_{'_'.join(args.overrides) or 'default'}.json"
    with open(Path(args.out_dir) / name, "w") as fh:
        json.dump({"coef": args.coef, "overrides": args.overrides, "data_seed": args.data_seed, "rows": rows}, fh)


if __name__ == "__main__":
    main()
