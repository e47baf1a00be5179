"""Offline prototype (not part of the package): predict_screen.py (MODE predict) or ``analysis.encoder_geometry``
(MODE geometry: seeds 0, 1, 1000 iterations) with the inverse-dynamics term of ``../../../representation/inverse/``
added (a head Linear(2d, 64) -> ReLU -> Linear(64, A) on [z_t, z_{t+1}], cross-entropy, weight COEF).

From the repository root: ``PYTHONPATH=. python results/agent_study/pixel_encoder/predictability/inverse_predict.py
COEF MODE OUT.json [OVERRIDES...]``."""

import runpy
import sys
from pathlib import Path

import torch

import curiosity.agents.paper as paper
from curiosity.agents.representation import LossWeights, representation_terms
from curiosity.intrinsic.icm import inverse_loss

coef, mode, out, overrides = float(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4:]
HEAD = {}
orig = LossWeights.of_terms
LossWeights.of_terms = lambda self: {**orig(self), "inverse": coef}


def terms(model, seg, enc, regulariser, w):
    t, logs = representation_terms(model, seg, enc, regulariser, w)
    logits = HEAD["head"](torch.cat([enc.z[:, 0], enc.z[:, 1]], dim=1))
    t["inverse"] = inverse_loss(logits, seg.act[:, 0])
    return t, logs


paper.representation_terms = terms
orig_init = paper.PaperAgent.__init__


def init(self, cfg):
    orig_init(self, cfg)
    d, a = int(cfg.agent.internal_dim), int(cfg.env.n_actions)
    torch.manual_seed(1234)
    HEAD["head"] = torch.nn.Sequential(torch.nn.Linear(2 * d, 64), torch.nn.ReLU(), torch.nn.Linear(64, a))
    self.optimizers["all"].add_param_group({"params": list(HEAD["head"].parameters())})


paper.PaperAgent.__init__ = init
if mode == "predict":
    sys.argv = ["predict_screen.py", "2000", out, *overrides]
    runpy.run_path(str(Path(__file__).with_name("predict_screen.py")), run_name="__main__")
else:
    import analysis.encoder_geometry as geo

    sys.exit(geo.main([*overrides, "--seeds", "0,1", "--train-iters", "1000", "--json", out]))
