//! Pass-through leaves: emission and straight transparency.

use crate::interp::leaves::{LobeAlbedo, LobeSample};
use crate::interp::math::Rgb;
use glam::Vec3;

/// Uniform emission (an EDF, not part of the BSDF): radiance `tint`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Emission {
    /// Emitted radiance.
    pub radiance: Rgb,
}

/// Straight transmission `L = −V` with tint τ (a delta lobe).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transparent {
    /// Transmittance τ.
    pub tint: Rgb,
}

impl Transparent {
    /// The delta sample `−V`, weight τ, discrete pdf 1.
    pub fn sample(&self, v: Vec3) -> LobeSample {
        LobeSample {
            l: -v,
            weight: self.tint,
            pdf: 1.0,
            delta: true,
        }
    }

    /// Albedo: τ, transmitted.
    pub fn albedo(&self) -> LobeAlbedo {
        LobeAlbedo {
            reflect: Vec3::ZERO,
            transmit: self.tint,
            transmit_energy: self.tint,
        }
    }
}
