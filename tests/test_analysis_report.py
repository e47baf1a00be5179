"""``analysis.report``: one Markdown file embedding the table and every figure, each of which exists."""

from __future__ import annotations

import re

from analysis.figures import FIGURES
from tests.synthetic_runs import make_runs
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
    assert images == [f"{name}.png" for name in FIGURES]
    assert all((out / image).stat().st_size > 0 for image in images)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert analysis("report", root, "--pool", "ours (Rényi, pooled)=ours-*renyi*").returncode == 0
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before  # exact: a re-run rewrites the same bytes
