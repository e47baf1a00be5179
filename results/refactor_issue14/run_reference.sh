#!/bin/bash
# reference runs of a commit for the issue-14 refactor: $1 = output dir
out=$1
run() { name=$1; shift; OMP_NUM_THREADS=1 nice -n 5 /work/main/.venv/bin/python -m runners.train budget=smoke seed=1 deterministic=true progress=false probe_every=50 "$@" hydra.run.dir=$out/$name > $out/$name.log 2>&1; echo "$name rc=$?"; }
mkdir -p $out
run default
run paper_text +experiment=paper_text
run paper_code +experiment=paper_code
run nsrs baseline=nsrs
run icm baseline=icm
run rnd baseline=rnd
run ensemble pe_imagined=ensemble transition_ensemble=3 hybrid_alpha=0.5
run oracle planner.model=oracle env.renderer=fast
run mc env=mountaincar
run knn_sa estimator=knn novelty_input=state_action memory_refresh_drift=0.05
