"""Figures for results: ADE per future frame (``evaluate --plot``).

matplotlib with the Agg canvas (no display needed); the PNG is written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from motion2video.core.atomic import atomic_output

BASELINE_STYLE = {"zero-velocity": ("0.35", "--"), "last-step": ("0.55", ":"), "sequence-motion": ("0.7", "-.")}


def plot_ade_per_frame(curves: dict[str, list[float]], out: str | Path, *, fps: float, units: str,
                       title: str = "", best_of: int | None = None) -> Path:
    """Draw one line per method: best-of-K displacement (y) at each future frame (x, seconds).

    Args:
        curves: method name -> per-frame values (T,); baselines (see ``BASELINE_STYLE``) are drawn grey.
        out: the PNG path.
        fps: frame rate of the future frames (x axis in seconds).
        units: y-axis units.
        title: figure title.
        best_of: K, written in the y label.
    Returns:
        The written path.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.2), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    for name, values in curves.items():
        t = (np.arange(len(values)) + 1) / fps
        color, style = BASELINE_STYLE.get(name, (None, "-"))
        ax.plot(t, values, style, color=color, linewidth=2.2 if name not in BASELINE_STYLE else 1.5,
                label=f"{name} (ADE {np.mean(values):.3f})")
    # Extrapolating baselines (last-step, sequence-motion) run far above the rest: keep the y range on the
    # models and zero-velocity, and let the clipped lines leave the top (their ADE is in the legend).
    near = [max(v) for n, v in curves.items() if n not in ("last-step", "sequence-motion")]
    if near and max(max(v) for v in curves.values()) > 1.5 * max(near):
        ax.set_ylim(0, 1.3 * max(near))
    ax.set_xlabel("time into the future (s)")
    ax.set_ylabel(f"{'best-of-' + str(best_of) + ' ' if best_of else ''}displacement ({units})")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    out = Path(out)
    with atomic_output(out) as tmp:
        fig.savefig(tmp, format="png")
    return out
