"""Resolve the vstruct connections of a RIB file and print, for each material, the member
connections resolution made (input <- upstream node.output), then the diagnostics.

    python python/examples/resolve_rib.py examples/layered.rib
"""

import sys

import vstructc


def member_inputs(reg, shader):
    """The inputs of `shader` that are vstruct members."""
    d = reg.definition(shader)
    if d is None:
        return set()
    return {p["name"] for p in d["inputs"] if p["vstruct"] is not None}


def main(argv):
    if len(argv) != 2:
        print(f"usage: {argv[0]} scene.rib", file=sys.stderr)
        return 2
    reg = vstructc.Registry(env=True)
    with open(argv[1], "rb") as f:
        try:
            net = vstructc.Network.from_rib(f.read(), reg, name=argv[1])
        except vstructc.Error as e:
            for d in e.diagnostics:
                print(d, file=sys.stderr)
            return 1
    diags = vstructc.resolve(net, reg)
    shaders = dict(net.nodes())
    for m in net.materials():
        print(f"material {m['name']}")
        for handle in m["nodes"]:
            members = member_inputs(reg, shaders[handle])
            for name, up, output in net.connections(handle):
                if name in members:
                    print(f"  {handle}.{name} <- {up}.{output or ''}")
    for d in diags:
        print(d, file=sys.stderr)
    return 1 if any(d.severity == "error" for d in diags) else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
