"""The stability explorer of the report and of a notebook: sliders, verdicts and a live positioning step.

Everything the page computes comes from the package's own generated code, nothing is written twice:

* the gains, the characteristic coefficients and the Proposition 1 bounds, and the observer's
  matrices ``A(k)``, ``b(k)``, ``g(k)`` of eq:3:1:2: SymPy's ``jscode`` of the derivation
  (:func:`obsdesign.export.codegen.js_module` and the same formulas);
* the dt verdicts: the fastest pole times dt and the spectral radius of the exactly discretized
  observer, ``exp(max Re(lambda) dt)`` at ``k = 0`` and ``k = kappa``, as ``obsdesign check``;
* the certificate of the switched sampled observer (:func:`obsdesign.design.certificate.certify`):
  **precomputed in Python** for the config and over a table of ``rho`` values at the config's other
  values (:data:`CERTIFICATE_RHOS` points); for other slider values the page names the tabulated point
  it shows, or says that none was computed;
* the live step: the generated JavaScript controller (:func:`obsdesign.export.controller_files`,
  ``js``) with the observer constants of the sliders, on a plant model in the page that repeats the
  simulator's physical paper plant (pre-sliding Coulomb and viscous friction, with the lag for
  ``beta > 0``; 10 Heun substeps per sample with the input held; the encoder quantization), without
  random noise. ``m`` moves the observer's and the plant's mass.

* the loop that runs: fields for the sample time, the drive's delay in samples and the PID gains start at
  :func:`obsdesign.design.sampled_loop.sampled_loop`'s values; the page computes the margins, crossover and
  largest closed-loop pole of the same discrete loop ``L(z) = C(z) H_zoh(z) z^-d`` (tests/test_explorer.py
  compares them with python-control). The live step follows the fields too: the controller's ``DT``,
  ``KP``, ``KI``, ``KD``, ``ALPHA_D = exp(-dt kp N / kd)`` and the low-pass ``LP_*`` (the generated
  ``coefficients`` of eq:3:4:5 at the field's dt), the step's samples and substeps
  (:func:`obsdesign.loop.numerics.substeps_for`'s rule on the config's fastest plant rate) at that dt, and the
  drive's delay on the plant side, as :func:`obsdesign.sim.kernel.run_loop` applies it (the command of sample
  ``n`` acts from ``n + d``, the drive holding the saturated ``G / K`` before); the controller does not delay its
  command, its estimator is fed the command the drive applies (``DRIVE_DELAY`` of the field).
  The dt verdicts follow the dt field; the certificate stays the config's (the page says so for another dt).

:func:`explorer_context` gathers the numbers; :class:`Explorer` shows the explorer in a notebook.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from ..params import Config

__all__ = ["explorer_context", "explorer_json", "Explorer", "CERTIFICATE_RHOS", "PREVIEW_DURATION", "preview_inputs"]

#: rho values of the precomputed certificate table (log-spaced over the rho slider).
CERTIFICATE_RHOS = 9
#: Length [s] of the live positioning run, with a 1 mm step up at 5 % of it and back at 55 %.
PREVIEW_DURATION = 1.0
#: Most samples of the live step (a coarser duration for a fast sample rate).
PREVIEW_SAMPLES = 12_000
#: Heun substeps per sample the live step asks for (``prepare``'s default; more where the plant needs them).
PREVIEW_SUBSTEPS = 10


def explorer_params(cfg: Config) -> list[dict]:
    """The sliders: name, label, config value, range and scale."""
    m, fr, rho = cfg.plant.m, cfg.friction, cfg.observer.rho
    rows = [
        {"name": "rho", "label": "rho", "value": rho, "min": 0.5, "max": max(5.0, 2 * rho), "log": False},
        {"name": "kappa", "label": "kappa [N/m]", "value": fr.kappa, "min": fr.kappa / 100, "max": fr.kappa * 100, "log": True},
        {"name": "m", "label": "m [kg]", "value": m, "min": m / 10, "max": m * 10, "log": True},
    ]
    if cfg.observer.variant == "lag":
        rows += [
            {"name": "sigma", "label": "sigma [N s/m]", "value": fr.sigma, "min": fr.sigma / 10, "max": fr.sigma * 10, "log": True},
            {"name": "beta", "label": "beta [s]", "value": fr.beta, "min": fr.beta / 100, "max": fr.beta * 100, "log": True},
        ]
    return [dict(row, label=cfg.units.label(str(row["label"]))) for row in rows]  # the units of the config's axis


def _observer_arrays_js(variant: str) -> str:
    """``observerArrays(params, k, L1, L2)``: ``[A (row-major), b, g]`` of eq:3:1:2 as printed by SymPy ``jscode``
    (the generated :data:`obsdesign.export._formulas.FORMULAS`: no SymPy at run time)."""
    from ..export.codegen import FORMULAS

    form = FORMULAS[variant]
    f = form["jscode"]
    params = ", ".join(form["parameters"])
    entries = [*f["observer_matrix"], *f["observer_input"], *f["observer_output_gain"]]
    return (f"function observerArrays({params}, {form['k']}, {form['L1']}, {form['L2']}) {{\n"
            f"  return [{', '.join(entries)}];\n}}\n")


def preview_inputs(cfg: Config):
    """The simulator's inputs of the live step: ``prepare`` of the config without random noise.

    Parameters
    ----------
    cfg : Config
        The design (with the sliders' values, to compare with the page).

    Returns
    -------
    LoopInputs
        :func:`obsdesign.loop.prepare` of ``cfg`` (``noise_rms = 0``) for a 1 mm step up at 5 % and
        back at 55 % of a run :data:`PREVIEW_DURATION` s long (at most :data:`PREVIEW_SAMPLES` samples).
    """
    from ..loop.inputs import prepare
    from ..loop.scenarios import Positioning

    quiet = cfg.override(noise_rms=0.0)
    duration = min(PREVIEW_DURATION, PREVIEW_SAMPLES * cfg.observer.dt)
    spec = Positioning(step_size=1e-3, step_up=0.05 * duration, step_down=0.55 * duration)
    return prepare(quiet, spec, duration=duration, substeps=PREVIEW_SUBSTEPS)


def _controller_js(loop) -> tuple[str, dict]:
    from ..export.controller import controller_constants, controller_files

    text = controller_files(loop.sampled, "js")["obsdesign_controller.mjs"]
    text = re.sub(r"^export ", "", text, flags=re.M)
    return ("const CTRL = (function () {\n" + text +
            "return {Controller: Controller, CONSTANTS: CONSTANTS, coulombN: coulombN, track: track,\n"
            "        coefficients: typeof coefficients === 'undefined' ? null : coefficients};\n})();\n",
            controller_constants(loop.sampled))


def _certificate_table(cfg: Config, rhos) -> list[dict]:
    from ..design import design_observer
    from ..design.certificate import certify

    rows = []
    for rho in rhos:
        c = certify(design_observer(cfg.override(rho=float(rho))))
        rows.append({"rho": float(rho), "verdict": c.verdict, "method": c.method, "decay_rate": c.decay_rate,
                     "detail": c.condition().detail})
    return rows


def explorer_context(cfg: Config, certificate=None) -> dict:
    """The numbers and the generated code of the explorer, for its template.

    Parameters
    ----------
    cfg : Config
        The design.
    certificate : StabilityCertificate, optional
        The config's certificate if already computed (``check_stability(cfg).certificate``).

    Returns
    -------
    dict
        ``explorer_js`` (the formulas, the controller module and the page's plant constants),
        ``explorer_params`` (the sliders) and ``explorer_data`` (JSON-ready numbers).
    """
    from ..design import design_observer
    from ..design.certificate import certify
    from ..export.codegen import js_module
    from ..loop.bands import SETTLE_DWELL
    from ..loop.numerics import MAX_STEP_RATE, fastest_rate
    from ..sim import kernel

    variant = cfg.observer.variant
    loop = preview_inputs(cfg)
    ctrl_js, consts = _controller_js(loop)
    plant = loop.kernel_args()[3]
    pp = plant.plant_params
    paper_plant = bool(plant.mode == kernel.PLANT_PHYSICAL and plant.friction_code == kernel.FRICTION_PAPER
                       and float(pp[kernel.PP_CF_NEG]) == float(pp[kernel.PP_CF])
                       and float(pp[kernel.PP_SIGMA_NEG]) == float(pp[kernel.PP_SIGMA])
                       and float(pp[kernel.PP_OFFSET]) == 0.0)
    fr = cfg.friction
    if paper_plant:
        levels = {n: float(pp[i]) for n, i in (("Cf", kernel.PP_CF), ("s", kernel.PP_S), ("sigma", kernel.PP_SIGMA),
                                                ("beta", kernel.PP_BETA))}
    else:  # the page's plant is the paper's at the config's levels (the page says so)
        levels = {"Cf": fr.Cf, "s": fr.s, "sigma": fr.sigma,
                  "beta": fr.beta if cfg.observer.variant == "lag" and fr.beta else 0.0}
    sliders = explorer_params(cfg)
    rho_row = sliders[0]
    x_ref = np.asarray(loop.x_ref)
    n_up = int(np.argmax(x_ref > 0.0))
    cert = certificate if certificate is not None else certify(design_observer(cfg))
    from ..design.sampled_loop import sampled_loop

    sl = sampled_loop(cfg)
    data = {
        # the loop that runs, as obsdesign.design.sampled_loop analyses it: its fields' starting values
        "loop": {"dt": sl.dt, "delay": sl.delay_samples, "kp": sl.kp, "ki": sl.ki, "kd": sl.kd,
                 "N": sl.derivative_N, "phi": sl.phi, "tau": sl.tau},
        "fixed": {"sigma": cfg.friction.sigma, "beta": cfg.friction.beta},
        "config": {p["name"]: p["value"] for p in sliders},
        "dt": cfg.observer.dt,
        "certificate": {"verdict": cert.verdict, "method": cert.method, "decay_rate": cert.decay_rate,
                        "detail": cert.condition().detail},
        "certificate_rhos": _certificate_table(cfg, np.geomspace(rho_row["min"], rho_row["max"], CERTIFICATE_RHOS)),
        "preview": {
            "n": int(loop.n_samples), "n_up": n_up, "n_down": n_up + int(np.argmax(x_ref[n_up:] == 0.0)), "step": 1e-3,
            "n_sub": int(plant.n_sub), "K": float(plant.K), "G": float(plant.G), **levels,
            "quantization": float(loop.quantization), "constants": consts, "paper_plant": paper_plant,
            # what the page needs to lay the step out at another dt (the fields): prepare's rules, the drive's
            # hold before the first command (PlantArgs.delay_init) and the low-pass cutoff
            "duration": PREVIEW_DURATION, "max_samples": PREVIEW_SAMPLES, "substeps": PREVIEW_SUBSTEPS,
            "rate": fastest_rate(cfg)[1], "max_step_rate": MAX_STEP_RATE, "delay_init": float(plant.delay_init),
            "omega_co": cfg.observer.omega_co,
            # the settling band of the run (noise-free: 2 counts, or 0.1 % of the step) and the simulator's dwell
            "band": float(loop.settle_tol), "band_rule": loop.settle_rule, "dwell": SETTLE_DWELL,
            **_reference_inputs(loop),
        },
    }
    formulas = re.sub(r"^export ", "", js_module(variant), flags=re.M) + _observer_arrays_js(variant)
    return {"explorer_js": formulas + ctrl_js, "explorer_params": sliders, "explorer_data": data}


def _reference_inputs(loop) -> dict:
    """The feed-forward modes' step inputs ``v_ref``, ``w_ff`` per sample (``LoopInputs.reference_feedforward``,
    the simulator's own arrays); nothing for the observer mode, whose step takes none."""
    if loop.sampled.compensation.mode == "observer":
        return {}
    v_ref, w_ff = loop.reference_feedforward()
    out = {"v_ref": [float(v) for v in v_ref], "w_ff": [float(w) for w in w_ff]}
    # at another dt (the page's field): the step's reference moves only on the two samples around each edge, its
    # central difference is step / (2 dt) there, and the weight there depends on the positions alone (look-ahead
    # in samples, build-up in metres, the pre-sliding curve): the page keeps these weights and recomputes v_ref
    x_ref = np.asarray(loop.x_ref)
    n_up = int(np.argmax(x_ref > 0.0))
    n_down = n_up + int(np.argmax(x_ref[n_up:] == 0.0))
    edges = [n_up - 1, n_up, n_down - 1, n_down]
    rest = np.ones(len(w_ff), bool)
    rest[edges] = False
    if n_up >= 2 and n_down - n_up >= 2 and np.all(v_ref[rest] == 0.0) and np.all(w_ff[rest] == 1.0):
        out["w_edges"] = [float(w_ff[i]) for i in edges]
    return out


def _finite(obj):
    """JSON-ready: non-finite floats as None (the page reads them as absent)."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def explorer_json(data: dict) -> str:
    """``data`` as JSON safe inside a ``<script>`` element (no ``<``, ``>``, ``&``, line separators).

    Parameters
    ----------
    data : dict
        JSON-ready numbers and strings; non-finite floats become ``null``.

    Examples
    --------
    >>> print(explorer_json({"name": "</script>", "x": float("inf")}))
    {"name": "\\u003c/script\\u003e", "x": null}
    """
    text = json.dumps(_finite(data), allow_nan=False)
    for ch, esc in (("<", "\\u003c"), (">", "\\u003e"), ("&", "\\u0026"), ("\u2028", "\\u2028"), ("\u2029", "\\u2029")):
        text = text.replace(ch, esc)
    return text


class Explorer:
    """The report's explorer for a notebook: ``Explorer(cfg)`` renders itself as HTML with its script.

    Parameters
    ----------
    cfg : Config
        The design.

    Examples
    --------
    >>> import obsdesign as od
    >>> page = Explorer(od.load_preset("vcm"))._repr_html_()
    >>> page.count("<script>"), 'id="steplot"' in page
    (1, True)
    """

    def __init__(self, cfg: Config):
        if not isinstance(cfg, Config):
            raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
        self.config = cfg

    def _repr_html_(self) -> str:
        from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape

        env = Environment(loader=PackageLoader("obsdesign.report", "templates"), undefined=StrictUndefined,
                          autoescape=select_autoescape(default=True, default_for_string=True))
        env.filters["log10"] = math.log10
        env.filters["explorer_json"] = explorer_json
        env.filters["unit"] = self.config.units.unit
        return env.get_template("_explorer.html.j2").render(**explorer_context(self.config))
