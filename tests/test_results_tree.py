"""What results/ may hold: data and reports, never code or TensorBoard events (code lives in the package, analysis/,
runners/ or studies/, tested; a run's events repeat its metrics.csv and only make the repository heavier)."""

from __future__ import annotations

import subprocess

from tests.conftest import REPO


def committed(under: str) -> list[str]:
    """The paths git tracks below ``under`` (relative to the repository)."""
    out = subprocess.run(["git", "ls-files", "-z", under], cwd=REPO, capture_output=True, text=True, check=True).stdout
    return [p for p in out.split("\0") if p]


def test_results_holds_no_event_files() -> None:
    files = committed("results")
    assert files, "results/ is tracked"
    events = [p for p in files if "tfevents" in p.rsplit("/", 1)[-1] or "/tb/" in p]
    assert events == [], f"TensorBoard files under results/: {len(events)}, e.g. {events[:3]}"


def test_results_has_no_pooled_root_report() -> None:
    # the per-preset reports (results/<preset>/report/) stay; a report pooling every run was rebuilt, figures and all,
    # at each landing
    assert committed("results/report") == []


def test_results_holds_no_code() -> None:
    # scripts and notebooks live in studies/ (python -m studies.<module>), where they are imported and tested
    code = [p for p in committed("results") if p.endswith((".py", ".sh", ".ipynb"))]
    assert code == [], f"code files under results/: {code}"
