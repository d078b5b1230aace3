"""The wait shown on a terminal (``bd_uv.progress.TerminalProgress``): the core's one progress
callback drawn on stderr when it is a terminal, nothing otherwise or with ``--quiet``."""
import io
import os
import subprocess
import sys

import numpy as np
import pytest

import bd_uv
from bd_uv.progress import TerminalProgress
from helpers import DATA

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def _two_grids():
    n = 6
    g = np.linspace(0.0, 1.0, n)
    x, y = np.meshgrid(g, g)
    V0 = np.c_[x.ravel(), y.ravel(), 0.2 * np.sin(3 * x.ravel())]
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    a = (j * n + i).ravel()
    F0 = np.r_[np.c_[a, a + 1, a + n + 1], np.c_[a, a + n + 1, a + n]]
    V = np.r_[V0, V0 + [2.0, 0, 0]]
    F = np.r_[F0, F0 + len(V0)].astype(np.int64)
    return V, F


def test_a_terminal_sees_stage_islands_done_and_the_end():
    V, F = _two_grids()
    seen = []
    term = FakeTerminal()
    with TerminalProgress(stream=term, min_interval=0.0) as bar:
        def progress(fraction, message):
            seen.append((fraction, message))
            bar(fraction, message)
        bd_uv.unwrap(V, F, bound=1.5, progress=progress)
        assert bar.fraction == 1.0
        bar.stage("storing")
    text = term.getvalue()
    # the core's messages name the island of the total (a bound of 1.5 makes both solve alone)
    assert any(m.startswith("island 2/2") for _, m in seen)
    assert "island 1/2" in text and "storing" in text and "100%" in text
    assert seen[-1] == (1.0, "done")


def test_the_bar_never_runs_backwards():
    term = FakeTerminal()
    bar = TerminalProgress(stream=term, min_interval=0.0)
    bar(0.5, "a")
    bar(0.2, "b")
    assert bar.fraction == 0.5 and bar.message == "b"
    bar(2.0, "c")
    assert bar.fraction == 1.0
    bar.close()


@pytest.mark.parametrize("stream, quiet", [(io.StringIO(), False), (FakeTerminal(), True)])
def test_quiet_off_a_terminal_or_when_asked(stream, quiet):
    with TerminalProgress(stream=stream, quiet=quiet) as bar:
        bar(0.5, "island 1/2: conformal initial map")
        bar.stage("storing")
    assert not bar.enabled and stream.getvalue() == ""


def _unwrap_on_a_terminal(tmp_path, *extra):
    """``python -m bd_uv unwrap`` with stderr on a pseudo-terminal; returns what it drew there."""
    import pty

    master, slave = pty.openpty()
    try:
        r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap",
                            os.path.join(DATA, "nefertiti.off"), "-o", str(tmp_path / "n.obj"),
                            "--bound", "1.3", *extra], stdout=subprocess.PIPE,
                           stderr=slave, cwd=REPO, text=True)
        os.close(slave)
        slave = None
        chunks = []
        while True:
            try:
                b = os.read(master, 65536)
            except OSError:  # the terminal closed: everything was read
                break
            if not b:
                break
            chunks.append(b)
    finally:
        if slave is not None:
            os.close(slave)
        os.close(master)
    return r, b"".join(chunks).decode("utf-8", "replace")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pseudo-terminals: Linux")
def test_the_command_draws_progress_on_a_terminal_and_not_with_quiet(tmp_path):
    r, drawn = _unwrap_on_a_terminal(tmp_path)
    assert r.returncode == 0 and "certified C = 1.3" in r.stdout
    # the bar, its end and the storing stage (a stage is drawn at once); the islands' texts are
    # redrawn at most every 0.1 s (tqdm's mininterval), so a quick run on an idle machine can go
    # from 0 % to done between two draws (CI did: "0%| ... 100%| done ... storing"); that the
    # core's island texts reach the bar is checked with no interval above
    assert "%|" in drawn and "100%" in drawn and "storing" in drawn
    r, drawn = _unwrap_on_a_terminal(tmp_path, "--quiet")
    assert r.returncode == 0 and "certified C = 1.3" in r.stdout
    assert drawn == ""


def test_the_command_is_silent_on_stderr_off_a_terminal(tmp_path):
    r = subprocess.run([sys.executable, "-m", "bd_uv", "unwrap",
                        os.path.join(DATA, "nefertiti.off"), "-o", str(tmp_path / "n.obj")],
                       capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 0 and r.stderr == ""
