"""Parts of ``python -m runners.bench``: what is measured (components, another commit, sweeps, whole seeds)."""
