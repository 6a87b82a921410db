"""Choice lists of the identification (one place; the CLI reads them without importing NumPy).

>>> STRIBECK_CHOICES, INPUT_TIMINGS
(('auto', 'on', 'off'), ('auto', 'sample', 'hold'))
"""

__all__ = ["STRIBECK_CHOICES", "INPUT_TIMINGS", "MAX_DELAY", "MAX_GIVEN_DELAY"]

#: ``stribeck`` of :func:`obsdesign.data.identify`: kept by the model selection, always, never.
STRIBECK_CHOICES = ("auto", "on", "off")
#: ``input_timing`` of :func:`obsdesign.data.identify`: found from the data (:mod:`obsdesign.data.timing`),
#: the input as logged, or held until the next sample.
INPUT_TIMINGS = ("auto", "sample", "hold")
#: The largest position delay [samples] :mod:`obsdesign.data.timing` tries when none is given.
MAX_DELAY = 3
#: The largest delay [samples] a caller may give (``delay_samples``, ``--delay-samples``).
MAX_GIVEN_DELAY = 50
