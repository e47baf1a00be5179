"""Offline prototype (not part of the package): the paper agent's representation loss plus an arrow-of-time term,
measured by ``python -m analysis.encoder_geometry``'s velocity geometry after offline training.

The term: from each segment's latents (z_t, z_{t+1}, z_{t+2}), a head (Linear(2d, 64) -> ReLU -> Linear(64, 1)) on
[z_{t+1}, z_x - z_{t+1}] tells the future step (x = t+2, label 1) from the past one (x = t, label 0), by binary
cross-entropy. Acrobot without friction is time-reversible: a latent that codes the pose alone sees a step forward
and a step back from the same pose alike (the chance loss, ln 2), so the term can only be lowered by a z_{t+1} that
knows which way the links move, i.e. the velocity, which the 4-frame stack shows the encoder. Segments whose first
two transitions end an episode are left out.

    python arrow_of_time.py COEF [OVERRIDES...] --seeds 0,1 --train-iters 1000 --json OUT.json

(the arguments after COEF are analysis.encoder_geometry's). COEF 0: the check unchanged.
"""

import sys

import torch
from torch.nn import functional as F

import analysis.encoder_geometry as geo
import curiosity.agents.paper as paper
from curiosity.agents.representation import LossWeights, representation_terms

coef = float(sys.argv[1])
HEAD = {}
orig_of_terms = LossWeights.of_terms
LossWeights.of_terms = lambda self: {**orig_of_terms(self), "arrow": coef}
LOG = []


def print_last():
    """The term's loss and accuracy over the last 50 iterations of the seed just trained."""
    loss, accuracy = (sum(x) / len(LOG[-50:]) for x in zip(*LOG[-50:], strict=True))
    print(f"arrow: last 50 iterations: loss {loss:.3f} accuracy {accuracy:.3f}")


def arrow_term(z, terminateds):
    """(B, 3, d) latents, (B, 2) terminal flags -> the BCE of telling z_{t+2} (future) from z_t (past) at z_{t+1}."""
    keep = terminateds.sum(1) == 0
    z = z[keep]
    mid = z[:, 1]
    head = HEAD["head"]
    fut = head(torch.cat([mid, z[:, 2] - mid], 1)).squeeze(1)
    past = head(torch.cat([mid, z[:, 0] - mid], 1)).squeeze(1)
    logits = torch.cat([fut, past])
    labels = torch.cat([torch.ones_like(fut), torch.zeros_like(past)])
    return F.binary_cross_entropy_with_logits(logits, labels), float(((logits > 0) == (labels > 0)).float().mean())


def terms_with_arrow(model, seg, enc, regulariser, w):
    terms, logs = representation_terms(model, seg, enc, regulariser, w)
    if coef > 0:
        terms["arrow"], acc = arrow_term(enc.z, seg.terminateds)
        logs["losses/arrow"] = terms["arrow"].item()
        LOG.append((terms["arrow"].item(), acc))
    return terms, logs


paper.representation_terms = terms_with_arrow
orig_init = paper.PaperAgent.__init__


def init(self, cfg):
    orig_init(self, cfg)
    d = int(cfg.agent.internal_dim)
    g = torch.Generator().manual_seed(1234)
    head = torch.nn.Sequential(torch.nn.Linear(2 * d, 64), torch.nn.ReLU(), torch.nn.Linear(64, 1))
    with torch.no_grad():
        for p in head.parameters():
            p.copy_(torch.empty_like(p).uniform_(-1, 1, generator=g) / p.shape[-1] ** 0.5)
    HEAD["head"] = head
    if LOG:  # the previous seed's
        print_last()
        LOG.clear()
    opt = next(iter(self.optimizers.values()))
    opt.add_param_group({"params": list(head.parameters())})


paper.PaperAgent.__init__ = init
status = geo.main(sys.argv[2:])
if LOG:
    print_last()
sys.exit(status)
