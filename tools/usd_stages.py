#!/usr/bin/env python3
"""Stages written by usd-core, for the USD reader's tests (tests/usd_time.rs).

    python tools/usd_stages.py every-type OUT.usda|OUT.usdc
    python tools/usd_stages.py sweep OUT.usda|OUT.usdc
    python tools/usd_stages.py bake IN FRAME OUT.usda
    python tools/usd_stages.py spline OUT.usda

every-type: a lit plane plus a prim with one animated attribute of every value type USD has
            (scalars, vectors, quaternions, matrices, strings, tokens, assets, each also as
            an array), with a default value and time samples (an empty asset `@@` among
            them), and property and prim metadata of every kind (doc, displayName, custom
            data, allowed tokens, colour space, primvar interpolation, asset info, kind,
            variant sets, ...).
sweep:      UsdLux test sweeps in the manner of the UsdLux test suite: a rect, sphere, disk,
            cylinder and distant light, each with its inputs animated over frames 1..6 (one
            input changing at a time, usd-core's `@@` for the unused IES file), an animated
            transform, a camera and a ground plane.
bake:       the stage at time code FRAME as a static stage: flattened, every time-sampled
            attribute replaced by its value at FRAME (usd-core's Get), the time range removed.
spline:     an attribute animated by a spline (OpenUSD 25's `.spline`), which the renderer
            does not evaluate and must refuse.

Run with the Python of the venv tools/venv.sh makes (usd-core is pinned in requirements.txt).
On failure prints one line, `usd_stages.py: <reason>`, and exits with status 1.
"""

import sys

PROG = "usd_stages.py"


def fail(reason):
    print(f"{PROG}: {reason}", file=sys.stderr)
    sys.exit(1)


try:
    from pxr import Gf, Kind, Sdf, Usd, UsdGeom, UsdLux, Vt
except ImportError as e:  # pragma: no cover - the venv always has usd-core
    fail(f"usd-core is not installed ({e}); run tools/venv.sh")


def new_stage(path):
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    return stage


def ground(stage):
    """A 4 m grey square at y = 0 facing +Y, and a camera above looking down at it."""
    mesh = UsdGeom.Mesh.Define(stage, "/World/ground")
    mesh.CreatePointsAttr([(-2, 0, 2), (2, 0, 2), (2, 0, -2), (-2, 0, -2)])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    cam = UsdGeom.Camera.Define(stage, "/World/camera")
    cam.CreateFocalLengthAttr(20.0)
    cam.CreateHorizontalApertureAttr(36.0)
    cam.CreateVerticalApertureAttr(36.0)
    cam.AddTranslateOp().Set(Gf.Vec3d(0, 5, 0))
    cam.AddRotateXOp().Set(-90.0)
    return mesh


# Every value type name of Sdf.ValueTypeNames with a sample value (the default of the type is
# the other sample).
SCALARS = {
    "bool": True,
    "uchar": 7,
    "int": -3,
    "uint": 3,
    "int64": -(2**40),
    "uint64": 2**40,
    "half": 0.5,
    "float": 1.25,
    "double": 2.5,
    "timecode": Sdf.TimeCode(12.0),
    "string": "a string",
    "token": "aToken",
    "asset": Sdf.AssetPath("texture.png"),
    "int2": Gf.Vec2i(1, 2),
    "int3": Gf.Vec3i(1, 2, 3),
    "int4": Gf.Vec4i(1, 2, 3, 4),
    "half2": Gf.Vec2h(1, 2),
    "half3": Gf.Vec3h(1, 2, 3),
    "half4": Gf.Vec4h(1, 2, 3, 4),
    "float2": Gf.Vec2f(1, 2),
    "float3": Gf.Vec3f(1, 2, 3),
    "float4": Gf.Vec4f(1, 2, 3, 4),
    "double2": Gf.Vec2d(1, 2),
    "double3": Gf.Vec3d(1, 2, 3),
    "double4": Gf.Vec4d(1, 2, 3, 4),
    "point3h": Gf.Vec3h(1, 2, 3),
    "point3f": Gf.Vec3f(1, 2, 3),
    "point3d": Gf.Vec3d(1, 2, 3),
    "vector3h": Gf.Vec3h(1, 2, 3),
    "vector3f": Gf.Vec3f(1, 2, 3),
    "vector3d": Gf.Vec3d(1, 2, 3),
    "normal3h": Gf.Vec3h(0, 1, 0),
    "normal3f": Gf.Vec3f(0, 1, 0),
    "normal3d": Gf.Vec3d(0, 1, 0),
    "color3h": Gf.Vec3h(0.5, 0.25, 1),
    "color3f": Gf.Vec3f(0.5, 0.25, 1),
    "color3d": Gf.Vec3d(0.5, 0.25, 1),
    "color4h": Gf.Vec4h(0.5, 0.25, 1, 1),
    "color4f": Gf.Vec4f(0.5, 0.25, 1, 1),
    "color4d": Gf.Vec4d(0.5, 0.25, 1, 1),
    "texCoord2h": Gf.Vec2h(0.5, 0.5),
    "texCoord2f": Gf.Vec2f(0.5, 0.5),
    "texCoord2d": Gf.Vec2d(0.5, 0.5),
    "texCoord3h": Gf.Vec3h(0.5, 0.5, 0.5),
    "texCoord3f": Gf.Vec3f(0.5, 0.5, 0.5),
    "texCoord3d": Gf.Vec3d(0.5, 0.5, 0.5),
    "quath": Gf.Quath(1, 0, 0, 0),
    "quatf": Gf.Quatf(0.7071, 0.7071, 0, 0),
    "quatd": Gf.Quatd(0.7071, 0, 0.7071, 0),
    "matrix2d": Gf.Matrix2d(2),
    "matrix3d": Gf.Matrix3d(2),
    "matrix4d": Gf.Matrix4d(2),
    "frame4d": Gf.Matrix4d(1),
}


def every_type(path):
    stage = new_stage(path)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(3)
    stage.SetTimeCodesPerSecond(24)
    stage.SetFramesPerSecond(24)
    stage.SetMetadata("comment", "every value type, animated, with metadata")
    stage.SetMetadata("documentation", "written by tools/usd_stages.py")
    stage.GetRootLayer().customLayerData = {"tool": "usd_stages.py", "nested": {"n": 1}}
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    ground(stage)
    light = UsdLux.RectLight.Define(stage, "/World/light")
    light.CreateIntensityAttr(10.0)
    light.AddTranslateOp().Set(Gf.Vec3d(0, 2, 0))
    light.AddRotateXOp().Set(-90.0)

    holder = stage.DefinePrim("/World/values", "Scope")
    for name, sample in SCALARS.items():
        for array in (False, True):
            type_name = Sdf.ValueTypeNames.Find(name + ("[]" if array else ""))
            if not type_name:
                fail(f"usd-core has no value type '{name}'")
            attr = holder.CreateAttribute(f"my:{name}{'Array' if array else ''}", type_name)
            default = type_name.defaultValue
            value = [sample, sample] if array else sample
            attr.Set(value)
            attr.Set(default if not array else [], 1.0)
            attr.Set(value, 2.0)
            attr.Set(default if not array else [sample], 3.0)
            attr.SetDocumentation(f"{name} with every kind of metadata")
            attr.SetDisplayName(name)
            attr.SetDisplayGroup("values")
            attr.SetHidden(False)
            attr.SetCustomDataByKey("note", name)
            attr.SetCustomDataByKey("nested:depth", 2)
    empty = holder.CreateAttribute("my:emptyAsset", Sdf.ValueTypeNames.Asset)
    empty.Set(Sdf.AssetPath(""), 1.0)
    empty.Set(Sdf.AssetPath("texture.png"), 2.0)
    blocked = holder.CreateAttribute("my:blocked", Sdf.ValueTypeNames.Float)
    blocked.Set(1.0, 1.0)
    blocked.Set(Sdf.ValueBlock(), 2.0)
    tok = holder.CreateAttribute("my:choice", Sdf.ValueTypeNames.Token, variability=Sdf.VariabilityUniform)
    tok.Set("a")
    tok.SetMetadata("allowedTokens", ["a", "b"])
    col = holder.CreateAttribute("my:colour", Sdf.ValueTypeNames.Color3f)
    col.Set(Gf.Vec3f(1, 0.5, 0.25))
    col.SetColorSpace("lin_rec709")
    src = holder.CreateAttribute("my:source", Sdf.ValueTypeNames.Float)
    src.Set(1.0)
    holder.CreateAttribute("my:connected", Sdf.ValueTypeNames.Float).AddConnection(src.GetPath())
    holder.CreateRelationship("my:targets").AddTarget(light.GetPath())

    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/ground"))
    api = UsdGeom.PrimvarsAPI(mesh)
    st = api.CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    st.Set([(0, 0), (1, 0), (1, 1), (0, 1)])
    st.Set([(0, 0), (1, 0), (1, 1), (0, 1)], 1.0)
    dv = api.CreatePrimvar("displayColor", Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.constant, 1)
    dv.Set([(0.5, 0.5, 0.5)])
    dv.GetAttr().SetMetadata("elementSize", 1)

    prim = holder
    prim.SetDocumentation("prim metadata of every kind")
    prim.SetCustomDataByKey("note", "prim")
    prim.SetAssetInfoByKey("identifier", Sdf.AssetPath("values.usda"))
    prim.SetAssetInfoByKey("version", "1")
    prim.SetHidden(False)
    prim.SetMetadata("comment", "a comment")
    Usd.ModelAPI(world.GetPrim()).SetKind(Kind.Tokens.assembly)
    variants = prim.GetVariantSets().AddVariantSet("look")
    for v in ("plain", "fancy"):
        variants.AddVariant(v)
    variants.SetVariantSelection("plain")
    with variants.GetVariantEditContext():
        prim.CreateAttribute("my:inVariant", Sdf.ValueTypeNames.Float).Set(1.0)
    stage.GetRootLayer().Save()


def animate(attr, values):
    """Samples 1.. of a sweep: `values` per frame."""
    for frame, value in enumerate(values, start=1):
        attr.Set(value, frame)


def sweep(path):
    stage = new_stage(path)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(6)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    ground(stage)
    kinds = [
        ("rect", UsdLux.RectLight),
        ("sphere", UsdLux.SphereLight),
        ("disk", UsdLux.DiskLight),
        ("cylinder", UsdLux.CylinderLight),
        ("distant", UsdLux.DistantLight),
    ]
    for i, (name, schema) in enumerate(kinds):
        light = schema.Define(stage, f"/World/lights/{name}")
        prim = light.GetPrim()
        x = -1.6 + 0.8 * i
        op = light.AddTranslateOp()
        animate(op, [Gf.Vec3d(x, 1.0 + 0.1 * f, 0) for f in range(6)])
        light.AddRotateXOp().Set(-90.0)
        animate(light.CreateIntensityAttr(), [1, 2, 2, 2, 2, 2] if name != "distant" else [1, 2, 2, 2, 2, 2])
        animate(light.CreateExposureAttr(), [0, 0, 1, 1, 1, 1])
        animate(light.CreateColorAttr(), [Gf.Vec3f(1, 1, 1)] * 3 + [Gf.Vec3f(1, 0.5, 0.25)] * 3)
        animate(light.CreateEnableColorTemperatureAttr(), [False] * 4 + [True] * 2)
        animate(light.CreateColorTemperatureAttr(), [6500] * 5 + [3000])
        animate(light.CreateNormalizeAttr(), [False] * 5 + [True])
        if name == "rect":
            animate(light.CreateWidthAttr(), [0.2, 0.2, 0.2, 0.3, 0.3, 0.3])
            light.CreateHeightAttr(0.2)
            animate(light.CreateTextureFileAttr(), [Sdf.AssetPath("")] * 6)
        elif name in ("sphere", "disk", "cylinder"):
            animate(light.CreateRadiusAttr(), [0.1, 0.1, 0.1, 0.15, 0.15, 0.15])
        else:
            animate(light.CreateAngleAttr(), [0.53, 0.53, 0.53, 5, 5, 5])
        if name != "distant":
            shaping = UsdLux.ShapingAPI.Apply(prim)
            animate(shaping.CreateShapingConeAngleAttr(), [90, 90, 90, 90, 45, 45])
            animate(shaping.CreateShapingConeSoftnessAttr(), [0, 0, 0, 0, 0.5, 0.5])
            animate(shaping.CreateShapingFocusAttr(), [0, 0, 0, 0, 0, 1])
            animate(shaping.CreateShapingIesFileAttr(), [Sdf.AssetPath("")] * 6)
    stage.GetRootLayer().Save()


def spline(path):
    stage = new_stage(path)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    ground(stage)
    light = UsdLux.SphereLight.Define(stage, "/World/light")
    light.AddTranslateOp().Set(Gf.Vec3d(0, 1, 0))
    attr = light.CreateIntensityAttr()
    try:
        from pxr import Ts
    except ImportError as e:
        fail(f"this usd-core has no splines (pxr.Ts): {e}")
    knots = Ts.Spline("float")
    for t, v in ((1.0, 1.0), (10.0, 5.0)):
        knot = Ts.Knot("float")
        knot.SetTime(t)
        knot.SetValue(v)
        knot.SetNextInterpolation(Ts.InterpLinear)
        knots.SetKnot(knot)
    attr.SetSpline(knots)
    stage.GetRootLayer().Save()


def bake(src, frame, out):
    stage = Usd.Stage.Open(src)
    if stage is None:
        fail(f"{src}: cannot open")
    time = Usd.TimeCode(frame)
    values = {}
    for prim in stage.TraverseAll():
        for attr in prim.GetAttributes():
            if attr.GetNumTimeSamples() > 0:
                values[attr.GetPath()] = attr.Get(time)
    layer = stage.Flatten()
    for path, value in values.items():
        spec = layer.GetAttributeAtPath(path)
        if spec is None:
            fail(f"{path}: not in the flattened layer")
        spec.ClearInfo("timeSamples")
        if value is None:
            spec.default = Sdf.ValueBlock()
        elif isinstance(value, Sdf.AssetPath):
            spec.default = Sdf.AssetPath(value.resolvedPath or value.path)
        else:
            spec.default = value
    layer.ClearStartTimeCode()
    layer.ClearEndTimeCode()
    if not layer.Export(out):
        fail(f"{out}: cannot write")


def main(argv):
    if len(argv) >= 3 and argv[1] == "every-type":
        every_type(argv[2])
    elif len(argv) >= 3 and argv[1] == "sweep":
        sweep(argv[2])
    elif len(argv) >= 3 and argv[1] == "spline":
        spline(argv[2])
    elif len(argv) >= 5 and argv[1] == "bake":
        try:
            frame = float(argv[3])
        except ValueError:
            fail(f"bad frame '{argv[3]}'")
        bake(argv[2], frame, argv[4])
    else:
        fail("usage: every-type OUT | sweep OUT | spline OUT | bake IN FRAME OUT")


if __name__ == "__main__":
    try:
        main(sys.argv)
    except Exception as e:  # one line, never a traceback
        fail(" ".join(str(e).split()))
