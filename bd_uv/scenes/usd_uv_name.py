"""Which primvar holds a USD mesh's UVs, when the user names none (``--uv-name`` not given).

USD has no fixed name for UVs: Houdini, Blender and most samples write ``st``, Maya's exports
``map1``, others ``st0`` or ``UVMap``. A material reads its UVs through a
``UsdPrimvarReader_float2`` (or MaterialX ``ND_geompropvalue_vector2``) whose ``varname`` (or
``geomprop``) names the primvar, possibly through an input of the material. New UVs written under
another name than the one the material reads are never seen by a renderer, and ``--seams uv``
would find no UVs to cut along. So, in this order:

1. the name every material bound to the mesh (the prim's, and its ``GeomSubset``s') reads;
2. else the mesh's one ``texCoord2f[]`` primvar holding values (``st`` among several);
3. else ``st``.
Where materials read several names, the one the mesh holds (``st`` first) is taken and the choice
is said in a warning.
"""
DEFAULT = "st"
READERS = {"UsdPrimvarReader_float2": "varname", "ND_geompropvalue_vector2": "geomprop"}


def uv_primvar(prim):
    """(name, warning or None): the primvar to read and write the UVs of mesh ``prim``."""
    from pxr import Sdf, UsdGeom
    api = UsdGeom.PrimvarsAPI(prim)
    held = sorted(pv.GetPrimvarName() for pv in api.GetPrimvarsWithValues()
                  if pv.GetTypeName() == Sdf.ValueTypeNames.TexCoord2fArray)
    read = _material_names(prim)
    if len(read) == 1:
        return read[0], None
    if read:
        both = [n for n in read if n in held]
        name = DEFAULT if DEFAULT in both else (both or read)[0]
        return name, (f"its materials read UVs from several primvars ({', '.join(read)}); "
                      f"the new UVs go to primvars:{name} (--uv-name chooses)")
    if len(held) == 1:
        return held[0], None
    if DEFAULT in held or not held:
        return DEFAULT, None
    return DEFAULT, (f"it holds several UV primvars ({', '.join(held)}) and no material reads "
                     f"one; the new UVs go to primvars:{DEFAULT} (--uv-name chooses)")


def _material_names(prim):
    """Sorted primvar names the materials bound to ``prim`` and its subsets read UVs from."""
    from pxr import Usd, UsdGeom, UsdShade
    holders = [prim] + [s.GetPrim() for s in UsdGeom.Subset.GetAllGeomSubsets(
        UsdGeom.Imageable(prim))]
    names = set()
    for holder in holders:
        material, _ = UsdShade.MaterialBindingAPI(holder).ComputeBoundMaterial()
        if not material:
            continue
        for p in Usd.PrimRange(material.GetPrim()):
            shader = UsdShade.Shader(p)
            key = READERS.get(str(shader.GetShaderId() or "")) if shader else None
            inp = shader.GetInput(key) if key else None
            if not inp:
                continue
            for attr in inp.GetValueProducingAttributes():
                value = attr.Get()
                if value:
                    names.add(str(value))
    return sorted(names)
