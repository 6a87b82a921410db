"""The report's section "Comparison with standard estimators": figure and folder reader (render only).

The numbers come from :func:`obsdesign.comparison.compare` (``obsdesign compare --out DIR``);
this module draws them and reads such a folder back for :func:`obsdesign.report.html.render_report`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .folder_files import read_csv_rows, read_json, svg_data_url

__all__ = ["comparison_figure", "comparison_section", "FILES"]

#: Files ``obsdesign compare`` writes into its folder.
FILES = ("compare.csv", "summary.json", "compare.svg")


def _float(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def comparison_figure(rows: list[dict]):
    """Friction RMS error per plant and estimator, one panel per scenario (mean over seeds, range as bars).

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`obsdesign.comparison.compare` (or of ``compare.csv``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    plants = list(dict.fromkeys(r["plant"] for r in rows))
    estimators = list(dict.fromkeys(r["estimator"] for r in rows))
    from .figures import plt

    fig, axes = plt.subplots(1, max(1, len(scenarios)), figsize=(4.2 * max(1, len(scenarios)), 3.6),
                             constrained_layout=True, squeeze=False)
    width = 0.8 / max(1, len(estimators))
    for ax, sc in zip(axes[0], scenarios):
        for j, est in enumerate(estimators):
            mean, lo, hi = [], [], []
            for p in plants:
                vals = [_float(r["friction_rms_error"]) for r in rows
                        if (r["scenario"], r["plant"], r["estimator"]) == (sc, p, est) and r["status"] == "ok"]
                vals = [v for v in vals if math.isfinite(v)]
                m = float(np.mean(vals)) if vals else math.nan
                mean.append(m)
                # equal seeds (an axis without random noise) can put the rounded mean an ulp outside
                # their range (mean of 0.7 three times: 0.7 - 1.1e-16): no negative error bar
                lo.append(max(m - min(vals), 0.0) if vals else 0.0)
                hi.append(max(max(vals) - m, 0.0) if vals else 0.0)
            x = np.arange(len(plants)) + (j - (len(estimators) - 1) / 2) * width
            ax.bar(x, mean, width, yerr=[lo, hi], label=est, capsize=2)
        ax.set_xticks(np.arange(len(plants)), plants)
        ax.set_title(sc)
        ax.set_xlabel("plant friction model")
        ax.set_ylabel("friction RMS error [N]")
    handles, labels = axes[0][0].get_legend_handles_labels()
    # below the panels, outside the bars (a figure read back from disk is not made legible by the report)
    fig.legend(handles, labels, loc="outside lower center", ncols=max(1, len(estimators)), title="estimator")
    return fig


def comparison_section(folder) -> dict | None:
    """The rows, summary and figure of an ``obsdesign compare`` folder, for the report.

    Parameters
    ----------
    folder : path or None
        A folder written by ``obsdesign compare --out``; None gives None.

    Raises
    ------
    ValueError
        If the folder lacks one of :data:`FILES`, or one of them is not what ``obsdesign compare`` writes
        (the message names the file).

    Notes
    -----
    The figure is never inlined: it is returned as a ``data:image/svg+xml;base64,`` address
    (``svg_src``) for an ``<img>`` element, where an SVG runs no script, loads nothing and cannot
    navigate the page.
    """
    if folder is None:
        return None
    from ..comparison import COLUMNS

    folder = Path(folder)
    if not all((folder / n).is_file() for n in FILES):
        raise ValueError(f"compare: expected a folder written by 'obsdesign compare' (with {', '.join(FILES)}), "
                         f"found {str(folder)!r}")
    rows = read_csv_rows(folder / "compare.csv", "compare", COLUMNS)
    summary = read_json(folder / "summary.json", "compare")
    if not isinstance(summary, dict) or not isinstance(summary.get("summary"), list):
        raise ValueError(f"compare: {str(folder / 'summary.json')!r} is not a summary written by obsdesign compare "
                         "(expected an object with a 'summary' list)")
    from ..comparison import NOT_TUNED, not_tuned

    ran = [r for r in rows if not str(r["status"]).startswith(NOT_TUNED)]
    return {"rows": rows, "runs": len(ran), "not_tuned": not_tuned(rows), "summary": summary["summary"],
            "seeds": summary.get("seeds"),
            "svg_src": svg_data_url(folder / "compare.svg", "compare"), "folder": str(folder)}
