"""Keep freed memory in the process instead of handing it back to the OS after every training iteration (glibc).

glibc serves an allocation above its mmap threshold with a fresh ``mmap`` and returns it to the OS on ``free``; the
next allocation of that size faults its pages in again, zero-filled. The threshold adapts upwards only when such a
block is freed, and freed memory at the top of the heap goes back to the OS above twice the threshold. A training
iteration allocates and frees the activations of 64 × 3 observations (tens of MB), so a good part of a run's time went
to page faults. Measured (``results/bench/allocator/``): two runs of the default agent side by side, seed 100, 250
env steps, 362.9 s with the thresholds set against 428.1 s without, the same metrics in every column but the
timings; one training iteration in a fresh process 39-42 ms against 60-65 ms. Setting them changes where memory comes
from, not one number a run computes (``tests/test_resume.py`` runs with and without).
"""

from __future__ import annotations

import ctypes
import os
import sys

M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3  # mallopt's parameter numbers (malloc.h)
MMAP_THRESHOLD = 32 * 2**20  # glibc's largest mmap threshold on 64-bit systems (DEFAULT_MMAP_THRESHOLD_MAX)
ENV_KEYS = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")  # the user's own settings, left alone


def keep_freed_memory() -> bool:
    """Raise glibc's mmap and trim thresholds for this process: blocks up to 32 MB come from the heap, and up to 64 MB
    of freed memory stays in it. Returns whether they were set: not with another C library or OS, nor when the
    environment sets either threshold itself."""
    if not sys.platform.startswith("linux") or any(key in os.environ for key in ENV_KEYS):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt  # the process's own C library
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(M_TRIM_THRESHOLD, 2 * MMAP_THRESHOLD))
