"""The documentation holds: the README fits its first screen, every relative link in README.md and docs/ resolves, the
configuration reference is what its generator writes, and the README's usage lines name modules that exist and
training commands that compose and validate."""

from __future__ import annotations

import importlib.util
import itertools
import re
import shlex
from pathlib import Path

import pytest
from hydra.core.override_parser.overrides_parser import OverridesParser

from curiosity.config.compose import compose_config
from curiosity.config.ranges import expand_ranges
from curiosity.runtime.preflight import checked_config
from tests.conftest import REPO

README = REPO / "README.md"
DOCS = sorted((REPO / "docs").glob("*.md"))
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^```.*?^```", re.M | re.S)


def _prose(text: str) -> str:
    """Markdown without its fenced code blocks and inline code (where brackets are not links)."""
    return re.sub(r"`[^`\n]*`", "", FENCE.sub("", text))


def test_the_readme_fits_150_lines() -> None:
    assert len(README.read_text().splitlines()) <= 150


def test_the_docs_the_readme_maps_exist() -> None:
    for name in ("usage", "pieces", "configuration", "method", "protocol", "results", "agent_study", "benchmarks"):
        assert (REPO / "docs" / f"{name}.md").is_file(), name


@pytest.mark.parametrize("doc", [README, *DOCS], ids=lambda p: str(p.relative_to(REPO)))
def test_every_relative_link_points_to_a_file_in_the_repository(doc: Path) -> None:
    missing = []
    for target in LINK.findall(_prose(doc.read_text())):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a URL or an anchor in the same file
        path = (doc.parent / target.split("#")[0]).resolve()
        if not path.exists() or REPO not in path.parents:
            missing.append(target)
    assert not missing, f"{doc.name}: links to nothing in the repository: {missing}"


def test_the_configuration_reference_is_what_its_generator_writes() -> None:
    from runners.config_reference import OUT, render

    assert OUT.read_text() == render(), "docs/configuration.md is out of date: run python -m runners.config_reference"


def _usage_lines() -> list[list[str]]:
    """The commands of the README's code blocks, each as its words (comments and `make` lines left out)."""
    lines = []
    for block in FENCE.findall(README.read_text()):
        for line in block.splitlines()[1:-1]:
            words = shlex.split(line, comments=True)
            if words[:2] == ["python", "-m"]:
                lines.append(words[2:])
    return lines


def test_the_readme_names_modules_that_exist() -> None:
    modules = {words[0] for words in _usage_lines()}
    assert {"runners.train", "analysis.tables", "analysis.verdicts", "runners.bench"} <= modules
    assert all(importlib.util.find_spec(m) is not None for m in modules), modules


def _jobs(args: list[str]) -> list[list[str]]:
    """The jobs of one ``runners.train`` command line: itself, or one per combination of its sweep values and of its
    sweep preset's (``+sweep=...``) parameters, with only the first seed (seeds do not change whether a job
    composes)."""
    overrides = [a for a in expand_ranges(args) if a != "-m"]
    if "-m" not in args:
        return [overrides]
    parser = OverridesParser.create()
    parsed = parser.parse_overrides(overrides)
    fixed = [o.input_line for o in parsed if not o.is_sweep_override()]
    sweeps = {o.get_key_element(): list(o.sweep_string_iterator()) for o in parsed if o.is_sweep_override()}
    params = compose_config(fixed, hydra_node=True).hydra.sweeper.params or {}
    for key, value in params.items():
        if key not in sweeps:
            (preset,) = parser.parse_overrides([f"{key}={value}"])
            sweeps[key] = list(preset.sweep_string_iterator()) if preset.is_sweep_override() else [str(value)]
    sweeps = {k: v[:1] if k == "seed" else v for k, v in sweeps.items()}
    return [fixed + [f"{k}={v}" for k, v in zip(sweeps, combo, strict=True)] for combo in itertools.product(*sweeps.values())]


def test_the_readme_training_commands_compose_and_validate() -> None:
    commands = [words[1:] for words in _usage_lines() if words[0] == "runners.train"]
    assert len(commands) >= 5
    for args in commands:
        for job in _jobs(args):
            checked_config(job)  # raises ConfigError, naming the key, for a job that would be refused
