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

/// `token spectral:lightGroup`: the light group of `--light-groups`.
pub(super) const LIGHT_GROUP: &str = "spectral:lightGroup";

/// The `spectral:` attributes a light (UsdLux light or `MeshLightAPI` prim) may carry.
const LIGHT_ATTRIBUTES: [&str; 6] = [
    EMISSION,
    EMISSION_SAMPLES,
    TEMPERATURE,
    LUMINOUS_FLUX,
    LUMINOUS_INTENSITY,
    LIGHT_GROUP,
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

/// The entry of `known` one edit (insertion, deletion, substitution or transposition of
/// adjacent characters) away from `name`, for "did you mean" hints.
pub(super) fn one_edit_away<'k>(name: &str, known: &[&'k str]) -> Option<&'k str> {
    known.iter().copied().find(|k| is_one_edit(name, k))
}

fn is_one_edit(a: &str, b: &str) -> bool {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    if a == b {
        return false;
    }
    let prefix = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let (ra, rb) = (&a[prefix..], &b[prefix..]);
    match ra.len() as isize - rb.len() as isize {
        0 => {
            ra[1..] == rb[1..]
                || (ra.len() >= 2 && ra[0] == rb[1] && ra[1] == rb[0] && ra[2..] == rb[2..])
        }
        1 => ra[1..] == *rb,
        -1 => *ra == rb[1..],
        _ => false,
    }
}

/// Warns about each authored `inputs:*` of `prim` that is not in `known` (names without the
/// `inputs:` prefix), with a "did you mean" when one is a single edit away. `what` names the
/// prim's kind (`SphereLight`, `UsdUVTexture`, …).
pub(super) fn warn_unknown_inputs(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    known: &[&str],
    what: &str,
) -> Result<()> {
    for name in ctx.property_names(prim)? {
        let Some(input) = name.strip_prefix("inputs:") else {
            continue;
        };
        if known.contains(&input) || is_spectral(&name) {
            continue;
        }
        let hint = one_edit_away(input, known)
            .map(|k| format!("; did you mean inputs:{k}?"))
            .unwrap_or_default();
        ctx.warn(
            prim,
            format!("unknown input '{name}' for {what}, ignored{hint}"),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_edit() {
        let known = ["intensity", "exposure", "color"];
        assert_eq!(one_edit_away("intensty", &known), Some("intensity"));
        assert_eq!(one_edit_away("intensityy", &known), Some("intensity"));
        assert_eq!(one_edit_away("intesnity", &known), Some("intensity"));
        assert_eq!(one_edit_away("colours", &known), None);
        assert_eq!(one_edit_away("colr", &known), Some("color"));
        assert_eq!(one_edit_away("color", &known), None);
    }
}
