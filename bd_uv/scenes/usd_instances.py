"""Meshes inside instanced USD prims (``instanceable = true``): unwrapped once per prototype.

USD shares one prototype among the instances whose composition arcs are equal, and allows no
opinion on an instance proxy (the prototype's prims as seen under each instance): an ``over`` at
``/World/Teapot_12/geo/body`` in the root layer is ignored. What every instance does compose is
a class it inherits. So the UVs of a prototype's mesh are authored once, on a class of the
output layer mirroring the prototype's namespace (``/_bd_uv_instanced/P<k>/geo/body``), and every
instance of that prototype is given the same added inherit to it: the instances keep sharing one
prototype (their arcs stay equal), and an inherit is stronger than the references and payloads
the mesh comes from, so the new primvar wins over the asset's own. The referenced asset's file
is never edited.

An instance inside another prototype (nested instancing) cannot be given the inherit where it
is: it is given it on its place under the outer prototype's class, which the outer instances
inherit in turn.
"""
import dataclasses

import numpy as np

from .usd_mesh import scene_mesh

ROOT = "/_bd_uv_instanced"


def prototype_meshes(stage, path, uv_name, errors):
    """One (SceneMesh, part) per mesh prim of each prototype of ``stage``.

    Parameters
    ----------
    stage : Usd.Stage
    path : str, the stage's file (for messages)
    uv_name : str or None, as for ``usd_mesh.mesh_arrays``
    errors : list of str, composition errors said on every mesh

    Returns
    -------
    list of (SceneMesh, part or None); a mesh is named by its path under the first instance
    (``/World/Teapot_0/geo/body``), its info says how many instances share it, and its part
    carries ``instanced``: {"class": the prim its UVs go to, "root": the prototype's class,
    "inherits": (prim, class) pairs that make every instance inherit it, "proxy": the path
    the report names}
    """
    from pxr import Sdf, Usd, UsdGeom
    protos = {str(p.GetPath()): k for k, p in enumerate(stage.GetPrototypes())}
    found, out = {}, []
    for k, proto in enumerate(stage.GetPrototypes()):
        meshes = [p for p in Usd.PrimRange(proto) if p.IsA(UsdGeom.Mesh)]
        if not meshes:
            continue
        klass = f"{ROOT}/P{k}"
        inherits, shown_root = _inherits(stage, proto, protos, Sdf, found)
        n = len(proto.GetInstances())
        base = proto.GetPath()
        for mesh in meshes:
            rel = mesh.GetPath().MakeRelativePath(base)
            shown = str(Sdf.Path(shown_root).AppendPath(rel))
            read = scene_mesh(UsdGeom.Mesh(mesh), f"{path}: prim {shown}", shown, uv_name,
                              errors, Usd)
            if read is None:
                continue
            sm, part = read
            if part is not None:
                sm = dataclasses.replace(sm, info={**sm.info, "instances": n})
                part = {**part, "instanced": {
                    "class": str(Sdf.Path(klass).AppendPath(rel)), "root": klass,
                    "inherits": inherits, "proxy": shown}}
            out.append((sm, part))
    return out


def _inherits(stage, proto, protos, Sdf, found):
    """The (prim path, class path) inherits that make every instance of ``proto`` compose its
    class ``ROOT/P<k>``, and the path under which the report shows its prims; ``found`` keeps
    each prototype's answer (an outer prototype is asked once per instance nested in it).

    An instance outside any prototype is given the inherit itself. One inside another prototype
    (nested instancing) cannot be: the inherit goes on its place under the outer prototype's
    class instead, and the outer prototype's instances are given that class the same way, as
    far out as the nesting goes."""
    key = str(proto.GetPath())
    if key in found:
        return found[key]
    pairs, shown = {}, None      # an ordered set of pairs
    klass = f"{ROOT}/P{protos[key]}"
    for inst in sorted(proto.GetInstances(), key=lambda p: str(p.GetPath())):
        path = inst.GetPath()
        if not inst.IsInPrototype():
            pairs[(str(path), klass)] = None
            shown = shown or str(path)
            continue
        outer_root = path.GetPrefixes()[0]             # the outer prototype: /__Prototype_<n>
        outer = stage.GetPrimAtPath(outer_root)
        rel = path.MakeRelativePath(outer_root)
        outer_class = f"{ROOT}/P{protos[str(outer_root)]}"
        pairs[(str(Sdf.Path(outer_class).AppendPath(rel)), klass)] = None
        more, outer_shown = _inherits(stage, outer, protos, Sdf, found)
        pairs.update(dict.fromkeys(more))
        shown = shown or str(Sdf.Path(outer_shown).AppendPath(rel))
    found[key] = list(pairs), shown
    return found[key]


def target_prim(stage, instanced):
    """The prim the UVs of an instanced mesh are authored on: its place under the prototype's
    class (made here: the classes under a class root, never drawn), and the instance proxy the
    report names (for the primvar it had)."""
    _class(stage, instanced["root"])
    return stage.OverridePrim(instanced["class"]), stage.GetPrimAtPath(instanced["proxy"])


def add_inherits(stage, instanced):
    """Every instance (and, for nested instances, their place under the outer prototype's
    class) given the inherit to its prototype's class, once each."""
    from pxr import Usd
    for path, klass in instanced["inherits"]:
        if path.startswith(ROOT + "/"):
            _class(stage, "/".join(path.split("/")[:3]))
            prim = stage.OverridePrim(path)
        else:
            prim = stage.GetPrimAtPath(path)
        inherits = prim.GetInherits()
        if klass not in [str(p) for p in inherits.GetAllDirectInherits()]:
            inherits.AddInherit(klass, Usd.ListPositionFrontOfPrependList)


def _class(stage, path):
    """The class prim ``path`` (``ROOT/P<k>``) and the class root above it."""
    stage.CreateClassPrim(ROOT)
    return stage.CreateClassPrim(path)


def undo_instanced(prim, pv):
    """Take back the primvar ``pv`` authored on the class prim ``prim`` for one mesh. The
    inherits stay: other meshes of the same prototype may use them, and without opinions of
    this mesh they change nothing."""
    prim.RemoveProperty(pv.GetAttr().GetName())
    prim.RemoveProperty(pv.GetIndicesAttr().GetName())


def proxy_uvs(stage, proxy_path, uv_name):
    """The UVs an instance proxy composes for ``uv_name`` (flattened), or None: what a reader
    of the written stage sees."""
    from pxr import UsdGeom
    pv = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath(proxy_path)).GetPrimvar(uv_name)
    if not pv or not pv.HasValue():
        return None
    return np.asarray(pv.ComputeFlattened(), dtype=np.float64)
