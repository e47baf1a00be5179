"""``analysis.figures`` on synthetic run directories: every figure is written as a PNG and a PDF that open, the same
bytes on a re-run, and the stable-reward steps are the ones the criterion gives."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from PIL import Image

from analysis.curves import mean_band, running_rate, stable_step
from analysis.figures import FIGURES, write_figures
from tests.synthetic_runs import make_runs
from tests.test_analysis import analysis


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    root = make_runs(tmp_path_factory.mktemp("runs"))
    out = root.parent / "figures"
    return root, out, write_figures(root, out, pools=["ours (Rényi, pooled)=ours-*renyi*"])


def test_every_figure_is_a_png_and_a_pdf_that_open(written: tuple) -> None:
    _, out, files = written
    for name in (n for n in FIGURES if n != "tv_presses"):  # no run here has a noisy TV (test_analysis_tables.py)
        png, pdf = out / f"{name}.png", out / f"{name}.pdf"
        assert png in files and pdf in files and png.stat().st_size > 0
        with Image.open(png) as im:
            im.verify()
        assert pdf.read_bytes().startswith(b"%PDF") and b"CreationDate" not in pdf.read_bytes()


def test_stability_lists_each_seed_and_kde_settles_before_knn(written: tuple) -> None:
    _, out, _ = written
    table = pd.read_csv(out / "stability.csv")
    assert len(table) == 16  # every finished synthetic run logs intrinsic/reward
    by = table.groupby("estimator")["stable_step"].median()
    assert by["kde"] < by["knn"]  # the synthetic KDE reward decays 4× faster
    assert "| mountaincar | ours (Rényi, pooled) |" in (out / "stability.md").read_text()


def test_stable_step_and_band_on_known_series() -> None:
    steps = np.arange(1, 61) * 10
    reward = np.r_[np.tile([1.0, 3.0], 20), np.full(20, 2.0)]  # CV 0.51 while alternating, 0 once constant
    assert stable_step(steps, reward, window=10, cv=0.1) == 500.0  # the first window wholly in the constant part
    assert np.isnan(stable_step(steps, np.tile([1.0, 3.0], 30), window=10, cv=0.1))
    curve = mean_band(pd.DataFrame({"a": [1.0, 2.0], "b": [3.0, np.nan]}, index=[10, 20]))
    assert curve.mean.tolist() == [2.0, 2.0] and curve.n.tolist() == [2, 1]
    assert curve.low[0] == 1.0 and curve.high[0] == 3.0 and np.isnan(curve.low[1])  # percentiles of {1, 2, 3}


def test_running_rate_weights_each_logged_window_by_its_env_steps() -> None:
    """Rows every 10 steps, 15 warm-up steps (no behaviour logged): the row at 20 covers steps 16-20 (5 steps), the
    next ones 10 each; a row written twice (a resumed run) counts once, the last."""
    run = pd.DataFrame({"step": [10, 20, 30, 30, 40, 45], "behaviour/tv": [np.nan, 1.0, 0.0, 0.5, 0.0, 0.2]})
    rate = running_rate(run, "behaviour/tv", warmup_steps=15)
    assert rate.index.tolist() == [20, 30, 40, 45]
    presses = np.cumsum([5 * 1.0, 10 * 0.5, 10 * 0.0, 5 * 0.2])
    assert rate.to_numpy() == pytest.approx(presses / np.cumsum([5, 10, 10, 5]))
    assert running_rate(run.drop(columns="behaviour/tv"), "behaviour/tv").empty


def test_the_command_rewrites_the_same_bytes(written: tuple, tmp_path) -> None:
    root, _, files = written
    res = analysis("figures", root, "--out", tmp_path, "--pool", "ours (Rényi, pooled)=ours-*renyi*")
    assert res.returncode == 0, res.stderr
    for f in files:
        assert (tmp_path / f.name).read_bytes() == f.read_bytes(), f.name  # exact: the same drawing, no timestamps


def test_no_finished_run_is_one_line(tmp_path) -> None:
    for root in (tmp_path, tmp_path / "missing"):
        res = analysis("figures", root)
        assert res.returncode != 0 and res.stderr.startswith("error: ") and len(res.stderr.splitlines()) == 1


def test_a_wide_figure_is_saved_at_most_png_max_width_pixels_wide(tmp_path) -> None:
    """A figure with many long row labels (the top-level report's) is written as a PNG at most ``PNG_MAX_WIDTH``
    pixels wide, at a lower dpi; the PDF beside it keeps every detail; a narrow figure keeps the default dpi."""
    from analysis.plotting import PNG_MAX_WIDTH, panels, save

    fig, axes = panels(6)  # 27 inches: 3,240 pixels at the default 120 dpi
    for ax in axes:
        ax.plot([0, 1], [0, 1], label="a long row label " * 8)
    png, pdf = save(fig, tmp_path, "wide")
    with Image.open(png) as image:
        assert PNG_MAX_WIDTH * 0.8 <= image.width <= PNG_MAX_WIDTH
    assert pdf.stat().st_size > 0
    fig, _ = panels(1)
    png, _ = save(fig, tmp_path, "narrow")
    with Image.open(png) as image:
        assert image.width < PNG_MAX_WIDTH and image.info["dpi"][0] == pytest.approx(120, abs=1)


def test_a_grid_too_tight_to_lay_out_is_saved_without_a_warning(tmp_path) -> None:
    """matplotlib's "Tight layout not applied" (panels whose labels cannot fit) is not printed by every report: the
    figure is saved as laid out, cropped to its contents; any other warning still shows."""
    import warnings

    import matplotlib.pyplot as plt

    from analysis.plotting import save

    fig, axes = plt.subplots(1, 8, figsize=(3, 2))
    for ax in axes:
        ax.set_ylabel("a long label " * 6)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fig.tight_layout()  # the condition itself: matplotlib warns here
        assert any("Tight layout not applied" in str(w.message) for w in caught)
        caught.clear()
        png, _ = save(fig, tmp_path, "tight")
    assert not [str(w.message) for w in caught]
    with Image.open(png) as image:
        assert image.width > 0
