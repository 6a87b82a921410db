"""The explorer's verdicts and its live step in headless Chromium, against the Python side (issue 18 item 3):
the step of the page (the generated JavaScript controller on the page's plant model) against
obsdesign's simulator on the same inputs, the dt verdicts against ``check``, the certificate against
``certify``."""

from __future__ import annotations

import os

import numpy as np
import pytest
from test_report import CHROMIUM, DRIVER, _browser

import obsdesign as od
from obsdesign.design import check_stability
from obsdesign.report.explorer import Explorer, preview_inputs
from obsdesign.sim.simulate import run

pytestmark = [pytest.mark.slow, pytest.mark.skipif(not (CHROMIUM and DRIVER) and os.environ.get("CI") != "true",
                                                   reason="headless Chromium not installed (CI installs it)")]
#: Largest difference [m] allowed between the page's step and the simulator's (1e-9 of the 1 mm step).
TOLERANCE = 1e-12


@pytest.fixture
def page(tmp_path):
    drivers = []

    def open_page(cfg):
        path = tmp_path / f"explorer-{len(drivers)}.html"
        path.write_text("<!DOCTYPE html><html><head><meta charset='utf-8'></head><body>"
                        + Explorer(cfg)._repr_html_() + "</body></html>", encoding="utf-8")
        driver = _browser()
        assert driver is not None, "Chromium, chromedriver and selenium are required in CI"
        drivers.append(driver)
        driver.get(path.as_uri())
        assert driver.get_log("browser") == []
        return driver

    yield open_page
    for d in drivers:
        d.quit()


def _values(cfg, **changes):
    v = {"m": cfg.plant.m, "sigma": cfg.friction.sigma, "kappa": cfg.friction.kappa, "rho": cfg.observer.rho,
         "beta": cfg.friction.beta}
    v.update(changes)
    return v


@pytest.mark.parametrize("preset, changes", [
    ("vcm", {}), ("vcm", {"rho": 2.5, "kappa": 3e4}), ("vcm", {"rho": 8.0, "kappa": 8e5}), ("vcm", {"m": 1.0}),
    ("table1", {}), ("table1", {"rho": 1.5, "sigma": 30.0, "beta": 0.002}),
])
def test_the_pages_step_is_the_simulators(page, preset, changes):
    """The page with the sliders at ``changes`` against ``simulate``'s kernel on the config with those values
    (the page keeps the config's PID: for a new mass the reference keeps the PID plant gain phi)."""
    cfg = od.load_preset(preset)
    driver = page(cfg)
    x_page = np.asarray(driver.execute_script("return previewStep(arguments[0]).x;", _values(cfg, **changes)))
    ref = cfg.override(**changes, phi=cfg.phi if "m" in changes else None)
    x_sim = run(preview_inputs(ref)).x
    assert x_page.shape == x_sim.shape and np.max(np.abs(x_sim)) > 5e-4  # the step happened
    assert np.max(np.abs(x_page - x_sim)) <= TOLERANCE


def test_the_dt_verdicts_and_the_certificate_are_checks(page):
    from selenium.webdriver.common.by import By

    from obsdesign.design.certificate import certify

    cfg = od.load_preset("vcm").override(dt=0.01)   # fastest pole -609.7 1/s times 0.01 s = 6.1 > 1
    with pytest.warns(UserWarning, match="faster than the sampling"):
        rep = check_stability(cfg)
    driver = page(cfg)
    failing = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#verdicts li.fail")]
    product = abs(rep.fastest_pole) * cfg.observer.dt
    (row,) = [t for t in failing if t.startswith("FAIL fastest pole x dt")]
    assert float(row.split(" = ")[-1].split(" <= ")[0]) == pytest.approx(product, rel=1e-3)   # 3 digits shown
    text = driver.find_element(By.ID, "dtverdict").text
    assert text.endswith("> 1: the observer is faster than the sampling")
    assert float(text.split(" is ")[1].split(" > ")[0]) == pytest.approx(product, rel=1e-3)
    cert = driver.find_element(By.ID, "certificate").text
    assert cert.startswith(rep.certificate.verdict) and cert.endswith("at the config's values")
    # table1 with rho 0.98: refuted in Python, and the page says so; the slider moves onto a tabulated rho
    t1 = od.load_preset("table1").override(rho=0.98)
    driver = page(t1)
    assert driver.find_element(By.ID, "verdict").text == "unstable"
    assert driver.find_element(By.ID, "certificate").text.startswith("not certified")
    slider = driver.find_element(By.ID, "s-rho")
    driver.execute_script("arguments[0].value = '2.0'; arguments[0].dispatchEvent(new Event('input'));", slider)
    text = driver.find_element(By.ID, "certificate").text
    rho = float(text.split("at the tabulated rho = ")[1].split(",")[0])
    assert text.startswith(certify(od.design_observer(t1.override(rho=rho))).verdict)
    assert "Step up: overshoot" in driver.find_element(By.ID, "stepsummary").text
    driver.find_element(By.ID, "reset").click()
    assert driver.find_element(By.ID, "certificate").text.startswith("not certified")


@pytest.mark.parametrize("mode", ["feedforward", "blend"])
def test_the_pages_step_is_the_simulators_in_the_reference_modes(page, mode):
    """A feed-forward mode's step takes the reference velocity and weight: the page feeds the simulator's own
    arrays (``LoopInputs.reference_feedforward``), so its step is still the kernel's."""
    cfg = od.load_preset("vcm").override(mode=mode, buildup=2e-4)
    driver = page(cfg)
    x_page = np.asarray(driver.execute_script("return previewStep(arguments[0]).x;", _values(cfg)))
    x_sim = run(preview_inputs(cfg)).x
    assert x_page.shape == x_sim.shape and np.max(np.abs(x_sim)) > 5e-4
    assert np.max(np.abs(x_page - x_sim)) <= TOLERANCE
