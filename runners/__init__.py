"""Command-line entry points: ``python -m runners.train``, ``python -m runners.bench``."""
