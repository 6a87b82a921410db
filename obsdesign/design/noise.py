"""Propagation of measurement noise into the observer's estimates (section 3.4).

At a constant stiffness ``k`` the observer is LTI; the transfer functions from
measurement noise ``eta`` (eq:3:4:1) to the velocity and friction estimates come
from the symbolic derivation (``Derivation.noise``). The friction estimate is
passed through the second-order low-pass of eq:3:4:5,
``F(p) = omega_co^2 / (p + omega_co)^2``.

Noise model: band-limited white noise, flat one-sided spectrum on
``[0, B]`` Hz and none above, with RMS ``eta``. Then
``rms^2 = eta^2 / B * integral_0^B |G(j 2 pi f)|^2 df``.

Examples
--------
>>> import obsdesign as od
>>> na = od.noise_analysis(od.load_preset("vcm"), noise_rms=1e-6, noise_bandwidth=1000.0)
>>> na.direct_gain  # kappa (1 - rho^2): 1 um of noise is 0.12 N at once
-120000.0
>>> na.rms_filtered < na.rms_raw
True
>>> na.warnings
()
>>> od.noise_analysis(od.load_preset("vcm").override(rho=0.5)).warnings[0].startswith("the observer design fails check")
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._display import ResultDisplay
from .._memo import list_of, memo
from .._validate import NONNEGATIVE, POSITIVE, Range
from ..params import Config
from .advisories import design_warnings
from .numeric import poly_coeffs
from .observer import design_observer
from .pid import lazy_system

if TYPE_CHECKING:
    import control as ct

__all__ = ["NoiseAnalysis", "noise_analysis", "lowpass", "band_limited_rms"]

_NONNEG = NONNEGATIVE
_POS = POSITIVE


def lowpass(omega_co: float) -> "ct.TransferFunction":
    """The second-order low-pass filter of eq:3:4:5.

    Parameters
    ----------
    omega_co : float
        Cutoff [rad/s], > 0.

    >>> F = lowpass(10.0)
    >>> F.num[0][0], F.den[0][0]
    (array([100.]), array([  1.,  20., 100.]))
    """
    import control as ct

    w = _POS.check("omega_co", omega_co)
    return ct.tf([w * w], [1.0, 2.0 * w, w * w])


def band_limited_rms(G: "ct.TransferFunction", noise_rms: float, bandwidth_hz: float) -> float:
    """RMS of ``G`` driven by band-limited white noise of RMS ``noise_rms`` over ``[0, B]`` Hz.

    Parameters
    ----------
    G : control.TransferFunction
        SISO transfer from the noise.
    noise_rms : float
        RMS of the noise, >= 0.
    bandwidth_hz : float
        Bandwidth B [Hz] of the flat one-sided spectrum, > 0.

    Examples
    --------
    >>> # First-order low-pass 1/(p/a + 1): closed form eta * sqrt(a/W * atan(W/a)), W = 2 pi B.
    >>> a, B = 100.0, 50.0
    >>> W = 2 * math.pi * B
    >>> import control as ct
    >>> round(band_limited_rms(ct.tf([1.0], [1 / a, 1.0]), 2.0, B) / (2 * math.sqrt(a / W * math.atan(W / a))), 12)
    1.0
    """
    import scipy.integrate

    eta = _NONNEG.check("noise_rms", noise_rms)
    B = _POS.check("noise_bandwidth", bandwidth_hz)
    if eta == 0.0:
        return 0.0
    num, den = np.asarray(G.num[0][0], float), np.asarray(G.den[0][0], float)

    def power(w: float) -> float:
        return abs(np.polyval(num, 1j * w) / np.polyval(den, 1j * w)) ** 2

    W = 2.0 * math.pi * B
    corners = sorted({abs(p) for p in np.roots(den) if 0.0 < abs(p) < W} | {abs(z) for z in np.roots(num) if 0.0 < abs(z) < W})
    # Between the corners the integrand is smooth on a log scale: split each interval into decades,
    # so that a band far beyond the corners (many decades) is integrated as accurately as a narrow one.
    edges = [0.0]
    for edge in (*corners, W):
        lo = edges[-1] if edges[-1] > 0.0 else edge / 10.0
        if edges[-1] == 0.0:
            edges.append(lo)
        while edge / lo > 10.0:
            lo *= 10.0
            edges.append(lo)
        edges.append(edge)
    edges = sorted(set(edges))
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:]):
        total += scipy.integrate.quad(power, lo, hi, limit=400, epsrel=1e-10, epsabs=0.0)[0]
    return eta * math.sqrt(total / W)


@dataclass(frozen=True, kw_only=True)
class NoiseAnalysis(ResultDisplay):
    """Noise propagation into the estimates at one stiffness.

    Attributes
    ----------
    stiffness : float
        Constant pre-sliding stiffness k [N/m] of the analysis.
    noise_rms, noise_bandwidth : float
        Measurement noise RMS [m] and bandwidth [Hz].
    omega_co : float
        Low-pass cutoff [rad/s].
    direct_gain : float
        Direct feedthrough of the noise into the friction estimate, ``L2`` [N/m] (eq:3:4:3).
    velocity_direct_gain : float
        Same for the velocity estimate, ``L1`` [1/s].
    rms_raw, rms_filtered : float
        RMS of the friction estimate's noise without and with the low-pass [N].
    rms_velocity_raw : float
        RMS of the velocity estimate's noise [m/s].
    friction_transfer, velocity_transfer : tuple
        Numerator and denominator coefficients (highest power first) of the noise transfers to the
        friction and the velocity estimate (``obsdesign.design.numeric.poly_coeffs``).
    G_friction, G_velocity, lowpass : control.TransferFunction
        Those transfers and the low-pass eq:3:4:5, built on first use (python-control).
    G_friction_filtered : control.TransferFunction
        ``lowpass * G_friction``: the noise transfer to the compensated friction estimate.
    warnings : tuple of str
        The design's warnings (:func:`obsdesign.design.design_warnings`): for a design that
        fails ``check`` the observer is not stable for every stiffness and the RMS values,
        computed at one stiffness, do not bound the estimates' noise (its variance is unbounded).
    """

    _title = "Measurement noise propagation"
    stiffness: float
    noise_rms: float
    noise_bandwidth: float
    omega_co: float
    direct_gain: float
    velocity_direct_gain: float
    rms_raw: float
    rms_filtered: float
    rms_velocity_raw: float
    friction_transfer: tuple = field(repr=False, compare=False)
    velocity_transfer: tuple = field(repr=False, compare=False)
    warnings: tuple = field(default=(), repr=False, compare=False)
    G_friction = lazy_system()
    G_velocity = lazy_system()
    lowpass = lazy_system()
    G_friction_filtered = lazy_system()

    def _system_args(self) -> tuple:
        return (self.friction_transfer, self.velocity_transfer, self.omega_co)

    def _build_systems(self) -> dict:
        return _systems(*self._system_args())

    def to_dict(self) -> dict:
        """JSON-ready values (the keys of ``obsdesign noise --json`` and more)."""
        keys = ("direct_gain", "rms_raw", "rms_filtered", "rms_velocity_raw", "velocity_direct_gain",
                "stiffness", "noise_rms", "noise_bandwidth", "omega_co")
        return {key: getattr(self, key) for key in keys}

    def _rows(self):
        return [("stiffness k [N/m]", self.stiffness), ("noise RMS [m]", self.noise_rms),
                ("noise bandwidth [Hz]", self.noise_bandwidth), ("omega_co [rad/s]", self.omega_co),
                ("direct gain to friction L2 [N/m]", self.direct_gain),
                ("friction estimate RMS, raw [N]", self.rms_raw),
                ("friction estimate RMS, filtered [N]", self.rms_filtered),
                ("velocity estimate RMS, raw [m/s]", self.rms_velocity_raw)]


def noise_analysis(cfg: Config, *, noise_rms: float | None = None,
                   noise_bandwidth: float | None = None, stiffness: float = 0.0) -> NoiseAnalysis:
    """Noise transfer, low-pass and RMS of the friction and velocity estimates.

    Parameters
    ----------
    cfg : Config
        The design (change values with :meth:`obsdesign.Config.override` before).
    noise_rms : float, optional
        Noise RMS [m]; default ``sqrt(sensor.noise_rms^2 + sensor.quantization^2 / 12)``.
    noise_bandwidth : float, optional
        Noise bandwidth [Hz]; default ``sensor.noise_bandwidth``.
    stiffness : float
        Constant stiffness k [N/m] of the analysis (default 0, gross sliding).

    Returns
    -------
    NoiseAnalysis
    """
    design = design_observer(cfg)
    sensor = cfg.sensor
    eta = (math.hypot(sensor.noise_rms, sensor.quantization / math.sqrt(12.0)) if noise_rms is None
           else _NONNEG.check("noise_rms", noise_rms))
    B = sensor.noise_bandwidth if noise_bandwidth is None else _POS.check("noise_bandwidth", noise_bandwidth)
    k = _NONNEG.check("stiffness", stiffness)
    values = design.parameter_values(k)
    friction = tuple(tuple(c.tolist()) for c in poly_coeffs(design.variant, "friction")(**values))
    velocity = tuple(tuple(c.tolist()) for c in poly_coeffs(design.variant, "velocity")(**values))
    omega_co = cfg.observer.omega_co
    args = (friction, velocity, omega_co, eta, B)
    # python-control's transfers and SciPy's integrals: computed once, kept on disk (obsdesign._memo)
    rms_raw, rms_filtered, rms_velocity_raw = memo("noise", args, lambda: _rms(*args), valid=list_of(3))
    return NoiseAnalysis(
        stiffness=k, noise_rms=eta, noise_bandwidth=B, omega_co=omega_co,
        direct_gain=design.L2, velocity_direct_gain=design.L1, rms_raw=rms_raw, rms_filtered=rms_filtered,
        rms_velocity_raw=rms_velocity_raw, friction_transfer=friction, velocity_transfer=velocity,
        warnings=design_warnings(cfg),
    )


def _systems(friction: tuple, velocity: tuple, omega_co: float) -> dict:
    import control as ct

    G_f, G_v, F = ct.tf(*friction), ct.tf(*velocity), lowpass(omega_co)
    return {"G_friction": G_f, "G_velocity": G_v, "lowpass": F, "G_friction_filtered": F * G_f}


def _rms(friction: tuple, velocity: tuple, omega_co: float, eta: float, B: float) -> list:
    """The three noise RMS values of :class:`NoiseAnalysis` (python-control transfers, SciPy quadrature)."""
    sys = _systems(friction, velocity, omega_co)
    return [band_limited_rms(sys["G_friction"], eta, B), band_limited_rms(sys["G_friction_filtered"], eta, B),
            band_limited_rms(sys["G_velocity"], eta, B)]
