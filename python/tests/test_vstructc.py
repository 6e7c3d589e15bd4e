"""The Python API: registry, networks (read, built, written), resolution and its
diagnostics, errors, compiled materials and images."""

import importlib.util
import json
import os
import struct
import subprocess
import sys
import threading

import pytest

import vstructc

# A layer mixed into a surface, and a mixer input wired to a node that has no
# pxrMaterialOut: resolution keeps that placeholder and reports VS010 on mixer.layer1.
SCENE = """##RenderMan RIB
version 3.04
WorldBegin
\tAttributeBegin
\t\tPattern "PxrLayer" "base"
\t\t\t"int enableDiffuse" [1]
\t\t\t"color diffuseColor" [0.2 0.5 0.2]
\t\tPattern "vsConstant" "notALayer"
\t\tPattern "PxrLayerMixer" "mixer"
\t\t\t"reference vstruct baselayer" ["base:pxrMaterialOut"]
\t\t\t"int layer1Enabled" [1]
\t\t\t"reference vstruct layer1" ["notALayer:pxrMaterialOut"]
\t\tBxdf "PxrLayerSurface" "surface"
\t\t\t"reference vstruct inputMaterial" ["mixer:pxrMaterialOut"]
\t\tSphere 1 -1 1 360
\tAttributeEnd
WorldEnd
"""


def built(reg=None):
    """The issue's example network: two layers, a mixer and a surface."""
    net = vstructc.Network(reg)
    net.add_node("base", "PxrLayer")
    net.set_param("base", "diffuseColor", (0.1, 0.4, 0.1))
    net.set_param("base", "enableDiffuse", 1)
    net.add_node("coat", "PxrLayer")
    net.set_param("coat", "enableClearcoat", 1)
    net.add_node("mixer", "PxrLayerMixer")
    net.set_param("mixer", "layer1Enabled", 1)
    net.add_node("surface", "PxrLayerSurface", kind="bxdf")
    net.connect("mixer", "baselayer", "base", "pxrMaterialOut")
    net.connect("mixer", "layer1", "coat", "pxrMaterialOut")
    net.connect("surface", "inputMaterial", "mixer", "pxrMaterialOut")
    net.add_material("mat", surface="surface")
    return net


def test_version():
    assert vstructc.__version__ == "0.1.0"


def test_error_classes():
    assert issubclass(vstructc.InputError, vstructc.Error)
    assert issubclass(vstructc.LimitError, vstructc.Error)
    assert issubclass(vstructc.Error, Exception)
    assert vstructc.Error("x").diagnostics == ()


# --- Registry ------------------------------------------------------------------------


def test_registry_lists_embedded_shaders(reg):
    shaders = reg.shaders()
    assert "PxrLayer" in shaders and "PxrLayerMixer" in shaders
    assert shaders == sorted(shaders)
    assert vstructc.Registry(embedded=False).shaders() == []


def test_registry_paths_are_searched(repo):
    only = vstructc.Registry(paths=[repo / "args" / "PxrLayer.args"], embedded=False)
    assert only.shaders() == ["PxrLayer"]
    d = only.definition("PxrLayer")
    assert d["path"].endswith("PxrLayer.args") and d["source"] == "args"


def test_registry_prefer_is_checked():
    assert vstructc.Registry(prefer="args").shaders()
    with pytest.raises(ValueError):
        vstructc.Registry(prefer="osl")


def test_definition_has_vstruct_heads_members_and_conditionals(reg):
    d = reg.definition("PxrLayerMixer")
    assert d["name"] == "PxrLayerMixer" and d["kind"] == "pattern"
    inputs = {p["name"]: p for p in d["inputs"]}
    outputs = {p["name"]: p for p in d["outputs"]}
    assert inputs["baselayer"]["vstruct_head"] is True
    assert inputs["layer1Enabled"]["type"] == "int"
    assert inputs["layer1Enabled"]["vstruct_head"] is False
    member = outputs["pxrMaterialOut_enableDiffuse"]["vstruct"]
    assert member["head"] == "pxrMaterialOut" and member["member"] == "enableDiffuse"
    assert member["conditional"].startswith("set 1 if")
    assert reg.definition("NoSuchShader") is None


def test_add_args_text_and_its_errors():
    r = vstructc.Registry(embedded=False)
    r.add_args_text(
        "Tiny",
        '<args format="1.0"><shaderType><tag value="pattern"/></shaderType>'
        '<param name="x" type="float" default="0.5"/>'
        '<output name="out"><tags><tag value="float"/></tags></output></args>',
    )
    assert r.shaders() == ["Tiny"]
    assert r.definition("Tiny")["inputs"][0]["default"] == 0.5
    with pytest.raises(vstructc.Error) as e:
        r.add_args_text("Broken", "<args><param name=")
    assert isinstance(e.value, vstructc.InputError)
    assert e.value.diagnostics and e.value.diagnostics[0].severity == "error"
    assert isinstance(r.diagnostics(), list)


# --- Networks built in code ----------------------------------------------------------


def test_built_network_resolves(reg):
    net = built(reg)
    assert net.nodes() == [
        ("base", "PxrLayer"),
        ("coat", "PxrLayer"),
        ("mixer", "PxrLayerMixer"),
        ("surface", "PxrLayerSurface"),
    ]
    assert net.value("mixer", "layer1_enableClearcoat") is None
    assert not net.resolved
    diags = vstructc.resolve(net, reg)
    assert net.resolved
    assert all(d.severity != "error" for d in diags)
    assert net.value("mixer", "layer1_enableClearcoat") == 1
    net.set_param("coat", "enableClearcoat", 0)
    assert not net.resolved  # a change after resolution: compile resolves again
    net.set_param("coat", "enableClearcoat", 1)
    vstructc.resolve(net, reg)
    conns = net.connections("surface")
    assert ("inputMaterial", "mixer", "pxrMaterialOut") not in conns
    assert any(c[0] == "diffuseColor" and c[1] == "mixer" for c in conns)
    assert net.materials() == [
        {
            "name": "mat",
            "terminals": {"surface": "surface"},
            "nodes": net.materials()[0]["nodes"],
        }
    ]
    assert set(net.materials()[0]["nodes"]) == {"base", "coat", "mixer", "surface"}


def test_set_param_types(reg):
    net = vstructc.Network(reg)
    net.add_node("n", "PxrLayer")
    net.set_param("n", "diffuseGain", 1)  # declared float: an int is widened
    assert net.value("n", "diffuseGain") == 1.0 and isinstance(net.value("n", "diffuseGain"), float)
    net.set_param("n", "diffuseColor", [0.5, 0.25, 1])
    assert net.value("n", "diffuseColor") == (0.5, 0.25, 1.0)
    net.set_param("n", "custom", (1.0, 2.0, 3.0), type="vector")
    net.set_param("n", "names", ["a", "b"])
    assert net.value("n", "names") == ["a", "b"]
    net.set_param("n", "weights", [1, 2.5], type="float[2]")
    assert net.value("n", "weights") == [1.0, 2.5]
    with pytest.raises(TypeError):
        net.set_param("n", "diffuseColor", "red")
    with pytest.raises(ValueError):
        net.set_param("n", "diffuseColor", (1, 2))
    with pytest.raises(ValueError):
        net.set_param("n", "x", 1, type="nosuchtype")
    with pytest.raises(ValueError):
        net.set_param("n", "weights", [1.0], type="float[2]")
    with pytest.raises(KeyError):
        net.set_param("missing", "x", 1)
    with pytest.raises(KeyError):
        net.connect("n", "baselayer", "missing", "pxrMaterialOut")
    with pytest.raises(KeyError):
        net.value("missing", "x")


def test_add_node_kind(reg):
    net = vstructc.Network(reg)
    net.add_node("s", "PxrSurface")  # the definition says bxdf
    net.add_node("p", "PxrLayer")
    rib = net.to_rib()
    assert 'Bxdf "PxrSurface" "s"' in rib and 'Pattern "PxrLayer" "p"' in rib
    with pytest.raises(ValueError):
        net.add_node("x", "PxrLayer", kind="shader")


def test_to_json_round_trips(reg):
    net = built(reg)
    vstructc.resolve(net, reg)
    text = net.to_json()
    json.loads(text)
    again = vstructc.Network.from_json(text, reg)
    assert again.value("mixer", "layer1_enableClearcoat") == 1
    loose = vstructc.Network()
    loose.add_node("n", "PxrLayer")
    with pytest.raises(vstructc.Error):
        loose.to_json()  # nodes but no material: they would be lost


# --- Networks read from text, diagnostics, errors -----------------------------------


def test_resolve_diagnostics_fields(reg):
    net = vstructc.Network.from_rib(SCENE, reg, name="scene.rib")
    diags = vstructc.resolve(net, reg)
    vs010 = [d for d in diags if d.code == "VS010"]
    assert len(vs010) == 1
    d = vs010[0]
    assert (d.node, d.param) == ("mixer", "layer1")
    assert d.severity in ("error", "warning", "info", "note")
    assert d.file == "scene.rib" and d.line == 12 and isinstance(d.column, int)
    assert d.meaning and d.message and "VS010" in str(d) and "VS010" in repr(d)
    assert d.pointer is None and isinstance(d.notes, list)
    # The placeholder stays, the good layer is expanded.
    conns = net.connections("mixer")
    assert ("layer1", "notALayer", "pxrMaterialOut") in conns
    assert any(c[0].startswith("baselayer_") for c in conns)


def test_built_network_diagnostics_have_no_position(reg):
    net = vstructc.Network(reg)
    net.add_node("s", "NoSuchShader")
    diags = vstructc.resolve(net, reg)
    d = next(d for d in diags if d.code == "VS020")
    assert d.file is None and d.line is None and d.column is None


def test_resolve_options(reg):
    net = built(reg)
    vstructc.resolve(net, reg, conditions=False, ext=["all"])
    with pytest.raises(ValueError):
        vstructc.resolve(built(reg), reg, ext=["no-such-extension"])


def test_malformed_rib_raises_with_diagnostics(reg):
    with pytest.raises(vstructc.Error) as e:
        vstructc.Network.from_rib('Pattern "PxrLayer" "a" "int x" [1', reg, name="bad.rib")
    assert isinstance(e.value, vstructc.InputError)
    d = e.value.diagnostics[-1]
    assert d.severity == "error" and d.file == "bad.rib" and d.line == 1
    assert d.code.startswith("RB")


def test_malformed_json_raises_with_pointer(reg):
    with pytest.raises(vstructc.InputError) as e:
        vstructc.Network.from_json('{"materials": 3}', reg, name="bad.json")
    assert e.value.diagnostics[-1].code.startswith("JS")
    with pytest.raises(TypeError):
        vstructc.Network.from_json(3, reg)


def test_rib_bytes_input_and_output(reg):
    net = vstructc.Network.from_rib(SCENE.encode(), reg)
    assert net.to_rib_bytes() == SCENE.encode()  # nothing resolved yet: byte for byte
    vstructc.resolve(net, reg)
    assert net.to_rib_bytes().decode() == net.to_rib()


def test_examples_round_trip_like_the_command_line(repo, reg, cli):
    examples = sorted((repo / "examples").glob("*.rib"))
    assert examples
    env = dict(os.environ)
    env.pop("VSTRUCTC_ARGS_PATH", None)
    for path in examples:
        expected = subprocess.run(
            [cli, "resolve", str(path)], capture_output=True, env=env, check=False
        ).stdout
        net = vstructc.Network.from_rib(path.read_bytes(), reg, name=str(path))
        vstructc.resolve(net, reg)
        assert net.to_rib_bytes() == expected, path.name


# --- Materials and images -------------------------------------------------------------


def test_compile_resolves_first_and_evaluates(reg):
    net = built(reg)
    diags = []
    mats = vstructc.compile(net, reg, diagnostics=diags)
    assert net.resolved
    assert [m.name for m in mats] == ["mat"] and mats[0].recipe == "pxr_surface"
    assert all(isinstance(d, vstructc.Diagnostic) for d in diags)
    m = mats[0]
    lobes = m.lobes()
    assert lobes and {"kind", "label", "weight"} <= set(lobes[0])
    e = m.eval(wo=(0, 0, 1), wi=(0.5, 0, 0.8))
    assert all(c > 0 for c in e["total"])
    # The total is the sum of the lobes' weighted values.
    for i in range(3):
        parts = sum(l["weight"][i] * l["f_cos"][i] for l in e["lobes"])
        assert e["total"][i] == pytest.approx(parts, rel=1e-4)
    assert e["pdf"] > 0 and len(e["lobes"]) == len(lobes)
    below = m.eval(wo=(0, 0, 1), wi=(0.5, 0, -0.8))
    assert below["total"] == (0.0, 0.0, 0.0)
    a = m.albedo(wo=(0, 0, 1))
    assert all(0 < c < 1 for c in a["reflect"]) and set(a) == {"reflect", "transmit"}
    with pytest.raises(ValueError):
        m.eval(wo=(0, 0, 0), wi=(0, 0, 1))
    assert "mat" in repr(m)


def test_compile_selects_a_material(reg):
    net = built(reg)
    assert [m.name for m in vstructc.compile(net, reg, material="mat")] == ["mat"]
    with pytest.raises(vstructc.Error) as e:
        vstructc.compile(net, reg, material="nope")
    assert e.value.diagnostics


def test_render_and_save(reg, tmp_path):
    m = vstructc.compile(built(reg), reg)[0]
    img = m.render(size=16)
    assert (img.width, img.height) == (16, 16)
    assert len(img.pixels) == 256
    raw = img.tobytes()
    assert len(raw) == 256 * 12
    assert struct.unpack_from("=3f", raw, 0) == pytest.approx(img.pixels[0])
    img.save(tmp_path / "ball.png")
    assert (tmp_path / "ball.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img.save(str(tmp_path / "ball.pfm"))
    assert (tmp_path / "ball.pfm").read_bytes()[:2] == b"PF"
    img.save(tmp_path / "ball.exr")
    assert (tmp_path / "ball.exr").read_bytes()[:4] == b"\x76\x2f\x31\x01"
    with pytest.raises(ValueError):
        img.save(tmp_path / "ball.jpg")
    furnace = m.render(size=8, furnace=True)
    assert max(max(p) for p in furnace.pixels) <= 1.0 + 1e-2
    with pytest.raises(vstructc.Error):
        m.render(size=0)


def test_to_numpy(reg):
    img = vstructc.compile(built(reg), reg)[0].render(size=8)
    if importlib.util.find_spec("numpy") is None:
        with pytest.raises(ImportError):
            img.to_numpy()
        return
    import numpy as np

    a = img.to_numpy()
    assert a.shape == (8, 8, 3) and a.dtype == np.float32
    assert tuple(a[0, 0]) == pytest.approx(img.pixels[0])


def test_long_calls_release_the_gil(reg):
    """Another thread runs while one renders: the render releases the GIL. A long switch
    interval keeps the interpreter from handing the GIL over on its own, so a call that held
    it would let the other thread count nothing."""
    m = vstructc.compile(built(reg), reg)[0]
    stop = threading.Event()
    count = [0]

    def spin():
        while not stop.is_set():
            count[0] += 1

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1.0)
    t = threading.Thread(target=spin)
    try:
        t.start()
        before = count[0]
        m.render(size=256)
        during = count[0] - before
    finally:
        stop.set()
        t.join()
        sys.setswitchinterval(interval)
    assert during > 1000


def test_resolve_rib_example(repo):
    script = repo / "python" / "examples" / "resolve_rib.py"
    out = subprocess.run(
        [sys.executable, str(script), str(repo / "examples" / "layered.rib")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "material layeredMaterial"
    assert "  surface.diffuseColor <- mixer.pxrMaterialOut_diffuseColor" in lines
    assert "  mixer.baselayer_diffuseColor <- greenBase.pxrMaterialOut_diffuseColor" in lines


def test_usd_example(repo):
    """With usd-core, the USD example reads a stage's materials into a network and resolves
    it; without, it says what is missing and exits 0."""
    script = repo / "python" / "examples" / "usd_materials.py"
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, check=False)
    assert out.returncode == 0, out.stderr
    if importlib.util.find_spec("pxr") is None:
        assert "usd-core" in out.stderr and out.stdout == ""
        return
    assert 'Bxdf "PxrLayerSurface" "/Looks/ball/surface"' in out.stdout
    assert (
        '"reference color diffuseColor" ["/Looks/ball/mixer:pxrMaterialOut_diffuseColor"]'
        in out.stdout
    )
    assert '"int layer1_enableClearcoat" [1]' in out.stdout
