"""Networks: encoders, latent transition, reward, backward predictor and Q."""

from curiosity.nets.backward import BackwardPredictor
from curiosity.nets.encoders import ConvEncoder, MLPEncoder, tanh_mlp
from curiosity.nets.onehot import one_hot
from curiosity.nets.q import QNetwork
from curiosity.nets.reward import RewardModel
from curiosity.nets.transition import ResidualTransition, TransitionEnsemble

__all__ = [
    "BackwardPredictor",
    "ConvEncoder",
    "MLPEncoder",
    "QNetwork",
    "ResidualTransition",
    "RewardModel",
    "TransitionEnsemble",
    "one_hot",
    "tanh_mlp",
]
