"""The sampled loop that runs: config field ``pid.delay_samples``, the discrete PID ``C(z)`` against the
kernel's recursion, margins against an independent python-control computation, the simulator's step."""

from __future__ import annotations

import pytest

import obsdesign as od


# --------------------------------------------------------------------------------------------
# pid.delay_samples: the config field
def test_delay_samples_defaults_to_zero_and_round_trips():
    cfg = od.load_preset("vcm")
    assert cfg.pid.delay_samples == 0
    for d in (0, 1, 3):
        c = cfg.override(delay_samples=d)
        back = od.Config.from_toml(c.to_toml())
        assert back == c and back.pid.delay_samples == d and type(back.pid.delay_samples) is int
    assert "delay_samples = 0  # [samples] computation delay" in cfg.to_toml()


@pytest.mark.parametrize("bad", [-1, 1.5, 2.0, "1", True, None])
def test_delay_samples_rejects_what_is_not_a_nonnegative_integer(bad):
    cfg = od.load_preset("vcm")
    with pytest.raises(ValueError, match=r"^pid\.delay_samples: expected an integer >= 0, found "):
        od.PIDSpec(max_S=1e-3, phase_margin_deg=60.0, tau=0.01, delay_samples=bad)
    text = cfg.to_toml().replace("delay_samples = 0", f"delay_samples = {bad!r}".replace("'", '"')
                                 .replace("True", "true").replace("None", '"none"'))
    with pytest.raises(ValueError, match=r"pid\.delay_samples: expected an integer >= 0, found "):
        od.Config.from_toml(text)


def test_config_command_prints_delay_samples_with_its_comment():
    from obsdesign.cli._config import config_toml

    text = config_toml(od.load_preset("vcm").override(delay_samples=2))
    line = next(x for x in text.splitlines() if x.startswith("delay_samples"))
    assert line.startswith("delay_samples = 2  # [samples] computation delay")
    assert od.Config.from_toml(text).pid.delay_samples == 2
