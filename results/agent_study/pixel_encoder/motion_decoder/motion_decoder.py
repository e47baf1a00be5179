"""Offline prototype (not part of the package): the paper agent's representation loss plus a motion-decoding term,
measured by ``python -m analysis.encoder_geometry``'s velocity geometry after offline training.

The term: a head on z_t (Linear(d, 64) -> ReLU -> Linear(64, 64)) predicts the motion image of o_t -- the difference
of the newest two frames after a Gaussian blur (sigma 4, the encoder's ``GaussianBlur``), average-pooled to 8 x 8 --
by mean squared error, the target divided by a fixed scale (its std over the first batch). A latent that must decode
where and how fast the links move has to carry the velocity.

    python motion_decoder.py COEF [OVERRIDES...] --seeds 0,1 --train-iters 1000 --json OUT.json

(the arguments after COEF are analysis.encoder_geometry's). COEF 0: the check unchanged.
"""

import sys

import torch
from torch.nn import functional as F

import analysis.encoder_geometry as geo
import curiosity.agents.paper as paper
from curiosity.agents.representation import LossWeights, representation_terms
from curiosity.nets.preprocess import GaussianBlur

coef = float(sys.argv[1])
HEAD, SCALE = {}, {}
BLUR = GaussianBlur(4.0)
orig_of_terms = LossWeights.of_terms
LossWeights.of_terms = lambda self: {**orig_of_terms(self), "motion": coef}


def motion_target(obs):
    """(B, C, 32, 32) stacked frames -> (B, 64): the newest two frames' blurred difference, 8 x 8 average pooled."""
    last2 = BLUR(obs[:, -2:])
    return F.avg_pool2d(last2[:, 1:] - last2[:, :1], 4).flatten(1)


def terms_with_motion(model, seg, enc, regulariser, w):
    terms, logs = representation_terms(model, seg, enc, regulariser, w)
    if coef > 0:
        target = motion_target(seg.obs[:, 0])
        if "s" not in SCALE:
            SCALE["s"] = float(target.std()) + 1e-8
        pred = HEAD["head"](enc.z[:, 0])
        terms["motion"] = F.mse_loss(pred, target / SCALE["s"])
        logs["losses/motion"] = terms["motion"].item()
    return terms, logs


paper.representation_terms = terms_with_motion
orig_init = paper.PaperAgent.__init__


def init(self, cfg):
    orig_init(self, cfg)
    d = int(cfg.agent.internal_dim)
    g = torch.Generator().manual_seed(1234)
    head = torch.nn.Sequential(torch.nn.Linear(d, 64), torch.nn.ReLU(), torch.nn.Linear(64, 64))
    with torch.no_grad():
        for p in head.parameters():
            p.copy_(torch.empty_like(p).uniform_(-1, 1, generator=g) / p.shape[-1] ** 0.5)
    HEAD["head"] = head
    SCALE.clear()
    opt = next(iter(self.optimizers.values()))
    opt.add_param_group({"params": list(head.parameters())})


paper.PaperAgent.__init__ = init
sys.exit(geo.main(sys.argv[2:]))
