#!/usr/bin/env python3
"""Check that Pixar's own USD library reads what vstructc writes (run by `.ci/run`).

    python3 -m venv /tmp/usd-core && /tmp/usd-core/bin/pip install usd-core
    cargo build
    /tmp/usd-core/bin/python tests/data/usd/pxr_check.py [target/debug/vstructc]

The script writes a small layered look with Pixar's USD (`pxr`), resolves it with vstructc
into `.usda` and binary `.usdc`, both flattened and as an override layer (`--usd-mode
over`), and into a flattened `.usdz` package, and opens each result with Pixar's USD (an
override layer composed with the look it sublayers): every
Shader keeps its `info:id`, the connections and input values Pixar's USD finds are exactly
those of vstructc's JSON output of the same resolution (member connections included), and
the Material's `outputs:ri:surface` leads to the surface. Then, for every look of the corpus
beside this script (conditions on and off), Pixar's USD finds the same connections and input
values in the override layer over the look as in the flattened output, in the `.usdc` and
`.usdz` outputs as in the `.usda` ones, and the flattened output gives every prim of the look
it holds the look's prim type.
Then strings: Pixar's USD writes a look whose inputs hold strings and asset paths with
quotes of both kinds, backslashes, tabs, line ends, control and non-ASCII characters (and
Windows paths), as `.usda` and `.usdc`; vstructc resolves it to `.usda` and `.usdc`,
directly and by way of RIB, and Pixar's USD reads back exactly the values it wrote. Last,
the `.usda` files of OpenUSD's own test suite in the fixtures (`../shared/fixtures/usd/
openusd`): vstructc opens and resolves each, and Pixar's USD finds in the output every
shader's `info:id`, input values and connections as it composes them from the file.
It exits with status 0 when every check holds. Not part of `cargo test`: usd-core is a
large download, which CI's Python step makes.
"""

import json
import os
import subprocess
import sys
import tempfile

from pxr import Gf, Sdf, Usd, UsdShade


def write_look(path):
    """Two PxrLayers mixed into a PxrLayerSurface, wired by vstruct heads only."""
    stage = Usd.Stage.CreateNew(path)
    material = UsdShade.Material.Define(stage, "/Looks/ball")

    def shader(name, shader_id):
        s = UsdShade.Shader.Define(stage, "/Looks/ball/" + name)
        s.CreateIdAttr(shader_id)
        return s

    base = shader("base", "PxrLayer")
    base.CreateInput("enableDiffuse", Sdf.ValueTypeNames.Int).Set(1)
    base.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(0.2, 0.5, 0.2))
    coat = shader("coat", "PxrLayer")
    coat.CreateInput("enableClearcoat", Sdf.ValueTypeNames.Int).Set(1)
    coat.CreateInput("clearcoatGain", Sdf.ValueTypeNames.Float).Set(1.0)
    mixer = shader("mixer", "PxrLayerMixer")
    out_type = Sdf.ValueTypeNames.Token
    mixer.CreateInput("baselayer", out_type).ConnectToSource(
        base.ConnectableAPI(), "pxrMaterialOut")
    mixer.CreateInput("layer1", out_type).ConnectToSource(
        coat.ConnectableAPI(), "pxrMaterialOut")
    mixer.CreateInput("layer1Enabled", Sdf.ValueTypeNames.Int).Set(1)
    mixer.CreateInput("layer1Mask", Sdf.ValueTypeNames.Float).Set(0.5)
    surface = shader("surface", "PxrLayerSurface")
    surface.CreateInput("inputMaterial", out_type).ConnectToSource(
        mixer.ConnectableAPI(), "pxrMaterialOut")
    surface.CreateOutput("out", out_type)
    material.CreateSurfaceOutput("ri").ConnectToSource(surface.ConnectableAPI(), "out")
    stage.GetRootLayer().Save()


def expected(vstructc, look):
    """The connections and authored input names vstructc's own JSON output of the same
    resolution holds: {(node, input, upstream node, upstream output)}, {(node, input)}."""
    run = subprocess.run([vstructc, "resolve", look, "--format", "json"],
                         capture_output=True, text=True, check=True)
    links, values = set(), set()
    for material in json.loads(run.stdout)["materials"].values():
        for handle, node in material["nodes"].items():
            for name, sources in node["inputConnections"].items():
                for src in sources:
                    links.add((handle, name, src["upstreamNode"], src["upstreamOutputName"]))
            values.update((handle, name) for name in node["parameters"])
    return links, values


def check(path, want_links, want_values):
    """Problems found in the resolved stage at `path`, as text."""
    problems = []
    stage = Usd.Stage.Open(path)
    if not stage:
        return ["Pixar's USD cannot open " + path]
    shaders = {}
    for prim in stage.Traverse():
        if prim.GetTypeName() == "Shader":
            shaders[str(prim.GetPath())] = UsdShade.Shader(prim)
    if len(shaders) != 4:
        problems.append("%d shaders, not 4" % len(shaders))
    links, values = set(), set()
    for name, s in shaders.items():
        if not s.GetShaderId():
            problems.append(name + " has no info:id")
        for inp in s.GetInputs():
            sources, invalid = inp.GetConnectedSources()
            if invalid:
                problems.append("%s.%s has invalid sources" % (name, inp.GetBaseName()))
            for src in sources:
                upstream = str(src.source.GetPrim().GetPath())
                if upstream not in shaders:
                    problems.append("%s.%s comes from %s" % (name, inp.GetBaseName(), upstream))
                links.add((name, inp.GetBaseName(), upstream, src.sourceName))
            if not sources and inp.Get() is not None:
                values.add((name, inp.GetBaseName()))
    if not any("_" in link[1] for link in links):
        problems.append("no member connections: the output is not resolved")
    for link in sorted(want_links - links):
        problems.append("missing connection %s.%s <- %s.%s" % link)
    for link in sorted(links - want_links):
        problems.append("unexpected connection %s.%s <- %s.%s" % link)
    for value in sorted(want_values ^ values):
        problems.append("value of %s.%s differs in presence" % value)
    material = UsdShade.Material(stage.GetPrimAtPath("/Looks/ball"))
    if not material:
        problems.append("no Material at /Looks/ball")
    else:
        source = material.ComputeSurfaceSource("ri")[0]
        if not source or str(source.GetPath()) != "/Looks/ball/surface":
            problems.append("outputs:ri:surface does not lead to /Looks/ball/surface")
    return problems


def shading(path):
    """What Pixar's USD finds on the stage at `path`: {(shader, input): the sorted shader
    outputs that feed it or the text of its value, found as UsdShade's
    GetValueProducingAttributes does (through node-graph interfaces)}, and {prim path:
    type name}."""
    stage = Usd.Stage.Open(path)
    inputs, types = {}, {}
    if not stage:
        return inputs, types
    for prim in stage.Traverse():
        types[str(prim.GetPath())] = prim.GetTypeName()
        if prim.GetTypeName() != "Shader":
            continue
        name = str(prim.GetPath())
        for inp in UsdShade.Shader(prim).GetInputs():
            sources, values = [], []
            for attr in inp.GetValueProducingAttributes():
                if UsdShade.Output.IsOutput(attr):
                    sources.append((str(attr.GetPrim().GetPath()), attr.GetBaseName()))
                elif attr.Get() is not None:
                    values.append(str(attr.Get()))
            if sources or values:
                inputs[(name, inp.GetBaseName())] = (sorted(sources), values)
    return inputs, types

def check_corpus(vstructc, tmp):
    """Problems found comparing the override layer with the flattened output of every
    corpus look, and the flattened output's prim types with the look's."""
    problems = []
    corpus = os.path.dirname(os.path.abspath(__file__))
    looks = sorted(f for f in os.listdir(corpus)
                   if f.endswith((".usda", ".usdc", ".usdz")) and f != "lib.usda")
    for look in looks:
        source = os.path.join(corpus, look)
        for flags in [[], ["--no-conditions"]]:
            at = "%s %s" % (look, " ".join(flags))
            flat = os.path.join(tmp, "flat.usda")
            outputs = [(flat, []), (os.path.join(tmp, "over.usda"), ["--usd-mode", "over"]),
                       (os.path.join(tmp, "flat.usdc"), []),
                       (os.path.join(tmp, "over.usdc"), ["--usd-mode", "over"]),
                       (os.path.join(tmp, "flat.usdz"), [])]
            runs = [subprocess.run([vstructc, "resolve", source, "-o", out] + flags + mode,
                                   capture_output=True, text=True)
                    for out, mode in outputs]
            failed = [r.stderr for r in runs if r.returncode != 0]
            if failed:
                problems.append("%s: vstructc failed:\n%s" % (at, failed[0]))
                continue
            flat_inputs, flat_types = shading(flat)
            look_inputs, look_types = shading(source)
            if flat_inputs == look_inputs:
                problems.append("%s: the output is the look: not resolved" % at)
            for out, _ in outputs[1:]:
                other, other_types = shading(out)
                if not other:
                    problems.append("%s: Pixar's USD finds no inputs in %s"
                                    % (at, os.path.basename(out)))
                for key in sorted(set(flat_inputs) | set(other)):
                    a, b = flat_inputs.get(key), other.get(key)
                    if a != b:
                        problems.append("%s: %s.%s is %s in flat.usda, %s in %s"
                                        % (at, key[0], key[1], a, b, os.path.basename(out)))
                if "flat" in out and other_types != flat_types:
                    problems.append("%s: %s has other prims or prim types than flat.usda"
                                    % (at, os.path.basename(out)))
            for path, t in sorted(flat_types.items()):
                if path in look_types and look_types[path] != t:
                    problems.append("%s: %s is a %r, not the look's %r"
                                    % (at, path, t, look_types[path]))
    return problems


# Strings Pixar's USD holds (a NUL aside: no crate file stores one).
STRINGS = [
    "it\\'s", "tab\there", "back\\slash", "C:\\tex\\a.tex", 'say "hi"', "it's",
    "both \" and '", 'three """ double', "three \'\'\' single", '""" and \'\'\'',
    'ends in "', "ends in '", "new\nline", "cr\rlf\r\n", "", "\\", "\\\\n\\t",
    "é ü 漢字 🎨", "\x01\x07\x1f\x7f", "\\x41 \\101", "end\\", "\"", "'",
]
ASSETS = ["C:\\tex\\a.tex", "\\\\server\\share\\b.tex", "./tex/c d.tex", "a@b.tex",
          "x@@@y.tex"]


def write_strings_look(path):
    """A PxrSurface whose inputs `s0`... hold STRINGS and `a0`... hold ASSETS."""
    stage = Usd.Stage.CreateNew(path)
    material = UsdShade.Material.Define(stage, "/Looks/strings")
    surface = UsdShade.Shader.Define(stage, "/Looks/strings/surface")
    surface.CreateIdAttr("PxrSurface")
    for i, text in enumerate(STRINGS):
        surface.CreateInput("s%d" % i, Sdf.ValueTypeNames.String).Set(text)
    for i, text in enumerate(ASSETS):
        surface.CreateInput("a%d" % i, Sdf.ValueTypeNames.Asset).Set(Sdf.AssetPath(text))
    surface.CreateOutput("out", Sdf.ValueTypeNames.Token)
    material.CreateSurfaceOutput("ri").ConnectToSource(surface.ConnectableAPI(), "out")
    stage.GetRootLayer().Save()


def string_values(path):
    """{input name: text} of the PxrSurface on the stage at `path` (an asset's path)."""
    stage = Usd.Stage.Open(path)
    if not stage:
        return None
    for prim in stage.Traverse():
        shader = UsdShade.Shader(prim)
        if prim.GetTypeName() == "Shader" and shader.GetShaderId() == "PxrSurface":
            values = {}
            for inp in shader.GetInputs():
                v = inp.Get()
                values[inp.GetBaseName()] = v.path if isinstance(v, Sdf.AssetPath) else v
            return values
    return {}


def check_strings(vstructc, tmp):
    """Problems found taking STRINGS and ASSETS through vstructc, as Pixar's USD reads them."""
    problems = []
    want = {"s%d" % i: t for i, t in enumerate(STRINGS)}
    want.update({"a%d" % i: t for i, t in enumerate(ASSETS)})
    look = os.path.join(tmp, "strings.usda")
    write_strings_look(look)
    binary = os.path.join(tmp, "strings-pixar.usdc")
    Sdf.Layer.FindOrOpen(look).Export(binary)
    if string_values(look) != want:
        problems.append("Pixar's USD does not read back the look it wrote")
    rib = os.path.join(tmp, "strings.rib")
    for source in [look, binary]:
        run = subprocess.run([vstructc, "resolve", source, "-o", rib], capture_output=True,
                             text=True)
        if run.returncode != 0:
            problems.append("%s to RIB: vstructc failed:\n%s" % (source, run.stderr))
            continue
        for via in [source, rib]:
            for ext in ["usda", "usdc"]:
                out = os.path.join(tmp, "strings-out." + ext)
                at = "%s%s to .%s" % (os.path.basename(source),
                                      " by way of RIB" if via == rib else "", ext)
                run = subprocess.run([vstructc, "resolve", via, "-o", out],
                                     capture_output=True, text=True)
                if run.returncode != 0:
                    problems.append("%s: vstructc failed:\n%s" % (at, run.stderr))
                    continue
                got = string_values(out)
                if got is None:
                    problems.append("%s: Pixar's USD cannot open the output" % at)
                    continue
                for name in sorted(want):
                    if got.get(name) != want[name]:
                        problems.append("%s: %s is %r, not %r" % (at, name, got.get(name),
                                                                   want[name]))
    return problems


def fixtures_dir():
    """`../shared/fixtures` beside the checkout, or None (an error under CI=true)."""
    here = os.path.dirname(os.path.abspath(__file__))
    path = os.path.normpath(os.path.join(here, "..", "..", "..", "..", "shared", "fixtures"))
    if os.path.isdir(path):
        return path
    if os.environ.get("CI") == "true":
        sys.exit("%s is missing (CI=true): the OpenUSD test files cannot be checked" % path)
    print("openusd files: NOT RUN (%s is missing)" % path)
    return None


def shader_ids(path):
    """{shader prim path: info:id} on the stage at `path`."""
    stage = Usd.Stage.Open(path)
    return {str(p.GetPath()): UsdShade.Shader(p).GetShaderId()
            for p in stage.Traverse() if p.GetTypeName() == "Shader"} if stage else {}


def check_pixar_files(vstructc, tmp):
    """Problems found resolving OpenUSD's own test files: Pixar's USD must find in the
    output the shaders, `info:id`s, input values and connections it composes from each."""
    fixtures = fixtures_dir()
    if fixtures is None:
        return []
    folder = os.path.join(fixtures, "usd", "openusd")
    files = sorted(f for f in os.listdir(folder) if f.endswith(".usda"))
    problems = [] if len(files) == 13 else ["%d OpenUSD files, not 13" % len(files)]
    for name in files:
        source = os.path.join(folder, name)
        want_ids, (want_inputs, _) = shader_ids(source), shading(source)
        if not want_ids:
            problems.append("%s: Pixar's USD finds no shaders" % name)
        for ext in ["usda", "usdc"]:
            out = os.path.join(tmp, "openusd." + ext)
            at = "%s to .%s" % (name, ext)
            run = subprocess.run([vstructc, "resolve", source, "-o", out],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                problems.append("%s: vstructc failed:\n%s" % (at, run.stderr))
                continue
            ids, (inputs, _) = shader_ids(out), shading(out)
            for shader in sorted(set(want_ids) | set(ids)):
                if want_ids.get(shader, "absent") != ids.get(shader, "absent"):
                    problems.append("%s: %s has info:id %r, not %r" % (
                        at, shader, ids.get(shader, "absent"), want_ids.get(shader, "absent")))
            for key in sorted(set(want_inputs) | set(inputs)):
                if want_inputs.get(key) != inputs.get(key):
                    problems.append("%s: %s.%s is %s, not %s" % (
                        at, key[0], key[1], inputs.get(key), want_inputs.get(key)))
    return problems


def main():
    vstructc = sys.argv[1] if len(sys.argv) > 1 else "target/debug/vstructc"
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        look = os.path.join(tmp, "look.usda")
        write_look(look)
        for mode, ext in [("flatten", "usda"), ("over", "usda"), ("flatten", "usdc"),
                          ("over", "usdc"), ("flatten", "usdz")]:
            out = os.path.join(tmp, "resolved-%s.%s" % (mode, ext))
            at = "%s .%s" % (mode, ext)
            run = subprocess.run([vstructc, "resolve", look, "--usd-mode", mode, "-o", out],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                print("%s: vstructc failed:\n%s" % (at, run.stderr))
                failed = True
                continue
            problems = check(out, *expected(vstructc, look))
            for p in problems:
                print("%s: %s" % (at, p))
            failed = failed or bool(problems)
            print("%s: %s" % (at, "FAILED" if problems else "ok"))
        for what, check_of in [("corpus", check_corpus), ("strings", check_strings),
                               ("openusd files", check_pixar_files)]:
            problems = check_of(vstructc, tmp)
            for p in problems:
                print("%s: %s" % (what, p))
            failed = failed or bool(problems)
            print("%s: %s" % (what, "FAILED" if problems else "ok"))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
