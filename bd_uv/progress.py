"""The wait shown on a terminal: one progress callback drawn as a tqdm bar on stderr.

Every long call of the core reports through the same callback, ``progress(fraction, message)``
(``fraction`` in [0, 1] of the whole call, ``message`` the stage and the islands or charts done of
their total, e.g. "island 3/12: conformal initial map", "seams: round 2, 5120/20000 faces in
charts"). The Blender operator draws it in the status bar (``operators/worker.py``), the batch
passes it per file, and the command line draws it here: a bar with the stage, the percentage and the
elapsed time, on a terminal only.
"""
import io
import os
import sys
import time


class TerminalProgress:
    """``progress(fraction, message)`` drawn as a one-line tqdm bar on ``stream``.

    Quiet (draws nothing, imports nothing) when ``stream`` is not a terminal or ``quiet`` is True,
    so a script, a pipe or a CI log sees no control characters. The bar shows the latest stage, the
    percentage done and the elapsed seconds; ``stage(message)`` names a step that reports no
    fraction of its own (storing the UVs after the unwrap). Use it as a context manager, or call
    ``close()``, to end the line.

    Parameters
    ----------
    stream : text stream, default ``sys.stderr``
    quiet : bool, draw nothing
    enabled : bool or None, force drawing on or off (None: ``stream.isatty()`` and not quiet)
    min_interval : float, seconds between redraws (tqdm's ``mininterval``)
    """

    def __init__(self, stream=None, quiet=False, enabled=None, min_interval=0.1):
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, "isatty", None)
        tty = bool(isatty()) if callable(isatty) else False
        self.enabled = (tty and not quiet) if enabled is None else bool(enabled)
        self.t0 = time.perf_counter()
        self.fraction = 0.0
        self.message = ""
        self._bar = None
        if self.enabled:
            from tqdm import tqdm

            cols, rows = _terminal_size(self.stream)
            self._bar = tqdm(total=1000, file=self.stream, mininterval=min_interval, leave=False,
                             ncols=cols, nrows=rows,
                             bar_format="{percentage:3.0f}%|{bar:20}| {desc} [{elapsed}]")

    def __call__(self, fraction, message):
        """One report of the core: ``fraction`` (clipped to [0, 1]) of the whole call done."""
        fraction = min(1.0, max(self.fraction, float(fraction)))  # a bar never runs backwards
        self.fraction, self.message = fraction, str(message)
        if self._bar is not None:
            self._bar.set_description_str(self.message, refresh=False)
            self._bar.update(int(round(1000 * fraction)) - self._bar.n)

    def stage(self, message):
        """A step with no fraction of its own: the bar keeps its length, the text changes."""
        self(self.fraction, message)
        if self._bar is not None:
            self._bar.refresh()

    def elapsed(self):
        """Seconds since the bar was made."""
        return time.perf_counter() - self.t0

    def close(self):
        """End the bar and clear its line (nothing is left behind on the terminal)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def _terminal_size(stream):
    """(columns, rows) of the terminal ``stream`` writes to; 80 x 24 where it reports none (a new
    pseudo-terminal reports 0 x 0, and tqdm draws nothing on a screen of no rows)."""
    try:
        cols, rows = os.get_terminal_size(stream.fileno())
    except (AttributeError, OSError, ValueError, io.UnsupportedOperation):
        cols, rows = 0, 0
    return (cols if cols > 0 else 80), (rows if rows > 0 else 24)
