"""Every intrinsic reward, one module each, behind one interface (:class:`IntrinsicReward`), combined by a
:class:`Mixture` from the ``intrinsic`` config group: latent novelty (KDE / kNN / NSRS's kNN score, by the
``estimator`` group), the prediction-error bonus, ICM and RND."""

from curiosity.intrinsic.base import IntrinsicContext, IntrinsicReward

__all__ = ["IntrinsicContext", "IntrinsicReward"]
