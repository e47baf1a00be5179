"""``analysis.report``: one Markdown file embedding the table and every figure, each of which exists (the noisy-TV
figure only where runs have a TV: ``tests/test_analysis_tables.py``)."""

from __future__ import annotations

import re

from analysis.figures import FIGURES
from tests.synthetic_runs import make_runs
from tests.conftest import REPO
from tests.test_analysis import analysis


def test_the_report_embeds_the_table_and_every_figure(tmp_path) -> None:
    root = make_runs(tmp_path / "runs")
    res = analysis("report", root, "--pool", "ours (Rényi, pooled)=ours-*renyi*")
    assert res.returncode == 0, res.stderr
    out = root / "report"
    text = (out / "README.md").read_text()
    assert "| mountaincar | ours (Rényi, pooled) | 4 / 5 | 1500, 1700, 1300, >1900, 1100 | 1500.0 ± 141.4 |" in text
    assert "--pool 'ours (Rényi, pooled)=ours-*renyi*'" in text and "stopped: " in text
    images = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert images == [f"{name}.png" for name in FIGURES if name != "tv_presses"]  # no run here has a noisy TV
    assert all((out / image).stat().st_size > 0 for image in images)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert analysis("report", root, "--pool", "ours (Rényi, pooled)=ours-*renyi*").returncode == 0
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # exact: a re-run rewrites the same bytes


# issue 15's claims and issue 16's test: results/<preset>/ (conf/sweep/)
PRESETS = ("table1", "table2", "fig6", "fig7", "hybrid", "noisy_tv", "cheap_seed")  # and issue 50's study
TABLES = ("steps_to_goal.md", "steps_to_goal.tex", "steps_to_goal.csv", "incomplete.csv", "spread.md", "spread.csv",
          "stable_step.md", "stable_step.csv", "distractor.md", "distractor.csv", "cost.md", "cost.csv",
          "pareto.csv")  # fmt: skip


def test_every_claims_table_committed_is_what_the_bare_command_writes(tmp_path) -> None:
    """``python -m analysis.tables results/<preset>`` (its analysis.yaml applied) rewrites each committed table byte for
    byte; a preset whose runs have not been committed yet has no report to compare."""
    checked = 0
    for preset in PRESETS:
        committed = REPO / "results" / preset / "report"
        if not (committed / "steps_to_goal.md").is_file():
            continue
        out = tmp_path / preset
        res = analysis("tables", f"results/{preset}", "--out", out)  # run from the repository, as the README says
        assert res.returncode == 0, res.stderr
        names = [n for n in TABLES if (committed / n).is_file()]
        assert {n for n in TABLES if (out / n).is_file()} == set(names), preset  # no table missing or extra
        for name in names:
            assert (out / name).read_bytes() == (committed / name).read_bytes(), f"{preset}/{name}"  # exact: same text
        checked += 1
    assert checked >= 1  # results/table1 is committed


def test_the_committed_verdicts_are_what_the_command_writes(tmp_path) -> None:
    """``python -m analysis.verdicts results`` (the README's "Does the paper hold?") rewrites ``results/verdicts.*``
    byte for byte from the committed tables."""
    res = analysis("verdicts", "results", "--out", tmp_path)
    assert res.returncode == 0, res.stderr
    for name in ("verdicts.md", "verdicts.csv"):
        assert (tmp_path / name).read_bytes() == (REPO / "results" / name).read_bytes(), name  # exact: same text
