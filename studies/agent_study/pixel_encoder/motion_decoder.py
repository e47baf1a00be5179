"""Offline prototype (not part of the package): the paper agent's representation loss plus a motion-decoding term,
measured by ``python -m studies.encoder_geometry``'s velocity geometry after offline training.

    python -m studies.agent_study.pixel_encoder.motion_decoder COEF [OVERRIDES...] --seeds 0,1 --train-iters 1000 --json OUT

The term is the plug-in ``studies.agent_study.terms.MotionDecoder`` at weight COEF (``agent.extra_terms.motion``): a
head on z_t predicts the motion image of o_t -- the difference of the newest two frames after a Gaussian blur
(sigma 4), average-pooled to 8 x 8 -- by mean squared error, the target divided by its std over the first batch. A
latent that must decode where and how fast the links move has to carry the velocity. The arguments after COEF are
``studies.encoder_geometry``'s. COEF 0: the check unchanged.
"""

from __future__ import annotations

from studies import encoder_geometry
from studies.agent_study.pixel_encoder.arrow_of_time import parse
from studies.agent_study.terms import MotionDecoder, extra_term


def main(argv: list[str] | None = None) -> int:
    coef, rest = parse("python -m studies.agent_study.pixel_encoder.motion_decoder", __doc__.splitlines()[0], argv)
    return encoder_geometry.main([*rest, *([extra_term("motion", MotionDecoder, coef)] if coef > 0 else [])])


if __name__ == "__main__":
    raise SystemExit(main())
