//! Light meters against closed-form answers (all references computed here): point-like,
//! rectangle (Lambert's polygon formula), disk, sphere, dome and distant lights; flux
//! conservation in a closed black box; an integrating sphere; coverage of the 95% interval;
//! stage units; the CLI's JSON, grid outputs and errors.
//!
//! Accuracy: every analytic case must be within 0.5 %, and each reading is sampled until
//! ci95/value < 0.2 % (σ ≤ 0.1 %), so 0.5 % is at least 4.9 σ of the estimator. Measured
//! errors are printed (`cargo test --release --test meters -- --nocapture`).

mod common;
use common::*;
use glam::{DMat4, DVec3, Vec3};
use spectral_render::scene::{self, Scene};
use spectral_render::sensor::meter::{measure, Meter, MeterOptions, Reading, Stop};
use std::f64::consts::PI;

/// The accuracy bound for analytic cases.
const TOL: f64 = 0.005;
/// Sampling target of accuracy tests: ci95/value below this (σ ≤ TOL / 4.9).
const REL: f64 = 0.002;

fn load(name: &str, text: &str) -> Scene {
    let dir = temp_dir(name);
    let path = write(&dir, &format!("{name}.usda"), text);
    scene::load(&path, Some((1, 1))).unwrap_or_else(|e| panic!("{e}"))
}

fn read(scene: &Scene, meters: &[Meter], stop: Stop, seed: u64, max_depth: u32) -> Vec<Reading> {
    let opts = MeterOptions {
        stop,
        seed,
        max_depth,
        max_samples: 1 << 23,
        ..Default::default()
    };
    let run = measure(scene, meters, &opts).unwrap();
    assert_eq!(run.dropped, 0, "non-finite samples");
    run.readings
}

fn v3(v: DVec3) -> Vec3 {
    v.as_vec3()
}

/// Checks a reading against its exact value: within 0.5 %, and sampled finely enough that
/// 0.5 % is at least 4 σ. Returns the relative error.
fn assert_exact(label: &str, r: &Reading, exact: f64) -> f64 {
    let rel = r.value / exact - 1.0;
    let sigma = r.ci95 / 1.96 / exact;
    eprintln!(
        "{label}: {:.6} vs {exact:.6} ({:+.4} %, σ {:.4} %, {} samples)",
        r.value,
        100.0 * rel,
        100.0 * sigma,
        r.samples
    );
    assert!(r.capped.is_none(), "{label}: stopped by a cap");
    assert!(
        4.0 * sigma <= TOL,
        "{label}: too noisy to judge (σ = {sigma})"
    );
    assert!(rel.abs() < TOL, "{label}: {} vs exact {exact}", r.value);
    rel
}

// ---------------------------------------------------------------------------------------
// Stage text
// ---------------------------------------------------------------------------------------

/// `xformOp`s in order (outermost first): ("translate", "(x, y, z)") or ("rotateX", "deg").
fn xform(ops: &[(&str, String)]) -> String {
    let mut s = String::new();
    let mut order = Vec::new();
    for (op, value) in ops {
        let ty = if *op == "translate" {
            "double3"
        } else {
            "float"
        };
        s += &format!("    {ty} xformOp:{op} = {value}\n");
        order.push(format!("\"xformOp:{op}\""));
    }
    s + &format!(
        "    uniform token[] xformOpOrder = [{}]\n",
        order.join(", ")
    )
}

fn prim(ty: &str, name: &str, body: &str) -> String {
    format!("def {ty} \"{name}\"\n{{\n{body}}}\n\n")
}

/// A Lambertian material of flat reflectance `rho` under /Looks.
fn looks(name: &str, rho: f64) -> String {
    let inputs =
        format!("        float2[] inputs:reflectance:samples = [(360, {rho}), (830, {rho})]\n");
    format!(
        "def Scope \"Looks\"\n{{\n{}}}\n\n",
        material(name, "spectral:diffuse", &inputs)
    )
}

/// A polygon mesh with the given faces, bound to /Looks/`look`.
fn mesh(name: &str, points: &[DVec3], faces: &[Vec<usize>], look: &str) -> String {
    let pts: Vec<String> = points
        .iter()
        .map(|p| format!("({}, {}, {})", p.x, p.y, p.z))
        .collect();
    let counts: Vec<String> = faces.iter().map(|f| f.len().to_string()).collect();
    let idx: Vec<String> = faces.iter().flatten().map(|i| i.to_string()).collect();
    format!(
        "def Mesh \"{name}\" (\n    prepend apiSchemas = [\"MaterialBindingAPI\"]\n)\n{{\n    int[] faceVertexCounts = [{}]\n    int[] faceVertexIndices = [{}]\n    point3f[] points = [{}]\n{}}}\n\n",
        counts.join(", "),
        idx.join(", "),
        pts.join(", "),
        binding(look)
    )
}

fn quad(name: &str, corners: [DVec3; 4], look: &str) -> String {
    mesh(name, &corners, &[vec![0, 1, 2, 3]], look)
}

// ---------------------------------------------------------------------------------------
// Integrating sphere
// ---------------------------------------------------------------------------------------

/// A UV sphere of radius `r` (`n_lon` × `n_lat` facets, pole fans): points and faces.
fn uv_sphere(r: f64, n_lon: usize, n_lat: usize) -> (Vec<DVec3>, Vec<Vec<usize>>) {
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

fn polygon_area(p: &[DVec3]) -> f64 {
    (1..p.len() - 1)
        .map(|i| 0.5 * (p[i] - p[0]).cross(p[i + 1] - p[0]).length())
        .sum()
}

/// Sampling target of the integrating sphere: its estimator's per-sample σ is ~0.9 (Russian
/// roulette over ~10 bounces), so it is held at 0.5 % ≥ 4.08 σ rather than 4.9 σ.
const REL_SPHERE: f64 = 0.0024;

#[test]
fn integrating_sphere_is_uniform_at_phi_over_a_one_minus_rho() {
    let (rho, flux, lamp) = (0.9, 1000.0, 0.02);
    let (n_lon, n_lat) = (32, 16);
    let (pts, faces) = uv_sphere(1.0, n_lon, n_lat);
    let mut s = header() + &looks("Wall", rho);
    s += &mesh("Sphere", &pts, &faces, "Wall");
    let inputs =
        format!("    float inputs:radius = {lamp}\n    float spectral:luminousFlux = {flux}\n");
    s += &prim("SphereLight", "Lamp", &inputs);
    let scene = load("sphere", &s);
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
    let meters: Vec<Meter> = points
        .iter()
        .map(|&(p, n)| Meter::illuminance(v3(p), v3(n)).unwrap())
        .collect();
    let readings = read(&scene, &meters, Stop::RelError(REL_SPHERE), 1, 1000);
    for (i, (r, &(p, n))) in readings.iter().zip(&points).enumerate() {
        let exact = exact_at(p, n);
        assert!(
            (exact / mean_e - 1.0).abs() < 0.005,
            "the reference is not uniform"
        );
        let rel = r.value / exact - 1.0;
        let sigma = r.ci95 / 1.96 / exact;
        eprintln!("integrating sphere, facet {i}: {:.4} vs {exact:.4} ({:+.4} %, σ {:.4} %, {} samples); ideal sphere {ideal:.4}", r.value, 100.0 * rel, 100.0 * sigma, r.samples);
        assert!(
            r.capped.is_none() && 4.0 * sigma <= TOL,
            "facet {i}: too noisy"
        );
        assert!(rel.abs() < TOL, "facet {i}: {} vs exact {exact}", r.value);
    }
}

// ---------------------------------------------------------------------------------------
// Analytic lights
// ---------------------------------------------------------------------------------------

/// Lambert's polygon formula (Lambert 1760; e.g. Arvo 1995, "Applications of irradiance
/// tensors", eq. 3): the illuminance from a uniform polygon of luminance L at `p` on a
/// surface of normal `n` is E = (L/2) Σᵢ βᵢ n·(rᵢ × rᵢ₊₁)/|rᵢ × rᵢ₊₁|, rᵢ the unit vectors to
/// the vertices and βᵢ the angle between rᵢ and rᵢ₊₁. Valid when the whole polygon is in
/// front of the surface (checked). Returns E/L.
fn lambert(p: DVec3, n: DVec3, verts: &[DVec3]) -> f64 {
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

/// A RectLight of `w` × `h` (m) and `l` nits at `c`, turned to face down (rotateX −90) and
/// then yawed about Y; returns the stage text and its world corners (USD op semantics).
fn rect_light(w: f64, h: f64, l: f64, c: DVec3, yaw: f64) -> (String, Vec<DVec3>) {
    let body = format!("    float inputs:width = {w}\n    float inputs:height = {h}\n    float inputs:intensity = {l}\n")
        + &xform(&[
            ("translate", format!("({}, {}, {})", c.x, c.y, c.z)),
            ("rotateY", yaw.to_string()),
            ("rotateX", "-90".into()),
        ]);
    let m = DMat4::from_translation(c)
        * DMat4::from_rotation_y(yaw.to_radians())
        * DMat4::from_rotation_x(-90f64.to_radians());
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| m.transform_point3(DVec3::new(0.5 * w * x, 0.5 * h * y, 0.0)));
    (prim("RectLight", "Panel", &body), corners.to_vec())
}

#[test]
fn rect_light_matches_lamberts_polygon_formula_on_a_floor_and_a_wall() {
    let l = 2000.0;
    let (light, corners) = rect_light(1.2, 0.6, l, DVec3::new(0.3, 2.5, -0.2), 30.0);
    // Black floor (y = 0) and wall (x = −0.5, facing +x) that the meters lie on.
    let mut s = header() + &looks("Black", 0.0) + &light;
    let p = |x, y, z| DVec3::new(x, y, z);
    s += &quad(
        "Floor",
        [
            p(-0.5, 0.0, -12.0),
            p(-0.5, 0.0, 12.0),
            p(25.0, 0.0, 12.0),
            p(25.0, 0.0, -12.0),
        ],
        "Black",
    );
    s += &quad(
        "Wall",
        [
            p(-0.5, 0.0, -8.0),
            p(-0.5, 2.49, -8.0),
            p(-0.5, 2.49, 8.0),
            p(-0.5, 0.0, 8.0),
        ],
        "Black",
    );
    let scene = load("rect", &s);
    let floor = [
        p(0.3, 0.0, -0.2),
        p(1.5, 0.0, 0.5),
        p(-0.3, 0.0, 2.0),
        p(3.0, 0.0, -2.0),
        p(6.0, 0.0, 0.0),
        p(10.0, 0.0, 0.5),
        p(20.0, 0.0, 0.0),
    ];
    // The last two wall points see the panel within ~7° of the wall's plane, the fourth
    // 5 cm below the panel's plane.
    let wall = [
        p(-0.5, 0.0, 0.0),
        p(-0.5, 1.2, -0.2),
        p(-0.5, 2.0, 1.0),
        p(-0.5, 2.45, 0.0),
        p(-0.5, 0.5, 6.0),
        p(-0.5, 2.3, -4.0),
    ];
    let points: Vec<(DVec3, DVec3)> = floor
        .iter()
        .map(|&q| (q, DVec3::Y))
        .chain(wall.iter().map(|&q| (q, DVec3::X)))
        .collect();
    let meters: Vec<Meter> = points
        .iter()
        .map(|&(q, n)| Meter::illuminance(v3(q), v3(n)).unwrap())
        .collect();
    let readings = read(&scene, &meters, Stop::RelError(REL), 2, 7);
    for (&(q, n), r) in points.iter().zip(&readings) {
        let exact = l * lambert(q, n, &corners);
        assert_exact(&format!("rect at {q} n {n}"), r, exact);
    }
}

#[test]
fn disk_light_on_axis() {
    let (l, radius, height) = (1500.0, 0.4, 3.0f64);
    let body = format!("    float inputs:radius = {radius}\n    float inputs:intensity = {l}\n")
        + &xform(&[
            ("translate", format!("(0, {height}, 0)")),
            ("rotateX", "-90".into()),
        ]);
    let scene = load("disk", &(header() + &prim("DiskLight", "Disk", &body)));
    let ys = [0.0f64, 2.0, 2.9];
    let meters: Vec<Meter> = ys
        .iter()
        .map(|&y| Meter::illuminance(Vec3::new(0.0, y as f32, 0.0), Vec3::Y).unwrap())
        .collect();
    for (&y, r) in ys
        .iter()
        .zip(&read(&scene, &meters, Stop::RelError(REL), 3, 7))
    {
        let h: f64 = height - y;
        // E = π L R² / (h² + R²): the disk's form factor on its axis.
        let exact = PI * l * radius * radius / (h * h + radius * radius);
        assert_exact(&format!("disk on axis, h = {h}"), r, exact);
    }
}

#[test]
fn sphere_light_gives_pi_l_r_over_d_squared() {
    let (l, radius) = (800.0, 0.25);
    let c = DVec3::new(0.0, 2.0, 0.0);
    let body = format!("    float inputs:radius = {radius}\n    float inputs:intensity = {l}\n")
        + &xform(&[("translate", "(0, 2, 0)".into())]);
    let scene = load(
        "sphere-light",
        &(header() + &prim("SphereLight", "Ball", &body)),
    );
    // (distance, direction from the centre to the meter, tilt of the receiver in degrees).
    let cases = [
        (0.5, DVec3::new(0.0, -1.0, 0.0), 0.0),
        (1.0, DVec3::new(1.0, -1.0, 0.5), 0.0),
        (3.0, DVec3::new(0.0, 0.0, 1.0), 0.0),
        (3.0, DVec3::new(-1.0, 0.0, 0.0), 45.0),
    ];
    let points: Vec<(DVec3, DVec3)> = cases
        .iter()
        .map(|&(d, dir, tilt)| {
            let dir = dir.normalize();
            let n = DMat4::from_axis_angle(dir.any_orthonormal_vector(), f64::to_radians(tilt))
                .transform_vector3(-dir);
            (c + d * dir, n)
        })
        .collect();
    let meters: Vec<Meter> = points
        .iter()
        .map(|&(q, n)| Meter::illuminance(v3(q), v3(n)).unwrap())
        .collect();
    let readings = read(&scene, &meters, Stop::RelError(REL), 4, 7);
    for ((&(d, _, tilt), &(_, n)), r) in cases.iter().zip(&points).zip(&readings) {
        // E = π L sin²α cos θ with sin α = r/d (the cap is entirely above the horizon).
        let cos = f64::to_radians(tilt).cos();
        assert!((n.length() - 1.0).abs() < 1e-12);
        let exact = PI * l * (radius / d).powi(2) * cos;
        assert_exact(&format!("sphere light, d = {d}, tilt {tilt}°"), r, exact);
    }
}

#[test]
fn point_like_source_follows_the_inverse_square_cosine_law() {
    // A 2 cm normalized SphereLight: L = intensity / (4π r²), so its luminous intensity is
    // I = L · π r² = intensity / 4 in every direction, and E = I cos θ / d² exactly for a
    // sphere whose cap is above the receiver's horizon.
    let (intensity, radius) = (5000.0, 0.02);
    let i_cd = intensity / 4.0;
    let body = format!("    float inputs:radius = {radius}\n    float inputs:intensity = {intensity}\n    bool inputs:normalize = 1\n")
        + &xform(&[("translate", "(0, 3, 0)".into())]);
    let scene = load("point", &(header() + &prim("SphereLight", "Bulb", &body)));
    let c = DVec3::new(0.0, 3.0, 0.0);
    let mut points = Vec::new();
    for d in [1.0, 2.0] {
        for theta in [0.0f64, 30.0, 60.0, 80.0] {
            let n = DVec3::new(theta.to_radians().sin(), theta.to_radians().cos(), 0.0);
            points.push((c - d * DVec3::Y, n, d, theta));
        }
    }
    let meters: Vec<Meter> = points
        .iter()
        .map(|&(q, n, _, _)| Meter::illuminance(v3(q), v3(n)).unwrap())
        .collect();
    for (&(_, _, d, theta), r) in
        points
            .iter()
            .zip(&read(&scene, &meters, Stop::RelError(REL), 5, 7))
    {
        let exact = i_cd * theta.to_radians().cos() / (d * d);
        assert_exact(&format!("point-like, d = {d}, θ = {theta}°"), r, exact);
    }
}

#[test]
fn uniform_dome_gives_pi_l() {
    let l = 300.0;
    let mut s = header() + &looks("Black", 0.0);
    s += &prim(
        "DomeLight",
        "Sky",
        &format!("    float inputs:intensity = {l}\n"),
    );
    let p = |x, y, z| DVec3::new(x, y, z);
    s += &quad(
        "Floor",
        [
            p(-1e3, 0.0, -1e3),
            p(-1e3, 0.0, 1e3),
            p(1e3, 0.0, 1e3),
            p(1e3, 0.0, -1e3),
        ],
        "Black",
    );
    let scene = load("dome", &s);
    // Upward meters see the whole sky: E = πL. A tilted one (angle β to the vertical) also
    // sees the black floor: E = πL (1 + cos β)/2, the sky view factor; a vertical one just
    // above the floor has half its hemisphere below the floor: E = πL/2. (The floor is
    // finite: the sky sliver under its edge, below atan(h / 1 km), adds < 0.003 % here.)
    // The third meter lies on the floor, facing away from it.
    let cos_b = 1.0 / 3f64.sqrt();
    let cases = [
        (p(0.0, 1.0, 0.0), p(0.0, 1.0, 0.0), 1.0),
        (p(2.0, 0.05, 0.0), p(1.0, 1.0, 1.0), 0.5 * (1.0 + cos_b)),
        (p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), 1.0),
        (p(3.0, 0.01, -1.0), p(1.0, 0.0, 0.0), 0.5),
    ];
    let meters: Vec<Meter> = cases
        .iter()
        .map(|&(q, n, _)| Meter::illuminance(v3(q), v3(n)).unwrap())
        .collect();
    for (&(q, n, frac), r) in cases
        .iter()
        .zip(&read(&scene, &meters, Stop::RelError(REL), 6, 7))
    {
        assert_exact(&format!("dome at {q} n {n}"), r, frac * PI * l);
    }
}

#[test]
fn normalized_distant_light_gives_intensity_times_cosine() {
    let e = 2000.0;
    // angle 0 is a delta light; 0.53° (the default) and 5° cones are fully above the horizon
    // for θ ≤ 85°.
    for angle in [0.0, 0.53, 5.0] {
        let body = format!("    float inputs:intensity = {e}\n    bool inputs:normalize = 1\n    float inputs:angle = {angle}\n")
            + &xform(&[("rotateX", "-60".into())]);
        let scene = load("distant", &(header() + &prim("DistantLight", "Sun", &body)));
        // The light comes from local +Z rotated by −60° about X: (0, sin 60°, cos 60°).
        let to_light = DVec3::new(0.0, 60f64.to_radians().sin(), 60f64.to_radians().cos());
        let thetas = [0.0f64, 30.0, 60.0, 85.0];
        let meters: Vec<Meter> = thetas
            .iter()
            .map(|t| {
                let n = DMat4::from_rotation_x(t.to_radians()).transform_vector3(to_light);
                Meter::illuminance(Vec3::new(0.0, 1.0, 0.0), v3(n)).unwrap()
            })
            .collect();
        for (t, r) in thetas
            .iter()
            .zip(&read(&scene, &meters, Stop::RelError(REL), 7, 7))
        {
            assert_exact(
                &format!("distant (angle {angle}°), θ = {t}°"),
                r,
                e * t.to_radians().cos(),
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// Flux conservation
// ---------------------------------------------------------------------------------------

#[test]
fn flux_through_the_walls_of_a_closed_black_box_is_the_sources_flux() {
    let flux = 10_000.0;
    let n = 16;
    // The cube [−1, 1]³ with black walls; an isotropic 10 000 lm lamp off centre.
    let p = |x, y, z| DVec3::new(x, y, z);
    let mut s = header() + &looks("Black", 0.0);
    // Each wall: corner, the two edge vectors, inward normal.
    let walls = [
        (
            p(-1.0, -1.0, -1.0),
            p(2.0, 0.0, 0.0),
            p(0.0, 2.0, 0.0),
            p(0.0, 0.0, 1.0),
        ),
        (
            p(-1.0, -1.0, 1.0),
            p(2.0, 0.0, 0.0),
            p(0.0, 2.0, 0.0),
            p(0.0, 0.0, -1.0),
        ),
        (
            p(-1.0, -1.0, -1.0),
            p(0.0, 2.0, 0.0),
            p(0.0, 0.0, 2.0),
            p(1.0, 0.0, 0.0),
        ),
        (
            p(1.0, -1.0, -1.0),
            p(0.0, 2.0, 0.0),
            p(0.0, 0.0, 2.0),
            p(-1.0, 0.0, 0.0),
        ),
        (
            p(-1.0, -1.0, -1.0),
            p(2.0, 0.0, 0.0),
            p(0.0, 0.0, 2.0),
            p(0.0, 1.0, 0.0),
        ),
        (
            p(-1.0, 1.0, -1.0),
            p(2.0, 0.0, 0.0),
            p(0.0, 0.0, 2.0),
            p(0.0, -1.0, 0.0),
        ),
    ];
    for (k, &(o, u, v, _)) in walls.iter().enumerate() {
        s += &quad(&format!("Wall{k}"), [o, o + u, o + u + v, o + v], "Black");
    }
    let body =
        format!("    float inputs:radius = 0.05\n    float spectral:luminousFlux = {flux}\n")
            + &xform(&[("translate", "(0.2, -0.1, 0.3)".into())]);
    s += &prim("SphereLight", "Lamp", &body);
    let scene = load("box", &s);
    let mut meters = Vec::new();
    for &(o, u, v, normal) in &walls {
        for j in 0..n {
            for i in 0..n {
                let c = o + (i as f64 + 0.5) / n as f64 * u + (j as f64 + 0.5) / n as f64 * v;
                meters.push(Meter::illuminance(v3(c), v3(normal)).unwrap());
            }
        }
    }
    let cell_area = 4.0 / (n * n) as f64;
    let readings = read(&scene, &meters, Stop::Samples(128), 8, 7);
    // Σ E·A (midpoint rule over the cells) and its 95 % interval from the readings'.
    let total: f64 = readings.iter().map(|r| r.value * cell_area).sum();
    let ci = readings
        .iter()
        .map(|r| (r.ci95 * cell_area).powi(2))
        .sum::<f64>()
        .sqrt();
    let rel = total / flux - 1.0;
    eprintln!(
        "flux through the box: {total:.2} lm vs {flux} lm ({:+.4} %, ci95 {:.4} %)",
        100.0 * rel,
        100.0 * ci / flux
    );
    assert!(ci / flux < 0.002, "too noisy to judge");
    assert!(rel.abs() < 0.01, "Σ E·A = {total} lm, Φ = {flux} lm");
}

// ---------------------------------------------------------------------------------------
// Honest intervals
// ---------------------------------------------------------------------------------------

/// A meter 5 cm below the plane of a panel, on a wall beside it: the area-sampling part of
/// the estimator is heavy-tailed there (its weights grow as 1/d² near the panel's edge).
fn heavy_tailed_case() -> (Scene, Meter, f64) {
    let l = 2000.0;
    let (light, corners) = rect_light(1.2, 0.6, l, DVec3::new(0.3, 2.5, -0.2), 30.0);
    let scene = load("coverage", &(header() + &light));
    let (q, n) = (DVec3::new(-0.5, 2.45, 0.0), DVec3::X);
    (
        scene,
        Meter::illuminance(v3(q), v3(n)).unwrap(),
        l * lambert(q, n, &corners),
    )
}

/// How many of 100 seeded readings' 95 % intervals contain `exact`.
fn coverage(scene: &Scene, meter: Meter, exact: f64, stop: Stop) -> usize {
    (0..100u64)
        .filter(|&seed| {
            let r = read(scene, &[meter], stop, 1000 + seed, 7)[0];
            (r.value - exact).abs() <= r.ci95
        })
        .count()
}

#[test]
fn ci95_covers_the_exact_value_at_least_90_times_in_100() {
    let (scene, meter, exact) = heavy_tailed_case();
    let fixed = coverage(&scene, meter, exact, Stop::Samples(4096));
    let adaptive = coverage(&scene, meter, exact, Stop::RelError(0.02));
    eprintln!("ci95 coverage in 100 seeded repeats: {fixed} (4096 samples), {adaptive} (--rel-error 0.02)");
    assert!(fixed >= 90, "fixed sample count: {fixed}/100");
    assert!(adaptive >= 90, "relative-error stopping: {adaptive}/100");
}

#[test]
fn readings_do_not_depend_on_the_number_of_threads() {
    let (scene, meter, _) = heavy_tailed_case();
    let other = Meter::illuminance(Vec3::new(1.0, 0.0, 0.5), Vec3::Y).unwrap();
    let run = |threads| {
        let opts = MeterOptions {
            stop: Stop::RelError(0.01),
            seed: 11,
            threads: Some(threads),
            ..Default::default()
        };
        measure(&scene, &[meter, other], &opts).unwrap().readings
    };
    let bits = |rs: Vec<Reading>| {
        rs.iter()
            .map(|r| (r.value.to_bits(), r.ci95.to_bits(), r.samples))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(run(1)), bits(run(2)));
}

// ---------------------------------------------------------------------------------------
// The command line
// ---------------------------------------------------------------------------------------

fn cli(args: &[&str], cwd: &std::path::Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_spectral-render"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run spectral-render")
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The raw JSON text of `"key":` in `entry` (a number, string, bool or flat array).
fn field<'a>(entry: &'a str, key: &str) -> &'a str {
    let pat = format!("\"{key}\":");
    let start = entry
        .find(&pat)
        .unwrap_or_else(|| panic!("no {key} in {entry}"))
        + pat.len();
    let rest = entry[start..].trim_start();
    let end = if rest.starts_with('[') {
        rest.find(']').unwrap() + 1
    } else {
        rest.find([',', '}']).unwrap()
    };
    rest[..end].trim()
}

fn number(entry: &str, key: &str) -> f64 {
    field(entry, key)
        .parse()
        .unwrap_or_else(|_| panic!("{key} is not a number in {entry}"))
}

fn numbers(entry: &str, key: &str) -> Vec<f64> {
    let a = field(entry, key);
    a[1..a.len() - 1]
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect()
}

/// A Z-up stage in centimetres: a normalized 100 × 50 cm RectLight of 1000 "nits" (so
/// L = 1000 / 0.5 m² = 2000 cd/m² in world units) 250 cm up, facing down (its local −Z).
fn cm_stage() -> String {
    "#usda 1.0\n(\n    metersPerUnit = 0.01\n    upAxis = \"Z\"\n)\n\n".to_string()
        + &prim(
            "RectLight",
            "Panel",
            &(String::from("    float inputs:width = 100\n    float inputs:height = 50\n    float inputs:intensity = 1000\n    bool inputs:normalize = 1\n")
                + &xform(&[("translate", "(0, 0, 250)".into())])),
        )
}

/// Lambert's formula is scale-free, so the reference is computed in stage coordinates.
fn cm_stage_exact(at: DVec3, n: DVec3) -> f64 {
    let c = [(-50.0, -25.0), (50.0, -25.0), (50.0, 25.0), (-50.0, 25.0)]
        .map(|(x, y)| DVec3::new(x, y, 250.0));
    2000.0 * lambert(at, n, &c)
}

#[test]
fn cli_json_readings_in_stage_units() {
    let dir = temp_dir("cli-meter");
    write(&dir, "room.usda", &cm_stage());
    let o = cli(
        &[
            "meter",
            "room.usda",
            "--at",
            "30,-40,0",
            "--normal",
            "0,0,1",
            "--at",
            "-20,10,120",
            "--normal",
            "0,-1,1",
            "--rel-error",
            "0.002",
            "--seed",
            "3",
            "--json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("loaded"), "no load summary");
    let out = stdout(&o);
    assert!(
        out.trim_start().starts_with("{\"meters\":[") && out.trim_end().ends_with("]}"),
        "{out}"
    );
    let entries: Vec<&str> = out.split("{\"kind\"").skip(1).collect();
    assert_eq!(entries.len(), 2, "{out}");
    for (entry, (at, n)) in entries.iter().zip([
        (DVec3::new(30.0, -40.0, 0.0), DVec3::new(0.0, 0.0, 1.0)),
        (DVec3::new(-20.0, 10.0, 120.0), DVec3::new(0.0, -1.0, 1.0)),
    ]) {
        assert!(entry.starts_with(":\"illuminance\","), "{entry}");
        let keys = [
            "\"at\"",
            "\"normal\"",
            "\"value\"",
            "\"unit\"",
            "\"ci95\"",
            "\"samples\"",
        ];
        let pos: Vec<usize> = keys.iter().map(|k| entry.find(k).unwrap()).collect();
        assert!(pos.windows(2).all(|w| w[0] < w[1]), "key order in {entry}");
        assert_eq!(numbers(entry, "at"), [at.x, at.y, at.z]);
        assert_eq!(numbers(entry, "normal"), [n.x, n.y, n.z]);
        assert_eq!(field(entry, "unit"), "\"lx\"");
        assert_eq!(field(entry, "converged"), "true");
        let (value, ci95) = (number(entry, "value"), number(entry, "ci95"));
        assert!(number(entry, "samples") >= 1024.0 && ci95 > 0.0 && ci95 / value < 0.002);
        let exact = cm_stage_exact(at, n.normalize());
        eprintln!("CLI, Z-up cm stage at {at}: {value} vs {exact} (ci95 {ci95})");
        assert!((value / exact - 1.0).abs() < TOL, "{value} vs {exact}");
    }
    // A luminance meter looking up at the panel reads its luminance; one looking down, 0.
    let o = cli(
        &[
            "meter",
            "room.usda",
            "--luminance",
            "--at",
            "0,0,100",
            "--dir",
            "0,0,1",
            "--at",
            "0,0,100",
            "--dir",
            "0,0,-1",
            "--spp",
            "4096",
            "--json",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let entries: Vec<&str> = out.split("{\"kind\"").skip(1).collect();
    assert_eq!(entries.len(), 2, "{out}");
    for e in &entries {
        assert!(e.starts_with(":\"luminance\","), "{e}");
        assert_eq!(field(e, "unit"), "\"cd/m2\"");
        assert_eq!(number(e, "samples"), 4096.0);
    }
    assert_eq!(numbers(entries[0], "dir"), [0.0, 0.0, 1.0]);
    let (l, ci) = (number(entries[0], "value"), number(entries[0], "ci95"));
    assert!(
        (l - 2000.0).abs() < 4.0 * ci / 1.96 + 1e-9 && ci / l < 0.002,
        "{l} ± {ci}"
    );
    assert_eq!(
        (number(entries[1], "value"), number(entries[1], "ci95")),
        (0.0, 0.0)
    );
}

#[test]
fn cli_grid_writes_csv_json_and_png_with_a_consistent_summary() {
    let dir = temp_dir("cli-grid");
    write(&dir, "room.usda", &cm_stage());
    std::fs::create_dir_all(dir.join("out")).unwrap();
    let o = cli(
        &[
            "meter",
            "room.usda",
            "--grid",
            "-150,-100,0",
            "--u",
            "300,0,0",
            "--v",
            "0,200,0",
            "--n",
            "12,8",
            "--normal",
            "0,0,1",
            "-o",
            "out/floor",
            "--spp",
            "256",
        ],
        &dir,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let console = stdout(&o);
    for k in ["E_min", "E_avg", "E_max", "U0"] {
        assert!(console.contains(k), "{k} missing from {console}");
    }
    let csv = std::fs::read_to_string(dir.join("out/floor.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("i,j,x,y,z,lux,ci95"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 96);
    assert_eq!(rows[0][..5], [0.0, 0.0, -137.5, -87.5, 0.0]);
    assert_eq!(rows[95][..5], [11.0, 7.0, 137.5, 87.5, 0.0]);
    let lux: Vec<f64> = rows.iter().map(|r| r[5]).collect();
    let (min, max) = lux
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let avg = lux.iter().sum::<f64>() / lux.len() as f64;
    // Every cell is near its exact value (here a loose 5σ check of the whole map).
    for r in &rows {
        let exact = cm_stage_exact(DVec3::new(r[2], r[3], r[4]), DVec3::Z);
        assert!(
            (r[5] - exact).abs() < 5.0 * r[6] / 1.96,
            "cell {r:?} vs {exact}"
        );
    }
    let json = std::fs::read_to_string(dir.join("out/floor.json")).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
    assert!(close(number(&json, "E_min"), min) && close(number(&json, "E_max"), max));
    assert!(close(number(&json, "E_avg"), avg) && close(number(&json, "U0"), min / avg));
    assert!(json.contains("\"summary\": {\"E_min\""));
    assert_eq!(json.matches("\"ci95\"").count(), 96);
    let png = std::fs::read(dir.join("out/floor.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let leftovers: Vec<_> = std::fs::read_dir(dir.join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 3, "{leftovers:?}");
}

#[test]
fn cli_errors_are_one_line_with_exit_code_1() {
    let dir = temp_dir("cli-meter-errors");
    write(&dir, "room.usda", &cm_stage());
    write(
        &dir,
        "broken.usda",
        "#usda 1.0\ndef Xform \"A\"\n{\n    float x = (1, \n",
    );
    let cases: &[(&[&str], &str)] = &[
        (
            &[
                "room.usda",
                "--at",
                "1,2,3",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
            ],
            "--normal",
        ),
        (
            &["room.usda", "--at", "1,2,3", "--normal", "0,0,0"],
            "zero length",
        ),
        (&["room.usda", "--at", "1,2", "--normal", "0,0,1"], "--at"),
        (
            &["room.usda", "--at", "nan,0,0", "--normal", "0,0,1"],
            "--at",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--spp",
                "8",
                "--rel-error",
                "0.01",
            ],
            "--rel-error",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--rel-error",
                "-1",
            ],
            "--rel-error",
        ),
        (
            &[
                "room.usda",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
                "--spp",
                "1",
            ],
            "--spp",
        ),
        (&["room.usda"], "nothing to measure"),
        (
            &[
                "room.usda",
                "--luminance",
                "--at",
                "0,0,0",
                "--normal",
                "0,0,1",
            ],
            "--dir",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--v",
                "2,0,0",
                "--n",
                "4,4",
                "--normal",
                "0,0,1",
            ],
            "--v",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--v",
                "0,1,0",
                "--n",
                "0,4",
                "--normal",
                "0,0,1",
            ],
            "--n",
        ),
        (
            &[
                "room.usda",
                "--grid",
                "0,0,0",
                "--u",
                "1,0,0",
                "--n",
                "4,4",
                "--normal",
                "0,0,1",
            ],
            "--v",
        ),
        (
            &["missing.usda", "--at", "0,0,0", "--normal", "0,0,1"],
            "missing.usda",
        ),
        (
            &["broken.usda", "--at", "0,0,0", "--normal", "0,0,1"],
            "broken.usda",
        ),
    ];
    for (args, must) in cases {
        let mut all = vec!["meter"];
        all.extend_from_slice(args);
        let o = cli(&all, &dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("loaded ")).collect();
        assert_eq!(lines.len(), 1, "{args:?}: {err}");
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(must),
            "{args:?}: {err}"
        );
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
}

#[test]
fn cli_reports_readings_stopped_by_a_cap() {
    let dir = temp_dir("cli-caps");
    write(&dir, "room.usda", &cm_stage());
    let base = [
        "meter",
        "room.usda",
        "--at",
        "30,-40,0",
        "--normal",
        "0,0,1",
        "--json",
        "--rel-error",
        "1e-7",
    ];
    for (extra, warning) in [
        (["--max-spp", "2048"], "sample cap"),
        (["--time", "0.3"], "time cap"),
    ] {
        let t = std::time::Instant::now();
        let o = cli(&[&base[..], &extra[..]].concat(), &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            t.elapsed().as_secs_f64() < 20.0,
            "the cap did not stop sampling"
        );
        assert!(stderr(&o).contains(warning), "{}", stderr(&o));
        let out = stdout(&o);
        assert_eq!(field(&out, "converged"), "false", "{out}");
        if warning == "sample cap" {
            assert_eq!(number(&out, "samples"), 2048.0);
        }
    }
}
