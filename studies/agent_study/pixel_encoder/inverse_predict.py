"""Offline prototype (not part of the package): ``studies.agent_study.pixel_encoder.predict_screen`` (MODE predict:
2000 iterations) or ``studies.encoder_geometry`` (MODE geometry: seeds 0, 1, 1000 iterations) with the inverse-dynamics
term of ``results/agent_study/representation/inverse/`` added to the representation loss (the plug-in
``studies.agent_study.terms.InverseDynamics``: a head Linear(2d, 64) -> ReLU -> Linear(64, A) on [z_t, z_{t+1}],
cross-entropy, weight COEF; COEF 0: the check unchanged).

    python -m studies.agent_study.pixel_encoder.inverse_predict COEF predict|geometry OUT.json [OVERRIDES...]
"""

from __future__ import annotations

import argparse
import json

from studies import encoder_geometry
from studies.agent_study.pixel_encoder import predict_screen
from studies.agent_study.terms import InverseDynamics, extra_term


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m studies.agent_study.pixel_encoder.inverse_predict",
                                     description=__doc__.splitlines()[0])  # fmt: skip
    parser.add_argument("coef", type=float, help="the inverse-dynamics term's weight (0: none)")
    parser.add_argument("mode", choices=("predict", "geometry"), help="which check to run with the term")
    parser.add_argument("out", help="JSON file of the check's result")
    parser.add_argument("overrides", nargs="*", help="config overrides, as for runners.train")
    args = parser.parse_args(argv)
    overrides = [*args.overrides, *([extra_term("inverse", InverseDynamics, args.coef)] if args.coef > 0 else [])]
    if args.mode == "predict":
        res = predict_screen.screen(2000, overrides)
        with open(args.out, "w") as f:
            json.dump(res, f, indent=1)
        return 0
    return encoder_geometry.main([*overrides, "--seeds", "0,1", "--train-iters", "1000", "--json", args.out])


if __name__ == "__main__":
    raise SystemExit(main())
