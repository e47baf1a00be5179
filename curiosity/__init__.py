"""curiosity: curiosity-driven exploration from state-action density in an Information-Bottleneck latent space.

Sub-packages are imported explicitly (``from curiosity.info import renyi_entropy``); importing ``curiosity``
itself loads nothing heavy, so ``curiosity.info`` and ``curiosity.novelty`` depend on torch and numpy only.
"""

__version__ = "0.1.0"
