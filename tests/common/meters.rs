//! What the light-meter tests of the library (`tests/meters.rs`) and of the command line
//! (`tests/meter_cli.rs`) and convergence (`tests/converge.rs`) share: the accuracy bound,
//! Lambert's closed form and the integrating sphere.

use super::load_text;
use super::stages::*;
use glam::DVec3;
use spectral_render::scene::Scene;
use spectral_render::Meter;
use std::f64::consts::PI;

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

/// A UV sphere of radius `r` (`n_lon` × `n_lat` facets, pole fans): points and faces.
pub fn uv_sphere(r: f64, n_lon: usize, n_lat: usize) -> (Vec<DVec3>, Vec<Vec<usize>>) {
    let mut pts = vec![DVec3::new(0.0, r, 0.0)];
    for k in 1..n_lat {
        let theta = PI * k as f64 / n_lat as f64;
        for j in 0..n_lon {
            let phi = 2.0 * PI * j as f64 / n_lon as f64;
            pts.push(
                r * DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ),
            );
        }
    }
    pts.push(DVec3::new(0.0, -r, 0.0));
    let ring = |k: usize, j: usize| 1 + (k - 1) * n_lon + j % n_lon;
    let south = pts.len() - 1;
    let mut faces = Vec::new();
    for j in 0..n_lon {
        faces.push(vec![0, ring(1, j + 1), ring(1, j)]);
        for k in 1..n_lat - 1 {
            faces.push(vec![
                ring(k, j),
                ring(k, j + 1),
                ring(k + 1, j + 1),
                ring(k + 1, j),
            ]);
        }
        faces.push(vec![south, ring(n_lat - 1, j), ring(n_lat - 1, j + 1)]);
    }
    (pts, faces)
}

pub fn polygon_area(p: &[DVec3]) -> f64 {
    (1..p.len() - 1)
        .map(|i| 0.5 * (p[i] - p[0]).cross(p[i + 1] - p[0]).length())
        .sum()
}

/// An integrating sphere: a UV sphere of reflectance `rho` around a small isotropic lamp, and
/// meters on facet centres next to the pole, at 45° and at the equator.
pub struct IntegratingSphere {
    /// The stage's text and the scene built from it.
    pub text: String,
    pub scene: Scene,
    pub meters: Vec<Meter>,
    /// The exact illuminance at each meter.
    pub exact: Vec<f64>,
    /// The area-averaged illuminance and that of an ideal sphere.
    pub mean_e: f64,
    pub ideal: f64,
}

pub fn integrating_sphere(rho: f64) -> IntegratingSphere {
    let (flux, lamp) = (1000.0, 0.02);
    let (n_lon, n_lat) = (32, 16);
    let (pts, faces) = uv_sphere(1.0, n_lon, n_lat);
    let mut s = header() + &looks_scope(&flat_diffuse("Wall", rho));
    s += &mesh("Sphere", BINDING_API, &pts, &faces, &binding("Wall"));
    let inputs =
        format!("    float inputs:radius = {lamp}\n    float spectral:luminousFlux = {flux}\n");
    s += &prim("SphereLight", "Lamp", &inputs);
    let scene = load_text(&format!("sphere-{rho}"), &s, (1, 1));
    let corners = |f: &Vec<usize>| f.iter().map(|&i| pts[i]).collect::<Vec<_>>();
    let area: f64 = faces.iter().map(|f| polygon_area(&corners(f))).sum();
    // Energy balance of a closed Lambertian enclosure gives the area-averaged illuminance:
    // Φ = (1 − ρ)⟨E⟩A + (lamp absorption f ρ⟨E⟩A). The lamp is an opaque, non-reflecting
    // UsdLux shape; from the wall it fills the cone of half-angle asin(a/R) around the inward
    // normal, which takes the fraction f = (a/R)² of Lambertian emission. As f → 0 this is the
    // issue's Φ/A·(1 + ρ/(1−ρ)).
    let f = lamp * lamp;
    let mean_e = flux / area / (1.0 - rho * (1.0 - f));
    let ideal = flux / area * (1.0 + rho / (1.0 - rho));
    assert!((mean_e / ideal - 1.0).abs() < 0.004);
    // The reflected part is uniform (ρ⟨E⟩ − … as in a true sphere); the direct part at a facet
    // point is I cos θ / d² with I = Φ/4π (a sphere's cap above the horizon), whose area
    // average is Φ/A. A facet centre is ~1 % closer to the lamp than the vertices.
    let exact_at = |p: DVec3, n: DVec3| {
        let d2 = p.length_squared();
        let direct = flux / (4.0 * PI) * n.dot(-p.normalize()) / d2;
        mean_e + direct - flux / area
    };
    // Facets next to the pole, at 45° and at the equator (faces run pole fan, rings, fan per
    // longitude): centroid, inward facet normal.
    let points: Vec<(DVec3, DVec3)> = [0usize, 3 * n_lat + 4, 9 * n_lat + 8]
        .iter()
        .map(|&fi| {
            let c = corners(&faces[fi]);
            let centroid = c.iter().sum::<DVec3>() / c.len() as f64;
            let mut n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
            if n.dot(centroid) > 0.0 {
                n = -n;
            }
            (centroid, n)
        })
        .collect();
    let exact: Vec<f64> = points.iter().map(|&(p, n)| exact_at(p, n)).collect();
    assert!(
        exact.iter().all(|e| (e / mean_e - 1.0).abs() < 0.005),
        "the reference is not uniform"
    );
    IntegratingSphere {
        text: s,
        scene,
        meters: points
            .iter()
            .map(|&(p, n)| Meter::illuminance(p.as_vec3(), n.as_vec3()).unwrap())
            .collect(),
        exact,
        mean_e,
        ideal,
    }
}
