//! Generated test scenes (for benchmarks and tests; not part of the stable API).

use std::fmt::Write as _;

/// A RIB scene of `materials` layered materials. Each material is three `PxrLayer`s wired by
/// placeholder connections (formats.md §3.5) into a `PxrLayerMixer` (`baselayer`, `layer1`,
/// `layer2`), which feeds a `PxrLayerSurface` through `inputMaterial`; each material is
/// wrapped in `AttributeBegin`/`AttributeEnd` with a few pass-through requests and a sphere.
/// Values vary with the material index so no two materials are identical.
///
/// ```
/// let rib = vstructc::network::testgen::layered_scene(2);
/// assert_eq!(rib.matches("Pattern \"PxrLayer\"").count(), 6);
/// assert_eq!(rib.matches("Bxdf \"PxrLayerSurface\"").count(), 2);
/// ```
pub fn layered_scene(materials: usize) -> String {
    let mut out = String::with_capacity(materials * 2600 + 256);
    out.push_str("##RenderMan RIB\nversion 3.04\n");
    out.push_str("Option \"ribparse\" \"string varsubst\" [\"\"]\n");
    out.push_str("Integrator \"PxrPathTracer\" \"integrator\" \"int maxPathLength\" [10]\n");
    out.push_str("WorldBegin\n");
    for m in 0..materials {
        write_material(&mut out, m);
    }
    out.push_str("WorldEnd\n");
    out
}

fn write_material(out: &mut String, m: usize) {
    // Values derived from the index; the exact numbers do not matter, only that they differ.
    let t = (m % 97) as f32 / 97.0;
    let _ = writeln!(out, "AttributeBegin");
    let _ = writeln!(
        out,
        "\tAttribute \"identifier\" \"string name\" [\"mesh{m}\"]"
    );
    for (l, name) in ["base", "top", "coat"].iter().enumerate() {
        let _ = writeln!(out, "\tPattern \"PxrLayer\" \"m{m}_{name}\"");
        let _ = writeln!(out, "\t\t\"int enableDiffuse\" [1]");
        let _ = writeln!(out, "\t\t\"float diffuseGain\" [{}]", 0.5 + t / 2.0);
        let _ = writeln!(
            out,
            "\t\t\"color diffuseColor\" [{} {} {}]",
            t,
            0.25 + l as f32 * 0.125,
            1.0 - t
        );
        let _ = writeln!(out, "\t\t\"int enableSpecular\" [{}]", (l + m) % 2);
        let _ = writeln!(out, "\t\t\"color specularFaceColor\" [0.04 0.04 0.04]");
        let _ = writeln!(out, "\t\t\"float specularRoughness\" [{}]", 0.1 + t / 4.0);
        let _ = writeln!(out, "\t\t\"int enableClearcoat\" [{}]", usize::from(l == 2));
        let _ = writeln!(out, "\t\t\"float clearcoatRoughness\" [0.05]");
        let _ = writeln!(out);
    }
    let _ = writeln!(out, "\tPattern \"PxrLayerMixer\" \"m{m}_mixer\"");
    let _ = writeln!(out, "\t\t\"int enableDiffuseAlways\" [1]");
    let _ = writeln!(
        out,
        "\t\t\"reference vstruct baselayer\" [\"m{m}_base:pxrMaterialOut\"]"
    );
    let _ = writeln!(out, "\t\t\"int layer1Enabled\" [1]");
    let _ = writeln!(
        out,
        "\t\t\"reference vstruct layer1\" [\"m{m}_top:pxrMaterialOut\"]"
    );
    let _ = writeln!(out, "\t\t\"float layer1Mask\" [{}]", 0.25 + t / 2.0);
    let _ = writeln!(out, "\t\t\"int layer2Enabled\" [1]");
    let _ = writeln!(
        out,
        "\t\t\"reference vstruct layer2\" [\"m{m}_coat:pxrMaterialOut\"]"
    );
    let _ = writeln!(out, "\t\t\"float layer2Mask\" [0.5]");
    let _ = writeln!(out);
    let _ = writeln!(out, "\tBxdf \"PxrLayerSurface\" \"m{m}_surface\"");
    let _ = writeln!(
        out,
        "\t\t\"reference float inputMaterial\" [\"m{m}_mixer:pxrMaterialOut\"]"
    );
    let _ = writeln!(out, "\t\t\"string __materialid\" [\"m{m}_SG\"]");
    let _ = writeln!(out, "\tSphere 1 -1 1 360");
    let _ = writeln!(out, "AttributeEnd");
}
