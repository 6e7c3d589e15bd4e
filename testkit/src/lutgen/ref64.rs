//! f64 formulas used by the table generator: GGX, exact dielectric
//! Fresnel, Ward, Conty–Kulla sheen and Oren–Nayar, all isotropic and in the local frame.

use std::f64::consts::PI;
use vstructc::glam::DVec3;

/// GGX NDF, isotropic.
pub fn ggx_d(alpha: f64, h: DVec3) -> f64 {
    let a2 = alpha * alpha;
    let t = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
    1.0 / (PI * a2 * t * t)
}

/// Smith Λ for GGX, isotropic, written without cancellation.
pub fn ggx_lambda(alpha: f64, w: DVec3) -> f64 {
    let z2 = (w.z * w.z).max(1e-300);
    let x = alpha * alpha * (w.x * w.x + w.y * w.y) / z2;
    x / (2.0 * (1.0 + (1.0 + x).sqrt()))
}

/// Masking–shadowing G2 for the named variant (`hc` = height-correlated, else separable).
pub fn ggx_g2(alpha: f64, v: DVec3, l: DVec3, hc: bool) -> f64 {
    let lv = ggx_lambda(alpha, v);
    let ll = ggx_lambda(alpha, l);
    if hc {
        1.0 / (1.0 + lv + ll)
    } else {
        1.0 / ((1.0 + lv) * (1.0 + ll))
    }
}

/// Visible-normal sample (Dupuy & Benyoub 2023) with precomputed `(cos φ, sin φ)`.
pub fn ggx_vndf(alpha: f64, v: DVec3, cs: (f64, f64), u2: f64) -> DVec3 {
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    ggx_vndf_stretched(alpha, vh, cs, u2)
}

/// [`ggx_vndf`] with the stretched, normalised view `vh = normalize(α V_x, α V_y, V_z)` given.
pub fn ggx_vndf_stretched(alpha: f64, vh: DVec3, cs: (f64, f64), u2: f64) -> DVec3 {
    let z = (1.0 - u2) * (1.0 + vh.z) - vh.z;
    let s = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
    let c = DVec3::new(s * cs.0, s * cs.1, z) + vh;
    DVec3::new(alpha * c.x, alpha * c.y, c.z.max(0.0)).normalize()
}

/// Exact unpolarised dielectric Fresnel reflectance (η = transmitted / incident index).
pub fn fresnel_dielectric(mu: f64, eta: f64) -> f64 {
    let g2 = eta * eta + mu * mu - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - mu) / (g + mu);
    let b = (mu * (g + mu) - 1.0) / (mu * (g - mu) + 1.0);
    0.5 * a * a * (1.0 + b * b)
}

/// Refraction of `v` (pointing away from the surface, on the side of `h`) through the
/// microfacet `h` into a medium of relative index `eta`; `None` on total internal reflection.
pub fn refract(v: DVec3, h: DVec3, eta: f64) -> Option<DVec3> {
    let c = v.dot(h);
    let s2t = (1.0 - c * c) / (eta * eta);
    if s2t >= 1.0 {
        return None;
    }
    let ct = (1.0 - s2t).sqrt();
    Some(-v / eta + (c / eta - ct) * h)
}

/// Cosine-distributed direction from `(u1, u2)` with precomputed `(cos φ, sin φ)` of `2π u2`.
pub fn cosine_dir(u1: f64, cs: (f64, f64)) -> DVec3 {
    let r = u1.sqrt();
    DVec3::new(r * cs.0, r * cs.1, (1.0 - u1).max(0.0).sqrt())
}

/// Ward `f·μ_i / pdf` for a Walter-sampled half vector (ρ_s = 1), classic or GM.
pub fn ward_weight(v: DVec3, h: DVec3, classic: bool) -> f64 {
    let vh = v.dot(h);
    if vh <= 0.0 {
        return 0.0;
    }
    let l = 2.0 * vh * h - v;
    if l.z <= 0.0 {
        return 0.0;
    }
    if classic {
        (l.z / v.z).sqrt() * vh * h.z * h.z * h.z
    } else {
        l.z / (vh * h.z)
    }
}

/// Conty–Kulla sheen `f` (not times μ_i), roughness `r`, masking `mx` (MaterialX) or original.
pub fn sheen_f(r: f64, v: DVec3, l: DVec3, mx: bool) -> f64 {
    let h = (v + l).normalize();
    let s2 = (h.x * h.x + h.y * h.y).min(1.0);
    let d = (2.0 + 1.0 / r) * s2.powf(0.5 / r) / (2.0 * PI);
    let (mi, mo) = (l.z, v.z);
    if mx {
        d / (4.0 * (mi + mo - mi * mo))
    } else {
        let li = sheen_ln_lambda(r, mi) * (1.0 + 2.0 * (1.0 - mi).powi(8));
        let g2 = 1.0 / (1.0 + li.exp() + sheen_ln_lambda(r, mo).exp());
        d * g2 / (4.0 * mi * mo)
    }
}

/// `ln Λ(μ)` of the original Conty–Kulla masking.
pub fn sheen_ln_lambda(r: f64, mu: f64) -> f64 {
    let t = (1.0 - r) * (1.0 - r);
    let p0 = [21.5473, 3.82987, 0.19823, -1.97760, -4.32054];
    let p1 = [25.3245, 3.32435, 0.16801, -1.27393, -4.85967];
    let c: Vec<f64> = (0..5).map(|k| p0[k] + (p1[k] - p0[k]) * t).collect();
    let big_l = |x: f64| c[0] / (1.0 + c[1] * x.powf(c[2])) + c[3] * x + c[4];
    if mu < 0.5 {
        big_l(mu)
    } else {
        2.0 * big_l(0.5) - big_l(1.0 - mu)
    }
}

/// Qualitative Oren–Nayar `π f` (ρ = 1).
pub fn qon_pi_f(sigma: f64, v: DVec3, l: DVec3) -> f64 {
    let s2 = sigma * sigma;
    let a = 1.0 - 0.5 * s2 / (s2 + 0.33);
    let b = 0.45 * s2 / (s2 + 0.09);
    let s = v.dot(l) - l.z * v.z;
    let st = if s > 0.0 { s / l.z.max(v.z) } else { 0.0 };
    a + b * st
}

/// The MiaDiffuse smoothstep terminator `s(μ)`.
pub fn mia_terminator(mu: f64) -> f64 {
    if mu >= 0.25 {
        mu
    } else if mu <= 0.0 {
        0.0
    } else {
        8.0 * mu * mu * (1.0 - 2.0 * mu)
    }
}

/// Smith Λ for anisotropic GGX (widths `ax`, `ay`), written without cancellation.
pub fn ggx_lambda_aniso(ax: f64, ay: f64, w: DVec3) -> f64 {
    let z2 = (w.z * w.z).max(1e-300);
    let x = (ax * ax * w.x * w.x + ay * ay * w.y * w.y) / z2;
    x / (2.0 * (1.0 + (1.0 + x).sqrt()))
}

/// Visible-normal sample of anisotropic GGX (Dupuy & Benyoub 2023) with precomputed
/// `(cos φ, sin φ)`.
pub fn ggx_vndf_aniso(ax: f64, ay: f64, v: DVec3, cs: (f64, f64), u2: f64) -> DVec3 {
    let vh = DVec3::new(ax * v.x, ay * v.y, v.z).normalize();
    let z = (1.0 - u2) * (1.0 + vh.z) - vh.z;
    let s = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
    let c = DVec3::new(s * cs.0, s * cs.1, z) + vh;
    DVec3::new(ax * c.x, ay * c.y, c.z.max(0.0)).normalize()
}

/// Walter's anisotropic Ward half vector for the grid point `(cos 2πu₁, sin 2πu₁)`, `u₂`.
pub fn ward_half_aniso(ax: f64, ay: f64, cs: (f64, f64), u2: f64) -> DVec3 {
    // φ_h = atan((α_y/α_x) tan 2πu₁) in the quadrant of 2πu₁.
    let d = DVec3::new(ax * cs.0, ay * cs.1, 0.0).normalize();
    let t2 = -(1.0 - u2).ln() / (d.x * d.x / (ax * ax) + d.y * d.y / (ay * ay));
    let cz = 1.0 / (1.0 + t2).sqrt();
    let sz = (t2 / (1.0 + t2)).sqrt();
    DVec3::new(sz * d.x, sz * d.y, cz)
}
