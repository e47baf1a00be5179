"""The allocator setting every run makes (curiosity/runtime/allocator.py). That it changes no number a run computes is
checked by ``tests/test_resume.py`` (a run without it has the same metrics)."""

from __future__ import annotations

import ctypes
import sys

import pytest

from curiosity.runtime.allocator import keep_freed_memory


def _glibc() -> bool:
    try:
        return ctypes.CDLL(None).gnu_get_libc_version is not None
    except (OSError, AttributeError):
        return False


@pytest.mark.skipif(not (sys.platform.startswith("linux") and _glibc()), reason="glibc's mallopt")
def test_thresholds_are_set_on_glibc(monkeypatch) -> None:
    for key in ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_"):
        monkeypatch.delenv(key, raising=False)
    assert keep_freed_memory()


def test_the_users_own_setting_is_left_alone(monkeypatch) -> None:
    monkeypatch.setenv("MALLOC_TRIM_THRESHOLD_", "131072")
    assert not keep_freed_memory()
