"""Analysis: tables and figures rebuilt from run directories (``.hydra/config.yaml``, ``summary.json``, ``metrics.csv``)."""
