import math

import pytest

import obsdesign as od
from obsdesign.params import Config


def test_presets_hold_the_paper_values():
    t1 = od.load_preset("table1")
    # Table 1 of the paper.
    assert (t1.plant.K, t1.plant.m, t1.friction.sigma, t1.friction.Cf, t1.friction.s) == (3.28, 0.538, 21.1, 0.35, 3000.0)
    assert (t1.friction.beta, t1.friction.kappa) == (0.001, 8000.0)
    assert t1.observer.omega_co == pytest.approx(2 * math.pi * 40)
    assert t1.observer.variant == "lag" and t1.observer.dt == 1e-4
    vcm = od.load_preset("vcm")
    assert (vcm.plant.K, vcm.plant.m, vcm.plant.G) == (3.28, 0.538, 5.27)
    assert vcm.observer.rho == 4.0 and vcm.observer.variant == "static" and vcm.friction.beta is None
    assert vcm.pid.max_S == 1 / 400 and vcm.pid.phase_margin == pytest.approx(math.pi / 3)
    assert vcm.pid.phi is None and vcm.phi == pytest.approx(vcm.plant.K * vcm.pid.tau / vcm.plant.m)
    assert vcm.sensor.quantization == 1e-6


@pytest.mark.parametrize("name", od.preset_names())
def test_toml_round_trip_gives_an_equal_object(name, tmp_path):
    cfg = od.load_preset(name)
    assert Config.from_toml(cfg.to_toml()) == cfg
    path = tmp_path / "c.toml"
    cfg.save(path)
    assert od.load_config(path) == cfg
    assert [p.name for p in tmp_path.iterdir()] == ["c.toml"]  # no temporary left behind


def test_round_trip_of_a_modified_config_is_exact():
    import dataclasses

    cfg = od.load_preset("table1")
    odd = dataclasses.replace(cfg, observer=dataclasses.replace(cfg.observer, rho=1 / 3, dt=1 / 7e3), name='a "quoted" <name>')
    assert Config.from_toml(odd.to_toml()) == odd


PLANT = dict(m=0.5, K=3.0)


@pytest.mark.parametrize(
    "cls, kwargs, exc, match",
    [
        (od.PlantParams, dict(PLANT, m=0.0), ValueError, r"plant\.m: expected a finite number > 0, found 0\.0"),
        (od.PlantParams, dict(PLANT, m=-1), ValueError, r"plant\.m: .*> 0, found -1\.0"),
        (od.PlantParams, dict(PLANT, m=float("nan")), ValueError, r"plant\.m: .*found nan"),
        (od.PlantParams, dict(PLANT, K="3"), TypeError, r"plant\.K: expected a finite number > 0, found str '3'"),
        (od.PlantParams, dict(PLANT, K=True), TypeError, r"plant\.K: .*found bool"),
        (od.PlantParams, dict(PLANT, G=float("inf")), ValueError, r"plant\.G: expected a finite number, found inf"),
        (od.ObserverSpec, dict(rho=0.0), ValueError, r"observer\.rho: expected a finite number > 0, found 0\.0"),
        (od.ObserverSpec, dict(rho=-2.0), ValueError, r"observer\.rho"),
        (od.ObserverSpec, dict(rho=2.0, variant="dyn"), ValueError, r"observer\.variant: expected one of 'lag', 'static', found 'dyn'"),
        (od.ObserverSpec, dict(rho=2.0, dt=0), ValueError, r"observer\.dt: .*> 0, found 0\.0"),
        (od.FrictionParams, dict(Cf=0.3, sigma=1, s=1, kappa=1, beta=0.0), ValueError, r"friction\.beta: .*> 0 \(or omitted\), found 0\.0"),
        (od.FrictionParams, dict(Cf=0.3, sigma=1, s=1, kappa=-5), ValueError, r"friction\.kappa: .*> 0, found -5\.0"),
        (od.PIDSpec, dict(max_S=0.01, phase_margin_deg=90.0, tau=0.01), ValueError, r"pid\.phase_margin_deg: expected a finite number > 0 and < 90, found 90\.0"),
        (od.PIDSpec, dict(max_S=0.01, phase_margin_deg=0.0, tau=0.01), ValueError, r"pid\.phase_margin_deg"),
        (od.SensorSpec, dict(noise_rms=-1e-6), ValueError, r"sensor\.noise_rms: expected a finite number >= 0, found -1e-06"),
    ],
)
def test_bad_values_name_field_range_and_value(cls, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        cls(**kwargs)


def test_parameters_are_frozen_and_keyword_only():
    p = od.PlantParams(m=1.0, K=1.0)
    with pytest.raises(AttributeError):
        p.m = 2.0
    with pytest.raises(TypeError):
        od.PlantParams(1.0, 1.0)


def _toml_with(section, line):
    text = od.load_preset("vcm").to_toml()
    return text.replace(f"[{section}]\n", f"[{section}]\n{line}\n", 1)


@pytest.mark.parametrize(
    "text, exc, match",
    [
        (_toml_with("plant", "mass = 1.0"), ValueError, r"plant\.mass: unknown key; expected one of G, K, m, u_max"),
        ('bogus = 1\n' + od.load_preset("vcm").to_toml(), ValueError, r"unknown key 'bogus'"),
        (od.load_preset("vcm").to_toml().replace("rho = 4.0", 'rho = "4"'), TypeError, r"observer\.rho: .*found str '4'"),
        (od.load_preset("vcm").to_toml().replace("rho = 4.0", "rho = nan"), ValueError, r"observer\.rho: .*found nan"),
        (od.load_preset("vcm").to_toml().replace("rho = 4.0", 'rho = "__import__(\'os\')"'), TypeError, r"observer\.rho"),
        (od.load_preset("vcm").to_toml().replace("m = 0.538", "m = -0.538"), ValueError, r"plant\.m: .*found -0\.538"),
        ("[plant\n", ValueError, r"not valid TOML"),
        (od.load_preset("vcm").to_toml().replace("tau = 0.006675", ""), ValueError, r"pid\.tau: required key is missing"),
        (od.load_preset("table1").to_toml().replace("beta = 0.001", ""), ValueError, r"friction\.beta: .*variant 'lag', found None"),
    ],
)
def test_bad_toml(text, exc, match):
    with pytest.raises(exc, match=match):
        Config.from_toml(text)


@pytest.mark.parametrize("name, exc, match", [("vcm2", ValueError, r"preset: expected one of table1, vcm, found 'vcm2'"), (3, TypeError, r"preset: expected a string")])
def test_unknown_preset(name, exc, match):
    with pytest.raises(exc, match=match):
        od.load_preset(name)


def test_missing_config_file(tmp_path):
    with pytest.raises(ValueError, match=r"config: expected an existing TOML file, found '.*nope\.toml'"):
        od.load_config(tmp_path / "nope.toml")


def test_explicit_phi_is_kept():
    cfg = od.load_preset("vcm")
    text = cfg.to_toml().replace("tau = 0.006675", "tau = 0.006675\nphi = 0.05")
    assert Config.from_toml(text).phi == 0.05
    assert Config.from_toml(text) != cfg


def test_override_validates_and_recomputes_derived_phi():
    cfg = od.load_preset("vcm")
    assert cfg.override(tau=0.01).phi == pytest.approx(3.28 * 0.01 / 0.538)
    with pytest.raises(ValueError, match=r"observer\.rho: expected a finite number > 0, found -1\.0"):
        cfg.override(rho=-1.0)
    with pytest.raises(ValueError, match=r"friction\.beta: .*variant 'lag', found None"):
        cfg.override(variant="lag")
