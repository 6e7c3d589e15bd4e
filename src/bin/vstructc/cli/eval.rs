//! `vstructc eval INPUT --wo X,Y,Z --wi X,Y,Z [--uv U,V] [--json] [--material HANDLE]
//! [--input NAME=VALUE]...`: prepare each material (or `--material`) for one view and
//! evaluate every lobe for one light direction.
//!
//! Directions are given in the shading frame: normal `+z`, tangent `+x` (they are
//! normalised; `wo` toward the viewer, `wi` toward the light). `--uv` sets the program's
//! `u`, `v` globals (default 0, 0); `P` is the origin.
//!
//! For each lobe that survives prepare: its node id, kind and label, weight `w_k`, the
//! unweighted value `f_k·|μ_i|`, the contribution `w_k ⊙ f_k·|μ_i|`, the lobe's pdf and its
//! selection probability; then the total `f_cos` and mixture pdf, the albedo, emission and
//! transparency. `--json` prints the same as one JSON object.

use super::CommonOptions;
use super::material::{
    MaterialArgs, check_input_names, check_input_syntax, load_materials, packed_inputs,
};
use glam::{Vec2, Vec3};
use serde_json::{Value as Json, json};
use std::fmt::Write as _;
use std::process::ExitCode;
use vstructc::interp::{Prepared, ShadingPoint};

/// Arguments of `vstructc eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Input, material and external inputs.
    #[command(flatten)]
    pub source: MaterialArgs,
    /// Direction toward the viewer, `X,Y,Z` in the shading frame (normal +z).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub wo: String,
    /// Direction toward the light, `X,Y,Z` in the shading frame.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub wi: String,
    /// Surface parameters `U,V`.
    #[arg(long, value_name = "U,V", allow_hyphen_values = true)]
    pub uv: Option<String>,
    /// Print a JSON document on standard output instead of the table (docs/json.md).
    #[arg(long)]
    pub json: bool,
}

fn parse_floats<const N: usize>(flag: &str, s: &str) -> Result<[f32; N], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--{flag} `{s}`: expected {N} comma-separated numbers"))?;
    let arr: [f32; N] = v
        .try_into()
        .map_err(|_| format!("--{flag} `{s}`: expected {N} comma-separated numbers"))?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(format!("--{flag} `{s}`: numbers must be finite"));
    }
    Ok(arr)
}

fn parse_dir(flag: &str, s: &str) -> Result<Vec3, String> {
    let v = Vec3::from_array(parse_floats::<3>(flag, s)?);
    if v.length_squared() == 0.0 {
        return Err(format!("--{flag} `{s}`: the direction must not be zero"));
    }
    Ok(v.normalize())
}

/// A colour as `x` when grey, else `(r, g, b)`, with 6 significant digits.
fn fmt_rgb(c: Vec3) -> String {
    if c.x == c.y && c.y == c.z {
        fmt_num(c.x)
    } else {
        format!("({}, {}, {})", fmt_num(c.x), fmt_num(c.y), fmt_num(c.z))
    }
}

fn fmt_num(x: f32) -> String {
    if x == 0.0 {
        return "0".to_string();
    }
    if x.abs() < 1e-3 {
        return format!("{x:.4e}");
    }
    let s = format!("{x:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// An RGB triple (or direction) as three numbers, each the shortest decimal of its `f32`.
fn rgb_json(c: Vec3) -> Json {
    super::json::nums(&[c.x, c.y, c.z])
}

/// One material's evaluation as rows of text.
fn text_report(
    name: &str,
    recipe: &str,
    p: &Prepared,
    leaves: &[LeafRow],
    wo: Vec3,
    wi: Vec3,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "material {name} (recipe {recipe})");
    let _ = writeln!(
        s,
        "wo = {}  wi = {}  mu_o = {}  mu_i = {}",
        fmt_rgb3(wo),
        fmt_rgb3(wi),
        fmt_num(wo.z),
        fmt_num(wi.z)
    );
    let mut rows = vec![[
        "lobe".to_string(),
        "kind".to_string(),
        "label".to_string(),
        "weight".to_string(),
        "f_cos".to_string(),
        "contribution".to_string(),
        "pdf".to_string(),
        "prob".to_string(),
    ]];
    for r in leaves {
        rows.push([
            format!("#{}", r.node),
            r.kind.to_string(),
            r.label.clone(),
            fmt_rgb(r.weight),
            fmt_rgb(r.value),
            fmt_rgb(r.weight * r.value),
            fmt_num(r.pdf),
            fmt_num(r.prob),
        ]);
    }
    let e = p.eval(wi);
    rows.push([
        "total".to_string(),
        String::new(),
        String::new(),
        String::new(),
        String::new(),
        fmt_rgb(e.f_cos),
        fmt_num(e.pdf),
        String::new(),
    ]);
    let widths: Vec<usize> = (0..8)
        .map(|c| rows.iter().map(|r| r[c].chars().count()).max().unwrap_or(0))
        .collect();
    for r in &rows {
        let mut line = String::new();
        for (c, cell) in r.iter().enumerate() {
            let pad = widths[c] - cell.chars().count();
            line.push_str(cell);
            line.push_str(&" ".repeat(pad + 2));
        }
        let _ = writeln!(s, "{}", line.trim_end());
    }
    let a = p.albedo();
    let _ = writeln!(
        s,
        "albedo: reflect {}  transmit {}",
        fmt_rgb(a.reflect),
        fmt_rgb(a.transmit)
    );
    let _ = writeln!(
        s,
        "emission {}  transparency {}",
        fmt_rgb(p.emission()),
        fmt_rgb(p.transparency())
    );
    s
}

fn fmt_rgb3(c: Vec3) -> String {
    format!("({}, {}, {})", fmt_num(c.x), fmt_num(c.y), fmt_num(c.z))
}

struct LeafRow {
    node: u32,
    kind: &'static str,
    label: String,
    weight: Vec3,
    value: Vec3,
    pdf: f32,
    prob: f32,
}

/// Run `vstructc eval`.
pub fn run(args: &EvalArgs, common: &CommonOptions) -> ExitCode {
    let usage = |msg: String| {
        eprintln_quiet!("error: {msg}");
        ExitCode::from(2)
    };
    let parsed = (|| {
        let wo = parse_dir("wo", &args.wo)?;
        let wi = parse_dir("wi", &args.wi)?;
        let uv = match &args.uv {
            Some(s) => Vec2::from_array(parse_floats::<2>("uv", s)?),
            None => Vec2::ZERO,
        };
        Ok::<_, String>((wo, wi, uv))
    })();
    let (wo, wi, uv) = match parsed {
        Ok(x) => x,
        Err(msg) => return usage(msg),
    };
    if let Err(msg) = check_input_syntax(&args.source.inputs) {
        return usage(msg);
    }
    let (materials, diags) = match load_materials(&args.source, common) {
        Ok(x) => x,
        Err(status) => return status,
    };
    let status = super::report(&diags, common);
    if status != ExitCode::SUCCESS {
        return status;
    }
    if let Err(msg) = check_input_names(&materials, &args.source.inputs) {
        return usage(msg);
    }
    let mut text = String::new();
    let mut list = Vec::new();
    for c in &materials {
        let inputs = match packed_inputs(&c.material, &args.source.inputs) {
            Ok(i) => i,
            Err(msg) => return usage(msg),
        };
        let point = ShadingPoint::new(Vec3::Z, Vec3::X, wo)
            .with_inputs(&inputs)
            .with_uv(uv);
        let p = c.material.prepare(&point);
        let rows: Vec<LeafRow> = p
            .lobes()
            .iter()
            .enumerate()
            .map(|(k, a)| {
                let info = &c.material.leaves()[a.leaf as usize];
                let e = a.lobe.eval(p.frame(k).to_local(wi));
                LeafRow {
                    node: info.node.0,
                    kind: info.leaf.kind.name(),
                    label: info.leaf.label.clone(),
                    weight: a.weight,
                    value: e.f_cos,
                    pdf: e.pdf,
                    prob: a.prob,
                }
            })
            .collect();
        let recipe = c.material.ir().recipe.name();
        if args.json {
            let e = p.eval(wi);
            let a = p.albedo();
            list.push(json!({
                "name": c.name,
                "recipe": recipe,
                "wo": rgb_json(wo),
                "wi": rgb_json(wi),
                "lobes": rows.iter().map(|r| json!({
                    "node": r.node,
                    "kind": r.kind,
                    "label": r.label,
                    "weight": rgb_json(r.weight),
                    "f_cos": rgb_json(r.value),
                    "contribution": rgb_json(r.weight * r.value),
                    "pdf": super::json::num(r.pdf),
                    "prob": super::json::num(r.prob),
                })).collect::<Vec<_>>(),
                "total": { "f_cos": rgb_json(e.f_cos), "pdf": super::json::num(e.pdf) },
                "albedo": { "reflect": rgb_json(a.reflect), "transmit": rgb_json(a.transmit) },
                "emission": rgb_json(p.emission()),
                "transparency": rgb_json(p.transparency()),
            }));
        } else {
            if !text.is_empty() {
                text.push('\n');
            }
            text.push_str(&text_report(&c.name, recipe, &p, &rows, wo, wi));
        }
    }
    if args.json {
        let doc = json!({ "materials": list });
        match serde_json::to_string_pretty(&doc) {
            Ok(s) => text = s + "\n",
            Err(e) => {
                eprintln_quiet!("error: {e}");
                return ExitCode::from(1);
            }
        }
    }
    match super::input::print_stdout(&text, common) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failed) => failed,
    }
}
