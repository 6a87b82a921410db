"""Choice lists of the identification (one place; the CLI reads them without importing NumPy).

>>> STRIBECK_CHOICES, INPUT_TIMINGS
(('auto', 'on', 'off'), ('sample', 'hold'))
"""

__all__ = ["STRIBECK_CHOICES", "INPUT_TIMINGS"]

#: ``stribeck`` of :func:`obsdesign.data.identify`: kept by the model selection, always, never.
STRIBECK_CHOICES = ("auto", "on", "off")
#: ``input_timing`` of :func:`obsdesign.data.identify`: the input as logged, or held until the next sample.
INPUT_TIMINGS = ("sample", "hold")
