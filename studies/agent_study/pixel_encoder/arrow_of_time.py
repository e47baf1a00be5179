"""Offline prototype (not part of the package): the paper agent's representation loss plus an arrow-of-time term,
measured by ``python -m studies.encoder_geometry``'s velocity geometry after offline training.

    python -m studies.agent_study.pixel_encoder.arrow_of_time COEF [OVERRIDES...] --seeds 0,1 --train-iters 1000 --json OUT

The term is the plug-in ``studies.agent_study.terms.ArrowOfTime`` at weight COEF (``agent.extra_terms.arrow``): from
each segment's latents (z_t, z_{t+1}, z_{t+2}), a head on [z_{t+1}, z_x - z_{t+1}] tells the future step (x = t+2)
from the past one (x = t) by binary cross-entropy; only a latent that knows which way the links move can lower it
below ln 2. After each seed's offline training its loss and accuracy over the last 50 iterations are printed. The
arguments after COEF are ``studies.encoder_geometry``'s. COEF 0: the check unchanged.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from curiosity.agents.paper import PaperAgent
from studies import encoder_geometry
from studies.agent_study.terms import ArrowOfTime, extra_term


def report(agent: PaperAgent) -> None:
    """Print the arrow term's loss and accuracy over the last 50 iterations of the agent just trained."""
    term = agent.extra_terms["arrow"]
    assert isinstance(term, ArrowOfTime)
    print(term.summary(), flush=True)


def run(coef: float, geometry_args: Sequence[str], geometry_of: encoder_geometry.Geometry = encoder_geometry.geometry) -> int:
    """``studies.encoder_geometry`` with ``geometry_args`` (and ``geometry_of``), the arrow term added at ``coef`` > 0."""
    if coef <= 0:
        return encoder_geometry.main(list(geometry_args), geometry_of)
    return encoder_geometry.main([*geometry_args, extra_term("arrow", ArrowOfTime, coef)], geometry_of, report)


def parse(prog: str, description: str, argv: list[str] | None) -> tuple[float, list[str]]:
    """COEF and the arguments left for ``studies.encoder_geometry``."""
    parser = argparse.ArgumentParser(prog=prog, description=description,
                                     epilog="Every other argument is studies.encoder_geometry's (config overrides, "
                                            "--seeds, --states, --data-seed, --train-iters, --run, --json).")  # fmt: skip
    parser.add_argument("coef", type=float, help="the arrow-of-time term's weight (0: none)")
    args, rest = parser.parse_known_args(argv)
    return args.coef, rest


def main(argv: list[str] | None = None) -> int:
    coef, rest = parse("python -m studies.agent_study.pixel_encoder.arrow_of_time", __doc__.splitlines()[0], argv)
    return run(coef, rest)


if __name__ == "__main__":
    raise SystemExit(main())
