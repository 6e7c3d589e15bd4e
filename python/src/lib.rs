//! Python bindings of vstructc: a [`Registry`] of shader definitions, shader [`Network`]s
//! read from RIB or JSON or built in code, vstruct resolution with its diagnostics, and
//! compiled materials that evaluate and render previews.
//!
//! Every call into the library runs under [`guarded`]: a panic becomes `vstructc.Error`
//! instead of crossing into Python. Long calls (reading a network, resolving, compiling,
//! rendering, writing) release the GIL.
//!
//! Test hook: built with the cargo feature `test-hooks` (CI builds the module with it
//! through `MATURIN_PEP517_ARGS="--features test-hooks"`), the module has a private
//! `_panic_for_test(message)` that panics inside [`guarded`], so the tests can show that a
//! panic arrives as `vstructc.Error`. A default build (`pip install ./python`) has no such
//! function.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::pybacked::{PyBackedBytes, PyBackedStr};
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::Arc;
use vstructc::back::json::write_json;
use vstructc::back::png::ImageFormat;
use vstructc::back::rib::write_rib;
use vstructc::cond::Extensions;
use vstructc::front::{NetFormat, ReadOptions, read_network};
use vstructc::glam::Vec3;
use vstructc::interp::ShadingPoint;
use vstructc::interp::preview::{PreviewOptions, render_ball};
use vstructc::limits::Limits;
use vstructc::network::{NoDefinitions, NodeId, ParamTypes, RequestKind};
use vstructc::pipeline::Lowering;
use vstructc::registry::{Prefer, RegistryOptions};
use vstructc::{ArraySpec, BaseType, Diagnostics, Type, Value};

mod story;

create_exception!(
    vstructc,
    Error,
    PyException,
    "A vstructc error. `.diagnostics` holds the diagnostics that explain it."
);
create_exception!(
    vstructc,
    InputError,
    Error,
    "Malformed input (a network or definition text); `.diagnostics[0]` says where."
);
create_exception!(
    vstructc,
    LimitError,
    Error,
    "A bound on sizes or counts was exceeded (code LM001)."
);

/// Runs `f`, turning a panic into an error message (no panic crosses into Python).
fn guarded<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_string());
        format!("internal error in vstructc: {what}")
    })
}

/// `vstructc.Error` (or `cls`) with `message` and `diagnostics` as `.diagnostics`.
fn raise_with<E: pyo3::PyTypeInfo>(
    py: Python<'_>,
    message: String,
    diagnostics: Vec<vstructc::Diagnostic>,
) -> PyErr {
    let err = PyErr::new::<E, _>(message);
    let list: Vec<Diagnostic> = diagnostics.into_iter().map(Diagnostic::from).collect();
    match PyList::new(py, list) {
        Ok(list) => {
            if let Err(e) = err.value(py).setattr("diagnostics", list) {
                return e;
            }
            err
        }
        Err(e) => e,
    }
}

/// A library error as the matching Python exception.
fn lib_error(py: Python<'_>, e: vstructc::Error) -> PyErr {
    let message = e.to_string();
    let diag = e.to_diagnostic();
    match e {
        vstructc::Error::Input(_) => raise_with::<InputError>(py, message, vec![diag]),
        vstructc::Error::Limit(_) => raise_with::<LimitError>(py, message, vec![diag]),
        _ => raise_with::<Error>(py, message, vec![diag]),
    }
}

/// `vstructc.Error` with `message` and no diagnostics (a caught panic, a write failure).
fn error_msg(py: Python<'_>, message: String) -> PyErr {
    raise_with::<Error>(py, message, Vec::new())
}

/// The names and values of `limits` as a dict.
fn limits_to_py<'py>(py: Python<'py>, limits: &Limits) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, value) in limit_fields(limits) {
        d.set_item(name, value)?;
    }
    Ok(d)
}

fn limit_fields(l: &Limits) -> [(&'static str, u64); 8] {
    [
        ("definition_file_bytes", l.definition_file_bytes),
        ("network_file_bytes", l.network_file_bytes),
        ("nodes", l.nodes),
        ("connections_per_input", l.connections_per_input),
        ("params_per_node", l.params_per_node),
        ("expr_terms", l.expr_terms),
        ("expr_depth", l.expr_depth),
        ("preview_pixels", l.preview_pixels),
    ]
}

/// The defaults with the bounds named in `given` replaced (None: the defaults). An unknown
/// name is a ValueError.
fn limits_from(given: Option<&Bound<'_, PyDict>>) -> PyResult<Limits> {
    let mut limits = Limits::default();
    let Some(given) = given else {
        return Ok(limits);
    };
    for (k, v) in given.iter() {
        let name: String = k.extract()?;
        let value: u64 = v
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("the limit {name} is a non-negative int")))?;
        let slot = match name.as_str() {
            "definition_file_bytes" => &mut limits.definition_file_bytes,
            "network_file_bytes" => &mut limits.network_file_bytes,
            "nodes" => &mut limits.nodes,
            "connections_per_input" => &mut limits.connections_per_input,
            "params_per_node" => &mut limits.params_per_node,
            "expr_terms" => &mut limits.expr_terms,
            "expr_depth" => &mut limits.expr_depth,
            "preview_pixels" => &mut limits.preview_pixels,
            _ => {
                let names: Vec<&str> = limit_fields(&limits).iter().map(|f| f.0).collect();
                return Err(PyValueError::new_err(format!(
                    "no limit {name:?}; the limits are {}",
                    names.join(", ")
                )));
            }
        };
        *slot = value;
    }
    Ok(limits)
}

/// The default bounds on sizes and counts, by name (definition_file_bytes,
/// network_file_bytes, nodes, connections_per_input, params_per_node, expr_terms, expr_depth,
/// preview_pixels). Functions taking `limits=` accept a dict of some of these names.
#[pyfunction]
fn default_limits(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    limits_to_py(py, &Limits::default())
}

// ---------------------------------------------------------------------------------------
// Diagnostics
// ---------------------------------------------------------------------------------------

/// One finding of a stage: a stable code, a severity, a message, and where it is (the file
/// position, and the node and parameter it is about). Absent fields are None.
#[pyclass(module = "vstructc", frozen)]
struct Diagnostic {
    inner: vstructc::Diagnostic,
}

impl From<vstructc::Diagnostic> for Diagnostic {
    fn from(inner: vstructc::Diagnostic) -> Self {
        Diagnostic { inner }
    }
}

#[pymethods]
impl Diagnostic {
    /// The stable code, such as "VS010".
    #[getter]
    fn code(&self) -> &'static str {
        self.inner.code.as_str()
    }
    /// "error", "warning", "info" or "note".
    #[getter]
    fn severity(&self) -> &'static str {
        self.inner.severity.as_str()
    }
    /// The one-line message.
    #[getter]
    fn message(&self) -> &str {
        &self.inner.message
    }
    /// The handle of the node the diagnostic is about, or None.
    #[getter]
    fn node(&self) -> Option<&str> {
        self.inner.node.as_deref()
    }
    /// The parameter of `node` the diagnostic is about, or None.
    #[getter]
    fn param(&self) -> Option<&str> {
        self.inner.param.as_deref()
    }
    /// The file (or pseudo-name such as "<rib>") of the position, or None.
    #[getter]
    fn file(&self) -> Option<&str> {
        self.inner.location.as_ref().map(|l| &*l.file)
    }
    /// The 1-based line, or None when unknown.
    #[getter]
    fn line(&self) -> Option<u32> {
        self.inner
            .location
            .as_ref()
            .map(|l| l.line)
            .filter(|&l| l > 0)
    }
    /// The 1-based column (in characters), or None when unknown.
    #[getter]
    fn column(&self) -> Option<u32> {
        self.inner
            .location
            .as_ref()
            .map(|l| l.column)
            .filter(|&c| c > 0)
    }
    /// The JSON Pointer of the position in a JSON input, or None.
    #[getter]
    fn pointer(&self) -> Option<&str> {
        self.inner
            .location
            .as_ref()
            .and_then(|l| l.pointer.as_deref())
    }
    /// Extra lines of explanation.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.inner.notes.clone()
    }
    /// The documented meaning of the code, or None.
    #[getter]
    fn meaning(&self) -> Option<&'static str> {
        self.inner.code.meaning()
    }
    fn __str__(&self) -> String {
        self.inner.render_human()
    }
    fn __repr__(&self) -> String {
        format!(
            "<Diagnostic {} {} {:?}>",
            self.inner.severity, self.inner.code, self.inner.message
        )
    }
}

fn diag_list(diags: Diagnostics) -> Vec<Diagnostic> {
    diags.into_iter().map(Diagnostic::from).collect()
}

// ---------------------------------------------------------------------------------------
// Values
// ---------------------------------------------------------------------------------------

/// A library value as a Python object: int, float, str, bool, tuple (triples, hpoints,
/// matrices) or list (arrays).
fn value_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Int(i) => i.into_pyobject(py)?.into_any(),
        Value::Float(x) => f64::from(*x).into_pyobject(py)?.into_any(),
        Value::Str(s) | Value::Token(s) | Value::Asset(s) => s.into_pyobject(py)?.into_any(),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Triple(_, c) => PyTuple::new(py, c.iter().map(|&x| f64::from(x)))?.into_any(),
        Value::HPoint(c) => PyTuple::new(py, c.iter().map(|&x| f64::from(x)))?.into_any(),
        Value::Matrix(c) => PyTuple::new(py, c.iter().map(|&x| f64::from(x)))?.into_any(),
        Value::Array(_, items) => {
            let list = PyList::empty(py);
            for item in items {
                list.append(value_to_py(py, item)?)?;
            }
            list.into_any()
        }
    })
}

/// Parses a type word: `color`, `float`, `float[3]`, `string[]`, `float2`, …
fn parse_type(word: &str) -> PyResult<Type> {
    let word = word.trim();
    let ty = if let Some(base) = word.strip_suffix("[]") {
        Type {
            base: BaseType::from_word(base.trim()),
            array: ArraySpec::Dynamic,
        }
    } else if let Some((base, rest)) = word.split_once('[') {
        let n: usize = rest
            .strip_suffix(']')
            .and_then(|n| n.trim().parse().ok())
            .ok_or_else(|| PyValueError::new_err(format!("bad type `{word}`")))?;
        Type {
            base: BaseType::from_word(base.trim()),
            array: ArraySpec::Fixed(n),
        }
    } else {
        Type::parse_decl(word)
    };
    if let BaseType::Unknown(w) = &ty.base {
        return Err(PyValueError::new_err(format!("unknown type `{w}`")));
    }
    Ok(ty)
}

fn floats<const N: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f32; N]> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("a {what} takes a sequence of {N} numbers")))?;
    if v.len() != N {
        return Err(PyValueError::new_err(format!(
            "a {what} takes {N} numbers, not {}",
            v.len()
        )));
    }
    let mut out = [0f32; N];
    for (o, x) in out.iter_mut().zip(v) {
        *o = x as f32;
    }
    Ok(out)
}

/// A Python object as a scalar value of `base`.
fn scalar_from_py(obj: &Bound<'_, PyAny>, base: &BaseType) -> PyResult<Value> {
    let wrong = |t: &str| PyTypeError::new_err(format!("a {t} value was expected"));
    Ok(match base {
        BaseType::Int => Value::Int(obj.extract().map_err(|_| wrong("int"))?),
        BaseType::Float => Value::Float(obj.extract::<f64>().map_err(|_| wrong("float"))? as f32),
        BaseType::String => Value::Str(obj.extract().map_err(|_| wrong("string"))?),
        BaseType::Token => Value::Token(obj.extract().map_err(|_| wrong("token"))?),
        BaseType::Asset => Value::Asset(obj.extract().map_err(|_| wrong("asset"))?),
        BaseType::Bool => Value::Bool(obj.extract().map_err(|_| wrong("bool"))?),
        b @ (BaseType::Color | BaseType::Point | BaseType::Vector | BaseType::Normal) => {
            Value::Triple(b.clone(), floats::<3>(obj, b.word())?)
        }
        BaseType::HPoint => Value::HPoint(floats::<4>(obj, "hpoint")?),
        BaseType::Matrix => Value::Matrix(floats::<16>(obj, "matrix")?),
        other => {
            return Err(PyTypeError::new_err(format!(
                "a parameter of type `{}` takes a connection, not a value",
                other.word()
            )));
        }
    })
}

/// A Python object as a value of type `ty`.
fn value_from_py(obj: &Bound<'_, PyAny>, ty: &Type) -> PyResult<Value> {
    if !ty.is_array() {
        return scalar_from_py(obj, &ty.base);
    }
    if obj.is_instance_of::<PyString>() {
        return Err(PyTypeError::new_err("an array takes a list or tuple"));
    }
    let items: Vec<Bound<'_, PyAny>> = obj
        .extract()
        .map_err(|_| PyTypeError::new_err("an array takes a list or tuple"))?;
    if let ArraySpec::Fixed(n) = ty.array
        && items.len() != n
    {
        return Err(PyValueError::new_err(format!(
            "an array of type `{ty}` takes {n} elements, not {}",
            items.len()
        )));
    }
    let values = items
        .iter()
        .map(|i| scalar_from_py(i, &ty.base))
        .collect::<PyResult<Vec<_>>>()?;
    Ok(Value::Array(ty.base.clone(), values))
}

/// The type a Python object has when nothing declares one: int, float, string, a
/// 3-sequence is a color, a 16-sequence a matrix, a list of scalars an array.
fn inferred_type(obj: &Bound<'_, PyAny>) -> PyResult<Type> {
    let scalar = |o: &Bound<'_, PyAny>| -> Option<BaseType> {
        if o.is_instance_of::<PyBool>() || o.is_instance_of::<PyInt>() {
            Some(BaseType::Int)
        } else if o.is_instance_of::<PyFloat>() {
            Some(BaseType::Float)
        } else if o.is_instance_of::<PyString>() {
            Some(BaseType::String)
        } else {
            None
        }
    };
    if let Some(b) = scalar(obj) {
        return Ok(Type::scalar(b));
    }
    let items: Vec<Bound<'_, PyAny>> = obj.extract().map_err(|_| {
        PyTypeError::new_err("a value is an int, float, str, or a list or tuple of them")
    })?;
    let bases: Vec<Option<BaseType>> = items.iter().map(scalar).collect();
    let numeric = bases
        .iter()
        .all(|b| matches!(b, Some(BaseType::Int | BaseType::Float)));
    if obj.is_instance_of::<PyTuple>() && numeric {
        match items.len() {
            3 => return Ok(Type::scalar(BaseType::Color)),
            16 => return Ok(Type::scalar(BaseType::Matrix)),
            _ => {}
        }
    }
    let base = if numeric && bases.contains(&Some(BaseType::Float)) {
        BaseType::Float
    } else {
        match bases.first() {
            Some(Some(b)) if bases.iter().all(|x| x.as_ref() == Some(b)) => b.clone(),
            None => BaseType::Float,
            _ => {
                return Err(PyTypeError::new_err(
                    "the type of this value is ambiguous: pass type=",
                ));
            }
        }
    };
    Ok(Type {
        base,
        array: ArraySpec::Dynamic,
    })
}

// ---------------------------------------------------------------------------------------
// Registry
// ---------------------------------------------------------------------------------------

/// Shader definitions (.args and compiled OSL .oso), loaded lazily: `paths` are searched
/// first, in order, then (with `env=True`) the folders of VSTRUCTC_ARGS_PATH, then (with
/// `embedded=True`) the definitions built into vstructc.
#[pyclass(module = "vstructc")]
struct Registry {
    inner: vstructc::registry::Registry,
}

fn prop_to_py<'py>(py: Python<'py>, p: &vstructc::model::Property) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &p.name)?;
    d.set_item("type", p.ty.to_string())?;
    d.set_item("declared_type", &p.declared_type)?;
    d.set_item(
        "default",
        match &p.default {
            Some(v) => Some(value_to_py(py, v)?),
            None => None,
        },
    )?;
    d.set_item("vstruct_head", p.ty.base == BaseType::Vstruct)?;
    match &p.vstruct {
        Some(m) => {
            let v = PyDict::new(py);
            v.set_item("head", &m.head)?;
            v.set_item("member", &m.member)?;
            v.set_item("alias", &m.alias)?;
            v.set_item("conditional", m.cond.as_ref().map(|c| &c.text))?;
            d.set_item("vstruct", v)?;
        }
        None => d.set_item("vstruct", py.None())?,
    }
    d.set_item("connectable", p.connectable)?;
    d.set_item("label", &p.label)?;
    d.set_item("page", &p.page)?;
    d.set_item("help", &p.help)?;
    d.set_item("widget", &p.widget)?;
    Ok(d)
}

#[pymethods]
impl Registry {
    /// A registry searching `paths` (files or folders) first, then VSTRUCTC_ARGS_PATH when
    /// `env` is true, then the embedded definitions when `embedded` is true. `prefer` is
    /// "oso" (default) or "args": which wins when one shader has both. `limits` (a dict, see
    /// default_limits()) bounds definition files (definition_file_bytes, params_per_node).
    #[new]
    #[pyo3(signature = (paths=None, embedded=true, prefer="oso", env=false, limits=None))]
    fn new(
        py: Python<'_>,
        paths: Option<Vec<PathBuf>>,
        embedded: bool,
        prefer: &str,
        env: bool,
        limits: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let limits = limits_from(limits)?;
        let prefer = match prefer {
            "oso" => Prefer::Oso,
            "args" => Prefer::Args,
            other => {
                return Err(PyValueError::new_err(format!(
                    "prefer is \"oso\" or \"args\", not {other:?}"
                )));
            }
        };
        let options = RegistryOptions {
            paths: paths.unwrap_or_default(),
            use_env: env,
            use_embedded: embedded,
            prefer,
            limits,
            ..RegistryOptions::default()
        };
        let inner = py
            .detach(|| guarded(|| vstructc::registry::Registry::new(options)))
            .map_err(|m| error_msg(py, m))?;
        Ok(Registry { inner })
    }

    /// Every shader id on the search path, sorted.
    fn shaders(&self) -> Vec<String> {
        self.inner.ids().into_iter().map(str::to_string).collect()
    }

    /// The definition of `shader` as a dict (name, kind, source, path, inputs, outputs; each
    /// property: name, type, declared_type, default, vstruct_head, vstruct = {head, member,
    /// alias, conditional} or None, connectable, label, page, help, widget), or None when no
    /// file provides it or its file was rejected (see diagnostics()).
    fn definition<'py>(
        &self,
        py: Python<'py>,
        shader: &str,
    ) -> PyResult<Option<Bound<'py, PyDict>>> {
        let def = guarded(|| self.inner.definition(shader)).map_err(|m| error_msg(py, m))?;
        let Some(def) = def else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("name", &def.id)?;
        d.set_item("kind", &def.kind)?;
        d.set_item(
            "source",
            match def.source {
                vstructc::model::SourceKind::Args => "args",
                vstructc::model::SourceKind::Oso => "oso",
            },
        )?;
        d.set_item("path", &*def.path)?;
        let inputs = PyList::empty(py);
        for p in &def.inputs {
            inputs.append(prop_to_py(py, p)?)?;
        }
        let outputs = PyList::empty(py);
        for p in &def.outputs {
            outputs.append(prop_to_py(py, p)?)?;
        }
        d.set_item("inputs", inputs)?;
        d.set_item("outputs", outputs)?;
        Ok(Some(d))
    }

    /// Adds a definition from .args XML text under shader id `shader`.
    fn add_args_text(&mut self, py: Python<'_>, shader: &str, text: &str) -> PyResult<()> {
        guarded(|| self.inner.add_args_text(shader, text))
            .map_err(|m| error_msg(py, m))?
            .map_err(|e| lib_error(py, e))
    }

    /// Adds a definition from compiled OSL (.oso) text; returns its shader id.
    fn add_oso_text(&mut self, py: Python<'_>, text: &str) -> PyResult<String> {
        guarded(|| self.inner.add_oso_text(text))
            .map_err(|m| error_msg(py, m))?
            .map_err(|e| lib_error(py, e))
    }

    /// Diagnostics of listing the search path and of every definition loaded so far.
    fn diagnostics(&self, py: Python<'_>) -> PyResult<Vec<Diagnostic>> {
        let d = guarded(|| self.inner.diagnostics()).map_err(|m| error_msg(py, m))?;
        Ok(diag_list(d))
    }

    fn __repr__(&self) -> String {
        format!("<Registry of {} shaders>", self.inner.ids().len())
    }
}

// ---------------------------------------------------------------------------------------
// Network
// ---------------------------------------------------------------------------------------

/// A shader network: nodes (handle, shader), their parameter values and connections, and
/// materials. Read one with from_rib/from_json, or build one with add_node, set_param,
/// connect and add_material.
#[pyclass(module = "vstructc")]
struct Network {
    net: vstructc::network::Network,
    /// The RIB text a network was read from: to_rib copies every byte outside the network.
    rib_source: Option<PyBackedBytes>,
    /// The registry the network was read with or last resolved against (parameter types).
    registry: Option<Py<Registry>>,
    /// True once resolved (compile resolves first otherwise).
    resolved: bool,
    /// The reader's diagnostics.
    read_diagnostics: Vec<vstructc::Diagnostic>,
}

/// Text as a Python str or bytes, readable without the GIL.
enum Text {
    Str(PyBackedStr),
    Bytes(PyBackedBytes),
}

impl Text {
    fn extract(obj: &Bound<'_, PyAny>) -> PyResult<Text> {
        if let Ok(s) = obj.extract::<PyBackedStr>() {
            return Ok(Text::Str(s));
        }
        obj.extract::<PyBackedBytes>()
            .map(Text::Bytes)
            .map_err(|_| PyTypeError::new_err("the text is a str or bytes"))
    }
    fn bytes(&self) -> &[u8] {
        match self {
            Text::Str(s) => s.as_bytes(),
            Text::Bytes(b) => b,
        }
    }
}

impl Network {
    /// The RIB text of the network, with the parameter types of `registry` or the network's.
    fn rib(&self, py: Python<'_>, registry: Option<Py<Registry>>) -> PyResult<Vec<u8>> {
        let reg = registry.or_else(|| self.registry.as_ref().map(|r| r.clone_ref(py)));
        let guard = reg.as_ref().map(|r| r.try_borrow(py)).transpose()?;
        let types: &(dyn ParamTypes + Sync) = match &guard {
            Some(g) => &g.inner,
            None => &NoDefinitions,
        };
        let source: &[u8] = self.rib_source.as_deref().unwrap_or(b"");
        let net = &self.net;
        py.detach(|| {
            guarded(|| {
                let mut out = Vec::with_capacity(source.len() + 1024);
                write_rib(source, net, types, &mut out).map(|()| out)
            })
        })
        .map_err(|m| error_msg(py, m))?
        .map_err(|e| error_msg(py, e.to_string()))
    }

    fn node(&self, handle: &str) -> PyResult<NodeId> {
        self.net
            .find(handle)
            .ok_or_else(|| PyKeyError::new_err(format!("no node `{handle}` in the network")))
    }

    fn read(
        py: Python<'_>,
        text: &Bound<'_, PyAny>,
        registry: &Bound<'_, Registry>,
        name: &str,
        format: NetFormat,
        read_options: &ReadOptions,
    ) -> PyResult<Network> {
        let text = Text::extract(text)?;
        let reg = registry.try_borrow()?;
        let types: &vstructc::registry::Registry = &reg.inner;
        let bytes = text.bytes();
        let mut diags = Diagnostics::new();
        let read = py
            .detach(|| {
                guarded(|| read_network(name, bytes, format, types, read_options, &mut diags))
            })
            .map_err(|m| error_msg(py, m))?;
        // Unknown shaders are reported by resolution (VS020) for every input form.
        let diags: Vec<_> = diags.into_iter().filter(|d| d.code != "RB019").collect();
        match read {
            Ok(net) => {
                let rib_source = match (format, text) {
                    (NetFormat::Rib, Text::Bytes(b)) => Some(b),
                    (NetFormat::Rib, Text::Str(s)) => {
                        let b = PyBytes::new(py, s.as_bytes());
                        Some(b.extract::<PyBackedBytes>()?)
                    }
                    _ => None,
                };
                Ok(Network {
                    net,
                    rib_source,
                    registry: Some(registry.clone().unbind()),
                    resolved: false,
                    read_diagnostics: diags,
                })
            }
            Err(e) => {
                let message = e.to_string();
                let mut all = diags;
                all.push(e.to_diagnostic());
                Err(match e {
                    vstructc::Error::Limit(_) => raise_with::<LimitError>(py, message, all),
                    vstructc::Error::Input(_) => raise_with::<InputError>(py, message, all),
                    _ => raise_with::<Error>(py, message, all),
                })
            }
        }
    }
}

#[pymethods]
impl Network {
    /// An empty network. With `registry`, set_param takes parameter types and add_node
    /// request kinds from its definitions.
    #[new]
    #[pyo3(signature = (registry=None))]
    fn new(registry: Option<Py<Registry>>) -> Self {
        Network {
            net: vstructc::network::Network::new(),
            rib_source: None,
            registry,
            resolved: false,
            read_diagnostics: Vec::new(),
        }
    }

    /// Reads a network from RIB text (str or bytes). Raises vstructc.Error on malformed
    /// text; warnings are in `.diagnostics`. to_rib() writes every byte outside the shading
    /// networks back unchanged. `strict=True` makes single-quoted strings an error (RB011)
    /// instead of an info; `limits` (a dict, see default_limits()) bounds the text's size,
    /// nodes, parameters and connections.
    #[staticmethod]
    #[pyo3(signature = (text, registry, name="<rib>", strict=false, limits=None))]
    fn from_rib(
        py: Python<'_>,
        text: &Bound<'_, PyAny>,
        registry: &Bound<'_, Registry>,
        name: &str,
        strict: bool,
        limits: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Network> {
        let options = ReadOptions {
            strict_rib: strict,
            limits: limits_from(limits)?,
        };
        Network::read(py, text, registry, name, NetFormat::Rib, &options)
    }

    /// Reads a network from vstructc's JSON form (str or bytes). Raises vstructc.Error on
    /// malformed text; warnings are in `.diagnostics`. `limits` as in from_rib().
    #[staticmethod]
    #[pyo3(signature = (text, registry, name="<json>", limits=None))]
    fn from_json(
        py: Python<'_>,
        text: &Bound<'_, PyAny>,
        registry: &Bound<'_, Registry>,
        name: &str,
        limits: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Network> {
        let options = ReadOptions {
            strict_rib: false,
            limits: limits_from(limits)?,
        };
        Network::read(py, text, registry, name, NetFormat::Json, &options)
    }

    /// The reader's diagnostics (warnings and infos) of a network read from text.
    #[getter]
    fn diagnostics(&self) -> Vec<Diagnostic> {
        self.read_diagnostics
            .iter()
            .cloned()
            .map(Diagnostic::from)
            .collect()
    }

    /// True once the network has been resolved and not changed since (add_node, set_param
    /// and connect clear it; compile resolves a network that is not resolved).
    #[getter]
    fn resolved(&self) -> bool {
        self.resolved
    }

    /// Adds node `handle` of shader `shader`. `kind` is "pattern", "bxdf", "displace",
    /// "light" or "lightfilter"; by default the definition's kind when the network has a
    /// registry, else "pattern". A handle added again is a new version of it, as a RIB
    /// redefinition is: this is how a node's shader is changed. Later add_node, set_param,
    /// connect and add_material calls and the lookups by handle reach the new version;
    /// connections made before keep the old one (reconnect them), and both versions are
    /// written.
    #[pyo3(signature = (handle, shader, kind=None))]
    fn add_node(
        &mut self,
        py: Python<'_>,
        handle: &str,
        shader: &str,
        kind: Option<&str>,
    ) -> PyResult<()> {
        let from_word = |w: &str| -> Option<RequestKind> {
            match w.to_ascii_lowercase().as_str() {
                "pattern" => Some(RequestKind::Pattern),
                "bxdf" | "surface" => Some(RequestKind::Bxdf),
                "displace" | "displacement" => Some(RequestKind::Displace),
                "light" => Some(RequestKind::Light),
                "lightfilter" => Some(RequestKind::LightFilter),
                _ => None,
            }
        };
        let kind = match kind {
            Some(w) => from_word(w).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "kind is pattern, bxdf, displace, light or lightfilter, not {w:?}"
                ))
            })?,
            None => self
                .registry
                .as_ref()
                .and_then(|r| r.try_borrow(py).ok()?.inner.definition(shader))
                .and_then(|d| from_word(&d.kind))
                .unwrap_or(RequestKind::Pattern),
        };
        self.net.add_node_of_kind(handle, shader, kind);
        self.resolved = false;
        Ok(())
    }

    /// Sets parameter `name` of node `handle` to `value`. The type comes from `type` (such
    /// as "color", "float", "string[]"), else from the definition when the network has a
    /// registry, else from the value (int, float, str; a 3-tuple is a color, a 16-tuple a
    /// matrix, a list an array).
    #[pyo3(signature = (handle, name, value, r#type=None))]
    fn set_param(
        &mut self,
        py: Python<'_>,
        handle: &str,
        name: &str,
        value: &Bound<'_, PyAny>,
        r#type: Option<&str>,
    ) -> PyResult<()> {
        let node = self.node(handle)?;
        let ty = match r#type {
            Some(word) => parse_type(word)?,
            None => {
                let declared = self.registry.as_ref().and_then(|r| {
                    let reg = r.try_borrow(py).ok()?;
                    reg.inner
                        .definition(self.net[node].shader())
                        .and_then(|d| d.input(name).map(|p| p.ty.clone()))
                });
                match declared {
                    Some(t) if t.base != BaseType::Vstruct && t.base.components() > 0 => t,
                    _ => inferred_type(value)?,
                }
            }
        };
        let v = value_from_py(value, &ty)?;
        self.net.set_param(node, name, v);
        self.resolved = false;
        Ok(())
    }

    /// Connects input `input` of node `down` to output `output` of node `up` (a vstruct
    /// connection when both are vstruct heads).
    fn connect(&mut self, down: &str, input: &str, up: &str, output: &str) -> PyResult<()> {
        let d = self.node(down)?;
        let u = self.node(up)?;
        self.net.connect(d, input, u, output);
        self.resolved = false;
        Ok(())
    }

    /// Removes connections of input `input` of node `down`: all of them, or with `up` only
    /// those from node `up` (and with `output` only those from that output). Returns how
    /// many were removed.
    #[pyo3(signature = (down, input, up=None, output=None))]
    fn disconnect(
        &mut self,
        down: &str,
        input: &str,
        up: Option<&str>,
        output: Option<&str>,
    ) -> PyResult<usize> {
        let d = self.node(down)?;
        let u = up.map(|h| self.node(h)).transpose()?;
        let links = self.net.connections(d, input).to_vec();
        let before = links.len();
        let keep: Vec<_> = links
            .into_iter()
            .filter(|l| {
                let from_up = u.is_none_or(|u| l.upstream_node() == Some(u));
                let from_output = output.is_none_or(|o| l.output() == Some(o));
                !(from_up && from_output)
            })
            .collect();
        let removed = before - keep.len();
        if removed > 0 {
            self.net.set_connections(d, input, keep);
            self.resolved = false;
        }
        Ok(removed)
    }

    /// Removes parameter `name` of node `handle`: its value and its connections (it is then
    /// not written). Nothing happens when the node has no such parameter.
    fn remove_param(&mut self, handle: &str, name: &str) -> PyResult<()> {
        let node = self.node(handle)?;
        if self.net[node].param(name).is_some() {
            self.net.remove_param(node, name);
            self.resolved = false;
        }
        Ok(())
    }

    /// Adds material `name` with its terminals: `surface` (a bxdf node's handle) and
    /// optionally `displacement`. Returns nothing; materials() lists them.
    #[pyo3(signature = (name, surface=None, displacement=None))]
    fn add_material(
        &mut self,
        name: &str,
        surface: Option<&str>,
        displacement: Option<&str>,
    ) -> PyResult<()> {
        let s = surface.map(|h| self.node(h)).transpose()?;
        let d = displacement.map(|h| self.node(h)).transpose()?;
        let m = self.net.add_material(name);
        if let Some(s) = s {
            self.net.set_terminal(m, "surface", s, None);
        }
        if let Some(d) = d {
            self.net.set_terminal(m, "displacement", d, None);
        }
        Ok(())
    }

    /// Every node as (handle, shader), in the order they were read or added.
    fn nodes(&self) -> Vec<(String, String)> {
        self.net
            .node_ids()
            .map(|id| {
                let n = &self.net[id];
                (n.handle().to_string(), n.shader().to_string())
            })
            .collect()
    }

    /// The materials: dicts of name, terminals ({terminal name: node handle}) and nodes
    /// (the handles of the material's nodes).
    fn materials<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let mut out = Vec::new();
        for (i, m) in self.net.materials().iter().enumerate() {
            let d = PyDict::new(py);
            d.set_item("name", &m.name)?;
            let terms = PyDict::new(py);
            for t in &m.terminals {
                let h = t
                    .link
                    .upstream_node()
                    .map(|n| self.net[n].handle().to_string())
                    .or_else(|| t.link.missing_handle().map(str::to_string));
                terms.set_item(&t.name, h)?;
            }
            d.set_item("terminals", terms)?;
            let nodes: Vec<&str> = self
                .net
                .material_nodes(i)
                .into_iter()
                .map(|n| self.net[n].handle())
                .collect();
            d.set_item("nodes", nodes)?;
            out.push(d);
        }
        Ok(out)
    }

    /// The value of parameter `name` of node `handle` (int, float, str, tuple or list), or
    /// None when it is neither authored nor written by resolution.
    fn value<'py>(
        &self,
        py: Python<'py>,
        handle: &str,
        name: &str,
    ) -> PyResult<Option<Bound<'py, PyAny>>> {
        let node = self.node(handle)?;
        self.net
            .value(node, name)
            .map(|v| value_to_py(py, v))
            .transpose()
    }

    /// The connections of node `handle` as (input, upstream handle, upstream output), the
    /// output None when the whole node is connected.
    fn connections(&self, handle: &str) -> PyResult<Vec<(String, String, Option<String>)>> {
        let node = self.node(handle)?;
        let mut out = Vec::new();
        for input in self.net.connected_inputs(node) {
            for link in self.net.connections(node, &input) {
                let up = link
                    .upstream_node()
                    .map(|n| self.net[n].handle())
                    .or(link.missing_handle())
                    .unwrap_or("")
                    .to_string();
                out.push((input.clone(), up, link.output().map(str::to_string)));
            }
        }
        Ok(out)
    }

    /// The network as RIB. A network read from RIB keeps every byte outside its shading
    /// networks, and nodes resolution did not change are copied verbatim. Parameter types
    /// come from `registry`, else the network's registry.
    #[pyo3(signature = (registry=None))]
    fn to_rib(&self, py: Python<'_>, registry: Option<Py<Registry>>) -> PyResult<String> {
        String::from_utf8(self.rib(py, registry)?)
            .map_err(|_| error_msg(py, "the RIB text is not UTF-8: use to_rib_bytes()".into()))
    }

    /// to_rib() as bytes (for RIB files that are not UTF-8).
    #[pyo3(signature = (registry=None))]
    fn to_rib_bytes<'py>(
        &self,
        py: Python<'py>,
        registry: Option<Py<Registry>>,
    ) -> PyResult<Bound<'py, PyBytes>> {
        Ok(PyBytes::new(py, &self.rib(py, registry)?))
    }

    /// The network in vstructc's JSON form. Raises vstructc.Error when it has nodes but no
    /// material (they would be lost).
    fn to_json(&self, py: Python<'_>) -> PyResult<String> {
        let net = &self.net;
        py.detach(|| guarded(|| write_json(net)))
            .map_err(|m| error_msg(py, m))?
            .map_err(|e| error_msg(py, e.to_string()))
    }

    fn __repr__(&self) -> String {
        format!(
            "<Network of {} nodes, {} materials>",
            self.net.node_count(),
            self.net.materials().len()
        )
    }
}

fn resolve_options(
    conditions: bool,
    ext: Option<Vec<String>>,
    verbose: bool,
    drop_unresolved: bool,
    limits: Option<&Bound<'_, PyDict>>,
) -> PyResult<vstructc::resolve::ResolveOptions> {
    let extensions = Extensions::from_names(ext.unwrap_or_default())
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(vstructc::resolve::ResolveOptions {
        conditions,
        extensions,
        verbose,
        drop_unresolved,
        limits: limits_from(limits)?,
        ..Default::default()
    })
}

/// Resolves in place; returns the diagnostics (the registry's and resolution's, sorted,
/// each once). Raises LimitError when the network exceeds a bound.
fn resolve_in_place(
    py: Python<'_>,
    net: &mut Network,
    registry: &Bound<'_, Registry>,
    options: &vstructc::resolve::ResolveOptions,
) -> PyResult<Diagnostics> {
    let reg = registry.try_borrow()?;
    let r = &reg.inner;
    let n = &mut net.net;
    let (res, mut diags) = py
        .detach(|| {
            guarded(|| {
                let res = vstructc::resolve::resolve(n, r, options);
                (res, r.diagnostics())
            })
        })
        .map_err(|m| error_msg(py, m))?;
    diags.extend(res.diagnostics);
    diags.sort();
    diags.dedup();
    if let Some(limit) = res.limit {
        return Err(raise_with::<LimitError>(
            py,
            limit.to_string(),
            diags.into_vec(),
        ));
    }
    net.resolved = true;
    if net.registry.is_none() {
        net.registry = Some(registry.clone().unbind());
    }
    Ok(diags)
}

/// Expands every vstruct connection of `network` in place, exactly as hdPrman does, and
/// returns the diagnostics (registry's and resolution's). `conditions=False` ignores the
/// vstruct conditionals; `ext` names opt-in extensions ("all" for every one); `verbose`
/// also reports notes (VS021); `drop_unresolved` deletes the connections still on input
/// heads afterwards (the VS010 placeholders) instead of keeping them; `limits` (a dict, see
/// default_limits()) bounds nodes, parameters per node and connections per input: beyond
/// one, the network is left as it was and LimitError is raised.
#[pyfunction]
#[pyo3(signature = (network, registry, conditions=true, ext=None, verbose=false, drop_unresolved=false, limits=None))]
#[allow(clippy::too_many_arguments)]
fn resolve(
    py: Python<'_>,
    network: &Bound<'_, Network>,
    registry: &Bound<'_, Registry>,
    conditions: bool,
    ext: Option<Vec<String>>,
    verbose: bool,
    drop_unresolved: bool,
    limits: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<Diagnostic>> {
    let options = resolve_options(conditions, ext, verbose, drop_unresolved, limits)?;
    let mut net = network.try_borrow_mut()?;
    let diags = resolve_in_place(py, &mut net, registry, &options)?;
    Ok(diag_list(diags))
}

/// Compiles the materials of `network` for the interpreter (resolving it in place first
/// when it has not been resolved). `material` selects one material by name or terminal
/// handle. A material that cannot be compiled is left out with an error diagnostic; when
/// `diagnostics` is a list, every diagnostic is appended to it. The resolution options are
/// resolve()'s, used when compile resolves.
#[pyfunction]
#[pyo3(signature = (network, registry, material=None, conditions=true, ext=None, diagnostics=None, verbose=false, drop_unresolved=false, limits=None))]
#[allow(clippy::too_many_arguments)]
fn compile(
    py: Python<'_>,
    network: &Bound<'_, Network>,
    registry: &Bound<'_, Registry>,
    material: Option<String>,
    conditions: bool,
    ext: Option<Vec<String>>,
    diagnostics: Option<&Bound<'_, PyList>>,
    verbose: bool,
    drop_unresolved: bool,
    limits: Option<&Bound<'_, PyDict>>,
) -> PyResult<Vec<Material>> {
    let options = resolve_options(conditions, ext, verbose, drop_unresolved, limits)?;
    let mut net = network.try_borrow_mut()?;
    let mut diags = if net.resolved {
        Diagnostics::new()
    } else {
        resolve_in_place(py, &mut net, registry, &options)?
    };
    let which = match material {
        Some(m) => Lowering::Only(m),
        None => Lowering::All,
    };
    let reg = registry.try_borrow()?;
    let r = &reg.inner;
    let n = &net.net;
    let d = &mut diags;
    let result = py
        .detach(|| guarded(|| vstructc::pipeline::compile(n, r, &which, d)))
        .map_err(|m| error_msg(py, m))?;
    let mats = match result {
        Ok(m) => m,
        Err(e) => {
            let message = e.to_string();
            let mut all = diags.into_vec();
            all.push(e.to_diagnostic());
            return Err(raise_with::<Error>(py, message, all));
        }
    };
    diags.sort();
    diags.dedup();
    if let Some(list) = diagnostics {
        for d in diags {
            list.append(Diagnostic::from(d))?;
        }
    }
    Ok(mats
        .into_iter()
        .map(|m| Material {
            name: m.name().to_string(),
            recipe: m.ir().recipe.name().to_string(),
            inner: Arc::new(m),
        })
        .collect())
}

/// The story of input `input` of node `handle`: where its value comes from and every
/// decision resolution makes about it, followed upstream. A dict with the fields of the
/// `vstructc explain --json` document (node, shader, input, origin, value, connections,
/// location, events, upstream, toldAbove, truncated; each event: head, upstreamNode,
/// upstreamHead, matchedOutput, matchedName, conditional, action, reads, outcome, written,
/// reason); values are {"type": ..., "value": ...} dicts as there. `network` is not
/// changed: a copy is resolved (so explain a network before resolving it). Raises KeyError
/// for an unknown node, and ValueError for an input the node's definition does not declare.
#[pyfunction]
#[pyo3(signature = (network, registry, handle, input, conditions=true, ext=None))]
fn explain<'py>(
    py: Python<'py>,
    network: &Bound<'py, Network>,
    registry: &Bound<'py, Registry>,
    handle: &str,
    input: &str,
    conditions: bool,
    ext: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut options = resolve_options(conditions, ext, false, false, None)?;
    options.record_events = true;
    let net = network.try_borrow()?;
    let node = net.node(handle)?;
    let reg = registry.try_borrow()?;
    let r = &reg.inner;
    if let Some(def) = r.definition(net.net[node].shader())
        && def.input(input).is_none()
        && net.net[node].param(input).is_none()
    {
        return Err(PyValueError::new_err(format!(
            "`{handle}` ({}) has no input `{input}`",
            def.id
        )));
    }
    let source = &net.net;
    let (copy, res) = py
        .detach(|| {
            guarded(|| {
                let mut copy = source.clone();
                let res = vstructc::resolve::resolve(&mut copy, r, &options);
                (copy, res)
            })
        })
        .map_err(|m| error_msg(py, m))?;
    if let Some(limit) = res.limit {
        return Err(raise_with::<LimitError>(
            py,
            limit.to_string(),
            res.diagnostics.into_vec(),
        ));
    }
    story::story_dict(py, &res.story(&copy, r, node, input))
}

/// Panics inside the guard (a test of the guard; built only with the `test-hooks` feature).
#[cfg(feature = "test-hooks")]
#[pyfunction]
fn _panic_for_test(py: Python<'_>, message: &str) -> PyResult<()> {
    guarded(|| -> () { panic!("{message}") }).map_err(|m| error_msg(py, m))
}

// ---------------------------------------------------------------------------------------
// Materials and images
// ---------------------------------------------------------------------------------------

/// A compiled material: evaluate it for a pair of directions, its albedo, its lobes, or
/// render a material-ball preview. Directions are in the surface frame (normal +Z).
#[pyclass(module = "vstructc", frozen)]
struct Material {
    inner: Arc<vstructc::interp::Material>,
    /// The material's name.
    #[pyo3(get)]
    name: String,
    /// The lowering recipe ("pxr_surface", …).
    #[pyo3(get)]
    recipe: String,
}

fn dir(v: (f32, f32, f32), what: &str) -> PyResult<Vec3> {
    let d = Vec3::new(v.0, v.1, v.2);
    if !d.is_finite() || d.length_squared() == 0.0 {
        return Err(PyValueError::new_err(format!(
            "{what} is a finite, non-zero direction"
        )));
    }
    Ok(d.normalize())
}

fn rgb(c: Vec3) -> (f32, f32, f32) {
    (c.x, c.y, c.z)
}

#[pymethods]
impl Material {
    /// The lobes that survive prepare for the view `wo` (None: along the normal, μ_o = 1):
    /// dicts of kind, label and weight (r, g, b).
    #[pyo3(signature = (wo=None))]
    fn lobes<'py>(
        &self,
        py: Python<'py>,
        wo: Option<(f32, f32, f32)>,
    ) -> PyResult<Vec<Bound<'py, PyDict>>> {
        let wo = dir(wo.unwrap_or((0.0, 0.0, 1.0)), "wo")?;
        let m = &self.inner;
        let rows = guarded(|| {
            let p = m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, wo));
            p.lobes()
                .iter()
                .map(|a| {
                    let info = &m.leaves()[a.leaf as usize];
                    (info.leaf.kind.name(), info.leaf.label.clone(), a.weight)
                })
                .collect::<Vec<_>>()
        })
        .map_err(|msg| error_msg(py, msg))?;
        rows.into_iter()
            .map(|(kind, label, weight)| {
                let d = PyDict::new(py);
                d.set_item("kind", kind)?;
                d.set_item("label", label)?;
                d.set_item("weight", rgb(weight))?;
                Ok(d)
            })
            .collect()
    }

    /// BSDF × cosine for view `wo` and light `wi`: a dict of total (r, g, b), pdf, and
    /// lobes (kind, label, weight, f_cos, pdf, prob per lobe).
    #[pyo3(signature = (wo, wi))]
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wo: (f32, f32, f32),
        wi: (f32, f32, f32),
    ) -> PyResult<Bound<'py, PyDict>> {
        let wo = dir(wo, "wo")?;
        let wi = dir(wi, "wi")?;
        let m = &self.inner;
        let (total, pdf, rows) = guarded(|| {
            let p = m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, wo));
            let e = p.eval(wi);
            let rows: Vec<_> = p
                .lobes()
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    let info = &m.leaves()[a.leaf as usize];
                    let le = a.lobe.eval(p.frame(k).to_local(wi));
                    (
                        info.leaf.kind.name(),
                        info.leaf.label.clone(),
                        a.weight,
                        le.f_cos,
                        le.pdf,
                        a.prob,
                    )
                })
                .collect();
            (e.f_cos, e.pdf, rows)
        })
        .map_err(|msg| error_msg(py, msg))?;
        let d = PyDict::new(py);
        d.set_item("total", rgb(total))?;
        d.set_item("pdf", pdf)?;
        let lobes = PyList::empty(py);
        for (kind, label, weight, f_cos, lpdf, prob) in rows {
            let l = PyDict::new(py);
            l.set_item("kind", kind)?;
            l.set_item("label", label)?;
            l.set_item("weight", rgb(weight))?;
            l.set_item("f_cos", rgb(f_cos))?;
            l.set_item("pdf", lpdf)?;
            l.set_item("prob", prob)?;
            lobes.append(l)?;
        }
        d.set_item("lobes", lobes)?;
        Ok(d)
    }

    /// Directional albedo for view `wo` (None: along the normal): a dict of reflect and
    /// transmit, each (r, g, b).
    #[pyo3(signature = (wo=None))]
    fn albedo<'py>(
        &self,
        py: Python<'py>,
        wo: Option<(f32, f32, f32)>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let wo = dir(wo.unwrap_or((0.0, 0.0, 1.0)), "wo")?;
        let m = &self.inner;
        let a = guarded(|| m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, wo)).albedo())
            .map_err(|msg| error_msg(py, msg))?;
        let d = PyDict::new(py);
        d.set_item("reflect", rgb(a.reflect))?;
        d.set_item("transmit", rgb(a.transmit))?;
        Ok(d)
    }

    /// Samples a light direction for view `wo` with the random numbers `u` (three numbers in
    /// [0, 1): the first picks a lobe, the other two drive its sampling), as a renderer does
    /// (one-sample MIS over the lobes). A dict of wi (the direction, unit), weight (f·cos /
    /// pdf, r g b), pdf, delta (a specular direction: pdf is then the probability of the
    /// choice) and lobe (the index in lobes(wo), or None for straight transparency); None
    /// when the material absorbs everything or the sample carries no energy.
    #[pyo3(signature = (wo, u))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wo: (f32, f32, f32),
        u: (f32, f32, f32),
    ) -> PyResult<Option<Bound<'py, PyDict>>> {
        let wo = dir(wo, "wo")?;
        let u = [u.0, u.1, u.2];
        if !u.iter().all(|x| (0.0..1.0).contains(x)) {
            return Err(PyValueError::new_err("u holds three numbers in [0, 1)"));
        }
        let m = &self.inner;
        let s = guarded(|| {
            m.prepare(&ShadingPoint::new(Vec3::Z, Vec3::X, wo))
                .sample(u)
        })
        .map_err(|msg| error_msg(py, msg))?;
        let Some(s) = s else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("wi", rgb(s.l))?;
        d.set_item("weight", rgb(s.weight))?;
        d.set_item("pdf", s.pdf)?;
        d.set_item("delta", s.delta)?;
        d.set_item(
            "lobe",
            (s.lobe != vstructc::interp::Sample::TRANSPARENCY_LOBE).then_some(s.lobe),
        )?;
        Ok(Some(d))
    }

    /// Renders the material ball, `size` × `size` pixels, lit by one light and a dim
    /// environment; `furnace=True` renders a white furnace (no light, environment 1).
    /// `limits` (a dict, see default_limits()) bounds the pixels (preview_pixels).
    #[pyo3(signature = (size=256, furnace=false, limits=None))]
    fn render(
        &self,
        py: Python<'_>,
        size: usize,
        furnace: bool,
        limits: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Image> {
        let mut opts = PreviewOptions {
            size,
            limits: limits_from(limits)?,
            ..PreviewOptions::default()
        };
        if furnace {
            opts = opts.furnace();
        }
        let m = &self.inner;
        let img = py
            .detach(|| guarded(|| render_ball(m, &opts, &|_| {})))
            .map_err(|msg| error_msg(py, msg))?
            .map_err(|e| match &e {
                vstructc::interp::preview::PreviewError::TooLarge { exceeded, .. } => {
                    raise_with::<LimitError>(py, e.to_string(), vec![exceeded.to_diagnostic()])
                }
                _ => error_msg(py, e.to_string()),
            })?;
        Ok(Image { inner: img })
    }

    fn __repr__(&self) -> String {
        format!("<Material {:?} ({})>", self.name, self.recipe)
    }
}

/// A linear RGB image (float32), rows top to bottom.
#[pyclass(module = "vstructc", frozen)]
struct Image {
    inner: vstructc::raster::Image,
}

impl Image {
    fn raw(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.inner.pixels.len() * 12);
        for p in &self.inner.pixels {
            for c in [p.x, p.y, p.z] {
                out.extend_from_slice(&c.to_ne_bytes());
            }
        }
        out
    }
}

#[pymethods]
impl Image {
    /// Width in pixels.
    #[getter]
    fn width(&self) -> usize {
        self.inner.width
    }
    /// Height in pixels.
    #[getter]
    fn height(&self) -> usize {
        self.inner.height
    }
    /// The pixels as (r, g, b) tuples, row-major, top row first.
    #[getter]
    fn pixels(&self) -> Vec<(f32, f32, f32)> {
        self.inner.pixels.iter().map(|&p| rgb(p)).collect()
    }
    /// The pixels as native-endian float32 bytes (r, g, b per pixel, row-major).
    fn tobytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.raw())
    }
    /// The pixels as a numpy float32 array of shape (height, width, 3). Raises ImportError
    /// when numpy is not installed.
    fn to_numpy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let np = py.import("numpy")?;
        let bytes = PyBytes::new(py, &self.raw());
        let arr = np.call_method1("frombuffer", (bytes, np.getattr("float32")?))?;
        arr.call_method1("reshape", ((self.inner.height, self.inner.width, 3),))?
            .call_method0("copy")
    }
    /// Writes the image: PNG (sRGB, 8 bit) when `path` ends in .png, PFM or OpenEXR (linear
    /// 32-bit float) when it ends in .pfm or .exr.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let format = match ext.as_deref() {
            Some("png") => ImageFormat::Png,
            Some("pfm") => ImageFormat::Pfm,
            Some("exr") => ImageFormat::Exr,
            _ => {
                return Err(PyValueError::new_err(
                    "the image file name ends in .png, .pfm or .exr",
                ));
            }
        };
        let img = &self.inner;
        let data = py
            .detach(|| guarded(|| img.encode(format)))
            .map_err(|m| error_msg(py, m))?
            .map_err(|e| lib_error(py, e))?;
        let p = path.as_path();
        py.detach(|| guarded(|| vstructc::back::output::write_file(p, |w| w.write_all(&data))))
            .map_err(|m| error_msg(py, m))?
            .map_err(|e| lib_error(py, e))
    }
    fn __repr__(&self) -> String {
        format!("<Image {}x{}>", self.inner.width, self.inner.height)
    }
}

/// vstructc: vstruct resolution for RenderMan shader networks, from Python.
#[pymodule]
#[pyo3(name = "vstructc")]
fn vstructc_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // An Error raised without diagnostics (by Python code) still has the attribute.
    py.get_type::<Error>()
        .setattr("diagnostics", PyTuple::empty(py))?;
    m.add("Error", py.get_type::<Error>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("LimitError", py.get_type::<LimitError>())?;
    m.add_class::<Diagnostic>()?;
    m.add_class::<Registry>()?;
    m.add_class::<Network>()?;
    m.add_class::<Material>()?;
    m.add_class::<Image>()?;
    m.add_function(wrap_pyfunction!(resolve, m)?)?;
    m.add_function(wrap_pyfunction!(compile, m)?)?;
    m.add_function(wrap_pyfunction!(explain, m)?)?;
    m.add_function(wrap_pyfunction!(default_limits, m)?)?;
    #[cfg(feature = "test-hooks")]
    m.add_function(wrap_pyfunction!(_panic_for_test, m)?)?;
    Ok(())
}
