"""The held-action study's offline checks (``results/agent_study/hold/``)."""
