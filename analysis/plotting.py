"""Matplotlib set-up shared by the figure commands: the Agg backend, one colour per row, and byte-stable files.

:func:`save` writes PNG and PDF without the timestamps and version strings matplotlib otherwise embeds, so re-running
a command leaves the files byte for byte as they were; a PNG is at most ``PNG_MAX_WIDTH`` pixels wide.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # before pyplot is imported: no display needed
import matplotlib.pyplot as plt
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from PIL import Image

plt.rcParams.update({"svg.hashsalt": "curiosity", "font.size": 8, "axes.titlesize": 9, "legend.fontsize": 6,
                     "figure.dpi": 100, "savefig.dpi": 120})  # fmt: skip

PNG_METADATA = {"Software": None}
# A PNG is at most this wide (a report with many long row labels would otherwise be 3,000+ pixels wide and 0.5 MB, and
# every landing of results rewrites it); the PDF beside it keeps every detail.
PNG_MAX_WIDTH = 1600
PDF_METADATA = {"CreationDate": None, "Producer": None, "Creator": None}


def colours(labels: Sequence[str]) -> dict[str, tuple[float, ...]]:
    """A colour per row label, in sorted order from the ``tab10``/``tab20`` cycle."""
    cmap = plt.get_cmap("tab10" if len(labels) <= 10 else "tab20")
    return {label: cmap(i % cmap.N) for i, label in enumerate(sorted(set(labels)))}


def panels(n: int, width: float = 4.5, height: float = 3.2) -> tuple[Figure, list[Axes]]:
    """A figure with ``n`` panels side by side (at least one)."""
    fig, axes = plt.subplots(1, max(n, 1), figsize=(width * max(n, 1), height), squeeze=False)
    return fig, list(axes[0])


def note(ax: Axes, text: str) -> None:
    """Write ``text`` in the middle of an empty panel (what it would show, and why it does not)."""
    ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, transform=ax.transAxes, fontsize=7)
    ax.set_xticks([])
    ax.set_yticks([])


def legend_below(fig: Figure, axes: Sequence[Axes]) -> None:
    """One legend for all panels, below them (row labels are long)."""
    handles: dict[str, object] = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, h)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=1,
                   frameon=False)  # fmt: skip


def save(fig: Figure, out: Path, name: str) -> list[Path]:
    """Write ``out/name.png`` and ``out/name.pdf`` (byte-stable) and close the figure; returns the two paths."""
    out.mkdir(parents=True, exist_ok=True)
    png, pdf = out / f"{name}.png", out / f"{name}.pdf"
    with warnings.catch_warnings():  # a panel grid too wide to fit is left as laid out; bbox_inches="tight" crops it
        warnings.filterwarnings("ignore", message="Tight layout not applied", category=UserWarning)
        fig.tight_layout()
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
