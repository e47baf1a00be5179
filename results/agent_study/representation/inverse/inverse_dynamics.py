"""Offline prototype (not part of the package): the representation check with an inverse-dynamics head added.

The question: does an ICM/NGU-style inverse-dynamics loss (which action led from s_t to s_{t+1}?, cross-entropy of an
MLP head on [s_t, s_{t+1}]) added to the paper agent's representation loss make the latent's novelty tell the
frontier (pumping states) from random play, i.e. raise ``python -m analysis.representation``'s AUC?

Run from the repository root (commits 6573038 and 445f89c, the same code):

    DS=<data seed> python results/agent_study/representation/inverse/inverse_dynamics.py COEF [OVERRIDES...]

COEF is the weight of the inverse loss (0: the check unchanged); the head is Linear(2d, 64) -> ReLU -> Linear(64, A),
its parameters added to the agent's optimiser. Prints the check's table and writes
``ds<DS>_c<COEF>_<overrides or default>.json`` into the current directory. Results: README.md beside this file.
"""

import json
import os
import sys

import torch

import analysis.representation as rep
import curiosity.agents.paper as paper
from curiosity.agents.representation import LossWeights, representation_terms
from curiosity.intrinsic.icm import inverse_loss

coef = float(sys.argv[1])
overrides = sys.argv[2:]
HEAD = {}
orig_of_terms = LossWeights.of_terms
LossWeights.of_terms = lambda self: {**orig_of_terms(self), "inverse": coef}


def terms_with_inverse(model, seg, enc, regulariser, w):
    terms, logs = representation_terms(model, seg, enc, regulariser, w)
    if coef > 0:
        logits = HEAD["head"](torch.cat([enc.z[:, 0], enc.z[:, 1]], dim=1))
        terms["inverse"] = inverse_loss(logits, seg.act[:, 0])  # the ICM baseline's L_inv (cross-entropy)
        logs["losses/inverse"] = terms["inverse"].item()
    return terms, logs


paper.representation_terms = terms_with_inverse
orig_init = paper.PaperAgent.__init__


def init(self, cfg):
    orig_init(self, cfg)
    d, n_actions = int(cfg.agent.internal_dim), int(cfg.env.n_actions)
    torch.manual_seed(1234)
    HEAD["head"] = torch.nn.Sequential(torch.nn.Linear(2 * d, 64), torch.nn.ReLU(), torch.nn.Linear(64, n_actions))
    self.optimizers["all"].add_param_group({"params": list(HEAD["head"].parameters())})


paper.PaperAgent.__init__ = init

ds = int(os.environ.get("DS", "1"))
rows = rep.study([*overrides, "env.renderer=fast"], [0, 300, 1000], data_seed=ds)
print(coef, overrides)
print(rep._table(rows))
name = f"ds{ds}_c{coef}_{'_'.join(overrides) or 'default'}.json"
with open(name, "w") as fh:
    json.dump({"coef": coef, "overrides": overrides, "data_seed": ds, "rows": rows}, fh)
