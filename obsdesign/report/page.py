"""The report's page: studies, figures and the template (what :func:`obsdesign.report.html.render_report` runs).

The entry point :mod:`obsdesign.report.html` imports nothing heavy: it checks the arguments, starts
the helper process and hands it the independent studies first; only then is this module imported
(SymPy where the memo does not hold the derivation, python-control, numba, matplotlib), in this
process and in the helper side by side.
"""

from __future__ import annotations

import datetime
import math
import time
import warnings

import numpy as np
from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape

from .. import __version__, studies
from .._memo import MemoWarning, memo
from ..design import check_stability, noise_analysis, pid_from_config
from ..design.pid import kept_response
from ..params import Config
from .circle_section import FEEDS as CIRCLE_FEEDS
from .circle_section import ballbar_figure, circle_section, feed_runs
from .explorer import explorer_context, explorer_json
from .kept import kept_svg
from .markup import _CSP_MARK, _quantity, _with_csp, derivation_tree, is_derivation_tree, render_derivation

__all__ = ["render_page", "loops_part", "circle_part", "derivation_markup", "css_string"]


def _eigen_figure(design):
    import matplotlib.pyplot as plt

    k = np.linspace(0.0, design.kappa, 300)
    eig = np.array([design.eigenvalues(x) for x in k])
    fig, ax = plt.subplots(figsize=(7, 3.6), constrained_layout=True)
    ax.plot(k, eig[:, 0].real, label="lambda_1 (dominant)")
    ax.plot(k, eig[:, 1].real, label="lambda_2")
    if np.any(np.abs(eig.imag) > 0):
        ax.plot(k, np.abs(eig[:, 0].imag), ":", label="|imaginary part|")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xlabel("pre-sliding stiffness k [N/m]")
    ax.set_ylabel("eigenvalue [1/s]")
    ax.legend(loc="best")
    return fig


def _bode_figure(curves, bound=None, ylabel=""):
    """Magnitude plot of ``(label, result, system name)`` curves (:func:`obsdesign.design.pid.kept_response`)."""
    import matplotlib.pyplot as plt

    w = np.logspace(-1, 5, 600)
    fig, ax = plt.subplots(figsize=(7, 3.6), constrained_layout=True)
    for label, result, name in curves:
        ax.loglog(w, np.abs(kept_response(result, name, w)), label=label)
    if bound is not None:
        ax.axhline(bound, color="r", ls="--", label=f"bound 1/k = {bound:.4g}")
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel(ylabel)
    ax.legend(loc="best")
    return fig


def css_string(text) -> str:
    """``text`` as the inside of a CSS string (for the printed page's ``@page`` footer): every character but
    letters and digits as a six-digit CSS escape, so no quote, backslash, ``<`` or line break of a user's
    name can end the string or the style element (a space is escaped too: one after an escape would be read
    as the escape's end).

    Parameters
    ----------
    text : str

    Examples
    --------
    >>> print(css_string('vcm "</style>"'))
    vcm\\000020\\000022\\00003c\\00002fstyle\\00003e\\000022
    """
    return "".join(ch if ch.isascii() and ch.isalnum() else f"\\{ord(ch):06x}" for ch in str(text))


def _loop_view_figure(view):
    """The loop view's figure on the page's grid (:func:`_loop_grid` of :func:`obsdesign.design.loop.loop_figure`)."""
    from ..design.loop import loop_figure

    return _loop_grid(loop_figure(view))


def _loop_grid(fig):
    """The loop view's five panels (Bode magnitude and phase, Nyquist, sensitivities, closed-loop poles:
    :func:`obsdesign.design.loop.loop_figure`) on a grid that fills the page's width: magnitude | phase,
    Nyquist | poles, then the sensitivities across the width (each legend below its panel)."""
    from .figures import PAGE_WIDTH_PX, regrid

    if len(fig.axes) != 5:  # another layout of the loop view: leave it to legible()
        return fig
    return regrid(fig, [(0, 0), (0, 1), (1, 0), (2, slice(0, 2)), (1, 1)], ncols=2, row_height=4.0,
                  width=PAGE_WIDTH_PX / 96.0)


def _derivation_tree(variant: str) -> list:
    from ..symbolic import derive  # SymPy: only when the memo does not hold the derivation
    from ..symbolic.printing import derivation_html

    return derivation_tree(derivation_html(derive(variant)))


def derivation_markup(variant: str) -> str:
    """The derivation table of the page (MathML), rendered from data kept in the result memo or from SymPy.

    The memo keeps the table as data (:func:`obsdesign.report.markup.derivation_tree`), never as markup:
    SymPy runs once per package version (:mod:`obsdesign._memo`), and the markup is written by
    :func:`obsdesign.report.markup.render_derivation` every time, escaping every text and attribute. A kept
    tree with an element or attribute outside the allowlist is a miss (derived again, one warning).

    Parameters
    ----------
    variant : str
        ``static`` or ``lag``.
    """
    return render_derivation(memo("derivation_tree", (variant,), lambda: _derivation_tree(variant),
                                  valid=is_derivation_tree))


def loops_part(cfg: Config, experiments) -> tuple[list, str]:
    """The friction loops study's claims and figure, drawn from the experiments' positioning run with the
    observer (the same simulation as the experiments figure's, not run twice).

    Parameters
    ----------
    cfg : Config
        The design.
    experiments : ExperimentsStudy
        :func:`obsdesign.studies.experiments_study` of ``cfg``.
    """
    loops = studies.friction_loops_study(cfg, experiments=experiments)
    return list(loops.claims), kept_svg("obsdesign.report.study_figures:friction_loops_figure", loops,
                                        units=cfg.units)


def circle_part(cfg: Config, runs: dict) -> dict:
    """The circle section with its figure as inline SVG.

    Parameters
    ----------
    cfg : Config
        The design.
    runs : dict
        Feed [m/s] -> runs already computed (by the helper), as :func:`obsdesign.report.circle_section.feed_runs`.
    """
    section = circle_section(cfg, runs=runs, figure=False)
    pictured = section.pop("pictured")
    section.pop("figure")
    section["svg"] = kept_svg(ballbar_figure, pictured, units=cfg.units) if pictured else None
    return section


def render_page(cfg, jobs, steps, paper, circle, *, source_label, progress, data, sweep_section, compare_section,
            flags, moving_speed) -> str:
    """:func:`obsdesign.report.html.render_report` after its arguments are checked.

    Parameters
    ----------
    cfg : Config
        The design.
    jobs : dict
        The helper's futures: ``kernels`` (the simulator's kernel compiled, waited for before this process's
        first simulation; ``None`` without a helper), ``convergence`` (:func:`obsdesign.report.html.convergence_part`, ``None`` without the paper's
        studies) and ``circle`` (feed -> the future of its runs, for the feeds the helper computes; empty
        without the circle test).
    steps : list of str
        The progress bar's steps.
    paper, circle : bool
        Whether the paper's studies and the circle test are on the page.
    source_label, progress, data, sweep_section, compare_section, flags, moving_speed
        As checked and prepared by :func:`obsdesign.report.html.render_report`.
    """
    from .._progress import progress_bar
    from ..criteria import judge_design
    from ..provenance import parameter_sources

    variant = cfg.observer.variant
    units = cfg.units  # every unit the report prints is written for this axis

    conv_job, helper_feeds = jobs["convergence"], jobs["circle"]
    bar = progress_bar(progress, iterable=steps, desc="obsdesign report", leave=False)  # no thread without a bar
    ctx: dict = {"cfg": cfg, "version": __version__, "source_label": source_label,
                 "date": datetime.date.today().isoformat()}
    t0 = time.perf_counter()
    bar.set_postfix_str(steps[0])
    ctx["derivation_html"] = derivation_markup(variant)
    sources = parameter_sources(cfg, source_label, flags=flags)
    ctx["params"] = [(r.name, r.value, r.unit, r.doc, sources[r.name]) for r in cfg.describe_fields()]
    bar.update()

    bar.set_postfix_str(steps[1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.simplefilter("default", MemoWarning)  # a refused memo entry is still said
        rep = check_stability(cfg)
    ctx["stability"] = rep
    ctx["eigen_svg"] = kept_svg(_eigen_figure, rep.design, units=units)
    bar.update()

    bar.set_postfix_str(steps[2])
    pid = pid_from_config(cfg)
    ctx["pid"] = pid
    ctx["pid_svg"] = kept_svg(_bode_figure, [("|S| = |H/(1+HC)|", pid, "S")], bound=1 / pid.k, ylabel="|S| [m/V]",
                              units=units)
    from ..design.loop import loop_analysis

    ctx["loop_view"] = loop_analysis(cfg)
    ctx["loop_svg"] = kept_svg(_loop_view_figure, ctx["loop_view"], units=units)
    bar.update()

    bar.set_postfix_str(steps[3])
    na = noise_analysis(cfg)
    ctx["noise"] = na
    ctx["noise_svg"] = kept_svg(_bode_figure, [("noise -> friction estimate", na, "G_friction"),
                                               ("after the low-pass eq:3:4:5", na, "G_friction_filtered")],
                                ylabel="gain [N/m]", units=units)
    bar.update()

    claims = []
    ctx["paper"] = paper
    if paper:
        claims = list(studies.derivation_claims()) + list(studies.pid_claims())
        conv_index = len(claims)  # the convergence claims go here when the helper returns them

    bar.set_postfix_str("experiments")
    if jobs.get("kernels") is not None:  # the helper has compiled the kernel: loaded from numba's cache
        jobs["kernels"].result()
    exp = studies.experiments_study(cfg)
    claims += exp.claims
    ctx["experiments"] = exp
    ctx["experiments_svg"] = kept_svg("obsdesign.report.study_figures:experiments_figure", exp, units=units)
    bar.update()

    # what runs here before the helper's results are asked for: the noise study and the circle's other
    # feeds (so this process does not wait while work is left); the page is assembled in its own order
    noise_claims = []
    if paper:
        bar.set_postfix_str("noise study")
        noise_claims = list(studies.noise_study().claims)
        bar.update()
    feeds = {}
    if circle:
        bar.set_postfix_str("circle test")
        feeds = {f: feed_runs(cfg, f) for f in CIRCLE_FEEDS if f not in helper_feeds}
    bar.set_postfix_str("friction loops")
    loops_claims, ctx["loops_svg"] = loops_part(cfg, exp)
    claims += loops_claims + noise_claims
    bar.update()
    if paper:
        bar.set_postfix_str("convergence (Table 1)")
        conv_claims, ctx["convergence_svg"] = conv_job.result()
        claims[conv_index:conv_index] = conv_claims
        bar.update()
    ctx["claims"] = claims if paper else []
    ctx["circle"] = None
    if circle:
        bar.set_postfix_str("circle test")
        ctx["circle"] = circle_part(cfg, {**feeds, **{f: job.result() for f, job in helper_feeds.items()}})
        bar.update()
    ctx["criteria"] = judge_design(cfg, sampled_loop=ctx["loop_view"].sampled, experiments=exp, noise=na,
                                   stability=rep)

    bar.set_postfix_str("render")
    ctx.update(explorer_context(cfg, certificate=rep.certificate))
    ctx["sweep"] = sweep_section
    ctx["data"] = None
    if data is not None:
        from .data_section import data_section

        ctx["data"] = data_section(data, cfg, moving_speed=moving_speed,
                                   label=f"the report's config ({source_label})")
    ctx["comparison"] = compare_section
    ctx["elapsed"] = time.perf_counter() - t0
    env = Environment(loader=PackageLoader("obsdesign.report", "templates"), undefined=StrictUndefined,
                      autoescape=select_autoescape(default=True, default_for_string=True))
    env.filters["num"] = _quantity  # one number format in the whole report: 4 significant digits
    env.filters["qty"] = lambda value, unit="": _quantity(value, units.unit(unit))
    env.filters["unit"] = units.unit
    env.filters["words"] = units.words  # mass, force, voltage in the words of the config's axis
    env.filters["log10"] = math.log10
    env.filters["explorer_json"] = explorer_json
    env.filters["css_string"] = css_string
    ctx["provenance"] = (f"obsdesign {__version__} design report of {cfg.name} ({source_label}), "
                         f"variant {variant}, rho {_quantity(cfg.observer.rho)}, generated {ctx['date']}")
    html = _with_csp(env.get_template("report.html.j2").render(csp=_CSP_MARK, **ctx))
    bar.update()
    bar.close()
    return html
