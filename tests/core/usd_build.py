"""Small USD stages built in the tests: quads, a pentagon, a custom primvar, a material binding
with a texture, a reference to a layer in another folder, time-sampled points."""
import os

import numpy as np

from helpers import grid


def quad_grid(nx=6, ny=5, bump=True):
    """A curved grid of quads, one of them a convex pentagon (a vertex pushed out of its top
    edge): (points (n,3), counts (p,), indices (sum counts,))."""
    V, _ = grid(nx, ny, z=lambda x, y: 0.25 * (x - 0.4) ** 2 + 0.1 * y)
    i = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = i[:-1, :-1].ravel(), i[:-1, 1:].ravel(), i[1:, 1:].ravel(), i[1:, :-1].ravel()
    polys = [list(q) for q in np.stack([a, b, c, d], 1)]
    if bump:   # the top-left quad of the last row gets a fifth vertex above its top edge
        top = polys[-(nx - 1)]
        p = (V[top[2]] + V[top[3]]) / 2 + [0, 0.06, 0]
        V = np.vstack([V, p])
        polys[-(nx - 1)] = [top[0], top[1], top[2], len(V) - 1, top[3]]
    counts = np.array([len(q) for q in polys])
    return V, counts, np.concatenate(polys)


def build_stage(folder):
    """Write ``folder/lib/asset.usda`` (a mesh to reference) and ``folder/shot.usda``; paths."""
    from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, Vt
    os.makedirs(os.path.join(folder, "lib", "tex"), exist_ok=True)
    with open(os.path.join(folder, "lib", "tex", "wood.png"), "wb") as fh:
        fh.write(b"\x89PNG not really")
    asset_path = os.path.join(folder, "lib", "asset.usda")
    asset = Usd.Stage.CreateNew(asset_path)
    root = UsdGeom.Xform.Define(asset, "/Asset")
    asset.SetDefaultPrim(root.GetPrim())
    V, counts, idx = quad_grid(5, 4, bump=False)
    rock = UsdGeom.Mesh.Define(asset, "/Asset/Geo/Rock")
    rock.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    rock.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    rock.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    asset.GetRootLayer().Save()

    shot_path = os.path.join(folder, "shot.usda")
    stage = Usd.Stage.CreateNew(shot_path)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    world.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    prop = stage.DefinePrim("/World/Prop")
    prop.GetReferences().AddReference("./lib/asset.usda")
    V, counts, idx = quad_grid()
    panel = UsdGeom.Mesh.Define(stage, "/World/Panel")
    pts = panel.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(V.astype(np.float32)))
    pts.Set(Vt.Vec3fArray.FromNumpy((V + [0, 0, 1]).astype(np.float32)), 10.0)  # animated
    panel.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts.astype(np.int32)))
    panel.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(idx.astype(np.int32)))
    panel.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)
    panel.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(
        np.tile([0, 0, 1], (len(idx), 1)).astype(np.float32)))
    panel.SetNormalsInterpolation(UsdGeom.Tokens.faceVarying)
    api = UsdGeom.PrimvarsAPI(panel.GetPrim())
    heat = api.CreatePrimvar("heat", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.faceVarying)
    heat.Set(Vt.FloatArray.FromNumpy(np.linspace(0, 1, len(idx)).astype(np.float32)))
    st = api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex)
    st.Set(Vt.Vec2fArray.FromNumpy(V[:, :2].astype(np.float32)))
    panel.GetPrim().SetCustomDataByKey("department", "props")
    mat = UsdShade.Material.Define(stage, "/World/Looks/Wood")
    tex = UsdShade.Shader.Define(stage, "/World/Looks/Wood/Tex")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./lib/tex/wood.png")
    UsdShade.MaterialBindingAPI.Apply(panel.GetPrim()).Bind(mat)
    vs = panel.GetPrim().GetVariantSets().AddVariantSet("look")
    vs.AddVariant("clean")
    vs.AddVariant("dirty")
    vs.SetVariantSelection("clean")
    stage.GetRootLayer().Save()
    return shot_path, asset_path
