//! Helpers shared by the network, RIB and JSON tests.
#![allow(dead_code)]

use vstructc::network::{Network, NodeId, ParamTypes, Upstream};
use vstructc::{BaseType, Diagnostics, Type, Value};

/// A canonical, order-independent description of a network: per node (sorted by key) its
/// shader, kind and every live parameter (sorted by name) with value and connections.
pub fn summary(net: &Network) -> Vec<String> {
    let mut out = Vec::new();
    let mut ids: Vec<NodeId> = net.node_ids().collect();
    ids.sort_by(|a, b| net[*a].key().cmp(net[*b].key()));
    for id in ids {
        let n = &net[id];
        out.push(format!("{} {} {}", n.key(), n.kind(), n.shader()));
        for p in n.params_by_name() {
            let mut line = format!("  {}", p.name());
            if p.is_connected() {
                let links: Vec<String> = p
                    .connections()
                    .iter()
                    .map(|l| {
                        let up = match l.upstream() {
                            Upstream::Node(u) => net[u].key().to_string(),
                            Upstream::Missing(h) => format!("<missing {h}>"),
                        };
                        format!("{up}:{}", l.output().unwrap_or("<node>"))
                    })
                    .collect();
                line.push_str(&format!(" <- {}", links.join(", ")));
            } else if let Some(v) = p.value() {
                line.push_str(&format!(" = {}", value_text(v)));
            }
            out.push(line);
        }
    }
    out
}

/// A value with its type, exactly (floats by bit pattern when needed).
pub fn value_text(v: &Value) -> String {
    format!("{:?}", v)
}

/// Codes of all diagnostics, in order.
pub fn codes(d: &Diagnostics) -> Vec<&'static str> {
    d.iter().map(|x| x.code.as_str()).collect()
}

/// Named, typed properties in declaration order.
pub type Props = Vec<(String, Type)>;

/// A small in-test definition table: (shader, inputs in declaration order, outputs).
pub struct Table {
    pub shaders: Vec<(String, Props, Props)>,
}

impl Table {
    pub fn new() -> Self {
        Table {
            shaders: Vec::new(),
        }
    }
    pub fn shader(mut self, id: &str, inputs: &[(&str, &str)], outputs: &[(&str, &str)]) -> Self {
        let conv = |list: &[(&str, &str)]| {
            list.iter()
                .map(|(n, t)| (n.to_string(), parse_type(t)))
                .collect::<Vec<_>>()
        };
        self.shaders
            .push((id.to_string(), conv(inputs), conv(outputs)));
        self
    }
    fn find(&self, id: &str) -> Option<&(String, Props, Props)> {
        self.shaders.iter().find(|s| s.0 == id)
    }
}

/// `float`, `color`, `vstruct`, `int[]`, `float[2]`, …
pub fn parse_type(t: &str) -> Type {
    if let Some(base) = t.strip_suffix("[]") {
        return Type {
            base: BaseType::from_word(base),
            array: vstructc::ArraySpec::Dynamic,
        };
    }
    if let Some((base, n)) = t.strip_suffix(']').and_then(|s| s.split_once('[')) {
        return Type {
            base: BaseType::from_word(base),
            array: vstructc::ArraySpec::Fixed(n.parse().unwrap()),
        };
    }
    Type::parse_decl(t)
}

impl ParamTypes for Table {
    fn shader_known(&self, shader: &str) -> bool {
        self.find(shader).is_some()
    }
    fn input_type(&self, shader: &str, input: &str) -> Option<Type> {
        let s = self.find(shader)?;
        s.1.iter().find(|(n, _)| n == input).map(|(_, t)| t.clone())
    }
    fn output_type(&self, shader: &str, output: &str) -> Option<Type> {
        let s = self.find(shader)?;
        s.2.iter()
            .find(|(n, _)| n == output)
            .map(|(_, t)| t.clone())
    }
    fn input_position(&self, shader: &str, input: &str) -> Option<usize> {
        let s = self.find(shader)?;
        s.1.iter().position(|(n, _)| n == input)
    }
}
