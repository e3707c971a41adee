"""matplotlib for the plots of both reports, set up and saved the one way: the Agg backend (no display), the figure
laid out, saved and closed."""
from __future__ import annotations


def pyplot():
    """``matplotlib.pyplot`` on the Agg backend (imported on first use: the sections that plot nothing never
    load it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path, dpi: int = 110) -> None:
    """Lay ``fig`` out, write it to ``path`` and close it."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)


def dress(ax, xlabel=None, ylabel=None, title=None, legend: int = 7, title_size=None, which: str = "both"):
    """An axes' labels and title (those given), a faint grid (``which`` lines: "both" on log scales) and the
    legend at font size ``legend``."""
    if xlabel is not None:
        ax.set_xlabel(xlabel)
    if ylabel is not None:
        ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title, **({"fontsize": title_size} if title_size else {}))
    ax.grid(True, which=which, alpha=0.3)
    ax.legend(fontsize=legend)
