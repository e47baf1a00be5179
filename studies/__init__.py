"""One-off study instruments and the scripts behind the numbers under ``results/`` (which holds data, not code).

Each module runs as ``python -m studies.<module> --help``. ``studies`` imports ``curiosity``, ``analysis`` and
``runners``; nothing in those imports ``studies``. Extra loss terms a study adds to the paper agent's representation
loss are :class:`~curiosity.agents.representation.LossTerm` plug-ins (``studies.agent_study.terms``), passed as config
overrides (``+agent.extra_terms.<name>={_target_: ..., coef: ...}``); no study patches the package.
"""
