"""The parts of a glTF 2.0 document bd-uv walks, checked before it walks them.

A document whose JSON has the wrong shape where the reader and writer look (``meshes[0].
primitives`` an object, a node's ``children`` a number, a buffer's ``uri`` a number) is refused
with the place named, as the glTF 2.0 schema words it, instead of failing inside the reader
(assimp's ``test/models/glTF2/wrongTypes``). A bufferView a primitive reads that reaches past the
bytes of its buffer (tinygltf's ``BoundsChecking/integer-out-of-bounds.gltf``: a ``byteLength``
of 1e300) refuses the meshes reading it, whose UVs could not be written back readable.

Properties bd-uv does not read (materials, animations, extensions) are not checked: they are
written back as read. Accessors, and the indices naming them, are checked where a primitive
reads them, so a malformed one refuses only its mesh (``gltf_mesh._refusal``,
``gltf_io.GltfFile.accessor``).
"""
from ..errors import SceneFileError

KINDS = {list: "an array", dict: "an object", str: "a string", int: "an integer"}
# the top-level arrays the reader or writer indexes, each of objects
ARRAYS = ("scenes", "nodes", "meshes", "accessors", "bufferViews", "buffers", "images",
          "materials")


def _kind(value):
    if isinstance(value, bool):
        return "a boolean"
    for t, name in KINDS.items():
        if isinstance(value, t):
            return name
    return "null" if value is None else f"a {type(value).__name__}"


class _Checker:
    def __init__(self, path, doc):
        self.path, self.doc = path, doc

    def fail(self, where, what):
        raise SceneFileError(f"{self.path}: not a valid glTF 2.0 document: {where} {what}")

    def typed(self, value, where, kind):
        if not isinstance(value, kind) or isinstance(value, bool):
            self.fail(where, f"is {_kind(value)}, where glTF requires {KINDS[kind]}")
        return value

    def index(self, value, where, array):
        self.typed(value, where, int)
        n = len(self.doc.get(array, []))
        if not 0 <= value < n:
            self.fail(where, f"is {value}, but the document has "
                      + (f"{n} {array} (0..{n - 1})" if n else f"no {array}"))

    def count(self, value, where):
        if self.typed(value, where, int) < 0:
            self.fail(where, f"is {value}, where glTF requires a count of 0 or more")

    def optional(self, item, key, where, check, *args):
        if key in item:
            check(item[key], f"{where}.{key}", *args)


def check_document(path, doc):
    """Refuse (``SceneFileError``) a document whose arrays, nodes, meshes, primitives, buffers,
    or images have the wrong JSON shape where bd-uv reads or writes them."""
    c = _Checker(path, doc)
    for key in ARRAYS:
        if key in doc:
            for i, item in enumerate(c.typed(doc[key], key, list)):
                c.typed(item, f"{key}[{i}]", dict)
    for i, node in enumerate(doc.get("nodes", [])):
        c.optional(node, "mesh", f"nodes[{i}]", c.index, "meshes")
        for k, child in enumerate(c.typed(node.get("children", []), f"nodes[{i}].children", list)):
            c.index(child, f"nodes[{i}].children[{k}]", "nodes")
    for i, mesh in enumerate(doc.get("meshes", [])):
        where = f"meshes[{i}].primitives"
        for j, prim in enumerate(c.typed(mesh.get("primitives", []), where, list)):
            at = f"{where}[{j}]"
            c.typed(prim, at, dict)
            c.typed(prim.get("attributes", {}), f"{at}.attributes", dict)
            c.optional(prim, "mode", at, c.typed, int)
            c.optional(prim, "extensions", at, c.typed, dict)
            for t, target in enumerate(c.typed(prim.get("targets", []), f"{at}.targets", list)):
                c.typed(target, f"{at}.targets[{t}]", dict)
    for key in ("buffers", "images"):   # a buffer's uri is read, and named, by gltf_io
        for i, item in enumerate(doc.get(key, [])):
            if key == "images":
                c.optional(item, "uri", f"{key}[{i}]", c.typed, str)
            c.optional(item, "extensions", f"{key}[{i}]", c.typed, dict)


def check_view(view_index, view, buffers):
    """Raise ``ValueError`` naming what is wrong with bufferView ``view_index`` (``view``, a
    dict): a buffer index, byteOffset or byteLength that is not a whole number in range, or a
    range reaching past the bytes its buffer holds (``buffers``: each buffer's bytes as read).
    Checked where a primitive reads the view, so only the meshes reading it are refused."""
    where = f"bufferView {view_index}"
    buffer, offset, length = view.get("buffer"), view.get("byteOffset", 0), view.get("byteLength")
    for name, value in (("buffer", buffer), ("byteOffset", offset), ("byteLength", length)):
        if not isinstance(value, int) or isinstance(value, bool) or value < 0:
            raise ValueError(f"{where}: its {name} is {value!r}, where glTF requires a whole "
                             "number of 0 or more")
    if buffer >= len(buffers):
        raise ValueError(f"{where}: buffer {buffer} does not exist ({len(buffers)} buffers)")
    if offset + length > len(buffers[buffer]):
        raise ValueError(f"{where} reaches past the end of buffer {buffer} (byteOffset {offset} "
                         f"+ byteLength {length} > {len(buffers[buffer])} bytes): the file is "
                         "damaged")
