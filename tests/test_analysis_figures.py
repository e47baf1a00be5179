"""``analysis.figures`` on synthetic run directories: every figure is written as a PNG and a PDF that open, the same
bytes on a re-run, and the stable-reward steps are the ones the criterion gives; rows are named by ``analysis.yaml``'s
short names, each in its own colour, every text at least 8 pt, the legend outside the panels."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from matplotlib.text import Text
from PIL import Image

import analysis.figures as figures_module
from analysis.curves import mean_band, running_rate, stable_step
from analysis.figures import FIGURES, write_figures
from tests.synthetic_runs import make_runs
from tests.test_analysis import analysis

POOL = "ours (Rényi, pooled)=ours-*renyi*"
# The synthetic rows' short names, in the order the legends list them ("[[]" a literal "[" in a glob).
LABELS = ["NSRS=nsrs", "NSRS (horizon 3)=nsrs [[]planner.horizon=3]", "NSRS (horizon 5)=nsrs [[]planner.horizon=5]",
          "Rényi (pooled)=ours (Rényi, pooled)", "Random=random"]  # fmt: skip
SHORT = [label.partition("=")[0] for label in LABELS]


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """The figures of the synthetic runs (``analysis.yaml`` holding the pool and the short names), and each figure as
    drawn (``save`` watched)."""
    root = make_runs(tmp_path_factory.mktemp("runs"))
    (root / "analysis.yaml").write_text(yaml.safe_dump({"pool": [POOL], "labels": LABELS}, allow_unicode=True))
    out = root.parent / "figures"
    drawn: dict[str, Figure] = {}
    save = figures_module.save

    def watched(fig: Figure, where, name: str) -> list:
        drawn[name] = fig
        return save(fig, where, name)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(figures_module, "save", watched)
        files = write_figures(root, out, pools=[POOL], labels=LABELS)
    return root, out, files, drawn


def test_every_figure_is_a_png_and_a_pdf_that_open(written: tuple) -> None:
    _, out, files, _ = written
    for name in (n for n in FIGURES if n != "tv_presses"):  # no run here has a noisy TV (test_analysis_tables.py)
        png, pdf = out / f"{name}.png", out / f"{name}.pdf"
        assert png in files and pdf in files and png.stat().st_size > 0
        with Image.open(png) as im:
            im.verify()
        assert pdf.read_bytes().startswith(b"%PDF") and b"CreationDate" not in pdf.read_bytes()


def test_stability_lists_each_seed_and_kde_settles_before_knn(written: tuple) -> None:
    _, out, _, _ = written
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
    """The bare command (the pool and the short names from ``analysis.yaml``) draws what ``write_figures`` drew."""
    root, _, files, _ = written
    res = analysis("figures", root, "--out", tmp_path)
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
    import matplotlib.pyplot as plt

    from analysis.plotting import PNG_MAX_WIDTH, panels, save

    fig, axes = panels(6, width=4.5)  # 27 inches side by side: 5,400 pixels at the default 200 dpi
    for ax in axes:
        ax.plot([0, 1], [0, 1], label="a long row label " * 8)
    png, pdf = save(fig, tmp_path, "wide")
    with Image.open(png) as image:
        assert PNG_MAX_WIDTH * 0.8 <= image.width <= PNG_MAX_WIDTH
    assert pdf.stat().st_size > 0
    fig, _ = panels(1)
    png, _ = save(fig, tmp_path, "narrow")
    with Image.open(png) as image:
        assert image.width < PNG_MAX_WIDTH and image.info["dpi"][0] == pytest.approx(plt.rcParams["savefig.dpi"], abs=1)


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


def _legend_texts(fig: Figure) -> list[str]:
    return [t.get_text() for t in fig.legends[0].get_texts()]


def test_rows_are_named_by_their_short_names_in_the_order_listed(written: tuple) -> None:
    """The legends and the steps-to-goal panels name the rows by ``analysis.yaml``'s short names, in its order (the
    tables keep the row labels: ``test_stability_lists_each_seed_and_kde_settles_before_knn``)."""
    drawn = written[3]
    assert _legend_texts(drawn["reached_fraction"]) == SHORT
    assert _legend_texts(drawn["coverage"]) == SHORT
    assert _legend_texts(drawn["intrinsic"])[:-1] == SHORT  # then the dashed stable step's key
    acrobot, mountaincar = drawn["steps_to_goal"].axes
    assert [t.get_text() for t in acrobot.get_yticklabels()] == ["NSRS (horizon 3)", "NSRS (horizon 5)", "Random"]
    assert [t.get_text() for t in mountaincar.get_yticklabels()] == ["NSRS", "Rényi (pooled)"]
    assert _legend_texts(drawn["behaviour"]) == [  # one panel draws both envs: the env before the name
        "mountaincar: NSRS", "acrobot: NSRS (horizon 3)", "acrobot: NSRS (horizon 5)", "mountaincar: Rényi (pooled)"]


def test_every_text_is_at_least_8_pt(written: tuple) -> None:
    for name, fig in written[3].items():
        texts = [t for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
        assert texts, name
        small = sorted({(t.get_text(), t.get_fontsize()) for t in texts if t.get_fontsize() < 8})
        assert not small, f"{name}: {small[:3]}"


def test_each_row_has_its_own_colour_in_every_figure(written: tuple) -> None:
    """Distinct colours within a legend, and a row's colour the same in every figure."""
    seen: dict[str, str] = {}
    for name in ("reached_fraction", "coverage", "intrinsic", "entropy"):
        legend = written[3][name].legends[0]
        colours = {t.get_text(): to_hex(h.get_color()) for t, h in zip(legend.get_texts(), legend.legend_handles,
                                                                        strict=True) if t.get_text() in SHORT}  # fmt: skip
        assert len(set(colours.values())) == len(colours), name
        for row, colour in colours.items():
            assert seen.setdefault(row, colour) == colour, (name, row)
    assert len(seen) == len(SHORT)


def _renderer(fig: Figure):
    """A renderer of a figure ``save`` closed (its layout as saved)."""
    return FigureCanvasAgg(fig).get_renderer()


def _overlaps(a, b) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_the_legend_covers_no_panel_and_no_panel_is_tall_and_narrow(written: tuple) -> None:
    for name, fig in written[3].items():
        renderer = _renderer(fig)
        panels = [ax.get_window_extent(renderer) for ax in fig.axes if ax.axison]
        for legend in fig.legends:
            box = legend.get_window_extent(renderer)
            assert not any(_overlaps(box, p) for p in panels), name
        assert all(p.width >= p.height for p in panels), name
        assert fig.get_figwidth() <= 6.9 + 1e-9, name  # at most two columns wide


def test_a_tall_legend_of_a_one_column_figure_goes_beside_the_panel(tmp_path) -> None:
    """Ten rows of long names under a one-column panel would take ten lines: the legend goes to the panel's right, the
    figure widened (at most to two columns), the panel laid out left of it."""
    from analysis.plotting import DOUBLE, SINGLE, legend_outside, panels, save

    fig, (ax,) = panels(1)
    assert fig.get_figwidth() == SINGLE
    for i in range(10):
        ax.plot([0, 1], [i, i + 1], label=f"a long name for row {i} of ten")
    legend = legend_outside(fig, [ax])
    save(fig, tmp_path, "beside")
    renderer = _renderer(fig)
    box, panel = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
    assert legend._ncols == 1 and box.x0 >= panel.x1 and SINGLE < fig.get_figwidth() <= DOUBLE


def test_two_rows_of_an_env_may_not_share_a_short_name_and_a_name_for_no_row_is_warned_of() -> None:
    from analysis.plotting import row_names

    rows = pd.DataFrame({"env": ["acrobot", "acrobot", "mountaincar"], "row": ["icm", "rnd", "icm"]})
    assert row_names(rows, ["baseline=icm", "RND=rnd"]).order == ["baseline", "RND"]  # one name over two envs: fine
    with pytest.raises(ValueError, match="two rows of acrobot are both named 'baseline'"):
        row_names(rows, ["baseline=icm", "baseline=rnd"])
    with pytest.warns(UserWarning, match="labels: 'α = 0.5=ours' matches no row"):  # the name ends at its first "="
        row_names(rows, ["α = 0.5=ours"])
