//! Normal mapping: tangent frames from texture coordinates and the perturbed shading normal
//! (UsdPreviewSurface `normal`, a tangent-space normal, constant or from a `UsdUVTexture`).
//!
//! - **Tangent frames.** Each triangle's ∂p/∂u and ∂p/∂v follow from its positions and st
//!   (PBR 4ed §6.5.3, eq. 6.8); they are computed once when the scene is built, only for
//!   meshes whose material perturbs the normal ([`Tangents`]). At a hit, the tangent is ∂p/∂u
//!   made orthogonal to the interpolated shading normal (Gram–Schmidt, as MikkTSpace does per
//!   pixel), and the bitangent is n × t, flipped to the side of ∂p/∂v so that mirrored st
//!   (v growing the "wrong" way) maps the texture's +Y correctly. Degenerate st (a triangle
//!   whose st has zero area) or a mesh without st gets the orthonormal basis of Duff et al.
//!   2017 around the shading normal instead — arbitrary, but never NaN.
//! - **Perturbation** (pbrt-v4 `NormalMap`, PBR 4ed §10.5.3): n = t·x + b·y + ns·z for the unit
//!   tangent-space normal (x, y, z). The scene puts n in `SurfaceHit::ns`, so the BSDF frame
//!   *and* every cosine the integrators take use it; the geometric normal is unchanged.
//! - **Guard.** A perturbed normal may end up below the geometric tangent plane. pbrt-v4
//!   flips it to the geometric side (`FaceForward`), which mirrors the texture's slope; we
//!   instead push it back along ng until n·ng ≥ [`MIN_COS_NG`] (or the unperturbed normal's
//!   own n·ng, if that is smaller), which is continuous in the texel value.

use crate::math::Frame;
use glam::{Vec2, Vec3};

/// The smallest cosine between a perturbed shading normal and the geometric normal (≈ 89.4°).
pub const MIN_COS_NG: f32 = 0.01;

/// Per-triangle (∂p/∂u, ∂p/∂v) of a mesh whose material perturbs the shading normal.
#[derive(Clone, Debug, Default)]
pub enum Tangents {
    /// The material does not perturb the normal: nothing is stored or computed.
    #[default]
    Unused,
    /// The mesh has no st: the frame is arbitrary around the shading normal.
    Arbitrary,
    /// One (∂p/∂u, ∂p/∂v) per triangle; zero vectors where st is degenerate.
    PerTriangle(Vec<[Vec3; 2]>),
}

impl Tangents {
    /// The tangents of every triangle of a mesh (`uvs` per corner, `None` without st).
    pub fn of(positions: &[Vec3], indices: &[[u32; 3]], uvs: Option<&[[Vec2; 3]]>) -> Tangents {
        let Some(uvs) = uvs else {
            return Tangents::Arbitrary;
        };
        let dp = indices
            .iter()
            .zip(uvs)
            .map(|(t, uv)| triangle_dpduv(t.map(|i| positions[i as usize]), *uv))
            .collect();
        Tangents::PerTriangle(dp)
    }

    /// (∂p/∂u, ∂p/∂v) of triangle `tri`; `None` when the normal is not perturbed.
    #[inline]
    pub fn at(&self, tri: u32) -> Option<[Vec3; 2]> {
        match self {
            Tangents::Unused => None,
            Tangents::Arbitrary => Some([Vec3::ZERO; 2]),
            Tangents::PerTriangle(d) => Some(d[tri as usize]),
        }
    }
}

/// ∂p/∂u and ∂p/∂v of a triangle with positions `p` and texture coordinates `uv`
/// (PBR 4ed §6.5.3, eq. 6.8); zeros when st is degenerate or the result is not finite.
pub fn triangle_dpduv(p: [Vec3; 3], uv: [Vec2; 3]) -> [Vec3; 2] {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = f64::from(duv02.x) * f64::from(duv12.y) - f64::from(duv02.y) * f64::from(duv12.x);
    if det.abs() < 1e-12 {
        return [Vec3::ZERO; 2];
    }
    let inv = (1.0 / det) as f32;
    let dpdu = (dp02 * duv12.y - dp12 * duv02.y) * inv;
    let dpdv = (dp12 * duv02.x - dp02 * duv12.x) * inv;
    if dpdu.is_finite() && dpdv.is_finite() && dpdu.cross(dpdv) != Vec3::ZERO {
        [dpdu, dpdv]
    } else {
        [Vec3::ZERO; 2]
    }
}

/// The unit tangent and bitangent around the unit shading normal `ns`.
#[inline]
fn tangent_basis(ns: Vec3, [dpdu, dpdv]: [Vec3; 2]) -> (Vec3, Vec3) {
    let t = dpdu - ns * ns.dot(dpdu);
    if t.length_squared() > 1e-10 * dpdu.length_squared() {
        if let Some(t) = t.try_normalize() {
            let b = ns.cross(t);
            return (t, if b.dot(dpdv) < 0.0 { -b } else { b });
        }
    }
    let f = Frame::from_normal(ns);
    (f.s, f.t)
}

/// The shading normal perturbed by the unit tangent-space normal `n_t` (pbrt-v4
/// `NormalMap`, PBR 4ed §10.5.3), kept above the geometric tangent plane.
#[inline]
pub fn perturb(n_t: Vec3, ns: Vec3, ng: Vec3, dpduv: [Vec3; 2]) -> Vec3 {
    if n_t == Vec3::Z {
        return ns;
    }
    let (t, b) = tangent_basis(ns, dpduv);
    let n = (t * n_t.x + b * n_t.y + ns * n_t.z).normalize_or_zero();
    if n == Vec3::ZERO {
        return ns;
    }
    let floor = MIN_COS_NG.min(ns.dot(ng));
    let c = n.dot(ng);
    if c >= floor {
        return n;
    }
    (n + (floor - c) * ng).try_normalize().unwrap_or(ns)
}

/// A texel's tangent-space normal made unit; (0, 0, 1) when it is zero or not finite.
#[inline]
pub fn texel_normal(rgb: [f32; 3]) -> Vec3 {
    Vec3::from_array(rgb).try_normalize().unwrap_or(Vec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: [Vec3; 3] = [Vec3::ZERO, Vec3::X, Vec3::Y];

    fn unit_and_finite(n: Vec3) -> bool {
        n.is_finite() && (n.length() - 1.0).abs() < 1e-5
    }

    #[test]
    fn dpduv_follow_st() {
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        assert_eq!(triangle_dpduv(P, uv), [Vec3::X, Vec3::Y]);
        // st rotated by 90°: u grows along +Y, v along −X.
        let rotated = [Vec2::ZERO, Vec2::new(0.0, -1.0), Vec2::X];
        let [dpdu, dpdv] = triangle_dpduv(P, rotated);
        assert!((dpdu - Vec3::Y).length() < 1e-6 && (dpdv + Vec3::X).length() < 1e-6);
        // Scaled st scales the derivatives inversely.
        let [dpdu, _] = triangle_dpduv(P, uv.map(|x| x * 4.0));
        assert!((dpdu - 0.25 * Vec3::X).length() < 1e-7);
    }

    #[test]
    fn degenerate_st_and_zero_area_give_an_arbitrary_frame_without_nan() {
        let same = [Vec2::splat(0.3); 3];
        let line = [Vec2::ZERO, Vec2::X, Vec2::new(2.0, 0.0)];
        assert_eq!(triangle_dpduv(P, same), [Vec3::ZERO; 2]);
        assert_eq!(triangle_dpduv(P, line), [Vec3::ZERO; 2]);
        let point = [Vec3::ONE; 3];
        let dp = triangle_dpduv(point, [Vec2::ZERO, Vec2::X, Vec2::Y]);
        assert_eq!(dp, [Vec3::ZERO; 2]);
        let tilt = Vec3::new(0.6, 0.0, 0.8);
        for dpduv in [[Vec3::ZERO; 2], dp, [Vec3::Z, Vec3::Z], [Vec3::X, Vec3::X]] {
            let n = perturb(tilt, Vec3::Z, Vec3::Z, dpduv);
            assert!(unit_and_finite(n) && (n.z - 0.8).abs() < 1e-6, "{n}");
        }
        // A degenerate shading normal (zero-area triangle) stays finite.
        assert!(perturb(tilt, Vec3::ZERO, Vec3::ZERO, dp).is_finite());
    }

    #[test]
    fn flat_normal_is_the_identity_and_tilts_follow_the_tangents() {
        let ns = Vec3::new(0.1, 0.2, 0.9).normalize();
        let dp = [Vec3::new(1.0, 0.0, 0.3), Vec3::new(0.0, 2.0, 0.0)];
        assert_eq!(perturb(Vec3::Z, ns, Vec3::Z, dp), ns);
        assert_eq!(texel_normal([0.0, 0.0, 1.0]), Vec3::Z);
        assert_eq!(texel_normal([f32::NAN, 0.0, 1.0]), Vec3::Z);
        // On a flat +Z surface the tangent-space x axis is ∂p/∂u, y follows ∂p/∂v's side.
        let n = perturb(
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::Z,
            Vec3::Z,
            [Vec3::X, Vec3::Y],
        );
        assert!((n - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6);
        let mirrored = [Vec3::X, -Vec3::Y];
        let n = perturb(Vec3::new(0.0, 0.6, 0.8), Vec3::Z, Vec3::Z, mirrored);
        assert!((n - Vec3::new(0.0, -0.6, 0.8)).length() < 1e-6);
    }

    #[test]
    fn normals_below_the_geometric_plane_are_clamped() {
        // The shading normal leans 60° from ng; a further 60° tilt would go below the surface.
        let ns = Vec3::new(0.866_025_4, 0.0, 0.5);
        let dp = [Vec3::X, Vec3::Y];
        let n = perturb(Vec3::new(0.866_025_4, 0.0, 0.5), ns, Vec3::Z, dp);
        assert!(unit_and_finite(n));
        assert!(n.z >= 0.99 * MIN_COS_NG && n.z < 0.02, "{n}");
        // Tangent-space normals pointing down are clamped too.
        let down = (0.1 * Vec3::X - Vec3::Z).normalize();
        let n = perturb(down, Vec3::Z, Vec3::Z, dp);
        assert!(unit_and_finite(n) && n.z > 0.0);
    }
}
