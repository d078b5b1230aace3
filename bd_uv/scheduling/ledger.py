"""The batch report on disk while a batch runs, and what ``--resume`` may skip.

Every finished file is appended at once to a journal next to the report (``REPORT.journal``: one
JSON line per file, its report entries), and the JSON report itself is rewritten (atomically) at
most every few seconds and at the end, when the journal is removed. A crash or a kill keeps every
line written before it; a line cut short by the kill is ignored when read back.

Each entry carries what ``--resume`` checks: ``input_sha256`` (the input's bytes as the worker read
them), ``options_sha256`` (solver options and seams mode) and ``output_sha256`` (the output as
written). A file is skipped on resume only when all its entries are certified, the input and the
options hash the same, and its output (and picture, when asked for) is still there with the same
hash; everything else is run again.
"""
import hashlib
import json
import os
import time

from .atomic import atomic_path, file_sha256


def options_sha256(options, seams_mode):
    """Hex SHA-256 of the options (a dict, or an object with ``as_dict()``: the batch's
    JobOptions) and seams mode (canonical JSON)."""
    if hasattr(options, "as_dict"):
        options = options.as_dict()
    text = json.dumps({"options": options, "seams": seams_mode}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def read_previous(report_path):
    """Entries of an earlier run, ``{absolute input path: [entry, ...]}``: the report's items,
    then the journal's lines (later lines win; a truncated last line is ignored)."""
    previous = {}
    try:
        with open(report_path, encoding="utf-8") as fh:
            items = json.load(fh).get("items", [])
    except (OSError, ValueError):
        items = []
    grouped = {}
    for e in items:
        if e.get("input"):
            grouped.setdefault(e["input"], []).append(e)
    previous.update(grouped)
    try:
        with open(journal_path(report_path), encoding="utf-8") as fh:
            for line in fh:
                try:
                    rec = json.loads(line)
                except ValueError:
                    continue
                previous[rec["input"]] = rec["entries"]
    except OSError:
        pass
    return previous


def journal_path(report_path):
    return report_path + ".journal"


def reusable(task, entries, options_hash):
    """True when ``entries`` (an earlier run's, for ``task``) certify its current output."""
    if not entries or any(e.get("status") != "certified" for e in entries):
        return False
    output = os.path.abspath(task.output)
    if any(e.get("options_sha256") != options_hash or e.get("output") != output
           for e in entries):
        return False
    if task.png and not all(e.get("png") and os.path.isfile(e["png"]) for e in entries):
        return False
    if len({e.get("input_sha256") for e in entries}) != 1:
        return False
    if entries[0].get("input_sha256") != file_sha256(task.path):
        return False
    return entries[0].get("output_sha256") == file_sha256(output) is not None


class Ledger:
    """The report file and its journal for one batch run.

    Parameters
    ----------
    report_path : str
    build : callable() -> dict, the full report from what is finished so far
    every : float, seconds between rewrites of the report while the batch runs; at least 20
        times the last rewrite's duration, so a report of many thousand files costs at most 5 %
        of the driver's time
    """

    def __init__(self, report_path, build, every=2.0):
        self.path, self.build, self.every = report_path, build, every
        self.journal = journal_path(report_path)
        self.last, self.cost = time.monotonic(), 0.0
        os.makedirs(os.path.dirname(os.path.abspath(report_path)), exist_ok=True)

    def start(self, carried):
        """Begin a fresh journal holding ``carried`` (``[(input, entries)]`` kept by --resume)."""
        with atomic_path(self.journal) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            for path, entries in carried:
                fh.write(json.dumps({"input": path, "entries": entries}) + "\n")
        self._fh = open(self.journal, "a", encoding="utf-8")

    def record(self, path, entries):
        """A file finished: append it to the journal now, and rewrite the report if it is due."""
        self._fh.write(json.dumps({"input": path, "entries": entries}) + "\n")
        self._fh.flush()
        if time.monotonic() - self.last >= max(self.every, 20 * self.cost):
            self.write(self.build())

    def write(self, report):
        """Replace the report file with ``report``, atomically."""
        t0 = time.monotonic()
        with atomic_path(self.path) as tmp, open(tmp, "w", encoding="utf-8") as fh:
            json.dump(report, fh, indent=2)
        self.last = time.monotonic()
        self.cost = self.last - t0

    def finish(self, report):
        """Write the final report; the journal is no longer needed."""
        self.write(report)
        self._fh.close()
        os.remove(self.journal)
