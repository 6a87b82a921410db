"""Streamed statistics of a metric: a mergeable quantile sketch and the moments.

:class:`QuantileSketch` is a log-bucket sketch (DDSketch, Masson, Rim and Lee, VLDB 2019):
a value ``x > 0`` is counted in bucket ``i = ceil(log(x) / log(gamma))`` with
``gamma = (1 + alpha) / (1 - alpha)``, negative values likewise by ``-x``, zeros apart. The
estimate of a bucket, ``2 gamma^i / (gamma + 1)``, is within the relative error ``alpha`` of
every value the bucket holds, so the ``q``-quantile it returns is within ``alpha |x|`` of the
exact ``x = numpy.quantile(values, q, method="lower")`` (the value of rank
``floor(q (n - 1))``). Its memory is the number of occupied buckets, at most
``log(max / min) / log(gamma)`` per sign (about 1,150 per decade for ``alpha = 1e-3``),
whatever the number of values; two sketches merge by adding their counts, in any order, to the
same sketch. Non-finite values are counted, not sketched.

Examples
--------
>>> import numpy as np
>>> values = np.random.default_rng(0).lognormal(size=10_000)
>>> sk = QuantileSketch(alpha=1e-3)
>>> sk.add(values)
>>> exact = np.quantile(values, 0.99, method="lower")
>>> bool(abs(sk.quantile(0.99) - exact) <= 1e-3 * exact)
True
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["QuantileSketch", "Moments"]


class QuantileSketch:
    """Quantiles of a stream of values within a relative error ``alpha`` (see the module notes).

    Parameters
    ----------
    alpha : float
        Relative accuracy, ``0 < alpha < 1`` (default 1e-3: 0.1 % of the value).
    """

    def __init__(self, alpha: float = 1e-3) -> None:
        if not 0.0 < alpha < 1.0:
            raise ValueError(f"alpha: expected 0 < alpha < 1, found {alpha!r}")
        self.alpha = float(alpha)
        self._log_gamma = math.log((1.0 + alpha) / (1.0 - alpha))
        self.positive: dict[int, int] = {}
        self.negative: dict[int, int] = {}
        self.zeros = 0
        self.count = 0  # finite values sketched
        self.nonfinite = 0
        self.min = math.inf
        self.max = -math.inf

    def _bucket(self, store: dict[int, int], x: np.ndarray) -> None:
        idx = np.ceil(np.log(x) / self._log_gamma).astype(np.int64)
        keys, counts = np.unique(idx, return_counts=True)
        for k, c in zip(keys.tolist(), counts.tolist()):
            store[k] = store.get(k, 0) + c

    def add(self, values) -> None:
        """Count ``values`` (array_like of floats; NaN and inf counted in :attr:`nonfinite`).

        Parameters
        ----------
        values : array_like
            The values.
        """
        x = np.asarray(values, dtype=float).ravel()
        finite = np.isfinite(x)
        self.nonfinite += int(x.size - np.count_nonzero(finite))
        x = x[finite]
        if not x.size:
            return
        self.count += int(x.size)
        self.min = min(self.min, float(x.min()))
        self.max = max(self.max, float(x.max()))
        self.zeros += int(np.count_nonzero(x == 0.0))
        self._bucket(self.positive, x[x > 0.0])
        self._bucket(self.negative, -x[x < 0.0])

    def merge(self, other: "QuantileSketch") -> None:
        """Add the counts of ``other`` (same ``alpha``).

        Parameters
        ----------
        other : QuantileSketch
            Another sketch.
        """
        if other.alpha != self.alpha:
            raise ValueError(f"other: expected a sketch of alpha {self.alpha:g}, found {other.alpha:g}")
        for mine, theirs in ((self.positive, other.positive), (self.negative, other.negative)):
            for k, c in theirs.items():
                mine[k] = mine.get(k, 0) + c
        self.zeros += other.zeros
        self.count += other.count
        self.nonfinite += other.nonfinite
        self.min = min(self.min, other.min)
        self.max = max(self.max, other.max)

    def quantile(self, q: float) -> float:
        """The ``q``-quantile (``0 <= q <= 1``) of the finite values; NaN when there are none.

        Parameters
        ----------
        q : float
            The probability.
        """
        if not 0.0 <= q <= 1.0:
            raise ValueError(f"q: expected 0 <= q <= 1, found {q!r}")
        if not self.count:
            return math.nan
        rank = math.floor(q * (self.count - 1))
        if rank == 0:
            return self.min  # the extremes are kept exactly
        if rank == self.count - 1:
            return self.max
        gamma = math.exp(self._log_gamma)
        seen = 0
        for k in sorted(self.negative, reverse=True):  # most negative first
            seen += self.negative[k]
            if seen > rank:
                return self._clamp(-2.0 * gamma ** k / (gamma + 1.0))
        seen += self.zeros
        if seen > rank:
            return 0.0
        for k in sorted(self.positive):
            seen += self.positive[k]
            if seen > rank:
                return self._clamp(2.0 * gamma ** k / (gamma + 1.0))
        return self.max  # not reached: the counts add up to count

    def _clamp(self, value: float) -> float:
        return min(max(value, self.min), self.max)

    @property
    def buckets(self) -> int:
        """Occupied buckets (the sketch's memory, in counters)."""
        return len(self.positive) + len(self.negative) + (1 if self.zeros else 0)


class Moments:
    """Count, mean and variance of a stream of finite values, merged batch by batch (Chan et al.).

    Examples
    --------
    >>> m = Moments()
    >>> m.add([1.0, 2.0]); m.add([3.0, 4.0, 5.0])
    >>> m.count, m.mean, round(m.std, 6)
    (5, 3.0, 1.581139)
    """

    def __init__(self) -> None:
        self.count = 0
        self.mean = 0.0
        self._m2 = 0.0

    def add(self, values) -> None:
        """Add the finite ones of ``values``.

        Parameters
        ----------
        values : array_like
            The values.
        """
        x = np.asarray(values, dtype=float).ravel()
        x = x[np.isfinite(x)]
        if not x.size:
            return
        n_b, mean_b = x.size, float(x.mean())
        m2_b = float(np.sum((x - mean_b) ** 2))
        n = self.count + n_b
        delta = mean_b - self.mean
        self.mean += delta * n_b / n
        self._m2 += m2_b + delta * delta * self.count * n_b / n
        self.count = n

    @property
    def std(self) -> float:
        """Sample standard deviation (``ddof=1``; NaN below two values)."""
        return math.sqrt(self._m2 / (self.count - 1)) if self.count > 1 else math.nan
