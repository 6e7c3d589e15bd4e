"""Read the RenderMan materials of a USD stage into a vstructc Network, resolve their vstruct
connections and print the resolved network as RIB, then the diagnostics.

    python python/examples/usd_materials.py [stage.usda]

Without a file it builds a small stage in memory (two PxrLayers mixed into a
PxrLayerSurface, each wired by one vstruct connection). Needs `usd-core` (`pip install
usd-core`); without it the script says so and exits 0.
"""

import sys

import vstructc

try:
    from pxr import Gf, Sdf, Usd, UsdShade
except ImportError:
    Gf = Sdf = Usd = UsdShade = None


def demo_stage():
    """Two PxrLayers mixed into a PxrLayerSurface, as a USD stage."""
    stage = Usd.Stage.CreateInMemory()
    mat = UsdShade.Material.Define(stage, "/Looks/ball")

    def shader(name, shader_id):
        s = UsdShade.Shader.Define(stage, f"/Looks/ball/{name}")
        s.SetShaderId(shader_id)
        return s

    base = shader("base", "PxrLayer")
    base.CreateInput("enableDiffuse", Sdf.ValueTypeNames.Int).Set(1)
    base.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.1, 0.4, 0.1))
    coat = shader("coat", "PxrLayer")
    coat.CreateInput("enableClearcoat", Sdf.ValueTypeNames.Int).Set(1)
    for layer in (base, coat):
        layer.CreateOutput("pxrMaterialOut", Sdf.ValueTypeNames.Token)
    mixer = shader("mixer", "PxrLayerMixer")
    mixer.CreateInput("layer1Enabled", Sdf.ValueTypeNames.Int).Set(1)
    mixer.CreateInput("baselayer", Sdf.ValueTypeNames.Token).ConnectToSource(
        base.ConnectableAPI(), "pxrMaterialOut"
    )
    mixer.CreateInput("layer1", Sdf.ValueTypeNames.Token).ConnectToSource(
        coat.ConnectableAPI(), "pxrMaterialOut"
    )
    mixer.CreateOutput("pxrMaterialOut", Sdf.ValueTypeNames.Token)
    surface = shader("surface", "PxrLayerSurface")
    surface.CreateInput("inputMaterial", Sdf.ValueTypeNames.Token).ConnectToSource(
        mixer.ConnectableAPI(), "pxrMaterialOut"
    )
    surface.CreateOutput("bxdf_out", Sdf.ValueTypeNames.Token)
    mat.CreateSurfaceOutput("ri").ConnectToSource(surface.ConnectableAPI(), "bxdf_out")
    return stage


def plain(value):
    """A USD attribute value as a value vstructc takes (int, float, str, tuple, list)."""
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (int, float, str)):
        return value
    if isinstance(value, Sdf.AssetPath):
        return value.path
    if hasattr(value, "__len__"):
        return [plain(v) for v in value] if not isinstance(value, tuple) else tuple(value)
    return str(value)


def network_from_stage(stage, reg):
    """Every UsdShade material with a RenderMan surface (outputs:ri:surface), as one network
    whose node handles are the shader prims' paths."""
    net = vstructc.Network(reg)
    for prim in stage.Traverse():
        if not prim.IsA(UsdShade.Material):
            continue
        material = UsdShade.Material(prim)
        shaders = [
            UsdShade.Shader(p) for p in Usd.PrimRange(prim) if p.IsA(UsdShade.Shader)
        ]
        for s in shaders:
            net.add_node(str(s.GetPath()), s.GetShaderId() or "")
        for s in shaders:
            handle = str(s.GetPath())
            for inp in s.GetInputs():
                if inp.HasConnectedSource():
                    source, output, _ = inp.GetConnectedSource()
                    net.connect(handle, inp.GetBaseName(), str(source.GetPath()), output)
                    continue
                value = inp.Get()
                if value is None:
                    continue
                if isinstance(value, (Gf.Vec3f, Gf.Vec3d)):
                    value = tuple(float(x) for x in value)
                net.set_param(handle, inp.GetBaseName(), plain(value))
        out = material.GetSurfaceOutput("ri")
        if out and out.HasConnectedSource():
            source, _, _ = out.GetConnectedSource()
            net.add_material(prim.GetName(), surface=str(source.GetPath()))
    return net


def main(argv):
    if Usd is None:
        print("usd-core (pxr) is not installed: pip install usd-core", file=sys.stderr)
        return 0
    stage = Usd.Stage.Open(argv[1]) if len(argv) > 1 else demo_stage()
    reg = vstructc.Registry(env=True)
    net = network_from_stage(stage, reg)
    diags = vstructc.resolve(net, reg)
    sys.stdout.write(net.to_rib())
    for d in diags:
        print(d, file=sys.stderr)
    return 1 if any(d.severity == "error" for d in diags) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
