"""What bridges need beyond building and resolving: editing a network (disconnect, remove a
parameter, change a node's shader), sampling a material, explaining a value, the pipeline's
options and limits, and the panic guard."""

import json
import os
import struct
import subprocess

import pytest

import vstructc

from test_vstructc import SCENE, built


def f32(obj):
    """`obj` with every float rounded to float32 (the command prints the shortest decimal of
    a 32-bit float, Python holds its double)."""
    if isinstance(obj, float):
        return struct.unpack("f", struct.pack("f", obj))[0]
    if isinstance(obj, dict):
        return {k: f32(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [f32(v) for v in obj]
    return obj


# --- Editing a network ---------------------------------------------------------------


def test_disconnect(reg):
    net = vstructc.Network(reg)
    for h in ("a", "b"):
        net.add_node(h, "PxrLayer")
    net.add_node("m", "PxrLayerMixer")
    net.connect("m", "baselayer", "a", "pxrMaterialOut")
    net.connect("m", "layer1", "a", "pxrMaterialOut")
    net.connect("m", "layer1", "b", "pxrMaterialOut")
    assert net.disconnect("m", "layer1", up="b") == 1
    assert ("layer1", "a", "pxrMaterialOut") in net.connections("m")
    assert net.disconnect("m", "layer1", up="a", output="other") == 0
    assert net.disconnect("m", "layer1", up="a", output="pxrMaterialOut") == 1
    assert net.disconnect("m", "nothing") == 0
    assert [c[0] for c in net.connections("m")] == ["baselayer"]
    with pytest.raises(KeyError):
        net.disconnect("missing", "layer1")
    with pytest.raises(KeyError):
        net.disconnect("m", "layer1", up="missing")
    # Resolution expanded baselayer into member connections; removing one is a change.
    vstructc.resolve(net, reg)
    assert net.disconnect("m", "nothing") == 0 and net.resolved
    member = net.connections("m")[0][0]
    assert net.disconnect("m", member) == 1
    assert not net.resolved
    assert all(c[0] != member for c in net.connections("m"))


def test_remove_param(reg):
    net = built(reg)
    net.remove_param("base", "diffuseColor")
    assert net.value("base", "diffuseColor") is None
    net.remove_param("mixer", "baselayer")  # a connection
    assert all(c[0] != "baselayer" for c in net.connections("mixer"))
    net.remove_param("mixer", "notAParam")  # nothing to remove
    rib = net.to_rib()
    assert "diffuseColor" not in rib and '"reference vstruct baselayer"' not in rib
    with pytest.raises(KeyError):
        net.remove_param("missing", "x")


def test_adding_a_handle_again_changes_its_shader(reg):
    net = vstructc.Network(reg)
    net.add_node("n", "PxrLayer")
    net.add_node("n", "PxrSurface")  # a new version: the shader changes
    assert net.nodes() == [("n", "PxrLayer"), ("n", "PxrSurface")]
    net.set_param("n", "diffuseGain", 0.5)  # the new version
    rib = net.to_rib()
    assert rib.index('Pattern "PxrLayer" "n"') < rib.index('Bxdf "PxrSurface" "n"')
    assert rib.index('Bxdf "PxrSurface" "n"') < rib.index('"float diffuseGain" [0.5]')


# --- Materials --------------------------------------------------------------------------


def layered(repo, reg):
    """The layered example's material: a diffuse, a specular and a clear coat lobe."""
    text = (repo / "examples" / "layered.rib").read_bytes()
    return vstructc.compile(vstructc.Network.from_rib(text, reg), reg)[0]


def test_sample(repo, reg):
    m = layered(repo, reg)
    lobes = m.lobes()
    assert len(lobes) == 3
    seen = set()
    n = 8
    for i in range(n):
        for j in range(n):
            s = m.sample(wo=(0, 0, 1), u=((i + 0.5) / n, (j + 0.5) / n, 0.37))
            if s is None:
                continue
            assert set(s) == {"wi", "weight", "pdf", "delta", "lobe"}
            assert sum(c * c for c in s["wi"]) == pytest.approx(1.0, rel=1e-4)
            assert s["pdf"] > 0
            seen.add(s["lobe"])
            if not s["delta"]:
                # weight = f·cos / pdf, both as eval() gives them for that direction.
                e = m.eval(wo=(0, 0, 1), wi=s["wi"])
                assert e["pdf"] == pytest.approx(s["pdf"], rel=1e-3)
                for k in range(3):
                    assert s["weight"][k] == pytest.approx(e["total"][k] / e["pdf"], rel=1e-3)
    # The first number picks the lobe: every lobe is reached.
    assert seen == set(range(len(lobes)))
    with pytest.raises(ValueError):
        m.sample(wo=(0, 0, 1), u=(1.0, 0.5, 0.5))
    with pytest.raises(ValueError):
        m.sample(wo=(0, 0, 0), u=(0.5, 0.5, 0.5))


# --- Explain ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "example,target",
    [
        ("chain.rib", "car.clearcoatFaceColor"),
        ("chain.rib", "finished.layer1_enableClearcoat"),
        ("chain.rib", "dusty.baselayer_diffuseColor"),
        ("layered.rib", "surface.diffuseColor"),
        ("layered.rib", "mixer.layer1_enableClearcoat"),
    ],
)
def test_explain_is_the_command_lines_document(repo, reg, cli, example, target):
    path = repo / "examples" / example
    env = dict(os.environ)
    env.pop("VSTRUCTC_ARGS_PATH", None)
    out = subprocess.run(
        [cli, "explain", target, str(path), "--json"],
        capture_output=True,
        env=env,
        check=True,
    ).stdout
    expected = json.loads(out)
    net = vstructc.Network.from_rib(path.read_bytes(), reg, name=str(path))
    handle, _, input = target.rpartition(".")
    story = vstructc.explain(net, reg, handle, input)
    assert f32(story) == f32(expected)
    assert story["events"] or story["upstream"]
    assert not net.resolved  # a copy was resolved
    assert net.to_rib_bytes() == path.read_bytes()


def test_explain_errors(reg):
    net = built(reg)
    with pytest.raises(KeyError):
        vstructc.explain(net, reg, "missing", "x")
    with pytest.raises(ValueError):
        vstructc.explain(net, reg, "mixer", "noSuchInput")
    story = vstructc.explain(net, reg, "mixer", "layer1_enableClearcoat", conditions=False)
    assert story["origin"] == "resolved"
    assert story["events"][0]["conditional"] is None  # conditions off: none evaluated


# --- Options and limits ---------------------------------------------------------------------


def test_default_limits():
    d = vstructc.default_limits()
    assert d["nodes"] == 1 << 24 and d["expr_depth"] == 64
    assert set(d) == {
        "definition_file_bytes",
        "network_file_bytes",
        "nodes",
        "connections_per_input",
        "params_per_node",
        "expr_terms",
        "expr_depth",
        "preview_pixels",
    }


def test_limits_are_applied(reg, repo):
    with pytest.raises(vstructc.LimitError) as e:
        vstructc.Network.from_rib(SCENE, reg, limits={"nodes": 2})
    assert e.value.diagnostics[-1].code == "LM001"
    with pytest.raises(vstructc.LimitError):
        vstructc.Network.from_rib(SCENE, reg, limits={"network_file_bytes": 10})
    with pytest.raises(vstructc.LimitError):
        vstructc.Network.from_json(built(reg).to_json(), reg, limits={"nodes": 2})
    net = built(reg)
    with pytest.raises(vstructc.LimitError) as e:
        vstructc.resolve(net, reg, limits={"nodes": 3})
    assert not net.resolved and net.value("mixer", "layer1_enableClearcoat") is None
    vstructc.resolve(net, reg, limits={"nodes": 4})
    with pytest.raises(vstructc.LimitError):
        vstructc.compile(built(reg), reg, limits={"nodes": 3})
    small = vstructc.Registry(
        paths=[repo / "args" / "PxrLayer.args"],
        embedded=False,
        limits={"definition_file_bytes": 100},
    )
    assert small.definition("PxrLayer") is None
    assert any(d.code == "LM001" for d in small.diagnostics())
    m = vstructc.compile(built(reg), reg)[0]
    with pytest.raises(vstructc.LimitError):
        m.render(size=16, limits={"preview_pixels": 255})
    assert m.render(size=16, limits={"preview_pixels": 256}).width == 16
    with pytest.raises(ValueError):
        vstructc.resolve(built(reg), reg, limits={"node": 5})
    with pytest.raises(TypeError):
        vstructc.resolve(built(reg), reg, limits={"nodes": -1})


def test_strict_rib(reg):
    text = "Pattern 'PxrLayer' 'a'\n"
    loose = vstructc.Network.from_rib(text, reg)
    assert any(d.code == "RB011" and d.severity == "info" for d in loose.diagnostics)
    with pytest.raises(vstructc.InputError) as e:
        vstructc.Network.from_rib(text, reg, strict=True)
    assert e.value.diagnostics[-1].code == "RB011"


def test_drop_unresolved(reg):
    kept = vstructc.Network.from_rib(SCENE, reg)
    vstructc.resolve(kept, reg)
    assert ("layer1", "notALayer", "pxrMaterialOut") in kept.connections("mixer")
    dropped = vstructc.Network.from_rib(SCENE, reg)
    diags = vstructc.resolve(dropped, reg, drop_unresolved=True)
    assert any(d.code == "VS010" for d in diags)
    assert all(c[0] != "layer1" for c in dropped.connections("mixer"))
    assert any(c[0].startswith("baselayer_") for c in dropped.connections("mixer"))


UP = """<args format="1.0"><shaderType><tag value="pattern"/></shaderType>
  <output name="out"><tags><tag value="vstruct"/></tags></output>
  <output name="out_a" vstructmember="out.a"><tags><tag value="float"/></tags></output>
</args>"""

DOWN = """<args format="1.0"><shaderType><tag value="bxdf"/></shaderType>
  <param name="inputMaterial" type="float"><tags><tag value="vstruct"/></tags></param>
  <param name="p_a" type="float" vstructmember="inputMaterial.a"/>
  <param name="p_zzz" type="float" vstructmember="inputMaterial.zzz"/>
</args>"""


def test_verbose_adds_notes():
    """A downstream member without upstream counterpart is a note (VS021) only when
    verbose."""
    r = vstructc.Registry(embedded=False)
    r.add_args_text("Up", UP)
    r.add_args_text("Down", DOWN)

    def net():
        n = vstructc.Network(r)
        n.add_node("U", "Up")
        n.add_node("D", "Down")
        n.connect("D", "inputMaterial", "U", "out")
        return n

    quiet = vstructc.resolve(net(), r)
    loud = vstructc.resolve(net(), r, verbose=True)
    assert not any(d.code == "VS021" for d in quiet)
    notes = [d for d in loud if d.code == "VS021"]
    assert len(notes) == 1 and notes[0].severity == "note" and notes[0].param == "p_zzz"


# --- The panic guard ----------------------------------------------------------------------


def test_a_panic_becomes_an_error():
    """A Rust panic arrives as vstructc.Error, and the module keeps working. The hook exists
    only in a build with the `test-hooks` feature (CI's); CI sets VSTRUCTC_TEST_HOOKS=1 so
    that a build without it fails here instead of skipping."""
    hook = getattr(vstructc, "_panic_for_test", None)
    if hook is None:
        if os.environ.get("VSTRUCTC_TEST_HOOKS") == "1":
            pytest.fail("VSTRUCTC_TEST_HOOKS=1 but the module was built without test-hooks")
        pytest.skip("the module was built without the test-hooks feature")
    with pytest.raises(vstructc.Error) as e:
        hook("boom at the test hook")
    assert "internal error in vstructc: boom at the test hook" in str(e.value)
    assert e.value.diagnostics == []
    with pytest.raises(vstructc.Error):
        hook("again")
    assert vstructc.Registry().shaders()


def test_view_defaults_to_the_normal(repo, reg):
    m = layered(repo, reg)
    assert m.lobes() == m.lobes(wo=(0, 0, 1)) == m.lobes(None)
    assert m.albedo() == m.albedo(wo=(0, 0, 2))
    assert m.lobes(wo=(1, 0, 0.2)) != m.lobes()  # the view matters
