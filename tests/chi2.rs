//! χ² goodness-of-fit tests of every sampling routine (docs/design.md §7, issue 3), all through the
//! one harness `spectral_render::sampling::chi2`: BSDF samplers, light sampling, wavelength
//! sampling, the warps and the piecewise-constant distributions.
//!
//! Every case is one member of a family of m = [`family_size`] tests and is run with 10⁶
//! samples at α = 0.01 Šidák-corrected for m, so the whole file rejects correct samplers with
//! probability 1 %. Seeds derive from the case names, so runs are deterministic. Cases of one
//! group run in parallel; a group reports all its rejected cases at once. `--nocapture` prints
//! one summary line (χ², dof, p) per case.
//!
//! Adding a BxDF model is one line in [`MODELS`]: it is then tested for every roughness in its
//! list and every incident direction in [`INCIDENT`] (including grazing, θ = 89°, and one
//! below the surface).

use glam::{EulerRot, Mat3, Mat4, Quat, Vec2, Vec3};
use rayon::prelude::*;
use spectral_render::bxdf::{
    Bxdf, ConductorBxdf, DielectricBxdf, DiffuseBxdf, OrenNayarBxdf, PlasticBxdf, TransportMode,
    TrowbridgeReitz,
};
use spectral_render::geometry::{triangle, Ray};
use spectral_render::light::dome::LatLong;
use spectral_render::light::ellipsoid::Ellipsoid;
use spectral_render::light::portal::Portal;
use spectral_render::light::{
    DiskLight, DistantLight, DomeLight, Light, LightHit, LightSampleContext, RectLight,
    SphereLight, TriangleLight,
};
use spectral_render::math::Frame;
use spectral_render::sampling::distribution::{Distribution1D, Distribution2D};
use spectral_render::sampling::warp;
use spectral_render::spectral::uplift::RgbIlluminantSpectrum;
use spectral_render::spectral::wavelengths::visible_wavelength_pdf;
use spectral_render::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use spectral_render::spectral::{LAMBDA_MAX, LAMBDA_MIN};
use spectral_render::testing::chi2::{
    Chi2Outcome, Chi2Test, IntervalDomain, PlanarDomain, SphericalDomain,
};
use std::f32::consts::PI;

// ---------------------------------------------------------------------------------------------
// Cases and the family
// ---------------------------------------------------------------------------------------------

type Run = Box<dyn Fn(&str, usize) -> Chi2Outcome + Send + Sync>;

/// One χ² test: its name and how to run it given the family size.
struct Case {
    name: String,
    run: Run,
}

impl Case {
    fn new(name: String, run: impl Fn(&str, usize) -> Chi2Outcome + Send + Sync + 'static) -> Case {
        Case {
            name,
            run: Box::new(run),
        }
    }
}

/// The number of χ² tests in this file (the m of the Šidák correction).
fn family_size() -> usize {
    bsdf_cases().len()
        + light_cases().len()
        + wavelength_cases().len()
        + warp_cases().len()
        + distribution_cases().len()
}

/// Runs a group's cases in parallel, prints a summary line each, and fails with the report of
/// every rejected case.
fn run_all(cases: Vec<Case>) {
    let m = family_size();
    let outcomes: Vec<Chi2Outcome> = cases.par_iter().map(|c| (c.run)(&c.name, m)).collect();
    for o in &outcomes {
        println!("{}", o.summary());
    }
    let rejected: Vec<&str> = outcomes
        .iter()
        .filter(|o| !o.passed)
        .map(|o| o.report.as_str())
        .collect();
    assert!(
        rejected.is_empty(),
        "{} of {} χ² cases rejected:\n{}",
        rejected.len(),
        outcomes.len(),
        rejected.join("\n")
    );
}

fn spherical_deg(theta: f32, phi: f32) -> Vec3 {
    let (t, p) = (theta.to_radians(), phi.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

// ---------------------------------------------------------------------------------------------
// BSDFs
// ---------------------------------------------------------------------------------------------

/// A reflection model under test: `make` builds it for one value of its roughness parameter.
struct Model {
    name: &'static str,
    roughness: &'static [f32],
    make: fn(f32) -> Bxdf,
}

/// Roughness values for models that have one (in the model's own parameterisation); unused
/// of the microfacet models.
const ROUGH: &[f32] = &[0.05, 0.2, 0.5, 1.0];
/// For models without a roughness parameter.
const NO_ROUGHNESS: &[f32] = &[0.0];

/// Every model of `spectral_render::bxdf::Bxdf`; adding a model is one line here, e.g.
/// `Model { name: "conductor", roughness: ROUGH, make: |a| Bxdf::Conductor(..) },`.
const MODELS: &[Model] = &[
    Model {
        name: "diffuse",
        roughness: NO_ROUGHNESS,
        make: |_| {
            Bxdf::Diffuse(DiffuseBxdf {
                r: SampledSpectrum::splat(0.5),
            })
        },
    },
    Model {
        name: "oren-nayar",
        roughness: &[0.3, 1.0],
        make: |sigma| Bxdf::OrenNayar(OrenNayarBxdf::new(SampledSpectrum::splat(0.5), sigma)),
    },
    Model {
        name: "conductor",
        roughness: ROUGH,
        make: |a| {
            Bxdf::Conductor(ConductorBxdf::new(
                TrowbridgeReitz::new(a, a),
                SampledSpectrum::splat(0.2),
                SampledSpectrum::splat(3.0),
            ))
        },
    },
    Model {
        name: "conductor-anisotropic",
        roughness: &[0.1],
        make: |a| {
            Bxdf::Conductor(ConductorBxdf::new(
                TrowbridgeReitz::new(a, 4.0 * a),
                SampledSpectrum::splat(0.2),
                SampledSpectrum::splat(3.0),
            ))
        },
    },
    Model {
        name: "dielectric",
        roughness: ROUGH,
        make: |a| Bxdf::Dielectric(DielectricBxdf::new(TrowbridgeReitz::new(a, a), 1.5)),
    },
    Model {
        name: "plastic",
        roughness: ROUGH,
        make: |a| Bxdf::Plastic(PlasticBxdf::new(SampledSpectrum::splat(0.5), 1.5, a)),
    },
    Model {
        name: "preview-surface-clearcoat",
        roughness: NO_ROUGHNESS,
        make: |_| example("preview-clearcoat"),
    },
    Model {
        name: "preview-surface-metal",
        roughness: NO_ROUGHNESS,
        make: |_| example("preview-metal"),
    },
];

/// A named instance from `bxdf::examples()` (the UsdPreviewSurface composites).
fn example(name: &str) -> Bxdf {
    spectral_render::testing::examples()
        .into_iter()
        .find(|e| e.name == name)
        .map(|e| e.bxdf)
        .unwrap_or_else(|| panic!("no example {name}"))
}

/// Incident directions (θ, φ) in degrees in the shading frame: normal, moderate, steep,
/// grazing (89°), and one from below the surface (the inside of a dielectric).
const INCIDENT: [(f32, f32); 6] = [
    (0.0, 0.0),
    (30.0, 20.0),
    (60.0, 135.0),
    (80.0, 250.0),
    (89.0, 45.0),
    (135.0, 300.0),
];

fn bsdf_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for model in MODELS {
        for &rough in model.roughness {
            for (theta, phi) in INCIDENT {
                cases.push(bsdf_case(model, rough, theta, phi));
            }
        }
    }
    cases
}

/// Directions from `Bxdf::sample_f` against `Bxdf::pdf` over the whole sphere. Samples flagged
/// `specular` (delta lobes) and samples with pdf 0 are failures: they go to the rest cell, and
/// the non-delta pdf must integrate to the probability of the other samples.
fn bsdf_case(model: &Model, rough: f32, theta: f32, phi: f32) -> Case {
    let bxdf = (model.make)(rough);
    let wo = spherical_deg(theta, phi);
    let mode = TransportMode::Radiance;
    let name = format!("bsdf {} r={rough} θo={theta}° φo={phi}°", model.name);
    Case::new(name, move |name, m| {
        Chi2Test::new(name, SphericalDomain::sphere())
            .test_count(m)
            .run(
                |s| {
                    let (uc, u) = (s.get_1d(), s.get_2d());
                    let bs = bxdf.sample_f(wo, uc, u, mode)?;
                    if bs.specular || bs.pdf_w == 0.0 {
                        return None;
                    }
                    Some((bs.wi, bs.pdf_w as f64))
                },
                |wi| bxdf.pdf(wo, wi, mode) as f64,
            )
    })
}

#[test]
fn chi2_bsdfs() {
    run_all(bsdf_cases());
}

// ---------------------------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------------------------

/// One light seen from one receiver (with unit normal `normal`, or zero for a point in space);
/// `domain` covers every direction the light can send.
struct LightCase {
    name: String,
    light: Light,
    receiver: Vec3,
    normal: Vec3,
    domain: SphericalDomain,
}

/// Directions within 15 % more than the angular radius of a bounding sphere (center, radius)
/// seen from `p`; the whole sphere when `p` is inside it.
fn cap_towards(p: Vec3, center: Vec3, radius: f32) -> SphericalDomain {
    let d = center - p;
    let dist = d.length();
    if dist <= radius * 1.01 {
        return SphericalDomain::around(if dist > 0.0 { d } else { Vec3::Z });
    }
    let theta = ((radius / dist) as f64).asin() * 1.15;
    SphericalDomain::cap(d, theta.min(std::f64::consts::PI))
}

/// Three receivers in front of a flat emitter (unit normal `n`, a tangent `t`, size `size`):
/// head-on near, 60° off the normal, and 85° off the normal (grazing).
fn receivers_in_front(center: Vec3, n: Vec3, t: Vec3, size: f32) -> [(String, Vec3); 3] {
    let at = |deg: f32, dist: f32| {
        let a = deg.to_radians();
        center + dist * size * (a.cos() * n + a.sin() * t)
    };
    [
        ("head-on".into(), at(0.0, 0.7)),
        ("60°".into(), at(60.0, 2.0)),
        ("grazing 85°".into(), at(85.0, 1.5)),
    ]
}

fn flat_light_cases(kind: &str, light: &Light, c: Vec3, n: Vec3, size: f32) -> Vec<LightCase> {
    let t = Frame::from_normal(n).s;
    receivers_in_front(c, n, t, size)
        .into_iter()
        .map(|(label, p)| LightCase {
            name: format!("light {kind}, receiver {label}"),
            light: light.clone(),
            receiver: p,
            normal: Vec3::ZERO,
            domain: cap_towards(p, c, 0.5 * size),
        })
        .collect()
}

/// The same receivers with a surface normal, which warps solid-angle sampling by cos θ
/// (`light::solid_angle`): facing the light, tilted 70° away from it, and facing away (|cos θ|
/// also weights transmission), plus one receiver so near that it sees nearly a hemisphere.
fn flat_light_cases_with_normals(
    kind: &str,
    light: &Light,
    c: Vec3,
    n: Vec3,
    size: f32,
) -> Vec<LightCase> {
    let t = Frame::from_normal(n).s;
    let tilt = (70f32.to_radians().cos() * -n + 70f32.to_radians().sin() * t).normalize();
    let near = c + 0.02 * size * n;
    let mut cases: Vec<LightCase> = receivers_in_front(c, n, t, size)
        .into_iter()
        .zip([-n, tilt, n])
        .map(|((label, p), normal)| LightCase {
            name: format!("light {kind}, receiver {label} with a normal"),
            light: light.clone(),
            receiver: p,
            normal,
            domain: cap_towards(p, c, 0.5 * size),
        })
        .collect();
    cases.push(LightCase {
        name: format!("light {kind}, receiver almost on it with a normal"),
        light: light.clone(),
        receiver: near,
        normal: -tilt,
        domain: SphericalDomain::around(-n),
    });
    cases
}

fn triangle_lights() -> Vec<LightCase> {
    let p = [
        Vec3::new(-0.5, 2.0, -0.3),
        Vec3::new(0.6, 2.2, -0.4),
        Vec3::new(0.1, 2.1, 0.7),
    ];
    let one = TriangleLight::new("/tri".into(), p, Spectrum::Constant(1.0), false);
    let two = TriangleLight::new("/tri2".into(), p, Spectrum::Constant(1.0), true);
    let c = (p[0] + p[1] + p[2]) / 3.0;
    let size = 2.0 * p.iter().map(|q| (*q - c).length()).fold(0.0, f32::max);
    let n = one.n;
    let mut cases = flat_light_cases("triangle", &Light::Triangle(one.clone()), c, n, size);
    cases.extend(flat_light_cases_with_normals(
        "triangle",
        &Light::Triangle(one),
        c,
        n,
        size,
    ));
    let behind = c - 0.8 * n + 0.3 * Frame::from_normal(n).t;
    cases.push(LightCase {
        name: "light triangle two-sided, receiver behind".into(),
        light: Light::Triangle(two.clone()),
        receiver: behind,
        normal: Vec3::ZERO,
        domain: cap_towards(behind, c, 0.5 * size),
    });
    cases.push(LightCase {
        name: "light triangle two-sided, receiver behind with a normal".into(),
        light: Light::Triangle(two),
        receiver: behind,
        normal: Vec3::new(0.3, 0.9, 0.1).normalize(),
        domain: cap_towards(behind, c, 0.5 * size),
    });
    // A sliver (50:1; thinner ones fall between the quadrature's points, and
    // `light::triangle`'s tests take them) seen from close by, with a normal.
    let sliver = [p[0], p[1], p[0] + 0.02 * (p[2] - p[0])];
    let thin = TriangleLight::new("/sliver".into(), sliver, Spectrum::Constant(1.0), true);
    let sc = (sliver[0] + sliver[1] + sliver[2]) / 3.0;
    let at = sc + 0.3 * thin.n + 0.1 * (p[2] - p[0]);
    cases.push(LightCase {
        name: "light triangle sliver, receiver near with a normal".into(),
        light: Light::Triangle(thin),
        receiver: at,
        normal: Vec3::new(0.2, 1.0, -0.4).normalize(),
        domain: cap_towards(at, sc, 0.7),
    });
    cases
}

fn rect_lights() -> Vec<LightCase> {
    let (corner, eu, ev) = (
        Vec3::new(-0.5, 1.0, -0.25),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.2, 0.5),
    );
    // Emitting along −(eu × ev), as scene::build orients a UsdLux RectLight.
    let n = -eu.cross(ev);
    let rect = RectLight::new("/rect".into(), corner, eu, ev, n, Spectrum::Constant(1.0));
    let c = corner + 0.5 * (eu + ev);
    let (n, size) = (rect.n, (eu + ev).length());
    let mut cases = flat_light_cases("rect", &Light::Rect(rect.clone()), c, n, size);
    cases.extend(flat_light_cases_with_normals(
        "rect",
        &Light::Rect(rect),
        c,
        n,
        size,
    ));
    // A sheared parallelogram is sampled by area whatever the receiver.
    let skew = RectLight::new(
        "/skew".into(),
        corner,
        eu,
        ev + 0.3 * eu,
        -eu.cross(ev),
        Spectrum::Constant(1.0),
    );
    let at = c + 0.4 * n;
    cases.push(LightCase {
        name: "light parallelogram, receiver near with a normal".into(),
        light: Light::Rect(skew),
        receiver: at,
        normal: -n,
        domain: cap_towards(at, c, 0.5 * size),
    });
    cases
}

fn disk_lights() -> Vec<LightCase> {
    let disk = DiskLight::round(
        "/disk".into(),
        Vec3::new(0.3, 2.0, 0.1),
        Frame::from_normal(Vec3::new(0.2, -1.0, 0.3).normalize()),
        0.4,
        Spectrum::Constant(1.0),
    );
    let (c, n) = (disk.center, disk.frame.n);
    let mut cases = flat_light_cases("disk", &Light::Disk(disk.clone()), c, n, 0.8);
    // The ellipse a shear and a non-uniform scale make of it: semi-axes 0.6 s and
    // 0.15 (s + t), normal still n.
    let (s, t) = (disk.frame.s, disk.frame.t);
    let ellipse = DiskLight {
        axes: [0.6 * s, 0.15 * (s + t)],
        radius: 0.6,
        ..disk
    };
    cases.extend(flat_light_cases(
        "ellipse",
        &Light::Disk(ellipse),
        c,
        n,
        1.2,
    ));
    cases
}

fn sphere_lights() -> Vec<LightCase> {
    let sphere = SphereLight {
        prim_path: "/sphere".into(),
        center: Vec3::new(0.0, 1.0, 0.0),
        radius: 0.5,
        radiance: Spectrum::Constant(1.0),
        shaping: None,
        ellipsoid: None,
    };
    let c = sphere.center;
    let dir = Vec3::new(0.3, -0.8, 0.5).normalize();
    let receivers = [
        ("outside, d = 1.5 r", c + 0.75 * dir),
        ("outside, d = 6 r", c + 3.0 * dir),
        ("outside, d = 100 r", c + 50.0 * dir),
        ("inside, near the centre", c + Vec3::new(0.05, -0.1, 0.08)),
        ("inside, near the surface", c + 0.45 * dir),
    ];
    receivers
        .into_iter()
        .map(|(label, p)| LightCase {
            name: format!("light sphere, receiver {label}"),
            light: Light::Sphere(sphere.clone()),
            receiver: p,
            normal: Vec3::ZERO,
            domain: cap_towards(p, c, sphere.radius),
        })
        .collect()
}

/// A sphere light under a rotation, a non-uniform scale (semi-axes 0.6, 0.25, 0.1) and a
/// shear: the cone through the map from outside, area sampling from inside.
fn ellipsoid_lights() -> Vec<LightCase> {
    let rot = Mat3::from_quat(Quat::from_euler(EulerRot::XYZ, 0.5, -0.3, 0.9));
    let shear = Mat3::from_cols(Vec3::X, Vec3::new(0.4, 1.0, 0.0), Vec3::Z);
    let m = rot * shear * Mat3::from_diagonal(Vec3::new(0.6, 0.25, 0.1));
    let e = Ellipsoid::new(m).unwrap();
    let sphere = SphereLight {
        prim_path: "/ellipsoid".into(),
        center: Vec3::new(0.0, 1.0, 0.0),
        radius: e.bounding_radius(),
        radiance: Spectrum::Constant(1.0),
        shaping: None,
        ellipsoid: Some(Box::new(e)),
    };
    let c = sphere.center;
    let r = sphere.radius;
    let receivers = [
        ("outside, near", c + m * Vec3::new(0.9, -1.2, 0.6)),
        (
            "outside, along the short axis",
            c + m * Vec3::new(0.0, 0.0, 3.0),
        ),
        ("outside, far", c + 40.0 * Vec3::new(0.3, -0.8, 0.5)),
        (
            "inside, near the centre",
            c + m * Vec3::new(0.1, -0.2, 0.15),
        ),
        ("inside, near the surface", c + m * Vec3::new(0.0, 0.9, 0.1)),
    ];
    receivers
        .into_iter()
        .map(|(label, p)| LightCase {
            name: format!("light ellipsoid, receiver {label}"),
            light: Light::Sphere(sphere.clone()),
            receiver: p,
            normal: Vec3::ZERO,
            domain: cap_towards(p, c, r),
        })
        .collect()
}

fn distant_lights() -> Vec<LightCase> {
    let to_light = Vec3::new(0.3, 1.0, 0.2).normalize();
    // Half-angles: the UsdLux default (angle 0.53°, the sun), 5° and 30°.
    [0.265f32, 5.0, 30.0]
        .into_iter()
        .map(|half_deg| LightCase {
            name: format!("light distant, θmax = {half_deg}°"),
            light: Light::Distant(DistantLight {
                prim_path: "/distant".into(),
                to_light,
                cos_theta_max: half_deg.to_radians().cos(),
                one_minus_cos: 2.0 * (0.5 * half_deg.to_radians()).sin().powi(2),
                radiance: Spectrum::Constant(1.0),
            }),
            receiver: Vec3::ZERO,
            normal: Vec3::ZERO,
            domain: SphericalDomain::cap(to_light, 1.15 * (half_deg as f64).to_radians()),
        })
        .collect()
}

/// A 32 × 16 lat-long map with a checker of two levels, a band of black texels (pdf 0) and a
/// bright "sun" texel, built as `scene::build` builds a textured dome (weights = luminance ×
/// sin θ of the row).
fn latlong() -> LatLong {
    let (width, height) = (32, 16);
    let rgb: Vec<[f32; 3]> = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let l = if (12..15).contains(&x) {
                0.0
            } else if x == 5 && y == 4 {
                200.0
            } else if (x / 4 + y / 4) % 2 == 0 {
                1.0
            } else {
                0.2
            };
            [l, 0.8 * l, 0.6 * l]
        })
        .collect();
    let luminance: Vec<f32> = rgb
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect();
    let weights: Vec<f32> = (0..width * height)
        .map(|i| {
            let sin_theta = ((i / width) as f32 + 0.5) / height as f32 * PI;
            luminance[i] * sin_theta.sin()
        })
        .collect();
    LatLong {
        width,
        height,
        texels: rgb
            .iter()
            .map(|&c| RgbIlluminantSpectrum::new_lookup(c))
            .collect(),
        luminance,
        distribution: Distribution2D::new(&weights, width, height),
    }
}

fn dome_lights() -> Vec<LightCase> {
    let rotation = Mat4::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
    // world_to_local exactly as scene::build computes it from the light's to_world; a stage in
    // centimetres (the USD default) scales to_world by 0.01.
    let dome = |name: &str, to_world: Mat4, map: Option<LatLong>| LightCase {
        name: format!("light dome, {name}"),
        light: Light::Dome(DomeLight {
            prim_path: "/dome".into(),
            world_to_local: Mat3::from_mat4(to_world).inverse(),
            radiance: Spectrum::Constant(1.0),
            map,
            portals: Vec::new(),
        }),
        receiver: Vec3::new(0.1, 0.2, 0.3),
        normal: Vec3::ZERO,
        domain: SphericalDomain::sphere(),
    };
    // Two portals facing the receiver (0.1, 0.2, 0.3) and one it is behind, over the
    // lat-long map: the one-sample mixture of `light/portal.rs`.
    let portal = |c: Vec3, eu: Vec3, ev: Vec3, out: Vec3| Portal::new(c, eu, ev, out).unwrap();
    let portals = vec![
        portal(Vec3::new(-0.5, 0.0, 1.0), Vec3::X, Vec3::Y * 0.8, Vec3::Z),
        portal(
            Vec3::new(1.0, -0.3, -0.2),
            Vec3::Z * 0.6,
            Vec3::new(0.1, 0.5, 0.0),
            Vec3::X,
        ),
        portal(Vec3::new(-0.4, -1.0, -0.4), Vec3::X, Vec3::Z, Vec3::Y),
    ];
    let mut guided = dome("lat-long map with portals", rotation, Some(latlong()));
    if let Light::Dome(d) = &mut guided.light {
        d.portals = portals;
    }
    vec![
        guided,
        dome("constant", rotation, None),
        dome("lat-long map, rotated", rotation, Some(latlong())),
        dome(
            "lat-long map, rotated, centimetre stage",
            Mat4::from_scale(Vec3::splat(0.01)) * rotation,
            Some(latlong()),
        ),
    ]
}

fn light_cases() -> Vec<Case> {
    [
        triangle_lights(),
        rect_lights(),
        disk_lights(),
        sphere_lights(),
        ellipsoid_lights(),
        distant_lights(),
        dome_lights(),
    ]
    .into_iter()
    .flatten()
    .map(light_case)
    .collect()
}

/// Where a ray from `o` along `d` meets an area light (triangles by the watertight test).
fn hit_light(light: &Light, o: Vec3, d: Vec3) -> Option<LightHit> {
    match light {
        Light::Triangle(t) => {
            let [p0, p1, p2] = t.p;
            let h = triangle::intersect(&Ray::new(o, d), p0, p1, p2, f32::INFINITY)?;
            Some(LightHit {
                p: h.point(p0, p1, p2),
                n: t.n,
                t: h.t,
            })
        }
        _ => light.intersect(o, d, f32::INFINITY),
    }
}

/// The density of `sample_li`'s successful samples: `pdf_li` at the point the direction hits,
/// restricted (for area lights) to points that emit towards the receiver, because `sample_li`
/// returns nothing where L = 0 (pbrt-v4 semantics).
fn light_pdf(
    light: &Light,
    ctx: &LightSampleContext,
    wi: Vec3,
    lambda: &SampledWavelengths,
) -> f64 {
    if light.is_infinite() {
        let far = LightHit {
            p: Vec3::ZERO,
            n: Vec3::ZERO,
            t: f32::INFINITY,
        };
        return light.pdf_li(ctx, wi, &far) as f64;
    }
    let Some(hit) = hit_light(light, ctx.p, wi) else {
        return 0.0;
    };
    if light.l(&hit, -wi, lambda).is_black() {
        return 0.0;
    }
    light.pdf_li(ctx, wi, &hit) as f64
}

/// Directions from `Light::sample_li` at the receiver against `Light::pdf_li`; delta samples
/// are failures.
fn light_case(c: LightCase) -> Case {
    let LightCase {
        name,
        light,
        receiver,
        normal,
        domain,
    } = c;
    Case::new(name, move |name, m| {
        let ctx = LightSampleContext {
            p: receiver,
            n: normal,
        };
        let lambda = SampledWavelengths::sample_visible(0.5);
        Chi2Test::new(name, domain).test_count(m).run(
            |s| {
                let ls = light.sample_li(&ctx, s.get_2d(), &lambda)?;
                if ls.delta || ls.pdf_w == 0.0 {
                    return None;
                }
                Some((ls.wi, ls.pdf_w as f64))
            },
            |wi| light_pdf(&light, &ctx, wi, &lambda),
        )
    })
}

#[test]
fn chi2_lights() {
    run_all(light_cases());
}

// ---------------------------------------------------------------------------------------------
// Wavelengths
// ---------------------------------------------------------------------------------------------

/// Each lane of `SampledWavelengths::sample_visible` (the hero and its three rotations)
/// against `visible_wavelength_pdf`, and each lane of `sample_uniform`, in 2 nm cells.
fn wavelength_cases() -> Vec<Case> {
    let domain = IntervalDomain::new(LAMBDA_MIN as f64, LAMBDA_MAX as f64);
    let cells = ((LAMBDA_MAX - LAMBDA_MIN) / 2.0) as usize;
    let mut cases = Vec::new();
    for lane in 0..4 {
        cases.push(Case::new(
            format!("wavelengths visible, lane {lane}"),
            move |name, m| {
                Chi2Test::new(name, domain)
                    .resolution([cells, 1])
                    .test_count(m)
                    .run(
                        |s| {
                            let w = SampledWavelengths::sample_visible(s.get_1d());
                            Some((w.lambda[lane], w.pdf[lane] as f64))
                        },
                        |l| visible_wavelength_pdf(l) as f64,
                    )
            },
        ));
        cases.push(Case::new(
            format!("wavelengths uniform, lane {lane}"),
            move |name, m| {
                Chi2Test::new(name, domain)
                    .resolution([cells, 1])
                    .test_count(m)
                    .run(
                        |s| {
                            let w = SampledWavelengths::sample_uniform(s.get_1d());
                            Some((w.lambda[lane], w.pdf[lane] as f64))
                        },
                        |_| 1.0 / (LAMBDA_MAX - LAMBDA_MIN) as f64,
                    )
            },
        ));
    }
    cases
}

#[test]
fn chi2_wavelengths() {
    run_all(wavelength_cases());
}

// ---------------------------------------------------------------------------------------------
// Warps
// ---------------------------------------------------------------------------------------------

fn warp_cases() -> Vec<Case> {
    let mut cases = vec![
        Case::new("warp cosine hemisphere".into(), |name, m| {
            Chi2Test::new(name, SphericalDomain::sphere())
                .test_count(m)
                .run(
                    |s| {
                        let w = warp::cosine_hemisphere(s.get_2d());
                        Some((w, warp::cosine_hemisphere_pdf(w.z) as f64))
                    },
                    |w| (w.z.max(0.0) / PI) as f64,
                )
        }),
        Case::new("warp uniform sphere".into(), |name, m| {
            Chi2Test::new(name, SphericalDomain::sphere())
                .test_count(m)
                .run(
                    |s| {
                        Some((
                            warp::uniform_sphere(s.get_2d()),
                            warp::UNIFORM_SPHERE_PDF as f64,
                        ))
                    },
                    |_| 0.25 / std::f64::consts::PI,
                )
        }),
        Case::new("warp concentric disk".into(), |name, m| {
            let inside = |p: Vec2| (p.as_dvec2()).length_squared() <= 1.0;
            Chi2Test::new(name, PlanarDomain::new(-Vec2::ONE, Vec2::ONE))
                .test_count(m)
                .run(
                    |s| {
                        Some((
                            warp::concentric_disk(s.get_2d()),
                            1.0 / std::f64::consts::PI,
                        ))
                    },
                    |p| {
                        if inside(p) {
                            1.0 / std::f64::consts::PI
                        } else {
                            0.0
                        }
                    },
                )
        }),
        Case::new("warp uniform triangle (b0, b1)".into(), |name, m| {
            Chi2Test::new(name, PlanarDomain::new(Vec2::ZERO, Vec2::ONE))
                .test_count(m)
                .run(
                    |s| {
                        let b = warp::uniform_triangle(s.get_2d());
                        Some((Vec2::new(b[0], b[1]), 2.0))
                    },
                    |p| {
                        if p.x as f64 + p.y as f64 <= 1.0 {
                            2.0
                        } else {
                            0.0
                        }
                    },
                )
        }),
    ];
    // Cones: wide (120°), moderate (25.8°) and sun-sized (0.265°).
    for cos_max in [-0.5f32, 0.9, 0.265f32.to_radians().cos()] {
        cases.push(Case::new(
            format!("warp uniform cone, cos θmax = {cos_max}"),
            move |name, m| {
                let theta_max = (cos_max as f64).acos();
                let reference = 1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_max as f64));
                Chi2Test::new(name, SphericalDomain::cap(Vec3::Z, 1.15 * theta_max))
                    .test_count(m)
                    .run(
                        |s| {
                            let w = warp::uniform_cone(s.get_2d(), cos_max);
                            Some((w, warp::uniform_cone_pdf(cos_max) as f64))
                        },
                        |w| {
                            let cos = w.as_dvec3().normalize().z;
                            if cos >= cos_max as f64 {
                                reference
                            } else {
                                0.0
                            }
                        },
                    )
            },
        ));
    }
    cases
}

#[test]
fn chi2_warps() {
    run_all(warp_cases());
}

// ---------------------------------------------------------------------------------------------
// Distributions
// ---------------------------------------------------------------------------------------------

const WEIGHTS_1D: [f32; 7] = [1.0, 0.0, 3.0, 4.0, 0.5, 0.0, 2.0];
const WEIGHTS_2D: [[f32; 6]; 4] = [
    [1.0, 2.0, 0.0, 4.0, 1.0, 0.5],
    [0.0, 0.0, 3.0, 1.0, 2.0, 8.0],
    [2.0, 1.0, 1.0, 0.0, 0.3, 1.0],
    [5.0, 0.1, 2.0, 2.0, 0.0, 1.0],
];

/// The reference density of piecewise-constant weights over [0,1): w[cell] / mean(w).
fn step_pdf(weights: &[f32], x: f32) -> f64 {
    let n = weights.len();
    let i = ((x * n as f32) as usize).min(n - 1);
    let mean = weights.iter().map(|&w| w as f64).sum::<f64>() / n as f64;
    weights[i] as f64 / mean
}

fn distribution_cases() -> Vec<Case> {
    vec![
        Case::new("distribution 1D continuous".into(), |name, m| {
            let d = Distribution1D::new(&WEIGHTS_1D);
            Chi2Test::new(name, IntervalDomain::new(0.0, 1.0))
                .test_count(m)
                .run(
                    |s| {
                        let (x, pdf, _) = d.sample_continuous(s.get_1d());
                        Some((x, pdf as f64))
                    },
                    |x| step_pdf(&WEIGHTS_1D, x),
                )
        }),
        Case::new("distribution 1D discrete".into(), |name, m| {
            // One cell per index; index i is the point (i + ½)/n with density n · pmf.
            let d = Distribution1D::new(&WEIGHTS_1D);
            let n = WEIGHTS_1D.len();
            Chi2Test::new(name, IntervalDomain::new(0.0, 1.0))
                .resolution([n, 1])
                .test_count(m)
                .run(
                    |s| {
                        let (i, pmf, _) = d.sample_discrete(s.get_1d());
                        Some(((i as f32 + 0.5) / n as f32, pmf as f64 * n as f64))
                    },
                    |x| step_pdf(&WEIGHTS_1D, x),
                )
        }),
        Case::new("distribution 2D".into(), |name, m| {
            let flat: Vec<f32> = WEIGHTS_2D.iter().flatten().copied().collect();
            let d = Distribution2D::new(&flat, 6, 4);
            Chi2Test::new(name, PlanarDomain::new(Vec2::ZERO, Vec2::ONE))
                .test_count(m)
                .run(
                    |s| {
                        let (p, pdf) = d.sample(s.get_2d());
                        Some((Vec2::from(p), pdf as f64))
                    },
                    |p| {
                        let (col, row) =
                            (((p.x * 6.0) as usize).min(5), ((p.y * 4.0) as usize).min(3));
                        let mean = flat.iter().map(|&w| w as f64).sum::<f64>() / 24.0;
                        WEIGHTS_2D[row][col] as f64 / mean
                    },
                )
        }),
    ]
}

#[test]
fn chi2_distributions() {
    run_all(distribution_cases());
}
