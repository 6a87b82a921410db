"""A tqdm progress bar, or an object that does nothing when there is no bar to show.

tqdm starts its monitor thread with the first bar, even a disabled one, and the thread lives as
long as the process: a process with it may no longer fork its workers
(:func:`obsdesign.sweeps.pool.can_fork`). So no tqdm object is made unless a bar is shown.

Examples
--------
>>> import threading
>>> before = threading.active_count()
>>> bar = progress_bar(False, total=3)
>>> bar.update(); bar.set_postfix_str("step"); bar.close()
>>> threading.active_count() == before   # no monitor thread started
True
"""

from __future__ import annotations

__all__ = ["progress_bar", "NoBar"]


class NoBar:
    """The progress bar when none is shown: every call does nothing."""

    def update(self, n: int = 1) -> None:
        """Nothing."""

    def set_postfix_str(self, text: str) -> None:
        """Nothing."""

    def close(self) -> None:
        """Nothing."""


def progress_bar(enabled: bool, **options):
    """``tqdm(**options)`` if ``enabled``, else a :class:`NoBar`.

    Parameters
    ----------
    enabled : bool
        Show the bar.
    **options
        Arguments of ``tqdm.tqdm``.
    """
    if not enabled:
        return NoBar()
    from tqdm import tqdm

    return tqdm(**options)
