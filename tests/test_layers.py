"""The layer order of ``curiosity/``: each package (or top-level module) imports only from the floors below its own,
so no import runs back up and there is no circle between packages. A new package gets a floor here."""

from __future__ import annotations

import ast
from pathlib import Path

from tests.conftest import REPO

PACKAGE = REPO / "curiosity"
# bottom to top; a unit may import any unit of a lower floor, none of its own floor or above
FLOORS: list[set[str]] = [
    {"types", "errors", "build", "device", "info", "losses", "nets"},
    {"replay", "novelty", "envs"},
    {"intrinsic", "planning"},
    {"agents"},
    {"baselines", "config"},
    {"runtime"},
]


def unit_of(path: Path) -> str:
    """The package (``agents``) or top-level module (``replay``) that ``path`` below ``curiosity/`` belongs to."""
    parts = path.relative_to(PACKAGE).parts
    return parts[0].removesuffix(".py")


def imported_units(path: Path) -> set[str]:
    """The units of ``curiosity`` that ``path`` imports, anywhere in the file (functions included)."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        modules = []
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            modules = [node.module]
        elif isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        found |= {m.split(".")[1] for m in modules if m.startswith("curiosity.")}
    return found


def test_every_import_of_the_package_runs_down_its_floors() -> None:
    floor = {unit: i for i, units in enumerate(FLOORS) for unit in units}
    files = [p for p in PACKAGE.rglob("*.py") if p.name != "__init__.py" or p.parent != PACKAGE]
    units = {unit_of(p) for p in files}
    assert units <= set(floor), f"give these a floor: {sorted(units - set(floor))}"
    upward = []
    for path in files:
        mine = unit_of(path)
        for other in imported_units(path) - {mine}:
            if floor[other] >= floor[mine]:
                upward.append(f"{path.relative_to(REPO)} ({mine}, floor {floor[mine]}) imports {other} (floor {floor[other]})")
    assert upward == [], "\n".join(upward)


def test_the_check_sees_an_upward_import(tmp_path: Path) -> None:
    # the parser the test relies on finds imports inside functions too
    probe = tmp_path / "probe.py"
    probe.write_text("def f():\n    from curiosity.runtime.loop import run\n\nimport curiosity.agents.base\n")
    assert imported_units(probe) == {"runtime", "agents"}
