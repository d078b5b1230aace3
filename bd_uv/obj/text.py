"""An OBJ file's text and its records, as the reader and the patch writer both walk them.

The two walk the same records in the same order (a line ending in a backslash goes on on the
next), so the k-th face the reader fan-triangulates is the k-th face the writer rewrites.
"""
import re

COMMENT = re.compile(r"\s#.*")   # an OBJ comment after a record (a '#' inside a name stays)

_UTF16 = {b"\xff\xfe": "utf-16-le", b"\xfe\xff": "utf-16-be"}


def obj_text(raw, errors="replace"):
    """(text, encoding) of an OBJ file's bytes ``raw``: UTF-8 (a byte order mark dropped from
    the text; bytes that are not UTF-8 decoded by ``errors``), or UTF-16 after its mark.
    ``encoding`` is (codec, mark): ``obj_bytes(text, encoding)`` gives the bytes back, the same
    bytes for ``errors="surrogateescape"``."""
    mark = raw[:2]
    if mark in _UTF16:
        codec = _UTF16[mark]
        try:
            return raw[2:].decode(codec, errors="surrogatepass"), (codec, mark)
        except UnicodeDecodeError:   # an odd byte count: what is read is read
            return raw[2:].decode(codec, errors="replace"), (codec, mark)
    mark = b"\xef\xbb\xbf" if raw.startswith(b"\xef\xbb\xbf") else b""
    return raw[len(mark):].decode("utf-8", errors=errors), ("utf-8", mark)


def obj_bytes(text, encoding):
    """The bytes of ``text`` in ``encoding`` (from :func:`obj_text`), its byte order mark first."""
    codec, mark = encoding
    errors = "surrogateescape" if codec == "utf-8" else "surrogatepass"
    return mark + text.encode(codec, errors=errors)


def obj_records(text):
    """(line number, record, source) of each record of an OBJ's text: a line ending in a
    backslash goes on on the next line (the OBJ format's continuation, as Rhino writes long
    faces); the number is the record's first line, ``record`` its text without line ends and
    ``source`` its lines as the file has them, line ends included."""
    pending, start, lines = None, 0, []
    for number, raw in enumerate(text.splitlines(keepends=True), 1):
        line = raw.splitlines()[0]
        lines.append(raw)
        if pending is not None:
            line, number = pending + " " + line, start
        body = line.rstrip()
        if body.endswith("\\"):
            pending, start = body[:-1], number
            continue
        pending = None
        yield number, line, "".join(lines)
        lines = []
    if pending is not None:
        yield start, pending, "".join(lines)
