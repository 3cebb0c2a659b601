//! UsdLux ShapingAPI: how an area light's emitted radiance varies with the emission direction
//! ω (pointing away from the light), relative to the light's axis, its local −Z. The formulas
//! are the UsdLux schema text (OpenUSD `usdLux/schema.usda`, clarified in PR #3182); where
//! hdEmbree (`HdEmbreeEvaluateDirectionalShaping`) reads it differently, `docs/usdlux.md` says
//! which reading is implemented and why:
//!
//! - cone: θ = acos(axis·ω), θ_cut = coneAngle, θ_soft = lerp(softness, θ_cut, 0) = (1 − s) θ_cut,
//!   factor 1 − smoothstep(θ, θ_soft, θ_cut); hard cutoff (zero beyond θ_cut) at softness 0;
//! - focus: ff = |axis·ω|^focus, colour factor lerp(ff, focusTint, white) = (1 − ff)·tint + ff;
//! - IES: θ_ies from θ by `shaping:ies:angleScale` (θ/s for s > 0, (θ − π)/(−s) + π for s < 0),
//!   φ = atan2(y, x) in light space (C0 along local +X), factor = candela(θ_ies, φ), divided by
//!   the profile's mean intensity when `shaping:ies:normalize` is on (see `ies.rs`); θ_ies
//!   outside [0, π] is outside the profile and emits nothing.
//!
//! The factors multiply the radiance L₀ set by intensity/exposure/normalize, exactly as the
//! schema says ("a scaling factor on the returned luminance"): shaping changes L(x, ω), never the
//! sampling pdfs, so next-event estimation stays unbiased. A consequence worth knowing: an IES
//! profile scales *radiance*, so a flat light with a profile emits profile × cos θ × area in
//! intensity, while a sphere light (constant projected area πr²) emits exactly the profile's
//! shape: I(ω) = L₀ πr² · candela(ω). Use a small SphereLight for a luminaire measured as a
//! point source.
//!
//! Spectral focusTint: the tint colour is uplifted as a reflectance (Jakob–Hanika sigmoid, so
//! black is 0 and white is 1 at every λ) and the emitted spectrum is multiplied by
//! (1 − ff)·τ(λ) + ff. For photometry the tint counts by its luminance-weighted mean over the
//! light's own spectrum, τ_v = ∫ L₀ τ ȳ / ∫ L₀ ȳ.

use super::ies::IesProfile;
use crate::desc::ShapingDesc;
use crate::error::Reason;
use crate::spectral::uplift::{self, Sigmoid};
use crate::spectral::{data, SampledSpectrum, SampledWavelengths, Spectrum};
use glam::{Mat3, Mat4, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// Angular resolution of [`Shaping::integrate`]: midpoints per π of θ and per 2π of φ.
const THETA_STEPS: f32 = 1024.0;
const PHI_STEPS: f32 = 256.0;

#[derive(Clone, Debug)]
pub struct Shaping {
    /// World → light-local rotation (orthonormalised from the light's transform).
    pub world_to_local: Mat3,
    pub cone: Option<Cone>,
    pub focus: Option<Focus>,
    pub ies: Option<IesShaping>,
    /// Luminous totals of this light's distribution, set by the scene builder
    /// ([`Shaping::integrate`] with the light's projected area).
    pub photometry: Directional,
}

/// The cone cutoff; angles in radians from the axis.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    pub theta_soft: f32,
    pub theta_cut: f32,
    cos_soft: f32,
    cos_cut: f32,
}

#[derive(Clone, Debug)]
pub struct Focus {
    pub exponent: f32,
    /// The uplifted focusTint; None for black (the default), which is 0 at every λ.
    pub tint: Option<Sigmoid>,
    /// τ_v: the tint's luminance-weighted mean over the light's spectrum.
    pub tint_luminous: f32,
}

#[derive(Clone, Debug)]
pub struct IesShaping {
    pub profile: Arc<IesProfile>,
    pub angle_scale: f32,
    /// 1, or 1 / mean intensity with `shaping:ies:normalize`.
    pub scale: f32,
}

/// Integrals of a shaped light over directions, per cd/m² of its base luminance L₀.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Directional {
    /// ∫ s_v(ω) P(ω) dω: luminous flux (lm) per nit, P the projected emitting area.
    pub flux_per_nit: f32,
    /// max_ω s_v(ω) P(ω): peak luminous intensity (cd) per nit.
    pub peak_per_nit: f32,
    /// max_ω s_v(ω): peak luminance per nit.
    pub max_factor: f32,
}

impl Cone {
    pub fn new(angle_deg: f32, softness: f32) -> Option<Cone> {
        let theta_cut = angle_deg.to_radians();
        if theta_cut.is_nan() || theta_cut >= PI {
            return None;
        }
        let theta_cut = theta_cut.max(0.0);
        let theta_soft = (1.0 - softness.clamp(0.0, 1.0)) * theta_cut;
        Some(Cone {
            theta_soft,
            theta_cut,
            cos_soft: theta_soft.cos(),
            cos_cut: theta_cut.cos(),
        })
    }

    /// 1 − smoothstep(θ, θ_soft, θ_cut) for cos θ = `cos_theta`.
    #[inline]
    pub fn factor(&self, cos_theta: f32) -> f32 {
        if cos_theta >= self.cos_soft {
            return 1.0;
        }
        if cos_theta < self.cos_cut {
            return 0.0;
        }
        let theta = cos_theta.clamp(-1.0, 1.0).acos();
        if theta > self.theta_cut {
            return 0.0;
        }
        let t = ((theta - self.theta_soft) / (self.theta_cut - self.theta_soft)).clamp(0.0, 1.0);
        1.0 - t * t * (3.0 - 2.0 * t)
    }
}

impl IesShaping {
    /// The profile's vertical angle for the light-space angle θ from the axis, or None when it
    /// falls outside [0, π] (UsdLux `shaping:ies:angleScale`).
    #[inline]
    pub fn profile_theta(&self, theta: f32) -> Option<f32> {
        let s = self.angle_scale;
        let t = if s > 0.0 {
            theta / s
        } else if s < 0.0 {
            (theta - PI) / -s + PI
        } else {
            theta
        };
        (0.0..=PI).contains(&t).then_some(t)
    }

    /// The inverse of [`IesShaping::profile_theta`].
    pub fn light_theta(&self, profile_theta: f32) -> f32 {
        let s = self.angle_scale;
        if s > 0.0 {
            profile_theta * s
        } else if s < 0.0 {
            (profile_theta - PI) * -s + PI
        } else {
            profile_theta
        }
    }

    /// The profile's factor for a light-local direction (axis −Z, C0 along +X).
    #[inline]
    pub fn factor(&self, w_local: Vec3) -> f32 {
        let theta = (-w_local.z).clamp(-1.0, 1.0).acos();
        let Some(t) = self.profile_theta(theta) else {
            return 0.0;
        };
        let phi = w_local.y.atan2(w_local.x);
        self.profile.candela(t, phi) * self.scale
    }
}

impl Shaping {
    /// Shaping from its description for a light with transform `to_world` whose base
    /// emission spectrum (any scale) is `base`; `ies` is the parsed profile of `desc.ies`.
    pub fn new(
        desc: &ShapingDesc,
        to_world: &Mat4,
        base: &Spectrum,
        ies: Option<Arc<IesProfile>>,
    ) -> Reason<Shaping> {
        if desc.focus_tint.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(format!(
                "shaping:focusTint {:?} must be finite and non-negative",
                desc.focus_tint
            ));
        }
        let focus = (desc.focus > 0.0).then(|| {
            let tint = (desc.focus_tint != [0.0; 3]).then(|| uplift::reflectance(desc.focus_tint));
            let tint_luminous = tint.as_ref().map_or(0.0, |t| luminous_mean(base, t));
            Focus {
                exponent: desc.focus,
                tint,
                tint_luminous,
            }
        });
        let ies = match (&desc.ies, ies) {
            (Some(d), Some(profile)) => {
                let scale = if d.normalize {
                    let mean = profile.mean_intensity();
                    if mean.is_nan() || mean <= 0.0 {
                        return Err(format!(
                            "{}: shaping:ies:normalize needs a profile with non-zero intensity",
                            d.file.display()
                        ));
                    }
                    (1.0 / mean) as f32
                } else {
                    1.0
                };
                Some(IesShaping {
                    profile,
                    angle_scale: d.angle_scale,
                    scale,
                })
            }
            _ => None,
        };
        Ok(Shaping {
            world_to_local: light_rotation(to_world).transpose(),
            cone: Cone::new(desc.cone_angle_deg, desc.cone_softness),
            focus,
            ies,
            photometry: Directional::default(),
        })
    }

    /// The emission axis in world space (local −Z).
    pub fn axis(&self) -> Vec3 {
        -self.world_to_local.row(2)
    }

    /// The cone × IES factor for a light-local direction (colourless).
    #[inline]
    fn scalar(&self, w_local: Vec3) -> f32 {
        let cos_theta = -w_local.z;
        let mut s = self.cone.map_or(1.0, |c| c.factor(cos_theta));
        if s > 0.0 {
            if let Some(ies) = &self.ies {
                s *= ies.factor(w_local);
            }
        }
        s
    }

    /// The focus factor ff = |cos θ|^focus (1 without focus).
    #[inline]
    fn focus_factor(&self, w_local: Vec3) -> f32 {
        self.focus
            .as_ref()
            .map_or(1.0, |f| w_local.z.abs().min(1.0).powf(f.exponent))
    }

    /// Radiance `l` (unshaped, at `lambda`) shaped for world emission direction `w`.
    #[inline]
    pub fn apply(
        &self,
        w: Vec3,
        l: SampledSpectrum,
        lambda: &SampledWavelengths,
    ) -> SampledSpectrum {
        let w_local = self.world_to_local * w;
        let s = self.scalar(w_local);
        if s == 0.0 {
            return SampledSpectrum::ZERO;
        }
        let Some(focus) = &self.focus else {
            return l * s;
        };
        let ff = self.focus_factor(w_local);
        match &focus.tint {
            None => l * (s * ff),
            Some(t) => {
                let tint = SampledSpectrum::from_fn(|i| t.eval(lambda.lambda[i]));
                l * (tint * ((1.0 - ff) * s) + SampledSpectrum::splat(ff * s))
            }
        }
    }

    /// The luminous factor s_v(ω) for a light-local direction: what shaping does to the
    /// luminance, cone × IES × ((1 − ff) τ_v + ff).
    pub fn luminous_factor(&self, w_local: Vec3) -> f32 {
        let s = self.scalar(w_local);
        if s == 0.0 {
            return 0.0;
        }
        match &self.focus {
            None => s,
            Some(f) => {
                let ff = self.focus_factor(w_local);
                s * ((1.0 - ff) * f.tint_luminous + ff)
            }
        }
    }

    /// Integrates the luminous factor times `projected_area(ω_world)` (the light's projected
    /// emitting area towards ω, m²) over the sphere, and finds its peak.
    ///
    /// Midpoint rule on panels whose edges are every place the integrand has a kink or a jump
    /// (the axis plane θ = π/2, the cone's θ_soft and θ_cut, the IES grid's angles), about
    /// 1024 × 256 points over the sphere, so the error is O(h²) ≈ 1e-6 relative. The peak is the
    /// largest value at those points, the axis, its opposite and the IES grid directions.
    pub fn integrate(&self, projected_area: impl Fn(Vec3) -> f32) -> Directional {
        let to_world = self.world_to_local.transpose();
        let mut out = Directional::default();
        let mut visit = |w_local: Vec3| {
            let s = self.luminous_factor(w_local);
            let v = s * projected_area(to_world * w_local);
            out.max_factor = out.max_factor.max(s);
            out.peak_per_nit = out.peak_per_nit.max(v);
            v
        };
        let mut flux = 0.0f64;
        let (thetas, phis) = (self.theta_breaks(), self.phi_breaks());
        for t in panels(&thetas, THETA_STEPS / PI) {
            let (st, ct) = t.x.sin_cos();
            for p in panels(&phis, PHI_STEPS / (2.0 * PI)) {
                let (sp, cp) = p.x.sin_cos();
                let v = visit(Vec3::new(st * cp, st * sp, -ct));
                flux += (v * st * t.width * p.width) as f64;
            }
        }
        for (theta, phi) in self.special_directions() {
            let (st, ct) = theta.sin_cos();
            visit(Vec3::new(st * phi.cos(), st * phi.sin(), -ct));
        }
        out.flux_per_nit = flux as f32;
        out
    }

    /// θ panel edges in [0, π] (up to the cone's cutoff, beyond which nothing is emitted).
    fn theta_breaks(&self) -> Vec<f32> {
        let top = self.cone.map_or(PI, |c| c.theta_cut);
        let mut b = vec![0.0, top, 0.5 * PI];
        if let Some(c) = self.cone {
            b.push(c.theta_soft);
        }
        if let Some(ies) = &self.ies {
            b.extend(
                ies.profile
                    .vertical_angles()
                    .iter()
                    .map(|&t| ies.light_theta(t)),
            );
        }
        sorted_within(b, 0.0, top)
    }

    fn phi_breaks(&self) -> Vec<f32> {
        let mut b = vec![0.0, 2.0 * PI];
        if let Some(ies) = &self.ies {
            b.extend_from_slice(ies.profile.horizontal_angles());
        }
        sorted_within(b, 0.0, 2.0 * PI)
    }

    /// Directions where a peak may sit exactly: the axis, its opposite, the IES grid.
    fn special_directions(&self) -> Vec<(f32, f32)> {
        let mut d = vec![(0.0, 0.0), (PI, 0.0)];
        if let Some(ies) = &self.ies {
            d.extend(
                ies.profile
                    .nodes()
                    .map(|(t, p)| (ies.light_theta(t).clamp(0.0, PI), p)),
            );
        }
        d
    }
}

/// Luminous flux of a shaped light with base luminance `lv` (cd/m²), or `unshaped_per_nit · lv`.
pub fn luminous_power(shaping: &Option<Shaping>, unshaped_per_nit: f32, lv: f32) -> f32 {
    shaping
        .as_ref()
        .map_or(unshaped_per_nit, |s| s.photometry.flux_per_nit)
        * lv
}

/// Applies optional shaping to a radiance sample.
#[inline]
pub fn shape(
    shaping: &Option<Shaping>,
    w: Vec3,
    l: SampledSpectrum,
    lambda: &SampledWavelengths,
) -> SampledSpectrum {
    match shaping {
        Some(s) => s.apply(w, l, lambda),
        None => l,
    }
}

/// The rotation part of a light's transform, orthonormalised (Gram–Schmidt from local Z,
/// then X), as columns: world-space local X, Y, Z.
fn light_rotation(m: &Mat4) -> Mat3 {
    let z = m.transform_vector3(Vec3::Z).normalize_or(Vec3::Z);
    let x_raw = m.transform_vector3(Vec3::X);
    let x = (x_raw - x_raw.dot(z) * z).normalize_or(z.any_orthonormal_vector());
    Mat3::from_cols(x, z.cross(x), z)
}

/// ∫ base τ ȳ / ∫ base ȳ.
fn luminous_mean(base: &Spectrum, tint: &Sigmoid) -> f32 {
    let yb = &data::cie_xyz()[1];
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (i, &y) in yb.values.iter().enumerate() {
        let lambda = crate::spectral::LAMBDA_MIN + i as f32;
        let w = (base.eval(lambda) * y) as f64;
        num += w * tint.eval(lambda) as f64;
        den += w;
    }
    if den > 0.0 {
        (num / den) as f32
    } else {
        0.0
    }
}

/// A midpoint and the width of its sub-interval.
struct Cell {
    x: f32,
    width: f32,
}

/// Midpoints of every panel between consecutive `edges`, each split into
/// max(4, ⌈density · length⌉) equal cells.
fn panels(edges: &[f32], density: f32) -> impl Iterator<Item = Cell> + '_ {
    edges.windows(2).flat_map(move |e| {
        let len = e[1] - e[0];
        let n = ((density * len).ceil() as usize).max(4);
        let width = len / n as f32;
        (0..n).map(move |k| Cell {
            x: e[0] + (k as f32 + 0.5) * width,
            width,
        })
    })
}

/// `v` clamped to [lo, hi], sorted, with near-duplicates (< 1e-5 rad) merged.
fn sorted_within(v: Vec<f32>, lo: f32, hi: f32) -> Vec<f32> {
    let mut v: Vec<f32> = v
        .into_iter()
        .filter(|x| x.is_finite())
        .map(|x| x.clamp(lo, hi))
        .collect();
    v.sort_by(f32::total_cmp);
    v.dedup_by(|b, a| (*b - *a).abs() < 1e-5);
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::ShapingDesc;

    fn shaping(desc: ShapingDesc) -> Shaping {
        Shaping::new(&desc, &Mat4::IDENTITY, &Spectrum::Constant(1.0), None).unwrap()
    }

    /// Direction at angle θ (degrees) from the −Z axis, in the XZ plane.
    fn dir(theta_deg: f32) -> Vec3 {
        let t = theta_deg.to_radians();
        Vec3::new(t.sin(), 0.0, -t.cos())
    }

    #[test]
    fn hard_cone_cuts_at_the_angle_and_soft_cone_is_a_smoothstep() {
        let hard = shaping(ShapingDesc {
            cone_angle_deg: 30.0,
            ..Default::default()
        });
        assert_eq!(hard.luminous_factor(dir(29.9)), 1.0);
        assert_eq!(hard.luminous_factor(dir(30.1)), 0.0);
        let soft = shaping(ShapingDesc {
            cone_angle_deg: 40.0,
            cone_softness: 0.5,
            ..Default::default()
        });
        // θ_soft = 20°; at 30° t = 0.5, smoothstep = 0.5.
        assert_eq!(soft.luminous_factor(dir(19.0)), 1.0);
        assert!((soft.luminous_factor(dir(30.0)) - 0.5).abs() < 1e-4);
        assert!((soft.luminous_factor(dir(35.0)) - (1.0 - 0.84375)).abs() < 1e-4);
        assert_eq!(soft.luminous_factor(dir(41.0)), 0.0);
    }

    #[test]
    fn focus_is_a_power_of_the_cosine_and_tint_lerps_to_white() {
        let f = shaping(ShapingDesc {
            focus: 3.0,
            ..Default::default()
        });
        let c = 50f32.to_radians().cos();
        assert!((f.luminous_factor(dir(50.0)) - c.powi(3)).abs() < 1e-5);
        // |cos| also behind the light.
        assert!((f.luminous_factor(dir(130.0)) - c.powi(3)).abs() < 1e-5);
        let white = shaping(ShapingDesc {
            focus: 3.0,
            focus_tint: [1.0; 3],
            ..Default::default()
        });
        assert!((white.luminous_factor(dir(70.0)) - 1.0).abs() < 1e-5);
        let lambda = SampledWavelengths::sample_visible(0.3);
        let l = white.apply(dir(70.0), SampledSpectrum::splat(2.0), &lambda);
        for i in 0..4 {
            assert!((l[i] - 2.0).abs() < 1e-5);
        }
    }

    #[test]
    fn integral_of_a_cone_on_a_flat_emitter() {
        // ∫ cos θ over a cone of half-angle α = π sin²α (per unit area and nit).
        let s = shaping(ShapingDesc {
            cone_angle_deg: 35.0,
            ..Default::default()
        });
        let d = s.integrate(|w| (-w.z).max(0.0));
        let expected = PI * 35f32.to_radians().sin().powi(2);
        assert!((d.flux_per_nit / expected - 1.0).abs() < 1e-5, "{d:?}");
        assert_eq!(d.peak_per_nit, 1.0);
        // Focus on a sphere (projected area 1): ∫ |cos|^n dω = 4π / (n + 1).
        let f = shaping(ShapingDesc {
            focus: 2.0,
            ..Default::default()
        });
        let d = f.integrate(|_| 1.0);
        assert!(
            (d.flux_per_nit / (4.0 * PI / 3.0) - 1.0).abs() < 1e-5,
            "{d:?}"
        );
    }

    #[test]
    fn angle_scale_follows_the_usdlux_formula() {
        let ies = |s| IesShaping {
            profile: Arc::new(
                IesProfile::parse(
                    "TILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 0\n0 180\n0\n1 1\n",
                    std::path::Path::new("x.ies"),
                )
                .unwrap(),
            ),
            angle_scale: s,
            scale: 1.0,
        };
        let t = 0.6;
        assert!((ies(0.5).profile_theta(t).unwrap() - 1.2).abs() < 1e-6);
        assert_eq!(ies(0.0).profile_theta(t), Some(t));
        let neg = ies(-0.5).profile_theta(2.8).unwrap();
        assert!((neg - ((2.8 - PI) / 0.5 + PI)).abs() < 1e-6);
        assert_eq!(ies(0.1).profile_theta(1.0), None);
        for s in [0.5, -0.5, 0.0, 2.0] {
            let i = ies(s);
            assert!((i.profile_theta(i.light_theta(0.3)).unwrap() - 0.3).abs() < 1e-5);
        }
    }
}
