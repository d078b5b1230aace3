"""The batch's progress: a line per mesh on stdout, a bar on stderr (on a terminal)."""
import sys
import time


class Progress:
    """Per-mesh lines on stdout and, when stderr is a terminal, a progress bar below them.

    The bar shows files done of the total, how many meshes were certified and failed, and the
    time left, estimated from the input bytes still to do at the rate of those done.

    Parameters
    ----------
    total : int, files to run
    weight : float, total input bytes of those files (for the estimate)
    """

    def __init__(self, total, weight=None, out=None, err=None, bar=None):
        self.total, self.done = total, 0
        self.weight, self.weight_done = weight, 0.0
        self.certified = self.failed = 0
        self.out, self.err = out or sys.stdout, err or sys.stderr
        self.bar = self.err.isatty() if bar is None else bar
        self.t0 = time.perf_counter()
        self._draw()

    def advance(self, lines, statuses=(), weight=0.0):
        """One file finished: print its ``lines``; ``statuses`` of its meshes; its bytes."""
        self.done += 1
        self.weight_done += weight
        self.certified += sum(s == "certified" for s in statuses)
        self.failed += sum(s != "certified" for s in statuses)
        self._clear()
        width = len(str(self.total))
        for line in lines.splitlines():
            print(f"[{self.done:>{width}}/{self.total}] {line}", file=self.out, flush=True)
        self._draw()

    def close(self):
        self._clear()

    def eta(self):
        """Seconds left (None before the first file)."""
        elapsed = time.perf_counter() - self.t0
        if self.weight:
            if self.weight_done <= 0:
                return None
            return elapsed * (self.weight - self.weight_done) / self.weight_done
        return elapsed * (self.total - self.done) / self.done if self.done else None

    def _clear(self):
        if self.bar:
            self.err.write("\r\033[K")
            self.err.flush()

    def _draw(self):
        if self.bar:
            n = int(30 * self.done / max(self.total, 1))
            eta = self.eta()
            left = "--" if eta is None else _clock(eta)
            self.err.write(f"[{'#' * n}{'.' * (30 - n)}] {self.done}/{self.total} files, "
                           f"{self.certified} certified, {self.failed} failed, "
                           f"{_clock(time.perf_counter() - self.t0)} elapsed, {left} left")
            self.err.flush()


def _clock(seconds):
    s = int(round(seconds))
    if s >= 3600:
        return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"
    return f"{s // 60}:{s % 60:02d}"
