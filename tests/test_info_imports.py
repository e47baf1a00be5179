"""Importing curiosity.info / curiosity.novelty pulls in torch and numpy only (checked in a fresh interpreter)."""

from __future__ import annotations

import json
import subprocess
import sys

PROBE = """
import json, sys
import numpy, torch
before = set(sys.modules)
from curiosity.info import renyi_entropy, renyi_joint_entropy, renyi_mutual_information, gaussian_potential
from curiosity.info import backward_predictor_nll
from curiosity.novelty import kde_log_density, knn_distance, nsrs_knn_score, KDENoveltyReward, EmbeddingMemory
new = sorted(set(sys.modules) - before)
print(json.dumps({"new": new, "all": sorted(sys.modules), "stdlib": sorted(sys.stdlib_module_names)}))
"""

FORBIDDEN = (
    "hydra",
    "omegaconf",
    "gymnasium",
    "gym",
    "tensorboard",
    "pygame",
    "sklearn",
    "scipy",
    "pandas",
    "matplotlib",
    "cv2",
)


def test_light_imports():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, check=True, timeout=120)
    report = json.loads(out.stdout.strip().splitlines()[-1])
    stdlib = set(report["stdlib"])
    tops = {name.split(".")[0] for name in report["new"]}
    allowed = stdlib | {"curiosity", "torch", "numpy"}
    assert tops <= allowed, sorted(tops - allowed)
    ours = {name for name in report["new"] if name.startswith("curiosity")}
    assert all(name == "curiosity" or name.startswith(("curiosity.info", "curiosity.novelty")) for name in ours), ours
    loaded = {name.split(".")[0] for name in report["all"]}
    assert not loaded & set(FORBIDDEN), sorted(loaded & set(FORBIDDEN))
