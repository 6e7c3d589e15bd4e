//! A generated scene of layered materials for benchmarks and tests, in resolved form:
//! per material three PxrLayers → one PxrLayerMixer → one PxrLayerSurface, with the member
//! connections and the `set` enable values that resolution writes (the shape of
//! `testgen::layered_scene`, built directly as a `SimpleGraph`).

use vstructc::lower::SimpleGraph;

const MEMBERS: [&str; 12] = [
    "diffuseGain",
    "diffuseColor",
    "diffuseRoughness",
    "specularFaceColor",
    "specularEdgeColor",
    "specularRoughness",
    "specularIor",
    "specularAnisotropy",
    "clearcoatFaceColor",
    "clearcoatEdgeColor",
    "clearcoatRoughness",
    "clearcoatIor",
];

/// `materials` layered materials; returns the graph and `(material name, surface node)`.
pub fn layered_scene(materials: usize) -> (SimpleGraph, Vec<(String, usize)>) {
    let mut g = SimpleGraph::new();
    let mut terminals = Vec::with_capacity(materials);
    for k in 0..materials {
        let x = (k % 97) as f32 / 97.0;
        let mut layers = [0usize; 3];
        for (i, l) in layers.iter_mut().enumerate() {
            let n = g.node(&format!("m{k}_layer{i}"), "PxrLayer");
            g.seti(n, "enableDiffuse", 1).seti(n, "enableSpecular", 1);
            g.seti(n, "enableClearcoat", i32::from(i == 2));
            g.setf(n, "diffuseGain", 1.0);
            g.setc(n, "diffuseColor", [x, 0.2 + 0.1 * i as f32, 0.5]);
            g.setf(n, "diffuseRoughness", 0.1 * i as f32);
            g.setf(n, "specularGain", 1.0)
                .setc(n, "specularFaceColor", [0.04; 3]);
            g.setc(n, "specularEdgeColor", [1.0; 3])
                .setf(n, "specularRoughness", 0.2 + 0.1 * x);
            g.setf(n, "clearcoatGain", 1.0)
                .setc(n, "clearcoatFaceColor", [0.04; 3]);
            g.setc(n, "clearcoatEdgeColor", [1.0; 3]);
            *l = n;
        }
        let mx = g.node(&format!("m{k}_mixer"), "PxrLayerMixer");
        for (i, (prefix, l)) in ["baselayer", "layer1", "layer2"]
            .iter()
            .zip(layers)
            .enumerate()
        {
            for m in MEMBERS {
                if m.starts_with("clearcoat") && i != 2 {
                    continue; // not connected: the layer's conditional is false
                }
                g.connect(
                    mx,
                    &format!("{prefix}_{m}"),
                    l,
                    &format!("pxrMaterialOut_{m}"),
                );
            }
            for x in ["Diffuse", "Specular"] {
                g.seti(mx, &format!("{prefix}_enable{x}"), 1);
            }
            g.seti(mx, &format!("{prefix}_enableClearcoat"), i32::from(i == 2));
        }
        g.seti(mx, "layer1Enabled", 1).setf(mx, "layer1Mask", 0.5);
        g.seti(mx, "layer2Enabled", 1)
            .setf(mx, "layer2Mask", 0.25 + 0.5 * x);
        let s = g.node(&format!("m{k}_surface"), "PxrLayerSurface");
        for m in MEMBERS {
            g.connect(s, m, mx, &format!("pxrMaterialOut_{m}"));
        }
        terminals.push((format!("material{k}"), s));
    }
    (g, terminals)
}
