"""Reference runs of a commit for the issue-14 refactor: short deterministic runs of ten configurations.

    python -m studies.refactor.reference_runs OUT_DIR [--checkout DIR] [--collect SIDE_DIR]

Runs ``python -m runners.train budget=smoke seed=1 deterministic=true progress=false agent.probe_every=50 ...`` for
each configuration of :func:`configurations`, one at a time, one thread each, under ``nice -n 5``, in ``--checkout``
(default: the current directory; check out the commit to measure there), into ``OUT_DIR/<name>`` with its log in
``OUT_DIR/<name>.log``, and prints ``<name> rc=<exit code>``. ``--collect SIDE_DIR`` then copies each run's
``metrics.csv`` to ``SIDE_DIR/<name>.csv``, the layout ``studies.refactor.compare`` reads
(``results/refactor_issue14/``: ``before/``, ``after/``, ...).

The keys are those of b07a83a and later (the ensemble and knn_sa lines; before it they were pe_imagined,
transition_ensemble, hybrid_alpha, novelty_input, memory_refresh_drift, as in ``results/refactor_issue14/
run_reference.sh``'s git history); the agent's keys take the ``agent.`` prefix where the checkout's
``conf/config.yaml`` has an ``agent:`` group (after dfebfdf), none before.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

COMMON = ("budget=smoke", "seed=1", "deterministic=true", "progress=false")


def configurations(agent: str = "agent.") -> dict[str, list[str]]:
    """name -> the overrides of each reference configuration; ``agent`` prefixes the agent's own keys."""
    return {
        "default": [],
        "paper_text": ["+experiment=paper_text"],
        "paper_code": ["+experiment=paper_code"],
        "nsrs": ["baseline=nsrs"],
        "icm": ["baseline=icm"],
        "rnd": ["baseline=rnd"],
        "ensemble": ["intrinsic.terms.pe.imagined=ensemble", f"{agent}transition_ensemble=3", "intrinsic.alpha=0.5"],
        "oracle": ["planner.model=oracle", "env.renderer=fast"],
        "mc": ["env=mountaincar"],
        "knn_sa": ["estimator=knn", "intrinsic.terms.novelty.input=state_action",
                   "intrinsic.terms.novelty.refresh_drift=0.05"],
    }


def agent_prefix(checkout: Path) -> str:
    """``agent.`` where the checkout's config has the ``agent`` group (in ``conf/config.yaml`` until the schema alone
    held it: ``AgentKeysConfig``), else the empty prefix (the keys before dfebfdf)."""
    config = (checkout / "conf" / "config.yaml").read_text()
    schema = checkout / "curiosity" / "config" / "schema.py"
    in_schema = schema.is_file() and "class AgentKeysConfig" in schema.read_text()
    return "agent." if re.search(r"^agent:", config, re.MULTILINE) or in_schema else ""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m studies.refactor.reference_runs", description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="where the runs and their logs go")
    parser.add_argument("--checkout", type=Path, default=Path("."), help="the checkout to run (default: .)")
    parser.add_argument("--python", default=sys.executable, help="the interpreter (default: this one)")
    parser.add_argument("--only", default="", help="comma-separated configuration names (default: all ten)")
    parser.add_argument("--collect", type=Path, help="then copy each run's metrics.csv to COLLECT/<name>.csv")
    args = parser.parse_args(argv)
    prefix = agent_prefix(args.checkout)
    configs = configurations(prefix)
    names = [n for n in args.only.split(",") if n] or list(configs)
    unknown = [n for n in names if n not in configs]
    if unknown:
        print(f"error: --only {unknown[0]}: allowed: {', '.join(configs)}", file=sys.stderr)
        return 2
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    failed = 0
    for name in names:
        cmd = ["nice", "-n", "5", args.python, "-m", "runners.train", *COMMON, f"{prefix}probe_every=50", *configs[name],
               f"hydra.run.dir={out / name}"]  # fmt: skip
        with open(out / f"{name}.log", "w") as log:
            rc = subprocess.run(cmd, cwd=args.checkout, env=env, stdout=log, stderr=subprocess.STDOUT).returncode
        print(f"{name} rc={rc}", flush=True)
        failed += rc != 0
        if args.collect is not None and rc == 0:
            args.collect.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(out / name / "metrics.csv", args.collect / f"{name}.csv")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
