//! Independent f64 reference formulas for the leaf tests (spec closures.md §3), written from
//! the spec's text without calling the crate's f32 code, plus shared test helpers.
#![allow(dead_code)]

use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use vstructc::interp::{Lobe, PreparedLobe, Sides};

pub fn d(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// Directions of the §5.1 point checks.
pub fn config_v() -> Vec3 {
    Vec3::new(0.5, 0.0, 0.866_025_4)
}
pub fn config_a() -> Vec3 {
    Vec3::new(-0.664_463, 0.241_844_8, std::f32::consts::FRAC_1_SQRT_2)
}
pub fn config_b() -> Vec3 {
    Vec3::new(-0.573_576_4, 0.0, 0.819_152)
}

/// The spec's tolerance: relative 1e-5, absolute 1e-8 below 1e-3.
pub fn close_golden(got: f64, want: f64) -> bool {
    if want.abs() < 1e-3 {
        (got - want).abs() <= 1e-8 + 1e-5 * want.abs()
    } else {
        (got - want).abs() <= 1e-5 * want.abs()
    }
}

pub fn prep(lobe: Lobe, v: Vec3) -> PreparedLobe {
    lobe.prepare(v, Sides::Front)
}

// ---- Fresnel ----

pub fn fresnel_dielectric(mu: f64, eta: f64) -> f64 {
    let g2 = eta * eta + mu * mu - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    0.5 * ((g - mu) / (g + mu)).powi(2)
        * (1.0 + ((mu * (g + mu) - 1.0) / (mu * (g - mu) + 1.0)).powi(2))
}

pub fn fresnel_conductor(mu: f64, eta: f64, k: f64) -> f64 {
    let c = mu;
    let s2 = 1.0 - c * c;
    let t = eta * eta - k * k - s2;
    let ab2 = (t * t + 4.0 * eta * eta * k * k).sqrt();
    let a = (0.5 * (ab2 + t)).max(0.0).sqrt();
    let rs = (ab2 - 2.0 * a * c + c * c) / (ab2 + 2.0 * a * c + c * c);
    let rp = rs * (c * c * ab2 - 2.0 * a * c * s2 + s2 * s2)
        / (c * c * ab2 + 2.0 * a * c * s2 + s2 * s2);
    0.5 * (rs + rp)
}

pub fn gen_schlick(f0: f64, f90: f64, q: f64, mu: f64) -> f64 {
    f0 + (f90 - f0) * (1.0 - mu).powf(q)
}

pub fn f82(f0: f64, f90: f64, q: f64, t: f64, mu: f64) -> f64 {
    let mb = 1.0 / 7.0;
    let a = gen_schlick(f0, f90, q, mb) * (1.0 - t) / (mb * (1.0 - mb).powi(6));
    gen_schlick(f0, f90, q, mu) - a * mu * (1.0 - mu).powi(6)
}

// ---- GGX ----

pub fn ggx_d(ax: f64, ay: f64, h: DVec3) -> f64 {
    1.0 / (PI * ax * ay * (h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay) + h.z * h.z).powi(2))
}

pub fn ggx_lambda(ax: f64, ay: f64, w: DVec3) -> f64 {
    0.5 * (-1.0 + (1.0 + (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / (w.z * w.z)).sqrt())
}

pub fn ggx_g2(ax: f64, ay: f64, v: DVec3, l: DVec3, hc: bool) -> f64 {
    let (lv, ll) = (ggx_lambda(ax, ay, v), ggx_lambda(ax, ay, l));
    if hc {
        1.0 / (1.0 + lv + ll)
    } else {
        1.0 / ((1.0 + lv) * (1.0 + ll))
    }
}

/// GGX reflection `f·μ_i` with Fresnel `fr(V·h)`.
pub fn ggx_reflect(ax: f64, ay: f64, v: DVec3, l: DVec3, hc: bool, fr: impl Fn(f64) -> f64) -> f64 {
    if v.z <= 0.0 || l.z <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize();
    fr(v.dot(h)) * ggx_d(ax, ay, h) * ggx_g2(ax, ay, v, l, hc) / (4.0 * v.z)
}

/// Dielectric transmission `f_t·|μ_i|` (radiance convention); `eta` = L side over V side,
/// V above (`v.z > 0`), L below.
pub fn ggx_transmit(ax: f64, ay: f64, v: DVec3, l: DVec3, eta: f64) -> f64 {
    let mut h = (v + eta * l).normalize();
    if h.z < 0.0 {
        h = -h;
    }
    let (vh, lh) = (v.dot(h), l.dot(h));
    if vh <= 0.0 || lh >= 0.0 {
        return 0.0;
    }
    let f = fresnel_dielectric(vh, eta);
    (1.0 - f) * ggx_d(ax, ay, h) * ggx_g2(ax, ay, v, l, true) * vh * lh.abs()
        / (v.z.abs() * (vh + eta * lh).powi(2))
}

// ---- diffuse ----

pub fn qon(sigma: f64, v: DVec3, l: DVec3) -> f64 {
    let s2 = sigma * sigma;
    let a = 1.0 - 0.5 * s2 / (s2 + 0.33);
    let b = 0.45 * s2 / (s2 + 0.09);
    let s = v.dot(l) - v.z * l.z;
    let st = if s > 0.0 { s / v.z.max(l.z) } else { 0.0 };
    (a + b * st) / PI * l.z
}

pub fn eon_g(mu: f64) -> f64 {
    let th = mu.acos();
    let (s, c) = th.sin_cos();
    s * (th - s * c) + 2.0 / 3.0 * ((s / c) * (1.0 - s * s * s) - s)
}

pub fn eon_c1() -> f64 {
    0.5 - 2.0 / (3.0 * PI)
}

pub fn eon_e_hat(sigma: f64, mu: f64) -> f64 {
    let af = 1.0 / (1.0 + eon_c1() * sigma);
    af + sigma * af / PI * eon_g(mu)
}

pub fn eon_e_avg(sigma: f64) -> f64 {
    (1.0 + (2.0 / 3.0 - 28.0 / (15.0 * PI)) * sigma) / (1.0 + eon_c1() * sigma)
}

pub fn fon(rho: f64, sigma: f64, v: DVec3, l: DVec3) -> f64 {
    let af = 1.0 / (1.0 + eon_c1() * sigma);
    let s = v.dot(l) - v.z * l.z;
    let st = if s > 0.0 { s / v.z.max(l.z) } else { s };
    rho / PI * af * (1.0 + sigma * st) * l.z
}

pub fn eon(rho: f64, sigma: f64, v: DVec3, l: DVec3) -> f64 {
    eon_with(rho, sigma, v, l, eon_e_hat)
}

/// EON's fast `Ê` (spec §3.3): `(1 + σ Gπ(1 − μ)) / (1 + c1 σ)` with the quartic `Gπ`.
pub fn eon_e_hat_fast(sigma: f64, mu: f64) -> f64 {
    let m = 1.0 - mu;
    let g = [0.0571085289, 0.491881867, -0.332181442, 0.0714429953];
    let g_pi = m * (g[0] + m * (g[1] + m * (g[2] + m * g[3])));
    (1.0 + sigma * g_pi) / (1.0 + eon_c1() * sigma)
}

/// EON with the directional albedo `e_hat(σ, μ)` given (exact or fast).
pub fn eon_with(rho: f64, sigma: f64, v: DVec3, l: DVec3, e_hat: fn(f64, f64) -> f64) -> f64 {
    let ea = eon_e_avg(sigma);
    let rms = rho * rho * ea / (1.0 - rho * (1.0 - ea));
    let fms = rms / PI * (1.0 - e_hat(sigma, v.z)) * (1.0 - e_hat(sigma, l.z)) / (1.0 - ea);
    fon(rho, sigma, v, l) + fms * l.z
}

pub fn burley(sigma: f64, v: DVec3, l: DVec3) -> f64 {
    let h = (v + l).normalize();
    let fd90 = 0.5 + 2.0 * sigma * l.dot(h).powi(2);
    let fd = |mu: f64| 1.0 + (fd90 - 1.0) * (1.0 - mu).powi(5);
    fd(l.z) * fd(v.z) / PI * l.z
}

pub fn mia_s(mu: f64) -> f64 {
    if mu >= 0.25 {
        mu
    } else {
        8.0 * mu * mu * (1.0 - 2.0 * mu)
    }
}

pub fn mia_diffuse(sigma: f64, v: DVec3, l: DVec3) -> f64 {
    qon(sigma, v, l) / l.z * mia_s(l.z)
}

// ---- Ward ----

pub fn ward(ax: f64, ay: f64, v: DVec3, l: DVec3, classic: bool) -> f64 {
    let h = (v + l).normalize();
    let e = ((h.x / ax).powi(2) + (h.y / ay).powi(2)) / (h.z * h.z);
    let f = if classic {
        (-e).exp() / (4.0 * PI * ax * ay * (l.z * v.z).sqrt())
    } else {
        (-e).exp() / (4.0 * PI * ax * ay * l.dot(h).powi(2) * h.z.powi(4))
    };
    f * l.z
}

pub fn mia_highlight(gloss: f64, v: DVec3, l: DVec3, classic: bool) -> f64 {
    mia_highlight_aniso(gloss, 1.0, v, l, classic)
}

/// MiaHighlight3 with anisotropy `a`: `α_x = α_j/√a`, `α_y = α_j √a` (spec §3.12).
pub fn mia_highlight_aniso(gloss: f64, aniso: f64, v: DVec3, l: DVec3, classic: bool) -> f64 {
    let n = 2f64.powf(8.0 * gloss);
    [(n, 1.0 / 6.0), (n / 2.0, 1.0 / 3.0), (n / 4.0, 0.5)]
        .iter()
        .map(|&(nj, w)| {
            let a = (2.0 / (nj + 2.0)).sqrt();
            w * ward(a / aniso.sqrt(), a * aniso.sqrt(), v, l, classic)
        })
        .sum()
}

// ---- sheen ----

pub fn sheen_d(r: f64, h: DVec3) -> f64 {
    let st = (1.0 - h.z * h.z).max(0.0).sqrt();
    (2.0 + 1.0 / r) * st.powf(1.0 / r) / (2.0 * PI)
}

pub fn sheen_ck_mx(r: f64, v: DVec3, l: DVec3) -> f64 {
    let h = (v + l).normalize();
    sheen_d(r, h) / (4.0 * (l.z + v.z - l.z * v.z)) * l.z
}

pub fn sheen_ck_orig(r: f64, v: DVec3, l: DVec3) -> f64 {
    let t = (1.0 - r).powi(2);
    let p0 = [21.5473, 3.82987, 0.19823, -1.97760, -4.32054];
    let p1 = [25.3245, 3.32435, 0.16801, -1.27393, -4.85967];
    let c: Vec<f64> = (0..5).map(|k| p0[k] * (1.0 - t) + p1[k] * t).collect();
    let big_l = |x: f64| c[0] / (1.0 + c[1] * x.powf(c[2])) + c[3] * x + c[4];
    let lam = |mu: f64| {
        if mu < 0.5 {
            big_l(mu).exp()
        } else {
            (2.0 * big_l(0.5) - big_l(1.0 - mu)).exp()
        }
    };
    let li = lam(l.z).powf(1.0 + 2.0 * (1.0 - l.z).powi(8));
    let g2 = 1.0 / (1.0 + li + lam(v.z));
    let h = (v + l).normalize();
    sheen_d(r, h) * g2 / (4.0 * l.z * v.z) * l.z
}

pub fn ltc_e_hat(x: f64, y: f64) -> f64 {
    let s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y));
    let m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y);
    let o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y));
    ((-0.5 * ((x - m) / s).powi(2)).exp() / (s * (2.0 * PI).sqrt()) + o).max(0.0)
}

pub fn ltc_density(r: f64, v: DVec3, l: DVec3) -> f64 {
    let (x, y) = (v.z, r);
    let a = (2.58126 * x + 0.813703 * y) * y / (1.0 + 0.310327 * x * x + 2.60994 * x * y);
    let b = (1.0 - x).sqrt() * (y - 1.0) * y * y * y
        / (0.0000254053 + 1.71228 * x - 1.71506 * x * y + 1.34174 * y * y);
    let n = DVec3::Z;
    let t = v - n * v.z;
    let xa = if t.length() > 1e-9 {
        t.normalize()
    } else {
        DVec3::X
    };
    let ya = n.cross(xa);
    let w = DVec3::new(l.dot(xa), l.dot(ya), l.z);
    let wp = DVec3::new(a * w.x + b * w.z, a * w.y, w.z);
    wp.z.max(0.0) / PI * (a / wp.length_squared()).powi(2)
}

pub fn sheen_ltc(r: f64, v: DVec3, l: DVec3) -> f64 {
    ltc_e_hat(v.z, r) * ltc_density(r, v, l)
}

// ---- deterministic quadrature (test-owned f64 maps) ----

/// `∫ g(L) dω` over the upper hemisphere by an n×n cosine-stratified midpoint grid;
/// `g_over_pdf` receives L and the cosine density.
pub fn cosine_quadrature(n: usize, mut g_over_pdf: impl FnMut(Vec3, f64) -> f64) -> f64 {
    let mut acc = 0.0;
    for i in 0..n {
        for j in 0..n {
            let u1 = (i as f64 + 0.5) / n as f64;
            let phi = 2.0 * PI * (j as f64 + 0.5) / n as f64;
            let r = u1.sqrt();
            let l = DVec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).sqrt());
            acc += g_over_pdf(l.as_vec3(), l.z / PI);
        }
    }
    acc / (n * n) as f64
}

/// A GGX visible normal (Dupuy & Benyoub spherical caps), f64.
pub fn vndf64(ax: f64, ay: f64, v: DVec3, u1: f64, u2: f64) -> DVec3 {
    let vh = DVec3::new(ax * v.x, ay * v.y, v.z).normalize();
    let phi = 2.0 * PI * u1;
    let z = (1.0 - u2) * (1.0 + vh.z) - vh.z;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let c = DVec3::new(s * phi.cos(), s * phi.sin(), z) + vh;
    DVec3::new(ax * c.x, ay * c.y, c.z.max(0.0)).normalize()
}

/// Deterministic VNDF-stratified quadrature of a lobe's `f·|μ_i|` over the whole sphere
/// (reflection and, with `eta`, refraction through each sampled microfacet): returns
/// `(E_R, E_T)` with E_T in the radiance convention. The grid is n×n with the second
/// coordinate warped (`u2 = 1 − (1 − t)²`) to resolve the grazing tail.
pub fn vndf_quadrature(
    n: usize,
    ax: f64,
    ay: f64,
    v: DVec3,
    eta: Option<f64>,
    f_cos: impl Fn(Vec3) -> f64,
) -> (f64, f64) {
    let g1v = 1.0 / (1.0 + ggx_lambda(ax, ay, v));
    let (mut er, mut et) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let u1 = (i as f64 + 0.5) / n as f64;
            let t = (j as f64 + 0.5) / n as f64;
            let (u2, wq) = (1.0 - (1.0 - t) * (1.0 - t), 2.0 * (1.0 - t));
            let h = vndf64(ax, ay, v, u1, u2);
            let vh = v.dot(h);
            if vh <= 0.0 {
                continue;
            }
            let dv = g1v * vh * ggx_d(ax, ay, h) / v.z;
            let lr = 2.0 * vh * h - v;
            if lr.z > 0.0 {
                let pdf = dv / (4.0 * vh);
                er += wq * f_cos(lr.as_vec3()) / pdf;
            }
            if let Some(eta) = eta {
                let c = vh;
                let s2t = (1.0 - c * c) / (eta * eta);
                if s2t < 1.0 {
                    let lt = -v / eta + (c / eta - (1.0 - s2t).sqrt()) * h;
                    if lt.z < 0.0 {
                        let lh = lt.dot(h);
                        let pdf = dv * eta * eta * lh.abs() / (vh + eta * lh).powi(2);
                        // Only the transmitted part of the response (F-weighting is in f).
                        et += wq * f_cos(lt.as_vec3()) / pdf;
                    }
                }
            }
        }
    }
    // Each microfacet contributes to both hemispheres: the two sums are separate
    // estimators of E_R and E_T (each with the full VNDF density).
    (er / (n * n) as f64, et / (n * n) as f64)
}
