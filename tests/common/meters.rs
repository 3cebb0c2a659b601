//! What the light-meter tests of the library (`tests/meters.rs`) and of the command line
//! (`tests/meter_cli.rs`) share: the accuracy bound and Lambert's closed form.

use glam::DVec3;

/// The accuracy bound for analytic cases.
pub const TOL: f64 = 0.005;

/// Lambert's polygon formula (Lambert 1760; e.g. Arvo 1995, "Applications of irradiance
/// tensors", eq. 3): the illuminance from a uniform polygon of luminance L at `p` on a
/// surface of normal `n` is E = (L/2) Σᵢ βᵢ n·(rᵢ × rᵢ₊₁)/|rᵢ × rᵢ₊₁|, rᵢ the unit vectors to
/// the vertices and βᵢ the angle between rᵢ and rᵢ₊₁. Valid when the whole polygon is in
/// front of the surface (checked). Returns E/L.
pub fn lambert(p: DVec3, n: DVec3, verts: &[DVec3]) -> f64 {
    assert!(
        verts.iter().all(|v| n.dot(*v - p) > 0.0),
        "polygon not above the horizon"
    );
    let r: Vec<DVec3> = verts.iter().map(|v| (*v - p).normalize()).collect();
    let sum: f64 = (0..r.len())
        .map(|i| {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            let c = a.cross(b);
            c.length().atan2(a.dot(b)) * n.dot(c.normalize())
        })
        .sum();
    0.5 * sum.abs()
}
