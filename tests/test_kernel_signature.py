"""One compiled signature of the simulator's kernel for every scenario (issue 37: a first report compiled
``run_loop`` three times, once per combination of read-only and writable input signals)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numba import typeof

import obsdesign as od
from obsdesign.sim import prepare


def _signals_type(loop):
    return typeof(loop.kernel_args()[4])


@pytest.mark.parametrize("scenario", ["positioning", "tracking", "excitation", "constant"])
def test_every_scenario_gives_the_kernel_one_signals_type(scenario):
    cfg = od.load_preset("vcm")
    reference = _signals_type(prepare(cfg, "positioning", duration=4.0))
    loop = prepare(cfg, scenario, duration=4.0)
    assert _signals_type(loop) == reference
    # a writable reference of the caller's own (the circle test's) too, and without a copy
    ref = np.linspace(0.0, 1e-3, loop.n_samples)
    edited = dataclasses.replace(loop, x_ref=ref)
    assert _signals_type(edited) == reference
    sig = edited.kernel_args()[4]
    assert np.shares_memory(sig.x_ref, ref) and ref.flags.writeable and not sig.x_ref.flags.writeable
