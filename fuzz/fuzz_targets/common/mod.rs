//! The structure-aware network generator shared by the network fuzz targets.
//!
//! `arbitrary` picks node types, handles, values and connections (forward references,
//! self-connections, cycles, missing handles, fan-in up to 64 on one input, whole-node
//! references); the network is rendered as RIB text. Besides the embedded shaders it uses two
//! generated definitions, `FuzzLayer` (a vstruct output whose members carry long `and`/`or`
//! conditional chains, a `set` of a huge float and a `copy`) and `FuzzMixer` (its vstruct
//! input), so resolution evaluates long chains on values the fuzzer chooses.

use arbitrary::Arbitrary;
use std::fmt::Write as _;
use std::sync::LazyLock;
use vstructc::registry::Registry;

/// Most nodes in one generated network.
pub const MAX_NODES: usize = 1024;
/// Most connections on one input.
pub const MAX_FAN_IN: usize = 64;
/// Terms in each generated conditional chain.
pub const CHAIN_TERMS: usize = 4096;

/// The embedded definitions plus `FuzzLayer` and `FuzzMixer`.
pub static REGISTRY: LazyLock<Registry> = LazyLock::new(|| {
    let mut registry = Registry::embedded();
    registry
        .add_args_text("FuzzLayer", &fuzz_layer_args())
        .expect("FuzzLayer.args reads");
    registry
        .add_args_text("FuzzMixer", FUZZ_MIXER_ARGS)
        .expect("FuzzMixer.args reads");
    registry
});

/// `p0 == 1 and p1 == 1 and …` (or `or`), `CHAIN_TERMS` terms over the eight `p` inputs.
fn chain(op: &str) -> String {
    let mut text = String::from("connect if ");
    for k in 0..CHAIN_TERMS {
        if k > 0 {
            let _ = write!(text, " {op} ");
        }
        let _ = write!(text, "p{} == {}", k % 8, k % 3);
    }
    text
}

/// Mixed `and`/`or` with parentheses, still long.
fn mixed_chain() -> String {
    let mut text = String::from("set 1 if ");
    for k in 0..CHAIN_TERMS / 4 {
        if k > 0 {
            text.push_str(if k % 2 == 0 { " and " } else { " or " });
        }
        let _ = write!(text, "(p{} > 0 or p{} is connected)", k % 8, (k + 3) % 8);
    }
    text.push_str(" else set 0");
    text
}

fn fuzz_layer_args() -> String {
    let mut params = String::new();
    for k in 0..8 {
        let _ = writeln!(params, r#"  <param name="p{k}" type="float" default="0"/>"#);
    }
    let member = |name: &str, ty: &str, expr: &str| {
        format!(
            "  <output name=\"out_{name}\" vstructmember=\"out.{name}\" \
             vstructConditionalExpr=\"{expr}\"><tags><tag value=\"{ty}\"/></tags></output>\n"
        )
    };
    format!(
        "<args format=\"1.0\">\n  <shaderType><tag value=\"pattern\"/></shaderType>\n{params}\
         {}{}{}{}{}</args>\n",
        member("all", "float", &chain("and")),
        member("any", "float", &chain("or")),
        member("mixed", "int", &mixed_chain()),
        member("huge", "float", "set 1e39 if p0 == 1 else set -1e39"),
        member("copied", "float", "copy p1 if p2 != 0 else connect"),
    )
}

const FUZZ_MIXER_ARGS: &str = r#"<args format="1.0">
  <shaderType><tag value="pattern"/></shaderType>
  <param name="in" type="vstruct"/>
  <param name="in_all" type="float" vstructmember="in.all"/>
  <param name="in_any" type="float" vstructmember="in.any"/>
  <param name="in_mixed" type="int" vstructmember="in.mixed"/>
  <param name="in_huge" type="float" vstructmember="in.huge"/>
  <param name="in_copied" type="float" vstructmember="in.copied"/>
  <output name="out" vstructmember="out.all"><tags><tag value="float"/></tags></output>
  <output name="result"><tags><tag value="float"/></tags></output>
</args>
"#;

const SHADERS: &[&str] = &[
    "PxrLayer",
    "PxrLayerMixer",
    "PxrLayerSurface",
    "PxrSurface",
    "PxrDiffuse",
    "FuzzLayer",
    "FuzzMixer",
    "Unknown",
];
const INPUTS: &[(&str, &str)] = &[
    ("struct", "baselayer"),
    ("struct", "layer1"),
    ("struct", "layer2"),
    ("struct", "inputMaterial"),
    ("float", "diffuseGain"),
    ("float", "layer1Mask"),
    ("int", "enableDiffuse"),
    ("int", "layer1Enabled"),
    ("color", "baselayer_diffuseColor"),
    ("vstruct", "baselayer"),
    ("vstruct", "in"),
    ("float", "p0"),
    ("float", "p1"),
    ("float", "p2"),
    ("float", "p5"),
    ("float", "in_all"),
];
const OUTPUTS: &[&str] = &[
    "pxrMaterialOut",
    "pxrMaterialOut_diffuseColor",
    "resultF",
    "bxdf_out",
    "out",
    "out_huge",
    "",
];
/// Values the fuzzer may author: ordinary ones, and floats at the edges of f32.
const FLOATS: &[&str] = &[
    "0",
    "1",
    "-1",
    "0.5",
    "2",
    "3.4028235e38",
    "-3.4028235e38",
    "1e38",
    "1e-45",
    "1e-38",
];

/// One generated network.
#[derive(Debug, Arbitrary)]
pub struct Net {
    nodes: Vec<Node>,
    /// Resolve with `enableConditions = false`.
    pub no_conditions: bool,
}

#[derive(Debug, Arbitrary)]
struct Node {
    shader: u8,
    values: Vec<(u8, u8)>,
    links: Vec<Link>,
}

#[derive(Debug, Arbitrary)]
struct Link {
    input: u8,
    /// Index of the upstream node; may point forward, at itself, or past the end (missing).
    upstream: u16,
    output: u8,
    /// Extra connections on the same input (fan-in).
    fan: u8,
}

fn pick<T: Copy>(list: &[T], i: usize) -> T {
    list[i % list.len()]
}

impl Net {
    /// The network as RIB text.
    pub fn rib(&self) -> String {
        let mut out = String::from("WorldBegin\n");
        let n = self.nodes.len().min(MAX_NODES);
        for (i, node) in self.nodes.iter().take(n).enumerate() {
            node.write(i, n, &mut out);
        }
        out.push_str("WorldEnd\n");
        out
    }
}

impl Node {
    fn write(&self, i: usize, n: usize, out: &mut String) {
        let shader = pick(SHADERS, self.shader as usize);
        let request = if shader.contains("Surface") || shader == "PxrDiffuse" {
            "Bxdf"
        } else {
            "Pattern"
        };
        let _ = write!(out, "{request} \"{shader}\" \"n{i}\"");
        for &(input, v) in self.values.iter().take(8) {
            let (ty, name) = pick(INPUTS, input as usize);
            let v = pick(FLOATS, v as usize);
            match ty {
                "float" => {
                    let _ = write!(out, " \"float {name}\" [{v}]");
                }
                "int" => {
                    let _ = write!(out, " \"int {name}\" [{}]", v.len() % 3);
                }
                "color" => {
                    let _ = write!(out, " \"color {name}\" [{v} 0 1]");
                }
                _ => {}
            }
        }
        for link in self.links.iter().take(8) {
            link.write(n, out);
        }
        out.push('\n');
    }
}

impl Link {
    fn write(&self, n: usize, out: &mut String) {
        let (ty, name) = pick(INPUTS, self.input as usize);
        let fan = 1 + self.fan as usize % MAX_FAN_IN;
        let mut targets = String::new();
        for k in 0..fan {
            let up = (self.upstream as usize + k) % (n + 2);
            if k > 0 {
                targets.push(' ');
            }
            let _ = match pick(OUTPUTS, self.output as usize) {
                "" => write!(targets, "\"n{up}\""),
                o => write!(targets, "\"n{up}:{o}\""),
            };
        }
        let decl = if fan > 1 {
            format!("{ty}[{fan}]")
        } else {
            ty.to_string()
        };
        let _ = write!(out, " \"reference {decl} {name}\" [{targets}]");
    }
}
