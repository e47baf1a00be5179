#!/bin/bash
# reference runs of a commit for the issue-14 refactor, from a checkout of that commit: $1 = output dir
# (the ensemble and knn_sa lines use the key names of b07a83a and later; before it they were pe_imagined,
# transition_ensemble, hybrid_alpha, novelty_input, memory_refresh_drift, as in this script's git history)
out=$1
A=; grep -q '^agent:' conf/config.yaml && A=agent.   # the agent's keys moved under agent. after dfebfdf
run() { name=$1; shift; OMP_NUM_THREADS=1 nice -n 5 /work/main/.venv/bin/python -m runners.train budget=smoke seed=1 deterministic=true progress=false ${A}probe_every=50 "$@" hydra.run.dir=$out/$name > $out/$name.log 2>&1; echo "$name rc=$?"; }
mkdir -p $out
run default
run paper_text +experiment=paper_text
run paper_code +experiment=paper_code
run nsrs baseline=nsrs
run icm baseline=icm
run rnd baseline=rnd
run ensemble intrinsic.terms.pe.imagined=ensemble ${A}transition_ensemble=3 intrinsic.alpha=0.5
run oracle planner.model=oracle env.renderer=fast
run mc env=mountaincar
run knn_sa estimator=knn intrinsic.terms.novelty.input=state_action intrinsic.terms.novelty.refresh_drift=0.05
