//! The small pattern set fused into the parameter program: constant, mix,
//! remap, clamp, checker, value noise and a uv manifold. Their definitions are
//! `args/vsConstant.args` … `args/vsUvManifold.args`; every pattern has the outputs
//! `resultRGB` (color) and `resultF` (float, the first channel), the manifold `result`
//! (point).
//!
//! Defaults when no definition is loaded are the same as in the `.args` files.

use super::{Graph, Lower};
use crate::diag::Error;
use crate::ir::{Global, OpCode, Reg};

/// The shader names of the fused patterns.
pub(crate) const PATTERNS: [&str; 7] = [
    "vsConstant",
    "vsMix",
    "vsRemap",
    "vsClamp",
    "vsChecker",
    "vsValueNoise",
    "vsUvManifold",
];

/// True for a fused pattern type.
pub(crate) fn is_pattern(shader: &str) -> bool {
    PATTERNS.contains(&shader)
}

/// The program expression of `output` of pattern node `n`; `None` for an unknown output.
pub fn output<G: Graph>(
    cx: &mut Lower<'_, G>,
    n: G::Id,
    output: &str,
) -> Result<Option<Reg>, Error> {
    let shader = cx.graph.shader(n).to_string();
    let result = match shader.as_str() {
        "vsConstant" => {
            if output == "resultF" {
                return Ok(Some(cx.pf(n, "value", 0.0)?));
            }
            cx.pc(n, "color", [0.5; 3])?
        }
        "vsMix" => {
            let a = cx.pc(n, "color1", [0.0; 3])?;
            let b = cx.pc(n, "color2", [1.0; 3])?;
            let t = cx.pf(n, "mix", 0.5)?;
            cx.b.prog.lerp(a, b, t)
        }
        "vsRemap" => {
            let x = cx.pc(n, "input", [0.0; 3])?;
            let in_min = cx.pf(n, "inputMin", 0.0)?;
            let in_max = cx.pf(n, "inputMax", 1.0)?;
            let out_min = cx.pf(n, "outputMin", 0.0)?;
            let out_max = cx.pf(n, "outputMax", 1.0)?;
            let p = &mut cx.b.prog;
            let num = p.sub(x, in_min);
            let den = p.sub(in_max, in_min);
            let t = p.div(num, den);
            p.lerp(out_min, out_max, t)
        }
        "vsClamp" => {
            let x = cx.pc(n, "input", [0.0; 3])?;
            let lo = cx.pc(n, "min", [0.0; 3])?;
            let hi = cx.pc(n, "max", [1.0; 3])?;
            let p = &mut cx.b.prog;
            let y = p.bin(OpCode::Max, x, lo);
            p.bin(OpCode::Min, y, hi)
        }
        "vsChecker" => {
            let st = manifold(cx, n, false)?;
            let freq = cx.pf(n, "frequency", 4.0)?;
            let a = cx.pc(n, "colorA", [0.0; 3])?;
            let b = cx.pc(n, "colorB", [1.0; 3])?;
            let p = &mut cx.b.prog;
            let scaled = p.mul(st, freq);
            let cells = p.un(OpCode::Floor, scaled);
            let s = p.splat(cells, 0);
            let t = p.splat(cells, 1);
            let sum = p.add(s, t);
            let half = p.constf(0.5);
            let h = p.mul(sum, half);
            let fr = p.un(OpCode::Fract, h);
            let two = p.constf(2.0);
            let parity = p.mul(fr, two);
            p.lerp(a, b, parity)
        }
        "vsValueNoise" => {
            let pt = manifold(cx, n, true)?;
            let freq = cx.pf(n, "frequency", 1.0)?;
            let amp = cx.pf(n, "amplitude", 1.0)?;
            let p = &mut cx.b.prog;
            let q = p.mul(pt, freq);
            let v = p.un(OpCode::ValueNoise, q);
            p.mul(v, amp)
        }
        "vsUvManifold" => {
            let ss = cx.pf(n, "scaleS", 1.0)?;
            let st = cx.pf(n, "scaleT", 1.0)?;
            let os = cx.pf(n, "offsetS", 0.0)?;
            let ot = cx.pf(n, "offsetT", 0.0)?;
            let p = &mut cx.b.prog;
            let u = p.global(Global::U);
            let v = p.global(Global::V);
            let us = p.mul(u, ss);
            let s = p.add(us, os);
            let vt = p.mul(v, st);
            let t = p.add(vt, ot);
            let z = p.constf(0.0);
            let r = p.tern(OpCode::Compose, s, t, z);
            return Ok((output == "result").then_some(r));
        }
        _ => return Ok(None),
    };
    Ok(match output {
        "resultRGB" => Some(result),
        "resultF" => Some(cx.b.prog.splat(result, 0)),
        _ => None,
    })
}

/// The `manifold` input: the connected point, else `(u, v, 0)` (checker) or `P` (noise).
fn manifold<G: Graph>(cx: &mut Lower<'_, G>, n: G::Id, use_p: bool) -> Result<Reg, Error> {
    if cx.is_connected(n, "manifold") {
        return cx.pv(n, "manifold", [0.0; 3]);
    }
    let p = &mut cx.b.prog;
    if use_p {
        return Ok(p.global(Global::P));
    }
    let u = p.global(Global::U);
    let v = p.global(Global::V);
    let z = p.constf(0.0);
    Ok(p.tern(OpCode::Compose, u, v, z))
}
