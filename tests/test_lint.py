"""``make lint`` passes: ``ruff check .`` (the rules in ``pyproject.toml``) finds nothing in any committed Python file,
the study instruments under ``studies/`` included."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import REPO

pytest.importorskip("ruff")  # the dev extra's linter


def test_ruff_finds_nothing_in_the_repository() -> None:
    res = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "."], cwd=REPO, capture_output=True,
                         text=True, timeout=300)  # fmt: skip
    assert res.returncode == 0, res.stdout + res.stderr
