//! What the network readers and writers need to know about shader definitions.
//!
//! The RIB and JSON readers need declared parameter types (decls without an inline type,
//! JSON shorthand values, RB016 checks) and the RIB writer needs the declaration order of a
//! node type's inputs (new parameters are appended in that order). Rather than depending on
//! the registry directly, they ask through [`ParamTypes`]; the registry implements it, and
//! [`NoDefinitions`] stands for "no definitions loaded".

use crate::types::{BaseType, Type};
use rustc_hash::FxHashMap;
use std::cell::RefCell;

/// Type information about shader definitions, as the network readers and writers need it.
///
/// All lookups are by shader id (`PxrLayer`) and property name. Inputs and outputs have
/// separate namespaces.
///
/// # Example
///
/// A tiny implementation over a fixed table, as a test might write it:
///
/// ```
/// use vstructc::network::ParamTypes;
/// use vstructc::{BaseType, Type};
///
/// struct OneShader;
/// impl ParamTypes for OneShader {
///     fn shader_known(&self, shader: &str) -> bool {
///         shader == "PxrExposure"
///     }
///     fn input_type(&self, shader: &str, input: &str) -> Option<Type> {
///         match (shader, input) {
///             ("PxrExposure", "stops") => Some(Type::scalar(BaseType::Float)),
///             ("PxrExposure", "inputRGB") => Some(Type::scalar(BaseType::Color)),
///             _ => None,
///         }
///     }
///     fn output_type(&self, shader: &str, output: &str) -> Option<Type> {
///         (shader == "PxrExposure" && output == "resultRGB").then(|| Type::scalar(BaseType::Color))
///     }
/// }
/// assert!(OneShader.is_output_head("PxrExposure", "resultRGB") == false);
/// assert_eq!(OneShader.input_position("PxrExposure", "stops"), None);
/// ```
pub trait ParamTypes {
    /// Whether any definitions are available at all. When `false`, checks that compare a
    /// network against definitions (RB016, RB019) are skipped instead of firing on every
    /// node. Defaults to `true`.
    fn has_definitions(&self) -> bool {
        true
    }

    /// True if a definition for `shader` exists.
    fn shader_known(&self, shader: &str) -> bool;

    /// The declared type of input `input` of `shader` (after head normalisation: `Vstruct`
    /// for input heads), or `None` if the shader or the input is unknown.
    fn input_type(&self, shader: &str, input: &str) -> Option<Type>;

    /// The declared type of output `output` of `shader`, or `None` if unknown.
    fn output_type(&self, shader: &str, output: &str) -> Option<Type>;

    /// The position of `input` among `shader`'s inputs in declaration order (0-based), or
    /// `None` if unknown. The RIB writer appends new parameters in this order; parameters
    /// without a position follow in the order they were added. Defaults to `None`.
    fn input_position(&self, shader: &str, input: &str) -> Option<usize> {
        let _ = (shader, input);
        None
    }

    /// The request kind `shader`'s definition states (`Bxdf` for a bxdf, `Displace` for a
    /// displacement shader, …), or `None` when unknown. Readers without request keywords
    /// (USD) and writers that need them (RIB) use it. Defaults to `None`.
    fn shader_kind(&self, shader: &str) -> Option<crate::network::RequestKind> {
        let _ = shader;
        None
    }

    /// True if `input` is an input head (a vstruct placeholder input) of `shader`. Defaults
    /// to "declared type is `Vstruct`", which is what the registry's head normalisation gives.
    fn is_input_head(&self, shader: &str, input: &str) -> bool {
        matches!(
            self.input_type(shader, input),
            Some(Type {
                base: BaseType::Vstruct,
                ..
            })
        )
    }

    /// True if `output` is an output head of `shader`. Defaults to "declared type is
    /// `Vstruct`".
    fn is_output_head(&self, shader: &str, output: &str) -> bool {
        matches!(
            self.output_type(shader, output),
            Some(Type {
                base: BaseType::Vstruct,
                ..
            })
        )
    }
}

/// No definitions: every lookup answers "unknown" and definition checks are skipped.
///
/// ```
/// use vstructc::network::{NoDefinitions, ParamTypes};
/// assert!(!NoDefinitions.has_definitions());
/// assert_eq!(NoDefinitions.input_type("PxrSurface", "diffuseGain"), None);
/// ```
#[derive(Debug, Clone, Copy, Default)]
pub struct NoDefinitions;

impl ParamTypes for NoDefinitions {
    fn has_definitions(&self) -> bool {
        false
    }
    fn shader_known(&self, _shader: &str) -> bool {
        false
    }
    fn input_type(&self, _shader: &str, _input: &str) -> Option<Type> {
        None
    }
    fn output_type(&self, _shader: &str, _output: &str) -> Option<Type> {
        None
    }
}

impl<T: ParamTypes + ?Sized> ParamTypes for &T {
    fn has_definitions(&self) -> bool {
        (**self).has_definitions()
    }
    fn shader_known(&self, shader: &str) -> bool {
        (**self).shader_known(shader)
    }
    fn input_type(&self, shader: &str, input: &str) -> Option<Type> {
        (**self).input_type(shader, input)
    }
    fn output_type(&self, shader: &str, output: &str) -> Option<Type> {
        (**self).output_type(shader, output)
    }
    fn input_position(&self, shader: &str, input: &str) -> Option<usize> {
        (**self).input_position(shader, input)
    }
    fn is_input_head(&self, shader: &str, input: &str) -> bool {
        (**self).is_input_head(shader, input)
    }
    fn is_output_head(&self, shader: &str, output: &str) -> bool {
        (**self).is_output_head(shader, output)
    }
}

/// What a [`Memo`] remembers about one input or output of one shader: each answer once it
/// was asked for (asking only what the caller asks keeps the wrapped registry's work, and so
/// its diagnostics, what they would be without the memo).
#[derive(Clone, Default)]
struct Known {
    ty: Option<Option<Type>>,
    position: Option<Option<usize>>,
    head: Option<bool>,
}

/// Which question a [`Memo`] is asked about a property.
#[derive(Clone, Copy)]
enum Ask {
    Type,
    Position,
    Head,
}

/// Per shader id, per property name: what the wrapped [`ParamTypes`] answered.
type Answers = rustc_hash::FxHashMap<Box<str>, rustc_hash::FxHashMap<Box<str>, Known>>;

/// A [`ParamTypes`] that asks another one each question once per shader and property and
/// then answers from memory (crate-internal: the RIB reader and writer ask for every
/// parameter of every node, a registry look-up costs a lock and reference counting each
/// time, and a scene repeats a few shader types many times).
pub(crate) struct Memo<'t> {
    inner: &'t dyn ParamTypes,
    shaders: RefCell<FxHashMap<Box<str>, bool>>,
    inputs: RefCell<Answers>,
    outputs: RefCell<Answers>,
}

impl<'t> Memo<'t> {
    /// Remembers the answers of `inner`.
    pub(crate) fn new(inner: &'t dyn ParamTypes) -> Memo<'t> {
        Memo {
            inner,
            shaders: RefCell::default(),
            inputs: RefCell::default(),
            outputs: RefCell::default(),
        }
    }

    /// The answer to `ask` about input (or output) `name` of `shader`, asking `inner` the
    /// first time.
    fn known(&self, input: bool, shader: &str, name: &str, ask: Ask) -> Known {
        let cell = if input { &self.inputs } else { &self.outputs };
        // The usual case: asked before, answered without copying the other answers.
        if let Some(k) = cell.borrow().get(shader).and_then(|m| m.get(name)) {
            let answered = match ask {
                Ask::Type => k.ty.as_ref().map(|ty| Known {
                    ty: Some(ty.clone()),
                    ..Known::default()
                }),
                Ask::Position => k.position.map(|position| Known {
                    position: Some(position),
                    ..Known::default()
                }),
                Ask::Head => k.head.map(|head| Known {
                    head: Some(head),
                    ..Known::default()
                }),
            };
            if let Some(answer) = answered {
                return answer;
            }
        }
        let mut k = cell
            .borrow()
            .get(shader)
            .and_then(|m| m.get(name))
            .cloned()
            .unwrap_or_default();
        let missing = match ask {
            Ask::Type => k.ty.is_none(),
            Ask::Position => k.position.is_none(),
            Ask::Head => k.head.is_none(),
        };
        if !missing {
            return k;
        }
        let inner = self.inner;
        match (ask, input) {
            (Ask::Type, true) => k.ty = Some(inner.input_type(shader, name)),
            (Ask::Type, false) => k.ty = Some(inner.output_type(shader, name)),
            (Ask::Position, true) => k.position = Some(inner.input_position(shader, name)),
            (Ask::Position, false) => k.position = Some(None),
            (Ask::Head, true) => k.head = Some(inner.is_input_head(shader, name)),
            (Ask::Head, false) => k.head = Some(inner.is_output_head(shader, name)),
        }
        let mut map = cell.borrow_mut();
        if !map.contains_key(shader) {
            map.insert(Box::from(shader), FxHashMap::default());
        }
        if let Some(m) = map.get_mut(shader) {
            match m.get_mut(name) {
                Some(slot) => *slot = k.clone(),
                None => {
                    m.insert(Box::from(name), k.clone());
                }
            }
        }
        k
    }
}

impl ParamTypes for Memo<'_> {
    fn has_definitions(&self) -> bool {
        self.inner.has_definitions()
    }
    fn shader_known(&self, shader: &str) -> bool {
        if let Some(&known) = self.shaders.borrow().get(shader) {
            return known;
        }
        let known = self.inner.shader_known(shader);
        self.shaders.borrow_mut().insert(Box::from(shader), known);
        known
    }
    fn input_type(&self, shader: &str, input: &str) -> Option<Type> {
        self.known(true, shader, input, Ask::Type).ty.flatten()
    }
    fn output_type(&self, shader: &str, output: &str) -> Option<Type> {
        self.known(false, shader, output, Ask::Type).ty.flatten()
    }
    fn input_position(&self, shader: &str, input: &str) -> Option<usize> {
        self.known(true, shader, input, Ask::Position)
            .position
            .flatten()
    }
    fn is_input_head(&self, shader: &str, input: &str) -> bool {
        self.known(true, shader, input, Ask::Head).head == Some(true)
    }
    fn is_output_head(&self, shader: &str, output: &str) -> bool {
        self.known(false, shader, output, Ask::Head).head == Some(true)
    }
}
