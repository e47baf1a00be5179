"""Matplotlib set-up shared by the figure commands: the Agg backend, paper sizes, a colour-blind-safe style per row,
legends beside the data, and byte-stable files.

Sizes are a paper's: a figure is one column wide (``SINGLE`` = 3.3 in) with one panel, two columns (``DOUBLE`` =
6.9 in) with more, in between where a legend beside the panel or long row names need the room; every text is at least
``TEXT`` = 8 pt at that size, and panels are not taller than wide. Rows are named by their short names
(:class:`RowNames`: ``analysis.yaml``'s ``labels``, :func:`analysis.cost.short_labels`), each with its own colour
(:data:`PALETTE`: Okabe & Ito's colour-blind-safe colours, then three more) and its own marker, in the order the
``labels`` list them. :func:`legend_outside` sets the legend below or beside the panels, never over the
data.
:func:`save` writes PNG and PDF without the timestamps and version strings matplotlib otherwise embeds, so re-running
a command leaves the files byte for byte as they were; a PNG is at most ``PNG_MAX_WIDTH`` pixels wide.
"""

from __future__ import annotations

import fnmatch
import math
import warnings
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # before pyplot is imported: no display needed
import matplotlib.pyplot as plt
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from PIL import Image

from analysis.cost import parse_labels, short_labels

SINGLE, DOUBLE = 3.3, 6.9  # inches: a figure one column wide, and two columns wide
TEXT = 8  # pt: the smallest text in a figure (tick labels, legends, notes); titles one point larger
plt.rcParams.update({"svg.hashsalt": "curiosity", "font.size": TEXT, "axes.titlesize": TEXT + 1,
                     "axes.labelsize": TEXT, "xtick.labelsize": TEXT, "ytick.labelsize": TEXT, "legend.fontsize": TEXT,
                     "legend.title_fontsize": TEXT, "figure.titlesize": TEXT + 1, "lines.linewidth": 1.2,
                     "lines.markersize": 4, "legend.handlelength": 1.8, "legend.columnspacing": 1.2,
                     "figure.dpi": 100, "savefig.dpi": 200})  # fmt: skip

PNG_METADATA = {"Software": None}
# A PNG is at most this wide (a report with many long row labels would otherwise be 3,000+ pixels wide and 0.5 MB, and
# every landing of results rewrites it); the PDF beside it keeps every detail.
PNG_MAX_WIDTH = 1600
PDF_METADATA = {"CreationDate": None, "Producer": None, "Creator": None}

# Okabe & Ito (2008), "Color Universal Design", without its yellow (too pale for a thin line on white): blue, orange,
# bluish green, reddish purple, vermillion, sky blue, black, in the order that keeps the first few as far apart as they
# go; then Paul Tol's "muted" olive, a grey and Tol's wine for an eighth to tenth row. A row keeps its colour in every
# figure of a results directory (and a marker of its own, for print in grey).
PALETTE = ("#0072B2", "#E69F00", "#009E73", "#CC79A7", "#D55E00", "#56B4E9", "#000000", "#999933", "#999999",
           "#882255")  # fmt: skip
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "<", ">", "h")
LINESTYLES = ("-", "--", ":", "-.")  # one per env where a panel draws the rows of several envs


@dataclass(frozen=True)
class Style:
    """How one row is drawn: its colour and its marker."""

    colour: str
    marker: str


def styles(names: Sequence[str]) -> dict[str, Style]:
    """A :class:`Style` per name, in the given order: the i-th name the i-th colour and marker (cycling past ten)."""
    unique = list(dict.fromkeys(names))
    return {n: Style(PALETTE[i % len(PALETTE)], MARKERS[i % len(MARKERS)]) for i, n in enumerate(unique)}


@dataclass
class RowNames:
    """The name each (env, row) is shown by in a figure and the style of each name; ``order`` lists the names as the
    legends do."""

    short: dict[tuple[str, str], str]
    order: list[str]
    style: dict[str, Style]

    def __call__(self, env: object, row: object) -> str:
        return self.short.get((str(env), str(row)), str(row))

    def rank(self, env: object, row: object) -> int:
        """Where (env, row) comes in ``order`` (a row the names do not know: after every known one)."""
        name = self(env, row)
        return self.order.index(name) if name in self.order else len(self.order)


def row_names(rows: pd.DataFrame, specs: Sequence[str] = ()) -> RowNames:
    """Short names of the (env, row) pairs of ``rows`` (:func:`analysis.cost.short_labels` of ``specs``, a list of
    ``SHORT=GLOB``), ordered as ``specs`` list them, then the other rows by label; ValueError when two rows of an env
    would have the same name (one colour for both), a warning for a ``SHORT=GLOB`` that names no row."""
    short = short_labels(rows, specs)
    for env in sorted({e for e, _ in short}):
        names = [n for (e, _), n in sorted(short.items()) if e == env]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"labels: two rows of {env} are both named {twice[0]!r}; give each row its own name")
    pairs = parse_labels(specs)
    labels = sorted(set(rows["row"].astype(str))) if len(rows) else []
    for spec, (_, pattern) in zip(specs, pairs, strict=True):
        if not any(fnmatch.fnmatchcase(r, pattern) for r in labels):
            warnings.warn(f"labels: {spec!r} matches no row (a short name ends at its first '=')", stacklevel=2)
    given = [s for s, _ in pairs]
    rank: dict[str, tuple[int, str]] = {}
    for (_, row), name in sorted(short.items()):
        key = (given.index(name) if name in given else len(given), row)
        rank[name] = min(rank.get(name, key), key)
    order = sorted(rank, key=lambda n: (rank[n], n))
    return RowNames(short, order, styles(order))


def marks(index: int, points: int) -> dict[str, object]:
    """Marker keywords for the curve of the ``index``-th name through ``points`` points: about eight markers along it,
    each name's shifted so that the markers of curves that run together do not sit on one another; the first names
    drawn on top (the legends list the rows a study is about first)."""
    step = max(1, points // 8)
    return {"markevery": ((index * step) // 7 % step, step), "markersize": 3.5, "zorder": 2.5 - 0.01 * index}


def panels(n: int, width: float | None = None, height: float | None = None) -> tuple[Figure, list[Axes]]:
    """A figure with ``n`` panels (at least one): one panel one column wide (``SINGLE``), more two columns wide
    (``DOUBLE``), at most three panels a line (two for four), each panel about 0.72 as tall as wide. ``width`` and
    ``height`` give a panel's size in inches instead (``n`` panels side by side)."""
    n = max(n, 1)
    if width is not None or height is not None:
        cols, lines = n, 1
        fig_width = (width or 4.5) * n
        panel_height = height or 3.2
    else:
        cols = n if n <= 3 else (2 if n == 4 else 3)
        lines = math.ceil(n / cols)
        fig_width = SINGLE if n == 1 else DOUBLE
        panel_height = max(1.9, min(2.5, 0.72 * fig_width / cols))
    fig, grid = plt.subplots(lines, cols, figsize=(fig_width, panel_height * lines), squeeze=False)
    axes = list(grid.ravel())
    for ax in axes[n:]:
        ax.remove()
    return fig, axes[:n]


def note(ax: Axes, text: str) -> None:
    """Write ``text`` in the middle of an empty panel (what it would show, and why it does not)."""
    ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, transform=ax.transAxes, fontsize=TEXT)
    ax.set_xticks([])
    ax.set_yticks([])


TALL_LEGEND = 4  # lines: a legend below the panels that would be taller goes beside them (where the figure can widen)
_LAYOUT_RECT: weakref.WeakKeyDictionary[Figure, tuple[float, float, float, float]] = weakref.WeakKeyDictionary()


def legend_outside(fig: Figure, axes: Sequence[Axes], handles: dict[str, object] | None = None) -> Legend | None:
    """One legend for all panels, outside every panel (so it covers no data): ``handles`` (label -> artist), by default
    every labelled artist of ``axes`` once, in drawing order. Below the panels in as many columns (at most four) as fit
    in the figure's width; where that takes more than ``TALL_LEGEND`` lines in a figure narrower than two columns, in
    one column to the right of the panels instead, the figure widened by the legend's width (to at most ``DOUBLE``)."""
    if handles is None:
        handles = {}
        for ax in axes:
            for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
                handles.setdefault(label, h)
    if not handles:
        return None
    renderer = fig.canvas.get_renderer()
    room = fig.get_figwidth() * fig.dpi
    wide = fig.get_figwidth() >= DOUBLE - 0.01
    for ncol in range(min(len(handles), 4), 0, -1):
        legend = fig.legend(list(handles.values()), list(handles), loc="upper center", bbox_to_anchor=(0.5, 0.0),
                            ncol=ncol, frameon=False)  # fmt: skip
        fits = legend.get_window_extent(renderer).width <= room
        if (fits and (wide or math.ceil(len(handles) / ncol) <= TALL_LEGEND)) or (ncol == 1 and wide):
            return legend
        legend.remove()
        if fits:
            break
    legend = fig.legend(list(handles.values()), list(handles), loc="center left", ncol=1, frameon=False)
    beside = legend.get_window_extent(renderer).width / fig.dpi + 0.1
    width = min(DOUBLE, fig.get_figwidth() + beside)
    fig.set_figwidth(width)
    right = max(0.5, 1 - beside / width)
    legend.set_bbox_to_anchor((right, 0.5), transform=fig.transFigure)
    _LAYOUT_RECT[fig] = (0.0, 0.0, right, 1.0)  # save's tight layout keeps the panels left of it
    return legend


def save(fig: Figure, out: Path, name: str) -> list[Path]:
    """Write ``out/name.png`` and ``out/name.pdf`` (byte-stable) and close the figure; returns the two paths."""
    out.mkdir(parents=True, exist_ok=True)
    png, pdf = out / f"{name}.png", out / f"{name}.pdf"
    with warnings.catch_warnings():  # a panel grid too wide to fit is left as laid out; bbox_inches="tight" crops it
        warnings.filterwarnings("ignore", message="Tight layout not applied", category=UserWarning)
        fig.tight_layout(rect=_LAYOUT_RECT.get(fig, (0.0, 0.0, 1.0, 1.0)))
    dpi = float(plt.rcParams["savefig.dpi"])
    for _ in range(4):  # the tight box scales almost, not exactly, with the dpi: a few re-saves converge
        fig.savefig(png, metadata=PNG_METADATA, bbox_inches="tight", dpi=dpi)
        with Image.open(png) as image:
            width = image.width
        if width <= PNG_MAX_WIDTH:
            break
        dpi *= 0.99 * PNG_MAX_WIDTH / width
    fig.savefig(pdf, metadata=PDF_METADATA, bbox_inches="tight")
    plt.close(fig)
    return [png, pdf]
