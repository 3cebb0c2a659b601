//! One or more instances of every model, including the numerically hard corners (roughness
//! 10⁻⁴, IOR 1 and 1.0001, anisotropy, roughness 1), built the way the scene builds them.
//! For tests and statistical harnesses (`tests/materials.rs`, the χ² tests): iterate over
//! [`examples`] and call `f`, `sample_f` and `pdf` on each [`Bxdf`].

use crate::bxdf::*;
use crate::desc::PreviewSurfaceDesc;
use crate::material::{Material, PlasticMaterial, PreviewMaterial};
use crate::spectral::sellmeier::Sellmeier;
use crate::spectral::{data, SampledSpectrum, SampledWavelengths, Spectrum};
use std::sync::Arc;

/// The wavelengths the examples are evaluated at (nm).
pub const EXAMPLE_LAMBDA: [f32; 4] = [450.0, 520.0, 590.0, 660.0];

/// A named model instance.
#[derive(Clone, Copy, Debug)]
pub struct Example {
    pub name: &'static str,
    pub bxdf: Bxdf,
    /// True when f is symmetric in (ωo, ωi) for reflection (every model here but the
    /// dielectrics, whose transmission is reciprocal only up to η²).
    pub reciprocal: bool,
}

fn lambda() -> SampledWavelengths {
    SampledWavelengths {
        lambda: EXAMPLE_LAMBDA,
        pdf: [1.0; 4],
    }
}

fn dense(d: &crate::spectral::DenseSpectrum) -> Spectrum {
    Spectrum::Dense {
        data: Arc::new(d.clone()),
        scale: 1.0,
    }
}

/// A conductor made of `metal` ("Au", "Ag", "Cu", "Al") with GGX (αx, αy).
pub fn metal(metal: &str, alpha_x: f32, alpha_y: f32) -> Bxdf {
    let (n, k) = data::metal(metal).expect("a metal in spectra/metal");
    let m = Material::Conductor {
        eta: dense(n),
        k: dense(k),
        distrib: TrowbridgeReitz::new(alpha_x, alpha_y),
        roughness: None,
    };
    m.bsdf(glam::Vec2::ZERO.into(), glam::Vec3::Z, &lambda())
        .bxdf
}

fn dielectric(eta: f32, alpha: f32) -> Bxdf {
    Bxdf::Dielectric(DielectricBxdf::new(TrowbridgeReitz::isotropic(alpha), eta))
}

fn plastic(alpha: f32) -> Bxdf {
    let rho = Spectrum::Sigmoid(crate::spectral::uplift::reflectance([0.7, 0.2, 0.1]));
    let m = Material::Plastic(PlasticMaterial::new(rho, 1.5, alpha));
    m.bsdf(glam::Vec2::ZERO.into(), glam::Vec3::Z, &lambda())
        .bxdf
}

fn preview(d: PreviewSurfaceDesc) -> Bxdf {
    let uplift = |c| Spectrum::Sigmoid(crate::spectral::uplift::reflectance(c));
    let m = PreviewMaterial::new(&d, uplift(d.diffuse_color), uplift(d.specular_color));
    m.bsdf(glam::Vec2::ZERO.into(), glam::Vec3::Z, &lambda())
        .bxdf
}

/// Every model, smooth and rough, with the corner cases of issue 3.
pub fn examples() -> Vec<Example> {
    let l = lambda();
    let rho = Spectrum::Sigmoid(crate::spectral::uplift::reflectance([0.2, 0.5, 0.8])).sample(&l);
    let bk7 = data::glass("BK7").expect("BK7 in spectra/glass");
    let ps = PreviewSurfaceDesc::default;
    let v = vec![
        ("lambert", Bxdf::Diffuse(DiffuseBxdf { r: rho }), true),
        (
            "oren-nayar-0.3",
            Bxdf::OrenNayar(OrenNayarBxdf::new(rho, 0.3)),
            true,
        ),
        (
            "oren-nayar-1.0",
            Bxdf::OrenNayar(OrenNayarBxdf::new(SampledSpectrum::ONE, 1.0)),
            true,
        ),
        ("gold-smooth", metal("Au", 0.0, 0.0), true),
        ("gold-1e-4", metal("Au", 1e-4, 1e-4), true),
        ("gold-0.3", metal("Au", 0.3, 0.3), true),
        ("silver-0.05", metal("Ag", 0.05, 0.05), true),
        ("copper-0.2", metal("Cu", 0.2, 0.2), true),
        ("aluminium-1.0", metal("Al", 1.0, 1.0), true),
        ("gold-aniso-0.1-0.4", metal("Au", 0.1, 0.4), true),
        ("glass-smooth", dielectric(1.5, 0.0), false),
        ("glass-1e-4", dielectric(1.5, 1e-4), false),
        ("glass-0.05", dielectric(1.5, 0.05), false),
        ("glass-0.3", dielectric(1.5, 0.3), false),
        ("glass-1.0", dielectric(1.5, 1.0), false),
        ("glass-inverted-0.3", dielectric(1.0 / 1.5, 0.3), false),
        ("bk7-hero-0.2", dielectric(bk7.ior(450.0), 0.2), false),
        ("ior-1", dielectric(1.0, 0.3), false),
        ("ior-1.0001", dielectric(1.0001, 0.3), false),
        ("ior-1.0001-smooth", dielectric(1.0001, 0.0), false),
        ("ior-1.01-0.3", dielectric(1.01, 0.3), false),
        (
            "thin-bk7",
            Bxdf::ThinDielectric(ThinDielectricBxdf::new(SampledSpectrum::from_fn(|i| {
                bk7.ior(EXAMPLE_LAMBDA[i])
            }))),
            true,
        ),
        (
            "thin-constant-1.5",
            Bxdf::ThinDielectric(ThinDielectricBxdf::new(SampledSpectrum::splat(
                Sellmeier::constant(1.5).ior(500.0),
            ))),
            true,
        ),
        ("plastic-smooth", plastic(0.0), true),
        ("plastic-1e-4", plastic(1e-4), true),
        ("plastic-0.1", plastic(0.1), true),
        ("plastic-0.6", plastic(0.6), true),
        ("preview-default", preview(ps()), true),
        (
            "preview-metal",
            preview(PreviewSurfaceDesc {
                diffuse_color: [0.9, 0.6, 0.2],
                metallic: 1.0,
                roughness: 0.4,
                ..ps()
            }),
            true,
        ),
        (
            "preview-smooth-metal",
            preview(PreviewSurfaceDesc {
                metallic: 1.0,
                roughness: 0.0,
                ..ps()
            }),
            true,
        ),
        (
            "preview-clearcoat",
            preview(PreviewSurfaceDesc {
                diffuse_color: [0.6, 0.05, 0.05],
                metallic: 0.5,
                roughness: 0.6,
                clearcoat: 1.0,
                clearcoat_roughness: 0.3,
                ..ps()
            }),
            true,
        ),
        (
            "preview-smooth-clearcoat",
            preview(PreviewSurfaceDesc {
                diffuse_color: [0.1, 0.3, 0.6],
                roughness: 0.0,
                clearcoat: 1.0,
                clearcoat_roughness: 0.0,
                ..ps()
            }),
            true,
        ),
        (
            "preview-specular-workflow",
            preview(PreviewSurfaceDesc {
                use_specular_workflow: true,
                specular_color: [0.9, 0.9, 0.2],
                diffuse_color: [0.5, 0.5, 0.5],
                roughness: 0.3,
                ..ps()
            }),
            true,
        ),
        (
            "preview-white",
            preview(PreviewSurfaceDesc {
                diffuse_color: [1.0, 1.0, 1.0],
                roughness: 0.2,
                clearcoat: 1.0,
                clearcoat_roughness: 0.5,
                ..ps()
            }),
            true,
        ),
    ];
    v.into_iter()
        .map(|(name, bxdf, reciprocal)| Example {
            name,
            bxdf,
            reciprocal,
        })
        .collect()
}
