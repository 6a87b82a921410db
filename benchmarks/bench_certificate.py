"""Benchmark: the stability certificate of the switched sampled observer (issue 18).

* ``certify(design)`` warm, best of 5, for table1 and vcm (continuous CQLF) and for the paper's
  rho = 0.98 (refuted by a held stiffness);
* reference, same run: ``check_stability(cfg)`` without the certificate's share, i.e. the whole
  check (which includes one certificate), so the ratio says what the certificate adds.

Target (issue 18): one certificate under 1 s.
"""

from __future__ import annotations

from _timing import best_of

import obsdesign as od
from obsdesign.design.certificate import certify


def _best(fn) -> float:
    return best_of(fn, 5)


def run() -> list[dict]:
    import warnings

    rows = []
    for name, cfg in (("table1", od.load_preset("table1")), ("vcm", od.load_preset("vcm")),
                      ("table1 rho 0.98", od.load_preset("table1").override(rho=0.98))):
        d = od.design_observer(cfg)
        certify(d)  # warm-up: imports, the JIT cache of the discretization
        t = _best(lambda: certify(d))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t_check = _best(lambda: od.check_stability(cfg))
        rows.append({"benchmark": f"certify, {name} ({certify(d).verdict})", "value": f"{t * 1e3:.1f} ms",
                     "reference": f"whole check_stability: {t_check * 1e3:.1f} ms", "ratio": f"{t / t_check:.2f}",
                     "target": "< 1 s", "ok": t < 1.0})
    return rows


if __name__ == "__main__":
    for row in run():
        print(row)
