"""The agent study's scripts (``results/agent_study/``, ``docs/agent_study.md``)."""
