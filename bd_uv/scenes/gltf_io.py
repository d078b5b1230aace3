"""glTF 2.0 containers and accessors: the JSON document and its buffers as numpy arrays.

The document is kept as the plain JSON it was read as (``dict``), so everything the unwrap does
not touch (extensions, extras, animations, unknown properties, ``asset.generator``) is written back
exactly as read. ``pygltflib`` was checked for this and not used: its dataclasses drop properties
they do not know, add defaults (``"mode": 4``) and rewrite ``asset.generator``.

A ``.glb`` is a 12-byte header, a JSON chunk and an optional BIN chunk (glTF 2.0, section 4.4);
a ``.gltf`` names its buffers by URI (relative files or ``data:`` URIs).
"""
import base64
import json
import os
import struct
from urllib.parse import quote, unquote

import numpy as np

from ..errors import SceneFileError
from .gltf_check import check_document, check_view

GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942
COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32,
             5126: np.float32}
COMPONENT_TYPE = {np.dtype(v).str: k for k, v in COMPONENT.items()}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
ZERO_FILL_FLOOR = 1 << 16  # elements a data-less accessor may always have (see zero_fill_limit)
MESHOPT = {"EXT_meshopt_compression", "KHR_meshopt_compression"}


class GltfFile:
    """A glTF document and its buffers' bytes.

    Attributes
    ----------
    path : str, the file read
    doc : dict, the JSON document
    buffers : list of bytes, one per ``doc["buffers"]`` entry
    glb : bool, read from a ``.glb``
    """

    def __init__(self, path, doc, buffers, glb):
        self.path, self.doc, self.buffers, self.glb = path, doc, buffers, glb

    def accessor(self, index, where):
        """Accessor ``index`` as a (count, width) array of its component type (raw values,
        not normalised); sparse accessors applied. ``where`` names the user of the accessor
        in error messages."""
        try:
            acc = self.doc["accessors"][index]
            dt = np.dtype(COMPONENT[acc["componentType"]]).newbyteorder("<")
            width, count = WIDTH[acc["type"]], int(acc["count"])
            if "bufferView" not in acc and count > self.zero_fill_limit():
                # zeros (with the sparse values put in): numpy's lazily zeroed pages would be
                # written in full later, so a count the file cannot mean fills the memory
                raise ValueError(f"it has no bufferView and {count} elements, more than the "
                                 f"file's {self.zero_fill_limit()} bytes of buffers can describe")
            out = np.zeros((count, width), dtype=dt)
            if "bufferView" in acc:
                out[:] = self._view(acc["bufferView"], acc.get("byteOffset", 0), count, width, dt)
            sparse = acc.get("sparse")
            if sparse:
                n = int(sparse["count"])
                idx = sparse["indices"]
                ids = self._view(idx["bufferView"], idx.get("byteOffset", 0), n, 1,
                                 np.dtype(COMPONENT[idx["componentType"]]).newbyteorder("<"))
                val = sparse["values"]
                out[ids[:, 0].astype(np.int64)] = self._view(
                    val["bufferView"], val.get("byteOffset", 0), n, width, dt)
            return out
        except SceneFileError:
            raise
        except (KeyError, IndexError, TypeError, ValueError) as exc:
            raise SceneFileError(f"{self.path}: {where}: accessor {index} cannot be read "
                                 f"({type(exc).__name__}: {exc})") from exc

    def zero_fill_limit(self):
        """Elements an accessor without a bufferView may have: every other accessor's element
        takes at least one byte of the buffers, so a zero-filled one (its few sparse values
        put in) larger than all of them together, or than ``ZERO_FILL_FLOOR``, describes no
        mesh (usually a corrupted count)."""
        return max(sum(len(b) for b in self.buffers), ZERO_FILL_FLOOR)

    def _view(self, view_index, offset, count, width, dt):
        view = self.doc["bufferViews"][view_index]
        if "EXT_meshopt_compression" in view.get("extensions", {}):
            raise SceneFileError(f"{self.path}: bufferView {view_index} is meshopt-compressed")
        check_view(view_index, view, self.buffers)
        data = self.buffers[view["buffer"]]
        start = view.get("byteOffset", 0) + offset
        item = dt.itemsize * width
        stride = view.get("byteStride") or item
        end = start + (stride * (count - 1) + item if count else 0)
        if end > view.get("byteOffset", 0) + view["byteLength"] or end > len(data):
            raise ValueError(f"bufferView {view_index} is too short for {count} elements")
        return np.ndarray((count, width), dtype=dt, buffer=data, offset=start,
                          strides=(stride, dt.itemsize)).copy()


def read_gltf(path):
    """Read a ``.gltf`` (with its ``.bin`` files and ``data:`` URIs) or a ``.glb``.

    Raises
    ------
    SceneFileError when the container, the JSON or a buffer cannot be read.
    """
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise SceneFileError(f"{path}: cannot read the file ({exc})") from exc
    glb = raw[:4] == b"glTF"
    bin_chunk = None
    try:
        if glb:
            magic, version, length = struct.unpack_from("<III", raw, 0)
            if version != 2:
                raise ValueError(f"GLB version {version}, not 2")
            if len(raw) < length:   # an interrupted download or copy: its last bytes are lost
                raise SceneFileError(f"{path}: the file is cut short: its GLB header says "
                                     f"{length} bytes, the file holds {len(raw)}")
            clen, ctype = struct.unpack_from("<II", raw, 12)
            if ctype != JSON_CHUNK:
                raise ValueError("the first GLB chunk is not JSON")
            doc = json.loads(raw[20:20 + clen].decode("utf-8"))
            pos = 20 + clen
            if pos + 8 <= min(length, len(raw)):
                blen, btype = struct.unpack_from("<II", raw, pos)
                if btype == BIN_CHUNK:
                    bin_chunk = raw[pos + 8:pos + 8 + blen]
        else:
            doc = json.loads(raw.decode("utf-8"))
    except (ValueError, struct.error, UnicodeDecodeError) as exc:
        raise SceneFileError(f"{path}: not a glTF 2.0 file ({exc})") from exc
    asset = doc.get("asset") if isinstance(doc, dict) else None
    if not isinstance(asset, dict) or not str(asset.get("version", "")).startswith("2"):
        raise SceneFileError(f"{path}: not a glTF 2.0 document (asset.version is not 2.x)")
    check_document(path, doc)
    buffers = []
    for i, buf in enumerate(doc.get("buffers", [])):
        data = _buffer_bytes(path, i, buf, bin_chunk if glb and i == 0 else None)
        declared = buf.get("byteLength") if isinstance(buf, dict) else None
        if (isinstance(declared, int) and len(data) < declared
                and not (data == b"" and MESHOPT & set(buf.get("extensions") or {}))):
            # written as it is, the file would carry the loss on (textures, animation cut off)
            raise SceneFileError(f"{path}: buffer {i} is cut short: it declares {declared} "
                                 f"bytes, {'the GLB BIN chunk' if 'uri' not in buf else 'its data'}"
                                 f" holds {len(data)}")
        buffers.append(data)
    return GltfFile(path, doc, buffers, glb)


def _buffer_bytes(path, i, buf, bin_chunk):
    uri = buf.get("uri")
    if uri is None:
        if bin_chunk is None and MESHOPT & set(buf.get("extensions") or {}):
            # A meshopt fallback buffer holds no bytes by design: its views are decoded from the
            # compressed buffer. Each primitive reading one is refused by name (``gltf_mesh._refusal``).
            return b""
        if bin_chunk is None:
            raise SceneFileError(f"{path}: buffer {i} has no uri and there is no GLB BIN chunk")
        return bytes(bin_chunk)
    if not isinstance(uri, str):
        raise SceneFileError(f"{path}: buffer {i}: its uri is not text ({uri!r})")
    if uri.startswith("data:"):
        head, _, data = uri.partition(",")
        if not head.endswith(";base64"):
            raise SceneFileError(f"{path}: buffer {i}: only base64 data URIs are supported")
        try:   # a damaged data URI (a byte changed, cut short) is named, not decoded to garbage
            return base64.b64decode(data, validate=True)
        except ValueError as exc:   # binascii.Error is a ValueError
            raise SceneFileError(f"{path}: buffer {i}: its base64 data URI is damaged "
                                 f"({exc})") from None
    file = os.path.join(os.path.dirname(os.path.abspath(path)), unquote(uri))
    try:
        with open(file, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise SceneFileError(f"{path}: buffer {i}: cannot read {uri!r} ({exc})") from exc


def rebase_uris(doc, src_dir, out_dir):
    """Point relative buffer and image URIs at the same files from ``out_dir`` (in place)."""
    if os.path.abspath(src_dir) == os.path.abspath(out_dir):
        return
    for key in ("buffers", "images"):
        for item in doc.get(key, []):
            uri = item.get("uri")
            if uri is None or uri.startswith("data:") or "://" in uri or os.path.isabs(unquote(uri)):
                continue
            target = os.path.join(os.path.abspath(src_dir), unquote(uri))
            try:
                rel = os.path.relpath(target, os.path.abspath(out_dir))
            except ValueError:   # Windows: another drive, which no relative URI can reach
                raise SceneFileError(
                    f"{key[:-1]} {doc[key].index(item)} ({uri!r}) is on another drive than "
                    f"the output folder {out_dir}: a glTF refers to its files by relative "
                    f"paths, so write the output on the drive of {target}") from None
            item["uri"] = quote(rel.replace(os.sep, "/"))


class BufferWriter:
    """New accessors appended to one buffer (``doc["buffers"][index]``), 4-byte aligned."""

    def __init__(self, doc, index, data=b""):
        self.doc, self.index, self.data = doc, index, bytearray(data)

    def accessor(self, values, component_type, acc_type, target=None, normalized=False,
                 bounds=False):
        """Append ``values`` (count, width) as a new tightly packed accessor; its index.

        Vertex attributes (``target`` ARRAY_BUFFER) are padded to a 4-byte stride, as glTF
        requires; ``bounds`` writes ``min``/``max`` (required on POSITION)."""
        dt = np.dtype(COMPONENT[component_type]).newbyteorder("<")
        arr = np.ascontiguousarray(np.asarray(values).reshape(len(values), -1), dtype=dt)
        item = arr.shape[1] * dt.itemsize
        stride = item
        if target == ARRAY_BUFFER and item % 4:
            stride = item + (-item) % 4
            padded = np.zeros((len(arr), stride), dtype=np.uint8)
            padded[:, :item] = arr.view(np.uint8).reshape(len(arr), item)
            blob = padded.tobytes()
        else:
            blob = arr.tobytes()
        self.data += b"\0" * ((-len(self.data)) % 4)
        view = {"buffer": self.index, "byteOffset": len(self.data), "byteLength": len(blob)}
        if stride != item:
            view["byteStride"] = stride
        if target is not None:
            view["target"] = target
        self.data += blob
        self.doc.setdefault("bufferViews", []).append(view)
        acc = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": component_type,
               "count": int(len(arr)), "type": acc_type}
        if normalized:
            acc["normalized"] = True
        if bounds and len(arr):
            cast = float if dt.kind == "f" else int
            acc["min"] = [cast(x) for x in arr.min(axis=0)]
            acc["max"] = [cast(x) for x in arr.max(axis=0)]
        self.doc.setdefault("accessors", []).append(acc)
        return len(self.doc["accessors"]) - 1

    def finish(self):
        """Pad the buffer to 4 bytes and set its byteLength; the bytes."""
        self.data += b"\0" * ((-len(self.data)) % 4)
        self.doc["buffers"][self.index]["byteLength"] = len(self.data)
        return bytes(self.data)


def write_glb(path, doc, bin_data):
    """Write a ``.glb``: the JSON chunk (space-padded) and the BIN chunk (zero-padded)."""
    js = json.dumps(doc, separators=(",", ":")).encode("utf-8")
    js += b" " * ((-len(js)) % 4)
    chunks = struct.pack("<II", len(js), JSON_CHUNK) + js
    if bin_data is not None:
        b = bytes(bin_data) + b"\0" * ((-len(bin_data)) % 4)
        chunks += struct.pack("<II", len(b), BIN_CHUNK) + b
    with open(path, "wb") as fh:
        fh.write(struct.pack("<III", GLB_MAGIC, 2, 12 + len(chunks)) + chunks)


def write_gltf_json(path, doc):
    """Write a ``.gltf`` JSON document."""
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(doc, fh, indent=1)
