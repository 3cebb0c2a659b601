//! The `spectral:` attribute vocabulary (docs/design.md §3) and its enforcement: any attribute in
//! the `spectral:` namespace that the vocabulary does not define for that kind of prim is an
//! error naming the prim and the attribute.

use openusd::usd;

use super::values::Ctx;
use crate::error::Result;

/// `token spectral:emission`: a named SPD, or `"blackbody"`.
pub(super) const EMISSION: &str = "spectral:emission";
/// `float2[] spectral:emission:samples`: (nm, value) pairs.
pub(super) const EMISSION_SAMPLES: &str = "spectral:emission:samples";
/// `float spectral:temperature` (K), with `spectral:emission = "blackbody"`.
pub(super) const TEMPERATURE: &str = "spectral:temperature";
/// `float spectral:luminousFlux` (lm).
pub(super) const LUMINOUS_FLUX: &str = "spectral:luminousFlux";
/// `float spectral:luminousIntensity` (cd).
pub(super) const LUMINOUS_INTENSITY: &str = "spectral:luminousIntensity";

/// The `spectral:` attributes a light (UsdLux light or `MeshLightAPI` prim) may carry.
const LIGHT_ATTRIBUTES: [&str; 5] = [
    EMISSION,
    EMISSION_SAMPLES,
    TEMPERATURE,
    LUMINOUS_FLUX,
    LUMINOUS_INTENSITY,
];

/// `true` for a property name in the `spectral:` namespace (also `inputs:spectral:...`,
/// a likely misspelling that must not pass silently).
fn is_spectral(name: &str) -> bool {
    name.starts_with("spectral:") || name.starts_with("inputs:spectral:")
}

/// Fails on the first `spectral:` property of `prim` that is not in the vocabulary for it.
pub(super) fn check_spectral_names(ctx: &Ctx, prim: &usd::Prim, is_light: bool) -> Result<()> {
    for name in ctx.property_names(prim)?.iter().filter(|n| is_spectral(n)) {
        if is_light && LIGHT_ATTRIBUTES.contains(&name.as_str()) {
            continue;
        }
        let reason = if LIGHT_ATTRIBUTES.contains(&name.as_str()) {
            format!("'{name}' is only allowed on UsdLux lights and MeshLightAPI prims")
        } else {
            format!("unknown attribute '{name}' in the spectral: namespace")
        };
        return Err(ctx.err(prim, reason));
    }
    Ok(())
}

/// The inputs (without the `inputs:` prefix) each `spectral:*` shader accepts.
pub(super) fn shader_inputs(id: &str) -> Option<&'static [&'static str]> {
    Some(match id {
        "spectral:diffuse" => &[
            "reflectance",
            "reflectance:spectrum",
            "reflectance:samples",
            "roughness",
        ],
        "spectral:conductor" => &["eta:spectrum", "k:spectrum", "metal", "roughness"],
        "spectral:dielectric" => &[
            "ior",
            "glass",
            "sellmeierB",
            "sellmeierC",
            "roughness",
            "thin",
        ],
        "spectral:plastic" => &[
            "reflectance",
            "reflectance:spectrum",
            "reflectance:samples",
            "ior",
            "roughness",
        ],
        _ => return None,
    })
}

/// The inputs of a `spectral:*` shader that may be connected to a `UsdUVTexture`: colour
/// reflectances and roughnesses.
pub(super) fn texturable_inputs(id: &str) -> &'static [&'static str] {
    match id {
        "spectral:diffuse" | "spectral:plastic" => &["reflectance", "roughness"],
        "spectral:conductor" | "spectral:dielectric" => &["roughness"],
        _ => &[],
    }
}
