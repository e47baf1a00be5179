"""The machine a run was made on, as ``summary.json`` records it.

A run is exactly repeatable only on the same machine: the same config and seed on another CPU (another BLAS kernel, a
different vector width) give floating-point results that differ in the last bits, and a training run amplifies them
until the trajectory is another one. Analysis that compares runs seed by seed needs to know which machine made each.
"""

from __future__ import annotations

import platform


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what :mod:`platform` says, else ``"unknown"``."""
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or "unknown"


def machine() -> dict[str, str | int]:
    """CPU model, the vector instructions torch's CPU kernels use (``torch.backends.cpu.get_cpu_capability()``, e.g.
    ``AVX512``), torch and Python versions, torch's intra-op threads and the platform."""
    import torch

    return {"cpu": cpu_model(), "cpu_capability": torch.backends.cpu.get_cpu_capability(), "torch": torch.__version__,
            "torch_threads": torch.get_num_threads(), "python": platform.python_version(),
            "platform": platform.platform()}  # fmt: skip


def machine_label(record: dict | None) -> str:
    """``"<cpu> (<capability>)"`` of a ``summary.json`` ``machine`` record; ``""`` for a run that recorded none."""
    if not record:
        return ""
    capability = record.get("cpu_capability")
    return f"{record.get('cpu', 'unknown')}" + (f" ({capability})" if capability else "")
