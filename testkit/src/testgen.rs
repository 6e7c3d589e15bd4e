//! Generated test scenes (for benchmarks and tests; not part of the stable API).

use std::fmt::Write as _;

/// A RIB scene of `materials` layered materials. Each material is three `PxrLayer`s wired by
/// placeholder connections into a `PxrLayerMixer` (`baselayer`, `layer1`,
/// `layer2`), which feeds a `PxrLayerSurface` through `inputMaterial`; each material is
/// wrapped in `AttributeBegin`/`AttributeEnd` with a few pass-through requests and a sphere.
/// Values vary with the material index so no two materials are identical.
///
/// ```
/// let rib = vstructc_testkit::testgen::layered_scene(2);
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

/// The scene shapes whose cost must grow linearly with their size `n` (each is a network in
/// which one thing is shared by, or holds, `n` others). Used by the `scale` bench and test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// One `PxrLayer` read by `n` `PxrLayerMixer`s, each feeding its own `PxrLayerSurface`.
    SharedLayer,
    /// One `PxrLayerMixer` read by `n` `PxrLayerSurface`s.
    SharedMixer,
    /// One input head with `n` connections (fan-in), from `n` `PxrLayer`s.
    FanIn,
    /// One `Bxdf` handle defined `n` times.
    RedefinedBxdf,
    /// An `.args` definition with `n` parameters, and a node setting each of them.
    ArgsParams,
    /// An `.args` definition with `n` input heads and `n` output heads, and one node
    /// connecting every input head to another's output head.
    ArgsHeads,
    /// [`Shape::ArgsParams`] with the `.args` file and the node's parameters each written
    /// on one line, as generated files often are (positions far into a line).
    ArgsParamsOneLine,
    /// [`Shape::ArgsHeads`] with the `.args` file and the node's connections each written
    /// on one line.
    ArgsHeadsOneLine,
}

/// A generated scene: RIB text and, for the `.args` shapes, one extra definition.
#[derive(Debug, Clone)]
pub struct ShapeScene {
    /// The RIB scene.
    pub rib: String,
    /// `(shader id, .args text)` of a definition the scene needs besides the embedded ones.
    pub args: Option<(String, String)>,
}

impl Shape {
    /// Every shape.
    pub const ALL: [Shape; 8] = [
        Shape::SharedLayer,
        Shape::SharedMixer,
        Shape::FanIn,
        Shape::RedefinedBxdf,
        Shape::ArgsParams,
        Shape::ArgsHeads,
        Shape::ArgsParamsOneLine,
        Shape::ArgsHeadsOneLine,
    ];

    /// A short name (bench ids, messages).
    pub fn name(self) -> &'static str {
        match self {
            Shape::SharedLayer => "shared_layer",
            Shape::SharedMixer => "shared_mixer",
            Shape::FanIn => "fan_in",
            Shape::RedefinedBxdf => "redefined_bxdf",
            Shape::ArgsParams => "args_params",
            Shape::ArgsHeads => "args_heads",
            Shape::ArgsParamsOneLine => "args_params_one_line",
            Shape::ArgsHeadsOneLine => "args_heads_one_line",
        }
    }

    /// The scene of size `n`.
    ///
    /// ```
    /// use vstructc_testkit::testgen::Shape;
    /// let s = Shape::SharedMixer.scene(3);
    /// assert_eq!(s.rib.matches("Bxdf \"PxrLayerSurface\"").count(), 3);
    /// assert!(Shape::ArgsHeads.scene(2).args.is_some());
    /// let one = Shape::ArgsParamsOneLine.scene(3);
    /// assert_eq!(one.args.unwrap().1.lines().count(), 1);
    /// ```
    pub fn scene(self, n: usize) -> ShapeScene {
        let mut rib = String::with_capacity(n * 160 + 256);
        rib.push_str("##RenderMan RIB\nversion 3.04\nWorldBegin\n");
        let mut args = None;
        match self {
            Shape::SharedLayer => {
                layer(&mut rib, "L", 0.5);
                for i in 0..n {
                    mixer(&mut rib, &format!("mix{i}"), &["L"]);
                    surface(&mut rib, &format!("S{i}"), &format!("mix{i}"));
                }
            }
            Shape::SharedMixer => {
                layer(&mut rib, "L", 0.5);
                mixer(&mut rib, "mix", &["L"]);
                for i in 0..n {
                    surface(&mut rib, &format!("S{i}"), "mix");
                }
            }
            Shape::FanIn => {
                let handles: Vec<String> = (0..n).map(|i| format!("L{i}")).collect();
                for (i, h) in handles.iter().enumerate() {
                    layer(&mut rib, h, (i % 97) as f32 / 97.0);
                }
                let refs: Vec<&str> = handles.iter().map(String::as_str).collect();
                mixer(&mut rib, "mix", &refs);
                surface(&mut rib, "S", "mix");
            }
            Shape::RedefinedBxdf => {
                for i in 0..n {
                    let _ = writeln!(rib, "Bxdf \"PxrSurface\" \"S\"");
                    let _ = writeln!(rib, "\t\"float diffuseGain\" [{}]", (i % 97) as f32 / 97.0);
                }
            }
            Shape::ArgsParams => {
                let mut text = String::from("<args format=\"1.0\">\n");
                for i in 0..n {
                    let _ = writeln!(
                        text,
                        "  <param name=\"p{i}\" type=\"float\" default=\"0\"/>"
                    );
                }
                text.push_str("  <output name=\"result\" type=\"float\"/>\n</args>\n");
                let _ = writeln!(rib, "Pattern \"Wide\" \"w\"");
                for i in 0..n {
                    let _ = writeln!(rib, "\t\"float p{i}\" [{}]", (i % 97) as f32 / 97.0);
                }
                args = Some(("Wide".to_string(), text));
            }
            Shape::ArgsHeads => {
                let mut text = String::from("<args format=\"1.0\">\n");
                for i in 0..n {
                    let _ = writeln!(text, "  <param name=\"in{i}\" type=\"vstruct\"/>");
                    let _ = writeln!(
                        text,
                        "  <param name=\"in{i}_v\" type=\"float\" default=\"0\" vstructmember=\"in{i}.v\"/>"
                    );
                }
                for i in 0..n {
                    let _ = writeln!(text, "  <output name=\"out{i}\" type=\"vstruct\"/>");
                    let _ = writeln!(
                        text,
                        "  <output name=\"out{i}_v\" type=\"float\" vstructmember=\"out{i}.v\"/>"
                    );
                }
                text.push_str("</args>\n");
                let _ = writeln!(rib, "Pattern \"Heads\" \"up\"");
                let _ = writeln!(rib, "Pattern \"Heads\" \"down\"");
                for i in 0..n {
                    let _ = writeln!(rib, "\t\"reference vstruct in{i}\" [\"up:out{i}\"]");
                }
                args = Some(("Heads".to_string(), text));
            }
            Shape::ArgsParamsOneLine => return one_line(Shape::ArgsParams.scene(n)),
            Shape::ArgsHeadsOneLine => return one_line(Shape::ArgsHeads.scene(n)),
        }
        rib.push_str("WorldEnd\n");
        ShapeScene { rib, args }
    }
}

/// `scene` with its `.args` text on one line and each RIB request on one line: a request's
/// parameter lines joined by spaces (RIB and XML read the same either way).
fn one_line(scene: ShapeScene) -> ShapeScene {
    let mut rib = String::with_capacity(scene.rib.len());
    for line in scene.rib.lines() {
        match line.strip_prefix('\t') {
            Some(param) => {
                rib.push(' ');
                rib.push_str(param);
            }
            None => {
                if !rib.is_empty() {
                    rib.push('\n');
                }
                rib.push_str(line);
            }
        }
    }
    rib.push('\n');
    let args = scene.args.map(|(id, text)| {
        let one: Vec<&str> = text.lines().map(str::trim).collect();
        (id, one.concat())
    });
    ShapeScene { rib, args }
}

fn layer(out: &mut String, handle: &str, t: f32) {
    let _ = writeln!(out, "Pattern \"PxrLayer\" \"{handle}\"");
    let _ = writeln!(out, "\t\"int enableDiffuse\" [1]");
    let _ = writeln!(out, "\t\"float diffuseGain\" [{t}]");
    let _ = writeln!(out, "\t\"int enableClearcoat\" [1]");
}

/// A mixer whose `baselayer` reads the `pxrMaterialOut` of every handle in `bases`.
fn mixer(out: &mut String, handle: &str, bases: &[&str]) {
    let _ = writeln!(out, "Pattern \"PxrLayerMixer\" \"{handle}\"");
    let refs: Vec<String> = bases
        .iter()
        .map(|b| format!("\"{b}:pxrMaterialOut\""))
        .collect();
    let decl = match bases.len() {
        1 => "vstruct".to_string(),
        k => format!("vstruct[{k}]"),
    };
    let _ = writeln!(out, "\t\"reference {decl} baselayer\" [{}]", refs.join(" "));
}

fn surface(out: &mut String, handle: &str, mixer: &str) {
    let _ = writeln!(out, "Bxdf \"PxrLayerSurface\" \"{handle}\"");
    let _ = writeln!(
        out,
        "\t\"reference float inputMaterial\" [\"{mixer}:pxrMaterialOut\"]"
    );
}

/// A RIB chain of `n` pattern nodes, each reading the previous one's output.
///
/// ```
/// let rib = vstructc_testkit::testgen::pattern_chain(3);
/// assert_eq!(rib.matches("Pattern ").count(), 3);
/// ```
pub fn pattern_chain(n: usize) -> String {
    let mut out = String::with_capacity(n * 90 + 64);
    out.push_str("##RenderMan RIB\nversion 3.04\nWorldBegin\n");
    for i in 0..n {
        let _ = writeln!(out, "Pattern \"vsClamp\" \"c{i}\"");
        if i > 0 {
            let _ = writeln!(
                out,
                "\t\"reference color input\" [\"c{}:resultRGB\"]",
                i - 1
            );
        }
    }
    out.push_str("WorldEnd\n");
    out
}
