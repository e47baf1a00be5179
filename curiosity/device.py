"""The ``device`` key: where a run's networks, batches, novelty memory and planning live."""

from __future__ import annotations

from typing import Any

import torch

DEVICES = ("auto", "cpu", "cuda")


def resolve_device(name: str) -> torch.device:
    """``auto`` -> ``cuda`` when torch sees a GPU, else ``cpu``; ``cpu`` / ``cuda`` as named."""
    if name not in DEVICES:
        raise ValueError(f"device={name!r}: must be one of {', '.join(DEVICES)}")
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def device_error(name: str) -> str | None:
    """Why ``device=name`` cannot run on this machine (one line naming key, value and what is allowed), or None."""
    if name == "cuda" and not torch.cuda.is_available():
        return f"device=cuda: torch {torch.__version__} sees no CUDA device on this machine; allowed: cpu, auto"
    return None


def to_device(state: Any, device: torch.device) -> Any:
    """``state`` (tensors in nested dicts, lists and tuples) with every floating-point tensor moved to ``device``;
    integer tensors (keys, indices) and byte tensors (generator states) stay where they are."""
    if isinstance(state, torch.Tensor):
        return state.to(device) if state.is_floating_point() else state
    if isinstance(state, dict):
        return {k: to_device(v, device) for k, v in state.items()}
    if isinstance(state, (list, tuple)):
        return type(state)(to_device(v, device) for v in state)
    return state
