//! The parameter program: straight-line SSA over `f32x3` registers.
//!
//! Op `i` of a [`Program`] defines register `i`. Scalars are broadcast to all three lanes.
//! Programs are built with [`ProgramBuilder`], which folds constants and shares identical
//! operations (value numbering) as it goes, so the two passes "constant folding" and
//! "common-subexpression elimination" are the builder applied to an existing program
//! ([`Program::rebuild`]).

use glam::Vec3;
// Fx hashing: keys are a few integers, so SipHash's DoS resistance is not needed (and cost
// most of the builder's time).
use rustc_hash::FxHashMap as HashMap;

/// A register: the index of the op that defines it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Reg(pub u32);

impl Reg {
    /// The register as an index into the register file.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Shading globals a program may read (`P, N, u, v, ...`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Global {
    /// Surface position.
    P,
    /// Shading normal.
    N,
    /// Surface tangent.
    T,
    /// Direction toward the viewer.
    I,
    /// Surface parameter u.
    U,
    /// Surface parameter v.
    V,
}

impl Global {
    fn from_index(i: u32) -> Global {
        match i {
            0 => Global::P,
            1 => Global::N,
            2 => Global::T,
            3 => Global::I,
            4 => Global::U,
            _ => Global::V,
        }
    }
    fn index(self) -> u32 {
        self as u32
    }
    /// Lower-case name used by the printers.
    pub fn name(self) -> &'static str {
        match self {
            Global::P => "P",
            Global::N => "N",
            Global::T => "T",
            Global::I => "I",
            Global::U => "u",
            Global::V => "v",
        }
    }
}

/// Per-point shading globals given to [`Program::run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Globals {
    /// Surface position.
    pub p: Vec3,
    /// Shading normal.
    pub n: Vec3,
    /// Surface tangent.
    pub t: Vec3,
    /// Direction toward the viewer.
    pub i: Vec3,
    /// Surface parameter u.
    pub u: f32,
    /// Surface parameter v.
    pub v: f32,
}

impl Default for Globals {
    fn default() -> Self {
        Globals {
            p: Vec3::ZERO,
            n: Vec3::Z,
            t: Vec3::X,
            i: Vec3::Z,
            u: 0.0,
            v: 0.0,
        }
    }
}

/// Operation codes. The comment gives the register operands, in order; `imm` holds clamp
/// bounds and constants, `args` after the register operands hold slot/frame/channel indices.
///
/// The set is the IR's whole instruction set; the current recipes emit most of it (the rest,
/// such as `Sign` or `Dot`, is built by tests and by IRs made by hand), hence the allowance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(not(feature = "testkit"), allow(dead_code))]
pub enum OpCode {
    /// A constant (`imm`).
    Const,
    /// External input slot `args[0]`.
    Input,
    /// `μ_o = n·V` of frame `args[0]`.
    ViewMu,
    /// Shading global `args[0]` (see [`Global`]).
    Global,
    /// a + b.
    Add,
    /// a − b.
    Sub,
    /// a ⊙ b.
    Mul,
    /// a / b per lane, 0 where b is 0.
    Div,
    /// −a.
    Neg,
    /// min(a, b).
    Min,
    /// max(a, b).
    Max,
    /// clamp(a, `imm[0]`, `imm[1]`).
    Clamp,
    /// lerp(a, b, t) = (1 − t) a + t b.
    Lerp,
    /// c ≠ 0 ? a : b, per lane.
    Select,
    /// a == b → 1 else 0.
    CmpEq,
    /// a ≠ b → 1 else 0.
    CmpNe,
    /// a > b → 1 else 0.
    CmpGt,
    /// a ≥ b → 1 else 0.
    CmpGe,
    /// a ≠ 0 or b ≠ 0.
    Or,
    /// a ≠ 0 and b ≠ 0.
    And,
    /// max(a, 0)^b.
    Pow,
    /// e^a.
    Exp,
    /// √max(a, 0).
    Sqrt,
    /// |a|.
    Abs,
    /// sign(a) (0 at 0).
    Sign,
    /// floor(a).
    Floor,
    /// a − floor(a).
    Fract,
    /// Hermite smoothstep(e0, e1, x).
    Smoothstep,
    /// Luminance (Rec.709) broadcast.
    Lum,
    /// Channel mean broadcast.
    Mean,
    /// Largest channel broadcast.
    MaxComp,
    /// Channel `args[1]` of a, broadcast.
    Splat,
    /// (x.x, y.x, z.x): a vector from three scalars.
    Compose,
    /// Dot product of a and b, broadcast.
    Dot,
    /// a / |a| (zero stays zero).
    Normalize3,
    /// a if a ≠ 0, else the shading normal.
    NormalOrDefault,
    /// Exact dielectric Fresnel F(μ, η), per lane.
    FresnelDielectric,
    /// Conductor Fresnel F(μ, η, κ), per lane.
    FresnelConductor,
    /// Generalized Schlick F0 + (F90 − F0)(1 − μ)^q.
    SchlickCurve,
    /// Hemispherical average 2∫F μ dμ of the dielectric Fresnel (d'Eon fit).
    FresnelAvgDielectric,
    /// Value noise of a 3-D point (trilinear over hashed lattice values in [0, 1]).
    ValueNoise,
}

impl OpCode {
    /// Number of register operands.
    pub fn arity(self) -> usize {
        use OpCode::*;
        match self {
            Const | Input | ViewMu | Global => 0,
            Neg | Clamp | Exp | Sqrt | Abs | Sign | Floor | Fract | Lum | Mean | MaxComp
            | Splat | Normalize3 | NormalOrDefault | FresnelAvgDielectric | ValueNoise => 1,
            Add | Sub | Mul | Div | Min | Max | CmpEq | CmpNe | CmpGt | CmpGe | Or | And | Pow
            | Dot | FresnelDielectric => 2,
            Lerp | Select | Smoothstep | Compose | FresnelConductor => 3,
            SchlickCurve => 4,
        }
    }

    /// True when the result depends only on the register operands (no inputs, globals or
    /// view), so the op can be folded when its operands are constants.
    pub fn is_pure(self) -> bool {
        !matches!(
            self,
            OpCode::Input | OpCode::ViewMu | OpCode::Global | OpCode::NormalOrDefault
        )
    }

    /// Lower-case mnemonic used by the printers.
    pub fn mnemonic(self) -> &'static str {
        use OpCode::*;
        match self {
            Const => "const",
            Input => "input",
            ViewMu => "view_mu",
            Global => "global",
            Add => "add",
            Sub => "sub",
            Mul => "mul",
            Div => "div",
            Neg => "neg",
            Min => "min",
            Max => "max",
            Clamp => "clamp",
            Lerp => "lerp",
            Select => "select",
            CmpEq => "eq",
            CmpNe => "ne",
            CmpGt => "gt",
            CmpGe => "ge",
            Or => "or",
            And => "and",
            Pow => "pow",
            Exp => "exp",
            Sqrt => "sqrt",
            Abs => "abs",
            Sign => "sign",
            Floor => "floor",
            Fract => "fract",
            Smoothstep => "smoothstep",
            Lum => "lum",
            Mean => "mean",
            MaxComp => "maxcomp",
            Splat => "splat",
            Compose => "compose",
            Dot => "dot",
            Normalize3 => "normalize",
            NormalOrDefault => "normal_or_default",
            FresnelDielectric => "fresnel_dielectric",
            FresnelConductor => "fresnel_conductor",
            SchlickCurve => "schlick_curve",
            FresnelAvgDielectric => "fresnel_avg_dielectric",
            ValueNoise => "value_noise",
        }
    }
}

/// One SSA operation. Register operands are `args[..code.arity()]`; an index operand (slot,
/// frame, global, channel) follows them; `imm` holds constants and clamp bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Op {
    /// What the op computes.
    pub code: OpCode,
    /// Register operands, then an index operand.
    pub args: [u32; 4],
    /// Immediate values.
    pub imm: [f32; 3],
}

impl Op {
    /// The register operands.
    pub fn operands(&self) -> impl Iterator<Item = Reg> + '_ {
        self.args[..self.code.arity()].iter().map(|&a| Reg(a))
    }

    /// The index operand that follows the registers (slot, frame, global, channel).
    #[cfg(any(test, feature = "testkit"))]
    pub fn index_operand(&self) -> u32 {
        let n = self.code.arity();
        if n < 4 { self.args[n] } else { 0 }
    }

    fn key(&self) -> (OpCode, [u32; 4], [u32; 3]) {
        (
            self.code,
            self.args,
            [
                self.imm[0].to_bits(),
                self.imm[1].to_bits(),
                self.imm[2].to_bits(),
            ],
        )
    }
}

/// A straight-line program; op `i` defines register `i`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Program {
    /// The operations in definition order.
    pub ops: Vec<Op>,
}

/// Per-point context of [`Program::run`].
#[derive(Debug, Clone, Copy)]
pub struct RunContext<'a> {
    /// External slot values, one `Vec3` per slot (scalars broadcast).
    pub inputs: &'a [Vec3],
    /// `μ_o` per frame; frames beyond the slice read 1.
    pub mu_o: &'a [f32],
    /// Shading globals.
    pub globals: Globals,
}

impl Program {
    /// Number of registers.
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// True when the program has no ops.
    #[cfg(any(test, feature = "testkit"))]
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The constant held by `r`, if `r` is defined by a `Const` op.
    pub fn constant(&self, r: Reg) -> Option<Vec3> {
        let op = self.ops.get(r.index())?;
        (op.code == OpCode::Const).then(|| Vec3::from_array(op.imm))
    }

    /// True when `r` is the constant zero (all lanes).
    #[cfg(any(test, feature = "testkit"))]
    pub fn is_zero(&self, r: Reg) -> bool {
        self.constant(r) == Some(Vec3::ZERO)
    }

    /// Run every op for one point into `regs` (resized to the program length).
    pub fn run_into(&self, ctx: &RunContext<'_>, regs: &mut Vec<Vec3>) {
        regs.clear();
        regs.reserve(self.ops.len());
        for op in &self.ops {
            let v = eval_op(op, regs, ctx);
            regs.push(v);
        }
    }

    /// Run every op for one point and return the register file.
    pub fn run(&self, ctx: &RunContext<'_>) -> Vec<Vec3> {
        let mut regs = Vec::new();
        self.run_into(ctx, &mut regs);
        regs
    }

    /// Keep only the ops reachable from `roots` (dead-code elimination without re-folding).
    /// Returns the new program and the mapping old register → new register.
    pub fn compact(&self, roots: &[Reg]) -> (Program, HashMap<Reg, Reg>) {
        let live = self.liveness(roots);
        let mut map = vec![u32::MAX; self.ops.len()];
        let mut ops = Vec::with_capacity(self.ops.len());
        for (i, op) in self.ops.iter().enumerate() {
            if !live[i] {
                continue;
            }
            let mut new = *op;
            for k in 0..op.code.arity() {
                new.args[k] = map[op.args[k] as usize];
            }
            map[i] = ops.len() as u32;
            ops.push(new);
        }
        let pairs = map
            .iter()
            .enumerate()
            .filter(|(_, n)| **n != u32::MAX)
            .map(|(i, n)| (Reg(i as u32), Reg(*n)))
            .collect();
        (Program { ops }, pairs)
    }

    fn liveness(&self, roots: &[Reg]) -> Vec<bool> {
        let mut live = vec![false; self.ops.len()];
        for r in roots {
            if let Some(l) = live.get_mut(r.index()) {
                *l = true;
            }
        }
        for i in (0..self.ops.len()).rev() {
            if live[i] {
                for a in self.ops[i].operands() {
                    live[a.index()] = true;
                }
            }
        }
        live
    }

    /// Re-emit the live ops through a fresh [`ProgramBuilder`] (constant folding and CSE),
    /// keeping only registers reachable from `roots`. Returns the new program and the mapping
    /// old register → new register (for the live ones).
    #[cfg(any(test, feature = "testkit"))]
    pub fn rebuild(&self, roots: &[Reg]) -> (Program, HashMap<Reg, Reg>) {
        let live = self.liveness(roots);
        let mut b = ProgramBuilder::new();
        let mut map: HashMap<Reg, Reg> = HashMap::default();
        for (i, op) in self.ops.iter().enumerate() {
            if !live[i] {
                continue;
            }
            let mut new = *op;
            for k in 0..op.code.arity() {
                new.args[k] = map[&Reg(op.args[k])].0;
            }
            map.insert(Reg(i as u32), b.push(new));
        }
        (b.finish(), map)
    }
}

/// Builds a [`Program`] with constant folding, algebraic simplification and value
/// numbering (an identical op is emitted once).
#[derive(Debug, Default)]
pub struct ProgramBuilder {
    ops: Vec<Op>,
    seen: HashMap<(OpCode, [u32; 4], [u32; 3]), Reg>,
}

impl ProgramBuilder {
    /// An empty builder.
    #[cfg(any(test, feature = "testkit"))]
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of ops so far.
    #[cfg(any(test, feature = "testkit"))]
    pub fn len(&self) -> usize {
        self.ops.len()
    }

    /// True when nothing was emitted yet.
    #[cfg(any(test, feature = "testkit"))]
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// The finished program.
    pub fn finish(self) -> Program {
        Program { ops: self.ops }
    }

    /// The program so far (for inspection during lowering).
    pub fn program(&self) -> Program {
        Program {
            ops: self.ops.clone(),
        }
    }

    /// The constant held by `r`, if any.
    pub fn constant(&self, r: Reg) -> Option<Vec3> {
        let op = self.ops.get(r.index())?;
        (op.code == OpCode::Const).then(|| Vec3::from_array(op.imm))
    }

    /// The scalar constant held by `r`, if it is a constant with equal lanes.
    pub fn scalar(&self, r: Reg) -> Option<f32> {
        self.constant(r)
            .filter(|c| c.x == c.y && c.y == c.z)
            .map(|c| c.x)
    }

    /// Emit `op` (after folding and sharing); returns its register.
    pub fn push(&mut self, op: Op) -> Reg {
        let op = self.canonical(op);
        if let Some(r) = self.simplify(&op) {
            return r;
        }
        let op = if op.code.is_pure()
            && op.code != OpCode::Const
            && op.operands().all(|a| self.constant(a).is_some())
        {
            // Evaluate on a local register file holding just the constant operands.
            let mut local = [Vec3::ZERO; 4];
            let mut renamed = op;
            for (k, slot) in local.iter_mut().enumerate().take(op.code.arity()) {
                *slot = Vec3::from_array(self.ops[op.args[k] as usize].imm);
                renamed.args[k] = k as u32;
            }
            let ctx = RunContext {
                inputs: &[],
                mu_o: &[],
                globals: Globals::default(),
            };
            const_op(eval_op(&renamed, &local, &ctx))
        } else {
            op
        };
        let key = op.key();
        if let Some(&r) = self.seen.get(&key) {
            return r;
        }
        let r = Reg(self.ops.len() as u32);
        self.ops.push(op);
        self.seen.insert(key, r);
        r
    }

    /// Commutative ops get their operands in register order so that `a+b` and `b+a` share.
    fn canonical(&self, mut op: Op) -> Op {
        use OpCode::*;
        if matches!(
            op.code,
            Add | Mul | Min | Max | CmpEq | CmpNe | Or | And | Dot
        ) && op.args[0] > op.args[1]
        {
            op.args.swap(0, 1);
        }
        op
    }

    /// Algebraic identities that return an existing register.
    fn simplify(&mut self, op: &Op) -> Option<Reg> {
        use OpCode::*;
        let a = Reg(op.args[0]);
        let b = Reg(op.args[1]);
        let c = Reg(op.args[2]);
        let s = |r: Reg| self.scalar(r);
        match op.code {
            Add if s(a) == Some(0.0) => Some(b),
            Add if s(b) == Some(0.0) => Some(a),
            Sub if s(b) == Some(0.0) => Some(a),
            Mul if s(a) == Some(1.0) => Some(b),
            Mul if s(b) == Some(1.0) => Some(a),
            Mul if s(a) == Some(0.0) || s(b) == Some(0.0) => Some(self.constant_reg(Vec3::ZERO)),
            Div if s(b) == Some(1.0) => Some(a),
            Lerp if a == b => Some(a),
            Lerp if s(c) == Some(0.0) => Some(a),
            Lerp if s(c) == Some(1.0) => Some(b),
            Select if b == c => Some(b),
            Select => match self.constant(a) {
                Some(k) if k.cmpne(Vec3::ZERO).all() => Some(b),
                Some(k) if k == Vec3::ZERO => Some(c),
                _ => None,
            },
            Min | Max if a == b => Some(a),
            _ => None,
        }
    }

    fn constant_reg(&mut self, v: Vec3) -> Reg {
        self.push(const_op(v))
    }

    // ---- convenience constructors -------------------------------------------------------

    fn op(&mut self, code: OpCode, regs: &[Reg], index: u32, imm: [f32; 3]) -> Reg {
        let mut args = [0u32; 4];
        for (k, r) in regs.iter().enumerate() {
            args[k] = r.0;
        }
        if regs.len() < 4 {
            args[regs.len()] = index;
        }
        self.push(Op { code, args, imm })
    }

    /// A constant colour/vector.
    pub fn constant3(&mut self, v: Vec3) -> Reg {
        self.constant_reg(v)
    }
    /// A scalar constant (broadcast).
    pub fn constf(&mut self, x: f32) -> Reg {
        self.constant_reg(Vec3::splat(x))
    }
    /// External input slot.
    pub fn input(&mut self, slot: u32) -> Reg {
        self.op(OpCode::Input, &[], slot, [0.0; 3])
    }
    /// `μ_o` of a frame.
    pub fn view_mu(&mut self, frame: u32) -> Reg {
        self.op(OpCode::ViewMu, &[], frame, [0.0; 3])
    }
    /// A shading global.
    pub fn global(&mut self, g: Global) -> Reg {
        self.op(OpCode::Global, &[], g.index(), [0.0; 3])
    }
    /// A binary op.
    pub fn bin(&mut self, code: OpCode, a: Reg, b: Reg) -> Reg {
        self.op(code, &[a, b], 0, [0.0; 3])
    }
    /// A unary op.
    pub fn un(&mut self, code: OpCode, a: Reg) -> Reg {
        self.op(code, &[a], 0, [0.0; 3])
    }
    /// A ternary op.
    pub fn tern(&mut self, code: OpCode, a: Reg, b: Reg, c: Reg) -> Reg {
        self.op(code, &[a, b, c], 0, [0.0; 3])
    }
    /// a + b.
    pub fn add(&mut self, a: Reg, b: Reg) -> Reg {
        self.bin(OpCode::Add, a, b)
    }
    /// a − b.
    pub fn sub(&mut self, a: Reg, b: Reg) -> Reg {
        self.bin(OpCode::Sub, a, b)
    }
    /// a ⊙ b.
    pub fn mul(&mut self, a: Reg, b: Reg) -> Reg {
        self.bin(OpCode::Mul, a, b)
    }
    /// a / b (0 where b = 0).
    pub fn div(&mut self, a: Reg, b: Reg) -> Reg {
        self.bin(OpCode::Div, a, b)
    }
    /// 1 − a.
    pub fn one_minus(&mut self, a: Reg) -> Reg {
        let one = self.constf(1.0);
        self.sub(one, a)
    }
    /// clamp(a, lo, hi).
    pub fn clamp(&mut self, a: Reg, lo: f32, hi: f32) -> Reg {
        self.op(OpCode::Clamp, &[a], 0, [lo, hi, 0.0])
    }
    /// clamp(a, 0, 1).
    pub fn saturate(&mut self, a: Reg) -> Reg {
        self.clamp(a, 0.0, 1.0)
    }
    /// lerp(a, b, t).
    pub fn lerp(&mut self, a: Reg, b: Reg, t: Reg) -> Reg {
        self.tern(OpCode::Lerp, a, b, t)
    }
    /// c ≠ 0 ? a : b.
    pub fn select(&mut self, c: Reg, a: Reg, b: Reg) -> Reg {
        self.tern(OpCode::Select, c, a, b)
    }
    /// Channel `ch` of a, broadcast.
    pub fn splat(&mut self, a: Reg, ch: u32) -> Reg {
        self.op(OpCode::Splat, &[a], ch.min(2), [0.0; 3])
    }
    /// max(a, 0)^b.
    pub fn pow(&mut self, a: Reg, b: Reg) -> Reg {
        self.bin(OpCode::Pow, a, b)
    }
    /// Luminance.
    pub fn lum(&mut self, a: Reg) -> Reg {
        self.un(OpCode::Lum, a)
    }
    /// Generalized Schlick curve at μ.
    pub fn schlick(&mut self, mu: Reg, f0: Reg, f90: Reg, q: Reg) -> Reg {
        self.op(OpCode::SchlickCurve, &[mu, f0, f90, q], 0, [0.0; 3])
    }
}

fn const_op(v: Vec3) -> Op {
    // Normalise −0 to +0 so that constants share one register.
    let z = |x: f32| if x == 0.0 { 0.0 } else { x };
    Op {
        code: OpCode::Const,
        args: [0; 4],
        imm: [z(v.x), z(v.y), z(v.z)],
    }
}

fn lanes(v: Vec3, f: impl Fn(f32) -> f32) -> Vec3 {
    Vec3::new(f(v.x), f(v.y), f(v.z))
}

fn lanes2(a: Vec3, b: Vec3, f: impl Fn(f32, f32) -> f32) -> Vec3 {
    Vec3::new(f(a.x, b.x), f(a.y, b.y), f(a.z, b.z))
}

fn lanes3(a: Vec3, b: Vec3, c: Vec3, f: impl Fn(f32, f32, f32) -> f32) -> Vec3 {
    Vec3::new(f(a.x, b.x, c.x), f(a.y, b.y, c.y), f(a.z, b.z, c.z))
}

fn b2f(b: bool) -> f32 {
    if b { 1.0 } else { 0.0 }
}

/// Luminance with the Rec.709 weights.
pub fn lum(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Exact unpolarised dielectric Fresnel; 1 under total internal reflection.
pub fn fresnel_dielectric(mu: f32, eta: f32) -> f32 {
    let mu = mu.abs().min(1.0);
    let g2 = eta * eta + mu * mu - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - mu) / (g + mu);
    let num = mu * (g + mu) - 1.0;
    let den = mu * (g - mu) + 1.0;
    let b = if den == 0.0 { 0.0 } else { num / den };
    (0.5 * a * a * (1.0 + b * b)).clamp(0.0, 1.0)
}

/// Conductor Fresnel for complex index η + iκ.
pub fn fresnel_conductor(mu: f32, eta: f32, kappa: f32) -> f32 {
    let c = mu.abs().min(1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - kappa * kappa - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * kappa * kappa).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let rs = (a2b2 - 2.0 * a * c + c2) / (a2b2 + 2.0 * a * c + c2).max(1e-12);
    let rp_num = c2 * a2b2 - 2.0 * a * c * s2 + s2 * s2;
    let rp_den = c2 * a2b2 + 2.0 * a * c * s2 + s2 * s2;
    let rp = if rp_den > 0.0 {
        rs * rp_num / rp_den
    } else {
        rs
    };
    (0.5 * (rs + rp)).clamp(0.0, 1.0)
}

/// d'Eon's fit of the hemispherical dielectric Fresnel average, with the exact
/// identity for η < 1.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn fresnel_avg_dielectric(eta: f32) -> f32 {
    fn fit(eta: f32) -> f32 {
        let eta = eta.clamp(1.0, 3.0);
        ((10893.0 * eta - 1438.2) / (-774.4 * eta * eta + 10212.0 * eta + 1.0))
            .ln()
            .max(0.0)
    }
    if eta <= 0.0 {
        0.0
    } else if eta < 1.0 {
        1.0 - eta * eta * (1.0 - fit(1.0 / eta))
    } else {
        fit(eta)
    }
}

fn hash3(x: i32, y: i32, z: i32) -> f32 {
    // A small integer hash (xorshift-multiply); deterministic across platforms.
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ (z as u32).wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_215.0
}

/// Value noise in [0, 1]: trilinear interpolation of hashed lattice values with a smoothstep
/// fade.
#[cfg_attr(feature = "testkit", visibility::make(pub))]
pub(crate) fn value_noise(p: Vec3) -> f32 {
    let f = p.floor();
    let t = p - f;
    let t = t * t * (Vec3::splat(3.0) - 2.0 * t);
    let (x, y, z) = (f.x as i32, f.y as i32, f.z as i32);
    let mut acc = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let w = (if dx == 1 { t.x } else { 1.0 - t.x })
                    * (if dy == 1 { t.y } else { 1.0 - t.y })
                    * (if dz == 1 { t.z } else { 1.0 - t.z });
                acc += w * hash3(x + dx, y + dy, z + dz);
            }
        }
    }
    acc
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    if e1 == e0 {
        return b2f(x >= e1);
    }
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Evaluate one op given the registers defined so far.
fn eval_op(op: &Op, regs: &[Vec3], ctx: &RunContext<'_>) -> Vec3 {
    use OpCode::*;
    let r = |k: usize| regs[op.args[k] as usize];
    match op.code {
        Const => Vec3::from_array(op.imm),
        Input => ctx
            .inputs
            .get(op.args[0] as usize)
            .copied()
            .unwrap_or(Vec3::ZERO),
        ViewMu => Vec3::splat(ctx.mu_o.get(op.args[0] as usize).copied().unwrap_or(1.0)),
        Global => {
            let g = &ctx.globals;
            match self::Global::from_index(op.args[0]) {
                self::Global::P => g.p,
                self::Global::N => g.n,
                self::Global::T => g.t,
                self::Global::I => g.i,
                self::Global::U => Vec3::splat(g.u),
                self::Global::V => Vec3::splat(g.v),
            }
        }
        Add => r(0) + r(1),
        Sub => r(0) - r(1),
        Mul => r(0) * r(1),
        Div => lanes2(r(0), r(1), |a, b| if b == 0.0 { 0.0 } else { a / b }),
        Neg => -r(0),
        Min => r(0).min(r(1)),
        Max => r(0).max(r(1)),
        Clamp => lanes(r(0), |a| a.max(op.imm[0]).min(op.imm[1])),
        Lerp => {
            // (1 − t)a + t b is exact at both ends (t = 0 gives a, t = 1 gives b).
            let (a, b, t) = (r(0), r(1), r(2));
            (Vec3::ONE - t) * a + t * b
        }
        Select => lanes3(r(0), r(1), r(2), |c, a, b| if c != 0.0 { a } else { b }),
        CmpEq => lanes2(r(0), r(1), |a, b| b2f(a == b)),
        CmpNe => lanes2(r(0), r(1), |a, b| b2f(a != b)),
        CmpGt => lanes2(r(0), r(1), |a, b| b2f(a > b)),
        CmpGe => lanes2(r(0), r(1), |a, b| b2f(a >= b)),
        Or => lanes2(r(0), r(1), |a, b| b2f(a != 0.0 || b != 0.0)),
        And => lanes2(r(0), r(1), |a, b| b2f(a != 0.0 && b != 0.0)),
        Pow => lanes2(r(0), r(1), |a, b| {
            let a = a.max(0.0);
            if b == 0.0 { 1.0 } else { a.powf(b) }
        }),
        Exp => lanes(r(0), f32::exp),
        Sqrt => lanes(r(0), |a| a.max(0.0).sqrt()),
        Abs => r(0).abs(),
        Sign => lanes(r(0), |a| if a == 0.0 { 0.0 } else { a.signum() }),
        Floor => r(0).floor(),
        Fract => {
            let a = r(0);
            a - a.floor()
        }
        Smoothstep => lanes3(r(0), r(1), r(2), smoothstep),
        Lum => Vec3::splat(lum(r(0))),
        Mean => {
            let a = r(0);
            Vec3::splat((a.x + a.y + a.z) / 3.0)
        }
        MaxComp => Vec3::splat(r(0).max_element()),
        Splat => Vec3::splat(r(0)[op.args[1].min(2) as usize]),
        Compose => Vec3::new(r(0).x, r(1).x, r(2).x),
        Dot => Vec3::splat(r(0).dot(r(1))),
        Normalize3 => r(0).normalize_or_zero(),
        NormalOrDefault => {
            let a = r(0);
            if a == Vec3::ZERO { ctx.globals.n } else { a }
        }
        FresnelDielectric => lanes2(r(0), r(1), fresnel_dielectric),
        FresnelConductor => lanes3(r(0), r(1), r(2), fresnel_conductor),
        SchlickCurve => {
            let (mu, f0, f90, q) = (r(0), r(1), r(2), r(3));
            let x = lanes2(mu, q, |m, q| (1.0 - m.clamp(0.0, 1.0)).powf(q.max(0.0)));
            f0 + (f90 - f0) * x
        }
        FresnelAvgDielectric => lanes(r(0), fresnel_avg_dielectric),
        ValueNoise => Vec3::splat(value_noise(r(0))),
    }
}
