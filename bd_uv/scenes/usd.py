"""OpenUSD scenes (``.usd``, ``.usda``, ``.usdc``, ``.usdz``) with ``usd-core``: every
``UsdGeom.Mesh`` unwrapped, UVs written as an indexed faceVarying ``texCoord2f[]`` primvar.

Reading: each mesh prim of the composed stage (references, payloads and variant selections
resolved) in its own space; polygons are fan-triangulated for the solve, and the triangles of
one polygon are one ``face_group`` so that seams run only along polygon edges, never through a
quad. Holes (``holeIndices``) are not unwrapped. Time-sampled points: the rest pose (the
default value, else the first time sample, with a warning). The UVs are read from and written to
the primvar named by ``--uv-name``, else the one the mesh's materials read (``usd_uv_name``:
``map1`` for a Maya export), else ``st``; the existing UVs give the seams, as an OBJ's ``vt`` do.

Instanced meshes (``instanceable = true``) are read once per prototype and their UVs authored on
a class every instance inherits (``usd_instances``).

Writing: the input layer is never edited. The output's root layer is a copy of the input's root
layer with every relative asset path (sublayers, references, payloads, textures) re-anchored so it
resolves from the output folder, and the new primvar is authored in it as an opinion (an ``over``
when the mesh is defined in a referenced layer or payload). Overrides rather than a flattened
stage: references, payloads and variant sets stay composition arcs (a library asset stays shared,
the variants stay selectable), and everything the unwrap does not touch keeps its source. Points,
topology, normals, other primvars, bindings, xforms and metadata are not written at all. A
``.usdz`` output is packaged with its dependencies (``UsdUtils.CreateNewUsdzPackage``).
"""
import dataclasses
import os

import numpy as np

from ..certificate import certify_islands
from ..errors import SceneFileError
from ..scheduling.atomic import atomic_path
from .usd_instances import (add_inherits, prototype_meshes, proxy_uvs, target_prim,
                            undo_instanced)
from .usd_mesh import scene_mesh
from .usd_probe import probe


def _pxr():
    from pxr import Sdf, Usd, UsdGeom, UsdUtils, Vt
    return Sdf, Usd, UsdGeom, UsdUtils, Vt


class UsdScene:
    """A USD stage read for unwrapping; ``meshes`` one ``SceneMesh`` per mesh prim."""

    # its v runs upwards: the UVs stored are u, v as certified (``layout.as_stored``)
    V_DOWN = False

    def __init__(self, path, uv_name, meshes, parts):
        self.path, self.uv_name, self.meshes, self._parts = path, uv_name, meshes, parts

    @classmethod
    def read(cls, path, uv_name=None):
        Sdf, Usd, UsdGeom, _, _ = _pxr()
        if not os.path.isfile(path):
            raise SceneFileError(f"{path}: no such file")
        probe(path)   # a file usd-core would end this process on is refused here
        try:
            stage = Usd.Stage.Open(path)
        except Exception as exc:  # pxr raises Tf.ErrorException for unreadable layers
            raise SceneFileError(f"{path}: not a USD stage USD can open "
                                 f"({_pxr_message(exc)})") from exc
        if stage is None:
            raise SceneFileError(f"{path}: not a USD stage USD can open")
        # what did not compose (a missing reference, payload or sublayer) is said on each mesh
        errors = [f"composition: {e}" for e in getattr(stage, "GetCompositionErrors",
                                                       lambda: [])()]
        from pxr import Tf
        meshes, parts, where = [], [], path
        try:   # a crate file's values are read lazily: a damaged one fails here, not at Open
            for prim in stage.Traverse():
                if not prim.IsA(UsdGeom.Mesh):
                    continue
                where = f"{path}: prim {prim.GetPath()}"
                read = scene_mesh(UsdGeom.Mesh(prim), where, str(prim.GetPath()), uv_name,
                                  errors, Usd)
                if read is not None:   # (an empty Mesh is skipped, as a glTF mesh of points)
                    meshes.append(read[0])
                    parts.append(read[1])
        except Tf.ErrorException as exc:
            raise SceneFileError(f"{where}: USD could not read its values, the file is damaged "
                                 f"({_pxr_message(exc)})") from None
        for sm, part in prototype_meshes(stage, path, uv_name, errors):
            meshes.append(sm)
            parts.append(part)
        scene = cls(path, uv_name, meshes, parts)
        scene.holds = "" if meshes else _holds_instead(stage, Usd, UsdGeom)
        scene.layers = {os.path.realpath(p) for p in (
            layer.realPath for layer in stage.GetUsedLayers()) if p}
        return scene

    def write(self, path, charts):
        """Write the output layer with the new primvar on every mesh in ``charts``.

        Returns
        -------
        dict {mesh position: (list of Certificate of the UVs as stored, list of warnings)}
        """
        Sdf, Usd, UsdGeom, UsdUtils, Vt = _pxr()
        if os.path.realpath(path) in self.layers | {os.path.realpath(self.path)}:
            raise SceneFileError(f"{path} would overwrite a layer {self.path} uses; choose "
                                 "another output name or folder")
        if not path.lower().endswith(".usdz"):
            try:
                with atomic_path(path) as tmp:
                    return self._write_layer(tmp, charts)
            except _NothingCertified as nothing:
                return nothing.result
        import tempfile
        out_dir = os.path.dirname(os.path.abspath(path))
        os.makedirs(out_dir, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix=".bd-uv-tmp-", dir=out_dir) as folder:
            layer_path = os.path.join(folder, os.path.splitext(os.path.basename(path))[0] + ".usdc")
            # a package's own files (textures) beside the new layer, at their paths inside it,
            # so the new package holds them as the input did
            local = self.path.lower().endswith(".usdz") and _unpack(self.path, folder,
                                                                     os.path.basename(layer_path))
            try:
                result = self._write_layer(layer_path, charts, local)
            except _NothingCertified as nothing:
                return nothing.result
            with atomic_path(path) as ztmp:
                if not UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(layer_path), ztmp):
                    raise SceneFileError(f"{path}: the .usdz package could not be written"
                                         + _unresolved(UsdUtils, Sdf, layer_path))
        return result

    def _write_layer(self, layer_path, charts, package_local=False):
        """A copy of the input's root layer at ``layer_path`` with asset paths re-anchored there
        (``package_local``: the input package's files are unpacked beside it), and the new
        primvars authored in it."""
        Sdf, Usd, UsdGeom, UsdUtils, Vt = _pxr()
        from pxr import Tf
        try:   # a crate file is read lazily: damage its stage did not show can show here
            src = Sdf.Layer.FindOrOpen(self.path)
            if src is None:
                raise SceneFileError(f"{self.path}: the root layer cannot be opened")
            layer = Sdf.Layer.CreateNew(layer_path)
            layer.TransferContent(src)
            folder = os.path.dirname(os.path.abspath(layer_path))
            UsdUtils.ModifyAssetPaths(layer, lambda p: _reanchor(src, p, folder, package_local))
            stage = Usd.Stage.Open(layer)
            result = {k: self._author(stage, k, ch, UsdGeom, Sdf, Vt) for k, ch in charts.items()}
        except Tf.ErrorException as exc:
            raise SceneFileError(f"{self.path}: USD could not copy its root layer to write the "
                                 f"UVs, the file is damaged ({_pxr_message(exc)}); nothing was "
                                 "written") from None
        if not any(all(c.certified for c in certs) for certs, _ in result.values()):
            raise _NothingCertified(result)   # no file at the output that looks like a result
        layer.Save()
        return result

    def _author(self, stage, k, ch, UsdGeom, Sdf, Vt):
        sm, part = self.meshes[k], self._parts[k]
        uv32 = ch.corner_uv.astype(np.float32)
        # one value per face-vertex: a polygon's triangles agree on it (seams only along edges)
        nfv = part["n_face_vertices"]
        fv_uv = np.zeros((nfv, 2), np.float32)
        T = part["T"]
        # faces of no island (zero-area, given their neighbours' UVs) first, so that where a
        # polygon also holds a certified triangle, the face-vertices they share keep its UVs
        order = np.argsort(np.asarray(ch.face_island) >= 0, kind="stable")
        fv_uv[T[order].reshape(-1)] = uv32[order].reshape(-1, 2)
        values, index = np.unique(fv_uv, axis=0, return_inverse=True)
        index = index.reshape(-1)
        back = values[index][T].astype(np.float64)        # the stored UVs, per triangle corner
        certs = certify_islands(sm.mesh.V, sm.mesh.F, back, ch.face_island, ch.bounds)
        if not all(c.certified for c in certs):
            return certs, ["the UVs as stored (float32, one per face-vertex) do not certify; "
                           "the mesh keeps the UVs it had"]
        instanced = part.get("instanced")
        if instanced is None:
            prim = seen = stage.GetPrimAtPath(sm.name)
        else:   # on the prototype's class, which every instance inherits (usd_instances)
            prim, seen = target_prim(stage, instanced)
        if not prim or not seen:   # the copied layer composes no such prim (a reference lost)
            return _refused(certs, f"{sm.name} is not in the stage as written (a reference of "
                                   "the copied root layer does not resolve there)")
        api = UsdGeom.PrimvarsAPI(prim)
        warnings = []
        name = part["uv_name"]
        old = UsdGeom.PrimvarsAPI(seen).GetPrimvar(name)
        if old and old.GetTypeName() != Sdf.ValueTypeNames.TexCoord2fArray:
            if instanced is not None:   # the asset's attribute: not removable from here
                return _refused(certs, f"primvars:{name} is {old.GetTypeName()} in the "
                                       "instanced asset, not texCoord2f[]")
            warnings.append(f"primvars:{name} was {old.GetTypeName()}; it becomes "
                            "texCoord2f[]")
            prim.RemoveProperty(old.GetAttr().GetName())
        pv = api.CreatePrimvar(name, Sdf.ValueTypeNames.TexCoord2fArray,
                               UsdGeom.Tokens.faceVarying)
        pv.SetInterpolation(UsdGeom.Tokens.faceVarying)
        if pv.GetAttr().GetNumTimeSamples() or pv.GetIndicesAttr().GetNumTimeSamples():
            warnings.append(f"primvars:{name} had time samples; they are blocked so "
                            "the new UVs hold at every time")
            pv.GetAttr().Block()
            pv.GetIndicesAttr().Block()
        pv.Set(Vt.Vec2fArray.FromNumpy(values))
        pv.SetIndices(Vt.IntArray.FromNumpy(index.astype(np.int32)))
        if instanced is not None:
            add_inherits(stage, instanced)
            seen_uv = proxy_uvs(stage, instanced["proxy"], name)
            if seen_uv is None or not np.array_equal(seen_uv, values[index]):
                undo_instanced(prim, pv)   # nothing of it left in the layer
                return _refused(certs, "the instances do not compose the UVs authored on their "
                                       "class")
            warnings.append(f"instanced: the UVs are authored once on {instanced['class']}, "
                            f"which the {sm.info['instances']} instance(s) inherit")
        return certs, warnings + part["warnings"]


def _holds_instead(stage, Usd, UsdGeom):
    """What a stage without a mesh holds instead, for its error message ("" when nothing):
    shapes that are not polygon meshes (a Sphere, Cube, ... has no faces to carry UVs), and Mesh
    prims the composed stage does not show (under an ``over`` that nothing defines, inactive,
    or in a class)."""
    said, hidden = {}, []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Gprim):
            kind = str(prim.GetTypeName()) or "untyped"
            said[kind] = said.get(kind, 0) + 1
    for prim in stage.Traverse(Usd.PrimAllPrimsPredicate):
        if prim.IsA(UsdGeom.Mesh) and not (prim.IsDefined() and prim.IsActive()
                                           and not prim.IsAbstract() and _shown(prim, Usd)):
            hidden.append(str(prim.GetPath()))
    parts = []
    if said:
        shapes = ", ".join(f"{n} {kind}" for kind, n in sorted(said.items()))
        parts.append(f"it has {shapes} prim(s), which are not polygon meshes: convert them to "
                     "Mesh prims to unwrap them")
    if hidden:
        more = f" and {len(hidden) - 3} more" if len(hidden) > 3 else ""
        parts.append(f"Mesh prim(s) {', '.join(hidden[:3])}{more} are not part of the composed "
                     "stage (under an `over` no layer defines, inactive, or in a class): open "
                     "the layer that defines them, or this one composed over it")
    return "; ".join(parts)


def _shown(prim, Usd):
    """Whether ``prim`` is on the stage's default traversal (its ancestors too)."""
    pred = Usd.PrimDefaultPredicate
    p = prim
    while p and not p.IsPseudoRoot():
        if not pred(p):
            return False
        p = p.GetParent()
    return True


def _refused(certs, why):
    """(certificates, warnings) of a mesh whose certified UVs are not written: each
    certificate failed with ``why``, so the mesh keeps the UVs it had."""
    return ([dataclasses.replace(c, certified=False, reason=why) for c in certs],
            [f"{why}; the mesh keeps the UVs it had"])


class _NothingCertified(Exception):
    """No mesh's UVs certify as stored: the layer is not written (``result`` says why)."""

    def __init__(self, result):
        super().__init__("no mesh certified as stored")
        self.result = result


def _unpack(package, folder, layer_name):
    """Extract a .usdz's files but its root layer into ``folder`` at their paths inside it from
    the root layer's folder, where the root layer's relative asset paths find them (a root
    layer in a subfolder, ``pkg.usdz_FILES/pkg.usdc``, as OpenUSD's own test packages have it);
    none leaving ``folder``, none named ``layer_name``. Returns True."""
    import posixpath
    import zipfile
    with zipfile.ZipFile(package) as z:
        names = z.namelist()
        base = posixpath.dirname(names[0]) if names else ""
        for name in names[1:]:   # the first file of a package is its root layer
            inside = posixpath.relpath(name, base) if base and not name.endswith("/") else name
            target = os.path.normpath(os.path.join(folder, inside))
            if (os.path.isabs(name) or not target.startswith(os.path.join(folder, ""))
                    or name.endswith("/") or os.path.basename(target) == layer_name):
                continue
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with z.open(name) as fin, open(target, "wb") as fout:
                fout.write(fin.read())
    return True


def _unresolved(UsdUtils, Sdf, layer_path):
    """Why a package could not be made, when USD names it: the assets the layer references that
    resolve to no file (a package holds only files that exist)."""
    try:
        missing = [str(p) for p in UsdUtils.ComputeAllDependencies(Sdf.AssetPath(layer_path))[2]]
    except Exception:   # noqa: BLE001 (only words for a message)
        return ""
    if not missing:
        return ""
    names = ", ".join(os.path.basename(p) for p in missing[:4])
    return (f": {len(missing)} asset(s) the scene references resolve to no file ({names}"
            + (", ..." if len(missing) > 4 else "") + "); write a .usd/.usda/.usdc instead, "
            "or restore them")


def _reanchor(src, asset, out_dir, package_local=False):
    """A relative asset path of the input layer, rewritten to resolve from ``out_dir``; one
    inside the input package is read from that package, or (``package_local``) from the copy of
    its files in ``out_dir``, where it keeps its path."""
    if not asset or "://" in asset or os.path.isabs(asset) or asset.startswith("@"):
        return asset
    inner = ""
    if asset.endswith("]") and "[" in asset:     # a file inside a package: pkg.usdz[tex.png]
        asset, inner = asset[:asset.index("[")], asset[asset.index("["):]
    full = src.ComputeAbsolutePath(asset)
    if not full:
        return asset + inner
    if "[" in full:   # inside the input package (pkg.usdz[tex.png]): read from that package
        package, inside = full[:full.index("[")], full[full.index("["):]
        if package_local or inner or not os.path.isfile(package):
            return asset + inner
        return _relative(package, out_dir) + inside
    if not asset.startswith(("./", "../")) and not os.path.exists(full):
        return asset + inner                     # a search path, resolved by the resolver
    return _relative(full, out_dir) + inner


def _relative(path, out_dir):
    """``path`` as an anchored relative asset path from ``out_dir`` ("./x", "../x"), or as the
    absolute path where none exists (Windows: another drive); USD resolves either."""
    try:
        rel = os.path.relpath(path, out_dir).replace(os.sep, "/")
    except ValueError:
        return os.path.abspath(path).replace(os.sep, "/")
    return rel if rel.startswith("../") else "./" + rel


def _pxr_message(exc):
    """The text of a pxr error, one line. ``str()`` of a ``Tf.ErrorException`` decodes the
    parser's message as UTF-8 and raises ``UnicodeDecodeError`` when it quotes a corrupted byte
    of the layer; the message is then decoded with those bytes replaced."""
    try:
        text = str(exc)
    except UnicodeError:
        parts = []
        for arg in getattr(exc, "args", ()):
            try:    # pxr.Tf.Error: its commentary is the message
                parts.append(str(getattr(arg, "commentary", arg)))
            except UnicodeError:
                parts.append("a corrupted byte the parser could not quote")
        text = "; ".join(parts) or type(exc).__name__
    # a damaged crate file's error lists every spec it skipped (400 MB of text seen: its split
    # raised MemoryError): the first words say what went wrong
    return " ".join(text[:MESSAGE_CHARS].split()) + (" ..." if len(text) > MESSAGE_CHARS else "")


MESSAGE_CHARS = 2000   # of a pxr error quoted in a message
