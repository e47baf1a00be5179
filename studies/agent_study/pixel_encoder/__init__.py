"""The pixel-encoder study's offline prototypes and checks (``results/agent_study/pixel_encoder/``)."""
