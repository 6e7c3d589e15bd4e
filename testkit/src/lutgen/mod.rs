//! The albedo-table generator behind `vstructc-lutgen`.
//!
//! Every entry is a deterministic f64 quadrature over a 512 × 512 grid (128 × 128 for the
//! 3-D anisotropic tables, [`grid`]) of cell midpoints in the unit square: VNDF-stratified for GGX lobes (the estimator averages `f μ_i / pdf`, i.e.
//! `G2/G1(V)` times the Fresnel-like factor), Walter-stratified half vectors for Ward,
//! cosine-stratified for diffuse and sheen lobes. Sums run sequentially in a fixed order, so
//! an entry computed alone ([`compute_entry`]) is bit-identical to the same entry computed in
//! a batch ([`generate`]); the batch is parallel over entries with rayon.
//!
//! Conventions: `V = (√(1 − μ²), 0, μ)` with `μ = max(j/31, 1e-4)`; isotropic widths
//! (anisotropic tables: widths `α_x` along the view's azimuth, `α_y` across it);
//! dielectric transmission in the radiance convention (what sampling weights average to); the
//! `Eavg` tables integrate the piecewise-linear interpolant of their parent table exactly
//! (`2∫E μ dμ`), so that Kulla–Conty compensation built on table lookups is energy-exact with
//! respect to those same lookups.

pub mod ref64;

use rayon::prelude::*;
use std::f64::consts::PI;
use vstructc::glam::DVec3;
use vstructc::interp::tables::{N, TableId};

/// Generator version written into every blob header; bump it when a formula changes.
pub const GENERATOR_VERSION: u32 = 1;
/// Grid points per axis of the per-entry quadrature (512² samples per entry).
pub const GRID: usize = 512;
/// Grid points per axis for the 3-D anisotropic tables (128² samples per entry: their
/// accuracy target is 2e-2, and 512² would cost 16 times the isotropic tables' time).
pub const GRID_ANISO: usize = 128;

/// Grid points per axis of `table`'s quadrature.
pub fn grid(table: TableId) -> usize {
    if is_aniso(table) { GRID_ANISO } else { GRID }
}

/// True for the anisotropic tables (views at azimuths 0, 22.5° and 45°).
pub fn is_aniso(t: TableId) -> bool {
    aniso_azimuth(t).is_some()
}

/// The view's azimuth of an anisotropic table (radians), `None` for the other tables.
pub fn aniso_azimuth(t: TableId) -> Option<f64> {
    use TableId::*;
    Some(match t {
        E1HcAniso | E1SepAniso | WardClassicAniso | WardGmAniso => 0.0,
        E1HcAniso22 | E1SepAniso22 | WardClassicAniso22 | WardGmAniso22 => PI / 8.0,
        E1HcAniso45 | E1SepAniso45 | WardClassicAniso45 | WardGmAniso45 => PI / 4.0,
        _ => return None,
    })
}
/// Smallest μ_o used for the grazing node.
pub const MU_MIN: f64 = 1e-4;

/// Physical value of node `i` on axis `axis` of `table`.
pub fn axis_value(table: TableId, axis: usize, i: usize) -> f64 {
    let x = i as f64 / (N - 1) as f64;
    if axis == 0 && table.eavg_parent().is_none() {
        return x.max(MU_MIN);
    }
    let (lo, hi) = table.axis_ranges()[axis];
    let t = f64::from(lo) + (f64::from(hi) - f64::from(lo)) * x;
    match (table, axis) {
        // √α axes → α.
        (_, 1) if is_ggx(table) => t * t,
        (TableId::WardClassic | TableId::WardGm, 1) => t * t,
        (_, 1 | 2) if is_aniso(table) => t * t,
        (TableId::EavgE1Hc | TableId::EavgE1Sep | TableId::EavgH82Hc | TableId::EavgH82Sep, 0) => {
            t * t
        }
        (TableId::EavgWardClassic | TableId::EavgWardGm, 0) => t * t,
        // log2(q)/4 → q.
        (TableId::SqHc | TableId::SqSep, 2) => 2f64.powf(4.0 * x),
        // (η − 1)/2 → η, (1/η − 1)/2 → η.
        (TableId::ErDiel | TableId::EtDiel | TableId::EtnDiel, 2) => 1.0 + 2.0 * x,
        (TableId::ErDielInv | TableId::EtDielInv | TableId::EtnDielInv, 2) => 1.0 / (1.0 + 2.0 * x),
        _ => t,
    }
}

fn is_ggx(t: TableId) -> bool {
    matches!(
        t,
        TableId::E1Hc
            | TableId::E1Sep
            | TableId::SqHc
            | TableId::SqSep
            | TableId::H82Hc
            | TableId::H82Sep
            | TableId::ErDiel
            | TableId::EtDiel
            | TableId::EtnDiel
            | TableId::ErDielInv
            | TableId::EtDielInv
            | TableId::EtnDielInv
    )
}

/// `(cos 2πu, sin 2πu)` at the grid's cell midpoints.
fn angles() -> Vec<(f64, f64)> {
    angles_n(GRID)
}

fn angles_n(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let phi = 2.0 * PI * (i as f64 + 0.5) / n as f64;
            (phi.cos(), phi.sin())
        })
        .collect()
}

fn midpoint(j: usize) -> f64 {
    midpoint_n(j, GRID)
}

fn midpoint_n(j: usize, n: usize) -> f64 {
    (j as f64 + 0.5) / n as f64
}

/// The VNDF grid's second coordinate, warped as `u2 = 1 − (1 − t)²` at cell midpoints `t`,
/// with its quadrature weight `2(1 − t)`. The spherical-cap map sends the last `1 − u2`
/// cells to the whole grazing tail of half vectors (`tan θ_h ∝ α/√(1 − u2)`); the warp makes
/// that tail smooth in `t` (`tan θ_h ∝ α/(1 − t)`), which removes a 5e-4 midpoint-rule error
/// at α ≈ 0.07.
fn vndf_u2(j: usize) -> (f64, f64) {
    let t = midpoint(j);
    (1.0 - (1.0 - t) * (1.0 - t), 2.0 * (1.0 - t))
}

fn view(mu: f64) -> DVec3 {
    DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu)
}

/// The view with cosine `mu` at azimuth `phi` (exactly [`view`] at `phi = 0`).
fn view_at(mu: f64, phi: f64) -> DVec3 {
    if phi == 0.0 {
        return view(mu);
    }
    let s = (1.0 - mu * mu).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), mu)
}

/// GGX moments at one (μ, α): `[E1, H82, S_q for each q in qs]`, F = 1, masking per `hc`.
pub fn ggx_moments(mu: f64, alpha: f64, hc: bool, qs: &[f64]) -> Vec<f64> {
    let cs = angles();
    let v = view(mu);
    let g1v = 1.0 / (1.0 + ref64::ggx_lambda(alpha, v));
    let mut acc = vec![0.0f64; 2 + qs.len()];
    for c in &cs {
        for j in 0..GRID {
            let (u2, wq) = vndf_u2(j);
            let h = ref64::ggx_vndf(alpha, v, *c, u2);
            let vh = v.dot(h);
            let l = 2.0 * vh * h - v;
            if l.z <= 0.0 {
                continue;
            }
            let w = wq * ref64::ggx_g2(alpha, v, l, hc) / g1v;
            let omv = (1.0 - vh).max(0.0);
            let ln_omv = omv.ln();
            acc[0] += w;
            acc[1] += w * vh * (6.0 * ln_omv).exp();
            for (k, q) in qs.iter().enumerate() {
                acc[2 + k] += w * (q * ln_omv).exp();
            }
        }
    }
    let n = (GRID * GRID) as f64;
    acc.iter().map(|a| a / n).collect()
}

/// Dielectric albedos at one (μ, α, η), height-correlated: `[E_R, E_T, E_T without 1 − F]`,
/// transmission in the radiance convention.
pub fn dielectric_moments(mu: f64, alpha: f64, eta: f64) -> [f64; 3] {
    let cs = angles();
    let v = view(mu);
    // View-only terms hoisted out of the sample loop: Λ(V), G1(V), the stretched view.
    let lambda_v = ref64::ggx_lambda(alpha, v);
    let g1v = 1.0 / (1.0 + lambda_v);
    let vh_dir = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let inv_eta2 = 1.0 / (eta * eta);
    let mut acc = [0.0f64; 3];
    for c in &cs {
        for j in 0..GRID {
            let (u2, wq) = vndf_u2(j);
            let h = ref64::ggx_vndf_stretched(alpha, vh_dir, *c, u2);
            let vh = v.dot(h);
            let f = wq * ref64::fresnel_dielectric(vh, eta);
            let lr = 2.0 * vh * h - v;
            if lr.z > 0.0 {
                acc[0] += f / ((1.0 + lambda_v + ref64::ggx_lambda(alpha, lr)) * g1v);
            }
            if let Some(lt) = ref64::refract(v, h, eta)
                && lt.z < 0.0
            {
                let w = inv_eta2 / ((1.0 + lambda_v + ref64::ggx_lambda(alpha, lt)) * g1v);
                acc[1] += (wq - f) * w;
                acc[2] += wq * w;
            }
        }
    }
    let n = (GRID * GRID) as f64;
    acc.map(|a| a / n)
}

/// Ward albedo (ρ_s = 1) at one (μ, α) by Walter-stratified half vectors.
pub fn ward_albedo(mu: f64, alpha: f64, classic: bool) -> f64 {
    let cs = angles();
    let v = view(mu);
    let mut acc = 0.0;
    for c in &cs {
        for j in 0..GRID {
            let t2 = -alpha * alpha * (1.0 - midpoint(j)).ln();
            let cz = 1.0 / (1.0 + t2).sqrt();
            let sz = (t2 / (1.0 + t2)).sqrt();
            let h = DVec3::new(sz * c.0, sz * c.1, cz);
            acc += ref64::ward_weight(v, h, classic);
        }
    }
    acc / (GRID * GRID) as f64
}

/// Anisotropic GGX albedo with F = 1 (widths `ax`, `ay`, view at azimuth `phi`) by
/// VNDF-stratified quadrature over a `GRID_ANISO²` grid.
pub fn ggx_albedo_aniso(mu: f64, phi: f64, ax: f64, ay: f64, hc: bool) -> f64 {
    let n = GRID_ANISO;
    let cs = angles_n(n);
    let v = view_at(mu, phi);
    let lambda_v = ref64::ggx_lambda_aniso(ax, ay, v);
    let mut acc = 0.0;
    for c in &cs {
        for j in 0..n {
            let t = midpoint_n(j, n);
            let (u2, wq) = (1.0 - (1.0 - t) * (1.0 - t), 2.0 * (1.0 - t));
            let h = ref64::ggx_vndf_aniso(ax, ay, v, *c, u2);
            let l = 2.0 * v.dot(h) * h - v;
            if l.z <= 0.0 {
                continue;
            }
            let lambda_l = ref64::ggx_lambda_aniso(ax, ay, l);
            // G2/G1(V).
            acc += wq
                * if hc {
                    (1.0 + lambda_v) / (1.0 + lambda_v + lambda_l)
                } else {
                    1.0 / (1.0 + lambda_l)
                };
        }
    }
    acc / (n * n) as f64
}

/// Anisotropic Ward albedo (ρ_s = 1, view at azimuth `phi`) by Walter-stratified half
/// vectors over a `GRID_ANISO²` grid.
pub fn ward_albedo_aniso(mu: f64, phi: f64, ax: f64, ay: f64, classic: bool) -> f64 {
    let n = GRID_ANISO;
    let cs = angles_n(n);
    let v = view_at(mu, phi);
    let mut acc = 0.0;
    for c in &cs {
        for j in 0..n {
            let h = ref64::ward_half_aniso(ax, ay, *c, midpoint_n(j, n));
            acc += ref64::ward_weight(v, h, classic);
        }
    }
    acc / (n * n) as f64
}

/// Albedo of a diffuse-like lobe by cosine-stratified quadrature of `π f(V, L)`.
fn cosine_albedo(mu: f64, pi_f: impl Fn(DVec3, DVec3) -> f64) -> f64 {
    let cs = angles();
    let v = view(mu);
    let mut acc = 0.0;
    for c in &cs {
        for j in 0..GRID {
            let l = ref64::cosine_dir(midpoint(j), *c);
            if l.z > 0.0 {
                acc += pi_f(v, l);
            }
        }
    }
    acc / (GRID * GRID) as f64
}

/// Conty–Kulla sheen albedo at one (μ, r).
pub fn sheen_albedo(mu: f64, r: f64, mx: bool) -> f64 {
    cosine_albedo(mu, |v, l| PI * ref64::sheen_f(r, v, l, mx))
}

/// QON albedo (ρ = 1) at one (μ, σ).
pub fn qon_albedo(mu: f64, sigma: f64) -> f64 {
    cosine_albedo(mu, |v, l| ref64::qon_pi_f(sigma, v, l))
}

/// MiaDiffuse albedo (ρ = 1) at one (μ, σ).
pub fn mia_albedo(mu: f64, sigma: f64) -> f64 {
    cosine_albedo(mu, |v, l| {
        ref64::qon_pi_f(sigma, v, l) * ref64::mia_terminator(l.z) / l.z
    })
}

/// One entry of a primary (quadrature) table, computed alone. `Eavg` tables are not
/// primary: use [`eavg_from`].
pub fn compute_entry(table: TableId, idx: [usize; 3]) -> f64 {
    let mu = axis_value(table, 0, idx[0]);
    let y = axis_value(table, 1, idx[1]);
    let z = axis_value(table, 2, idx[2]);
    match table {
        TableId::E1Hc | TableId::E1Sep => ggx_moments(mu, y, table == TableId::E1Hc, &[])[0],
        TableId::H82Hc | TableId::H82Sep => ggx_moments(mu, y, table == TableId::H82Hc, &[])[1],
        TableId::SqHc | TableId::SqSep => ggx_moments(mu, y, table == TableId::SqHc, &[z])[2],
        TableId::ErDiel | TableId::ErDielInv => dielectric_moments(mu, y, z)[0],
        TableId::EtDiel | TableId::EtDielInv => dielectric_moments(mu, y, z)[1],
        TableId::EtnDiel | TableId::EtnDielInv => dielectric_moments(mu, y, z)[2],
        TableId::WardClassic => ward_albedo(mu, y, true),
        TableId::WardGm => ward_albedo(mu, y, false),
        TableId::SheenMx => sheen_albedo(mu, y, true),
        TableId::SheenOrig => sheen_albedo(mu, y, false),
        TableId::Qon => qon_albedo(mu, y),
        TableId::Mia => mia_albedo(mu, y),
        t => {
            use TableId::*;
            let Some(phi) = aniso_azimuth(t) else {
                return f64::NAN;
            };
            match t {
                E1HcAniso | E1HcAniso22 | E1HcAniso45 => ggx_albedo_aniso(mu, phi, y, z, true),
                E1SepAniso | E1SepAniso22 | E1SepAniso45 => ggx_albedo_aniso(mu, phi, y, z, false),
                WardClassicAniso | WardClassicAniso22 | WardClassicAniso45 => {
                    ward_albedo_aniso(mu, phi, y, z, true)
                }
                _ => ward_albedo_aniso(mu, phi, y, z, false),
            }
        }
    }
}

/// `2∫E μ dμ` of the piecewise-linear interpolant of one row (32 values at μ = j/31).
pub fn eavg_of_row(row: &[f32]) -> f64 {
    let h = 1.0 / (N - 1) as f64;
    (0..N - 1)
        .map(|j| {
            let (a, b) = (j as f64 * h, (j + 1) as f64 * h);
            let (ea, eb) = (f64::from(row[j]), f64::from(row[j + 1]));
            (b - a) / 6.0 * (ea * (2.0 * a + b) + eb * (a + 2.0 * b))
        })
        .sum::<f64>()
        * 2.0
}

/// The `Eavg` table of a 2-D parent table's data.
pub fn eavg_from(parent: &[f32]) -> Vec<f32> {
    parent
        .chunks_exact(N)
        .map(|row| eavg_of_row(row) as f32)
        .collect()
}

/// Which primary tables one quadrature pass produces together.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// E1, S_q, H82 for one masking variant (`true` = height-correlated).
    Ggx(bool),
    /// ER, ET, ETn for η ≥ 1 (`false`) or η ≤ 1 (`true`).
    Dielectric(bool),
    /// One 2-D table computed entry by entry.
    Single(TableId),
    /// One 3-D anisotropic table computed entry by entry.
    Aniso(TableId),
}

impl Group {
    /// The groups, 2-D first (cheap), then 3-D.
    pub const ALL: [Group; 22] = [
        Group::Single(TableId::WardClassic),
        Group::Single(TableId::WardGm),
        Group::Single(TableId::SheenMx),
        Group::Single(TableId::SheenOrig),
        Group::Single(TableId::Qon),
        Group::Single(TableId::Mia),
        Group::Ggx(true),
        Group::Ggx(false),
        Group::Dielectric(false),
        Group::Dielectric(true),
        Group::Aniso(TableId::E1HcAniso),
        Group::Aniso(TableId::E1SepAniso),
        Group::Aniso(TableId::WardClassicAniso),
        Group::Aniso(TableId::WardGmAniso),
        Group::Aniso(TableId::E1HcAniso22),
        Group::Aniso(TableId::E1HcAniso45),
        Group::Aniso(TableId::E1SepAniso22),
        Group::Aniso(TableId::E1SepAniso45),
        Group::Aniso(TableId::WardClassicAniso22),
        Group::Aniso(TableId::WardClassicAniso45),
        Group::Aniso(TableId::WardGmAniso22),
        Group::Aniso(TableId::WardGmAniso45),
    ];

    /// The tables this group writes, in output order.
    pub fn tables(self) -> Vec<TableId> {
        match self {
            Group::Ggx(true) => vec![TableId::E1Hc, TableId::H82Hc, TableId::SqHc],
            Group::Ggx(false) => vec![TableId::E1Sep, TableId::H82Sep, TableId::SqSep],
            Group::Dielectric(false) => vec![TableId::ErDiel, TableId::EtDiel, TableId::EtnDiel],
            Group::Dielectric(true) => {
                vec![TableId::ErDielInv, TableId::EtDielInv, TableId::EtnDielInv]
            }
            Group::Single(t) | Group::Aniso(t) => vec![t],
        }
    }
}

/// Computes every table of a group (parallel over entries).
pub fn generate(group: Group) -> Vec<(TableId, Vec<f32>)> {
    match group {
        Group::Single(t) => {
            let data: Vec<f32> = (0..t.len())
                .into_par_iter()
                .map(|k| compute_entry(t, [k % N, k / N, 0]) as f32)
                .collect();
            vec![(t, data)]
        }
        Group::Aniso(t) => {
            let data: Vec<f32> = (0..t.len())
                .into_par_iter()
                .map(|k| compute_entry(t, [k % N, (k / N) % N, k / (N * N)]) as f32)
                .collect();
            vec![(t, data)]
        }
        Group::Ggx(hc) => {
            let ts = group.tables();
            let qs: Vec<f64> = (0..N).map(|k| axis_value(ts[2], 2, k)).collect();
            let rows: Vec<Vec<f64>> = (0..N * N)
                .into_par_iter()
                .map(|k| {
                    let mu = axis_value(ts[0], 0, k % N);
                    let alpha = axis_value(ts[0], 1, k / N);
                    ggx_moments(mu, alpha, hc, &qs)
                })
                .collect();
            let e1 = rows.iter().map(|r| r[0] as f32).collect();
            let h82 = rows.iter().map(|r| r[1] as f32).collect();
            let mut sq = vec![0f32; N * N * N];
            for (k, r) in rows.iter().enumerate() {
                for q in 0..N {
                    sq[q * N * N + k] = r[2 + q] as f32;
                }
            }
            vec![(ts[0], e1), (ts[1], h82), (ts[2], sq)]
        }
        Group::Dielectric(_) => {
            let ts = group.tables();
            let rows: Vec<[f64; 3]> = (0..N * N * N)
                .into_par_iter()
                .map(|k| {
                    let mu = axis_value(ts[0], 0, k % N);
                    let alpha = axis_value(ts[0], 1, (k / N) % N);
                    let eta = axis_value(ts[0], 2, k / (N * N));
                    dielectric_moments(mu, alpha, eta)
                })
                .collect();
            (0..3)
                .map(|c| (ts[c], rows.iter().map(|r| r[c] as f32).collect()))
                .collect()
        }
    }
}
