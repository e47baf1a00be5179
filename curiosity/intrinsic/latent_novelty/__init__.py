"""The paper's novelty (§3.3): how rare a latent state, or state–action pair, is in a memory of the agent's own
experience, by a density (KDE) or distance (kNN) estimator from the ``estimator`` group.

:class:`LatentNovelty` (:mod:`~curiosity.intrinsic.latent_novelty.base`) keeps the memory, one row per real transition,
re-embeds it with the current encoder (a *refresh*: every ``refresh_every`` env steps from the end of the warm-up, and
in between whenever its drift exceeds ``refresh_drift``), standardises and checkpoints. One subclass per ``input``
(:mod:`~curiosity.intrinsic.latent_novelty.inputs`) overrides only what its input does: the memory row of a
transition (``embed``) and the novelty of an edge (s, a, s') (``novelty``):
    ``state_action`` (paper text), :class:`StateActionNovelty`: memory rows y_t = [s_t, c·onehot(a_t)], an edge
    (s, a, s') is scored by novelty(y) with y = [s, c·onehot(a)]; c = ``action_scale`` sets how far apart actions are
    (docs/method.md §9).
    ``state`` (precursor code, NSRS), :class:`StateNovelty`: memory rows s_t; an edge is scored by the novelty of the
    state reached, s'.
    ``state_motion`` (ours, off by default), :class:`StateMotionNovelty`: memory rows [s_{t+1}, m·(s_{t+1} − s_t)], the
    state each transition reached and the latent's one-step motion into it; an edge (s, a, s') is scored by
    novelty([s', m·(s' − s)]). A latent that codes the pose but not the velocity (the trained pixel encoder,
    ``studies.encoder_geometry``) then still tells a fast swing from a slow one through its motion; m =
    ``motion_scale``, in motion standard deviations.
    ``random_target`` (ours, off by default; image observations), :class:`RandomTargetNovelty`: memory rows r_t =
    R(o_t), the codes of a frozen random conv encoder of blurred frames
    (:class:`~curiosity.novelty.random_target.RandomTarget`); a real edge is scored by novelty(R(o_{t+1})), an imagined
    one (no frame) by novelty(g(s')), g a head trained on replay batches to predict R(o) from the agent's latent. The
    model plans in the trained latent; the novelty keeps R's geometry.
:meth:`LatentNovelty.from_context` (the config's ``_target_``) builds the class of ``input``, looked up in
:data:`NOVELTY_INPUTS`. With ``standardise=True`` the latent part is standardised per dimension by the memory's mean
and standard deviation at the last refresh (the motion part of ``state_motion`` by its own), so the bandwidth,
``action_scale`` and ``motion_scale`` are in units of the latent spread, which drifts while the encoder trains.
"""

from curiosity.intrinsic.latent_novelty.base import MEMORY_KEYS, NOVELTY_INPUTS, LatentNovelty, novelty_class
from curiosity.intrinsic.latent_novelty.inputs import (
    TARGET_KEYS,
    RandomTargetNovelty,
    StateActionNovelty,
    StateMotionNovelty,
    StateNovelty,
)

INPUTS = tuple(NOVELTY_INPUTS)  # ("state_action", "state", "state_motion", "random_target")

__all__ = [
    "INPUTS",
    "MEMORY_KEYS",
    "NOVELTY_INPUTS",
    "TARGET_KEYS",
    "LatentNovelty",
    "RandomTargetNovelty",
    "StateActionNovelty",
    "StateMotionNovelty",
    "StateNovelty",
    "novelty_class",
]
