//! The registry as the source of declared parameter types for the network readers and the
//! RIB writer ([`crate::network::ParamTypes`]).

use super::Registry;
use crate::network::{ParamTypes, RequestKind};
use crate::types::Type;

impl ParamTypes for Registry {
    fn shader_known(&self, shader: &str) -> bool {
        self.definition(shader).is_some()
    }

    fn input_type(&self, shader: &str, input: &str) -> Option<Type> {
        Some(self.indexed(shader)?.input(input)?.ty.clone())
    }

    fn output_type(&self, shader: &str, output: &str) -> Option<Type> {
        Some(self.indexed(shader)?.output(output)?.ty.clone())
    }

    fn input_position(&self, shader: &str, input: &str) -> Option<usize> {
        self.indexed(shader)?.input_position(input)
    }

    fn shader_kind(&self, shader: &str) -> Option<RequestKind> {
        Some(match self.definition(shader)?.kind.as_str() {
            "bxdf" | "surface" | "volume" => RequestKind::Bxdf,
            "displace" | "displacement" | "displacementShader" => RequestKind::Displace,
            "light" => RequestKind::Light,
            "lightFilter" | "lightfilter" => RequestKind::LightFilter,
            "pattern" => RequestKind::Pattern,
            _ => return None,
        })
    }

    fn is_input_head(&self, shader: &str, input: &str) -> bool {
        self.tables(shader).is_some_and(|t| t.is_input_head(input))
    }

    fn is_output_head(&self, shader: &str, output: &str) -> bool {
        self.tables(shader)
            .is_some_and(|t| t.is_output_head(output))
    }
}
