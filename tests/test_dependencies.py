"""Declared dependencies match the imports: every third-party module that the package, the runners, the analysis or
the studies import is a dependency in ``pyproject.toml``, and every one the tests import is one or in the ``dev`` extra."""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO

tomllib = pytest.importorskip("tomllib")  # Python >= 3.11

LOCAL = {"curiosity", "runners", "analysis", "studies", "tests"}
DISTRIBUTION = {
    "yaml": "pyyaml",
    "cv2": "opencv-python-headless",
    "hydra": "hydra-core",
    "sklearn": "scikit-learn",
    "PIL": "pillow",
}


def _name(requirement: str) -> str:
    """The normalised distribution name of a requirement such as ``"gymnasium[classic-control]>=1.3"``."""
    match = re.match(r"[A-Za-z0-9_.\-]+", requirement)
    assert match, requirement
    return match[0].lower().replace("_", "-")


def _imported(*folders: str) -> set[str]:
    """Distribution names of the third-party modules imported by the ``.py`` files below ``folders``."""
    modules = set()
    for folder in folders:
        for path in (REPO / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    modules |= {alias.name.split(".")[0] for alias in node.names}
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    modules.add(node.module.split(".")[0])
    third_party = modules - LOCAL - set(sys.stdlib_module_names) - {"__future__"}
    return {DISTRIBUTION.get(m, m).lower() for m in third_party}


def _declared() -> tuple[set[str], set[str]]:
    project = tomllib.loads(Path(REPO / "pyproject.toml").read_text())["project"]
    return {_name(r) for r in project["dependencies"]}, {_name(r) for r in project["optional-dependencies"]["dev"]}


def test_the_code_imports_only_declared_dependencies() -> None:
    main, _ = _declared()
    code = _imported("curiosity", "runners", "analysis", "studies")
    assert code <= main, code - main


def test_the_tests_import_only_declared_dependencies() -> None:
    main, dev = _declared()
    assert _imported("tests") <= main | dev, _imported("tests") - main - dev
