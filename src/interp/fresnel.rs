//! Fresnel forms.
//!
//! Every function takes `μ`, the cosine between the relevant direction and the microfacet
//! normal (`V·h` inside microfacet lobes, `μ_o` for view-dependent weights).

use super::math::{Rgb, pow_q, pow5};
use super::vmath::select;
use glam::{Vec3, Vec3A};
use std::ops::{Add, Div, Mul, Sub};

/// `μ̄ = 1/7`, the angle (cosine) at which F82 forms are pinned.
pub(crate) const MU_BAR: f32 = 1.0 / 7.0;

/// Normal-incidence reflectance of a dielectric interface: `((η − 1)/(η + 1))²`.
#[inline]
#[cfg(feature = "testkit")]
pub fn f0_from_eta(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Schlick: `F0 + (1 − F0)(1 − μ)⁵`.
#[inline]
pub fn schlick(f0: Rgb, mu: f32) -> Rgb {
    f0 + (Vec3::ONE - f0) * pow5((1.0 - mu).clamp(0.0, 1.0))
}

/// Generalized Schlick: `F0 + (F90 − F0)(1 − μ)^q`.
#[inline]
pub(crate) fn generalized_schlick(f0: Rgb, f90: Rgb, q: f32, mu: f32) -> Rgb {
    f0 + (f90 - f0) * pow_q((1.0 - mu).clamp(0.0, 1.0), q)
}

/// Hoffman's F82 coefficient `a = [F0 + (F90 − F0)(1 − μ̄)^q](1 − t) / (μ̄(1 − μ̄)⁶)`.
pub fn f82_coefficient(f0: Rgb, f90: Rgb, q: f32, t: Rgb) -> Rgb {
    let om = 1.0 - MU_BAR;
    let denom = MU_BAR * om.powi(6);
    generalized_schlick(f0, f90, q, MU_BAR) * (Vec3::ONE - t) / denom
}

/// Hoffman F82 with precomputed coefficient `a` ([`f82_coefficient`]):
/// `F0 + (F90 − F0)(1 − μ)^q − a μ(1 − μ)⁶`.
#[inline]
pub(crate) fn hoffman_f82(f0: Rgb, f90: Rgb, q: f32, a: Rgb, mu: f32) -> Rgb {
    let om = (1.0 - mu).clamp(0.0, 1.0);
    let om3 = om * om * om;
    generalized_schlick(f0, f90, q, mu) - a * (mu * om3 * om3)
}

/// OpenPBR's F82-tint metal Fresnel (without `specular_weight`): Hoffman F82 with
/// `F90 = 1`, `q = 5`, `t = specular_color`.
#[cfg(feature = "testkit")]
pub fn openpbr_f82_tint(f0: Rgb, specular_color: Rgb, mu: f32) -> Rgb {
    let a = f82_coefficient(f0, Vec3::ONE, 5.0, specular_color);
    hoffman_f82(f0, Vec3::ONE, 5.0, a, mu)
}

/// Exact unpolarised dielectric reflectance; `eta` = transmitted-side over incident-side
/// index. Total internal reflection gives 1.
#[inline]
pub fn dielectric(mu: f32, eta: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let g2 = eta * eta + mu * mu - 1.0;
    if g2 < 0.0 {
        return 1.0;
    }
    let g = g2.sqrt();
    let a = (g - mu) / (g + mu).max(1e-30);
    let b = (mu * (g + mu) - 1.0) / (mu * (g - mu) + 1.0);
    (0.5 * a * a * (1.0 + b * b)).min(1.0)
}

/// [`dielectric`] at the unnormalised half vector `H = V + L` of a reflection: `m = V·H`,
/// `hh = |H|²`, `e2m1 = η² − 1`, as a quotient `(F_n, F_d)` with `F = F_n/F_d` (`(1, 1)` under
/// total internal reflection).
///
/// The formula is homogeneous in `|H|`: with `G = √(|H|²(η² − 1) + m²) = |H| g`,
/// `a = (G − m)/(G + m)` and `b = (m(G + m) − |H|²)/(m(G − m) + |H|²)`, so `V·h` (a square
/// root and a division) is never formed. Apart from the cost, this is also the better
/// conditioned form near η = 1, where `g − μ` cancels: against f64, its worst relative error
/// over random GGX reflections was 1e-4 where normalising first gave 1e-3.
/// The scalar dielectric leaf and the batched kernels share it, so they agree to rounding.
#[inline(always)]
pub fn dielectric_half_quotient(m: f32, hh: f32, e2m1: f32) -> (f32, f32) {
    let m = m.max(0.0);
    let g2 = hh * e2m1 + m * m;
    let g = g2.max(0.0).sqrt();
    let (an, ad) = (g - m, g + m);
    let (bn, bd) = (m * ad - hh, m * an + hh);
    let bd2 = bd * bd;
    // A select rather than a branch: the batched kernels run this on every lane.
    let tir = g2 < 0.0;
    (
        select(tir, 1.0, 0.5 * an * an * (bd2 + bn * bn)),
        select(tir, 1.0, (ad * ad * bd2).max(1e-30)),
    )
}

/// [`dielectric_half_quotient`] as a value, clamped to 1.
#[inline(always)]
pub fn dielectric_half(m: f32, hh: f32, e2m1: f32) -> f32 {
    let (n, d) = dielectric_half_quotient(m, hh, e2m1);
    (n / d).min(1.0)
}

/// Conductor reflectance for the complex index `η + iκ`, per channel.
#[inline]
pub fn conductor(mu: f32, eta: Rgb, kappa: Rgb) -> Rgb {
    let c = mu.clamp(0.0, 1.0);
    conductor_squared(c * c, eta, kappa)
}

/// [`conductor`] at the squared cosine `c² ∈ [0, 1]`: the three channels of
/// [`conductor_c2`] side by side in SIMD registers (two `sqrtps` and one `divps` for RGB), with
/// the same bits.
#[inline]
pub fn conductor_squared(c2: f32, eta: Rgb, kappa: Rgb) -> Rgb {
    let (eta, kappa) = (Vec3A::from(eta), Vec3A::from(kappa));
    let (e2, k2) = (eta * eta, kappa * kappa);
    let r = Vec3::from(conductor_unclamped(c2, e2 - k2, 4.0 * e2 * k2));
    // `f32::clamp` per channel, as in `conductor_c2` (a NaN stays NaN; `Vec3::clamp` would
    // make it 0).
    Vec3::from_array(r.to_array().map(|c| c.clamp(0.0, 1.0)))
}

/// One channel of [`conductor`] at `c² = (V·h)²` (in [0, 1]), given `η² − κ²` and `4η²κ²`.
///
/// With `a + ib = √((η + iκ)² − s²)` (`s² = 1 − c²`) the textbook form is
/// `½ (r_s + r_s·num/den)`, `r_s = (|a+ib|² − 2ac + c²)/(|a+ib|² + 2ac + c²)`,
/// `num/den = (c²|a+ib|² ∓ 2ac s² + s⁴)`; the `2ac s²` terms cancel in `den + num`, so it is
/// `r_s (c² |a+ib|² + s⁴)/den`, one division; and `2ac = 2√(c² a²)` is one square root
/// where the textbook form takes two in sequence (`c`, then `a`). The batched kernels call it
/// per lane.
#[inline(always)]
pub fn conductor_c2(c2: f32, e2mk2: f32, four_e2k2: f32) -> f32 {
    conductor_unclamped(c2, e2mk2, four_e2k2).clamp(0.0, 1.0)
}

/// The arithmetic of [`conductor_c2`] before the clamp, for one channel (`f32`) or three side
/// by side (`Vec3A`): one formula, so the scalar leaves and the kernels agree bit for bit.
#[inline(always)]
fn conductor_unclamped<T: Channels>(c2: f32, e2mk2: T, four_e2k2: T) -> T {
    let s2 = 1.0 - c2;
    let (c2v, s2v, s4) = (T::splat(c2), T::splat(s2), T::splat(s2 * s2));
    let t0 = e2mk2 - s2v;
    let ab2 = (t0 * t0 + four_e2k2).sqrt();
    let a2 = (T::splat(0.5) * (ab2 + t0)).max(T::splat(0.0));
    let two_ac = T::splat(2.0) * (c2v * a2).sqrt();
    let rs_num = ab2 - two_ac + c2v;
    let rs_den = ab2 + two_ac + c2v;
    let den = c2v * ab2 + two_ac * s2v + s4;
    rs_num * (c2v * ab2 + s4) / (rs_den * den).max(T::splat(1e-30))
}

/// What [`conductor_unclamped`] needs of its channel type. `max` returns `o` where `self` is
/// NaN in both implementations (`f32::max`, `maxps`).
trait Channels:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    fn splat(x: f32) -> Self;
    fn sqrt(self) -> Self;
    fn max(self, o: Self) -> Self;
}

impl Channels for f32 {
    #[inline(always)]
    fn splat(x: f32) -> f32 {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> f32 {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn max(self, o: f32) -> f32 {
        f32::max(self, o)
    }
}

impl Channels for Vec3A {
    #[inline(always)]
    fn splat(x: f32) -> Vec3A {
        Vec3A::splat(x)
    }
    #[inline(always)]
    fn sqrt(self) -> Vec3A {
        Vec3A::sqrt(self)
    }
    #[inline(always)]
    fn max(self, o: Vec3A) -> Vec3A {
        Vec3A::max(self, o)
    }
}

/// Conductor reflectance at normal incidence: `((η − 1)² + κ²)/((η + 1)² + κ²)`.
#[cfg(feature = "testkit")]
pub fn conductor_f0(eta: Rgb, kappa: Rgb) -> Rgb {
    let k2 = kappa * kappa;
    ((eta - Vec3::ONE) * (eta - Vec3::ONE) + k2) / ((eta + Vec3::ONE) * (eta + Vec3::ONE) + k2)
}

/// Gulbrandsen's artistic IOR: reflectivity `r` and edge tint `g` → `(η, κ)` per channel.
#[cfg(feature = "testkit")]
pub fn artistic_ior(r: Rgb, g: Rgb) -> (Rgb, Rgb) {
    let r = r.clamp(Vec3::ZERO, Vec3::splat(0.99));
    let sr = r.sqrt();
    let n_min = (Vec3::ONE - r) / (Vec3::ONE + r);
    let n_max = (Vec3::ONE + sr) / (Vec3::ONE - sr);
    let n = n_max + (n_min - n_max) * g;
    let np = n + Vec3::ONE;
    let nm = n - Vec3::ONE;
    let k2 = (np * np * r - nm * nm) / (Vec3::ONE - r);
    (n, k2.max(Vec3::ZERO).sqrt())
}

/// mia_material's reflectivity curve `R0(1 − x) + R90 x`, `x = (1 − μ)^E` (the spec's
/// `SchlickCurve`).
#[inline]
#[cfg(feature = "testkit")]
pub fn mia_curve(mu: f32, r0: f32, r90: f32, e: f32) -> f32 {
    let x = pow_q((1.0 - mu).clamp(0.0, 1.0), e);
    r0 * (1.0 - x) + r90 * x
}

/// Hemispherical average `2∫F μ dμ` of generalized Schlick:
/// `F0 + (F90 − F0)·2/((q + 1)(q + 2))`.
pub fn generalized_schlick_avg(f0: Rgb, f90: Rgb, q: f32) -> Rgb {
    f0 + (f90 - f0) * (2.0 / ((q + 1.0) * (q + 2.0)))
}

/// Hemispherical average of Hoffman F82 (`2∫ μ·μ(1 − μ)⁶ dμ = 1/126`).
pub(crate) fn f82_avg(f0: Rgb, f90: Rgb, q: f32, a: Rgb) -> Rgb {
    generalized_schlick_avg(f0, f90, q) - a / 126.0
}

/// Hemispherical average of the exact dielectric Fresnel: d'Eon's 2021 fit for η ∈ [1, 3]
/// (clamped to that range), and the exact identity `1 − η²(1 − E_F(1/η))` for η < 1.
pub fn dielectric_avg(eta: f32) -> f32 {
    fn fit(eta: f32) -> f32 {
        let e = eta.clamp(1.0, 3.0);
        ((10893.0 * e - 1438.2) / (-774.4 * e * e + 10212.0 * e + 1.0))
            .ln()
            .max(0.0)
    }
    if eta >= 1.0 {
        fit(eta)
    } else {
        (1.0 - eta * eta * (1.0 - fit(1.0 / eta.max(1e-3)))).clamp(0.0, 1.0)
    }
}

/// Fit of a conductor to Hoffman F82: `F0 = F(1)`, `t = F(1/7)/F_Schlick(1/7)`,
/// `F90 = 1`, `q = 5`. Returns `(F0, t)`.
pub(crate) fn conductor_to_f82(eta: Rgb, kappa: Rgb) -> (Rgb, Rgb) {
    let f0 = conductor(1.0, eta, kappa);
    let s = schlick(f0, MU_BAR).max(Vec3::splat(1e-6));
    (f0, conductor(MU_BAR, eta, kappa) / s)
}

/// The Fresnel factor of a microfacet reflection lobe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fresnel {
    /// F = 1 (no Fresnel).
    One,
    /// Generalized Schlick `F0 + (F90 − F0)(1 − μ)^q` (Schlick is `F90 = 1`, `q = 5`).
    Schlick {
        /// Reflectance at normal incidence.
        f0: Rgb,
        /// Reflectance at grazing incidence.
        f90: Rgb,
        /// Exponent q.
        q: f32,
    },
    /// Hoffman F82: generalized Schlick minus `a μ(1 − μ)⁶` (see [`Fresnel::f82`]).
    F82 {
        /// Reflectance at normal incidence.
        f0: Rgb,
        /// Reflectance at grazing incidence.
        f90: Rgb,
        /// Exponent q.
        q: f32,
        /// Precomputed coefficient ([`f82_coefficient`]).
        a: Rgb,
    },
    /// Exact dielectric, relative index η.
    Dielectric {
        /// Relative index (transmitted over incident).
        eta: f32,
    },
    /// Conductor with complex index `η + iκ` per channel.
    Conductor {
        /// Real part.
        eta: Rgb,
        /// Imaginary part (extinction).
        kappa: Rgb,
    },
}

impl Fresnel {
    /// Hoffman F82 with tint `t` at `μ̄ = 1/7` (the coefficient is precomputed).
    pub fn f82(f0: Rgb, f90: Rgb, q: f32, t: Rgb) -> Fresnel {
        Fresnel::F82 {
            f0,
            f90,
            q,
            a: f82_coefficient(f0, f90, q, t),
        }
    }

    /// OpenPBR's F82-tint metal (`F90 = 1`, `q = 5`, `t = specular_color`).
    #[cfg(feature = "testkit")]
    pub fn openpbr_metal(f0: Rgb, specular_color: Rgb) -> Fresnel {
        Fresnel::f82(f0, Vec3::ONE, 5.0, specular_color)
    }

    /// Evaluates F at cosine `mu`. F82 values are clamped at 0 (extreme tints can otherwise
    /// dip below zero).
    #[inline]
    pub fn eval(&self, mu: f32) -> Rgb {
        match *self {
            Fresnel::One => Vec3::ONE,
            Fresnel::Schlick { f0, f90, q } => generalized_schlick(f0, f90, q, mu),
            Fresnel::F82 { f0, f90, q, a } => hoffman_f82(f0, f90, q, a, mu).max(Vec3::ZERO),
            Fresnel::Dielectric { eta } => Vec3::splat(dielectric(mu, eta)),
            Fresnel::Conductor { eta, kappa } => conductor(mu, eta, kappa),
        }
    }

    /// [`Fresnel::eval`] at the squared cosine `c² ∈ [0, 1]`: a conductor needs no square
    /// root ([`conductor_squared`]); the other forms take `√c²`.
    #[inline]
    pub fn eval_squared(&self, c2: f32) -> Rgb {
        match *self {
            Fresnel::Conductor { eta, kappa } => conductor_squared(c2, eta, kappa),
            _ => self.eval(c2.sqrt()),
        }
    }

    /// Hemispherical average `2∫F μ dμ` (conductors through their F82 fit).
    pub fn average(&self) -> Rgb {
        match *self {
            Fresnel::One => Vec3::ONE,
            Fresnel::Schlick { f0, f90, q } => generalized_schlick_avg(f0, f90, q),
            Fresnel::F82 { f0, f90, q, a } => f82_avg(f0, f90, q, a).max(Vec3::ZERO),
            Fresnel::Dielectric { eta } => Vec3::splat(dielectric_avg(eta)),
            Fresnel::Conductor { eta, kappa } => {
                let (f0, t) = conductor_to_f82(eta, kappa);
                let a = f82_coefficient(f0, Vec3::ONE, 5.0, t);
                f82_avg(f0, Vec3::ONE, 5.0, a).clamp(Vec3::ZERO, Vec3::ONE)
            }
        }
    }

    /// True for conductors (which make a microfacet lobe opaque).
    pub fn is_conductor(&self) -> bool {
        matches!(self, Fresnel::Conductor { .. })
    }
}
