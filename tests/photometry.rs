//! Photometry and UsdLux completeness (issue 4): the `lights` report against colour-science
//! and closed forms, `spectral:luminousFlux` / `spectral:luminousIntensity` on every light
//! type (shaped and cylinder lights included) checked by the flux through an enclosing sphere,
//! and an IES profile read back from renders in several directions.
//!
//! The colour-science side is `tools/check_lights.py`, run in the venv `tools/venv.sh` makes.

mod common;
use common::*;
use spectral_render::light::emission::color_temperature_rgb;
use spectral_render::light::report::{self, LightReport};
use spectral_render::light::{Light, LightSampleContext};
use spectral_render::sampling::Sampler;
use spectral_render::scene;
use spectral_render::session::{self, RenderOptions};
use spectral_render::spectral::{blackbody, data, photometry, xyz};
use spectral_render::spectral::{DenseSpectrum, SampledWavelengths};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a / b - 1.0).abs() <= rel
}

fn json_num(v: Option<f64>) -> String {
    v.map_or("null".into(), |v| format!("{v}"))
}

// ---------------------------------------------------------------------------------------
// colour-science

/// A RectLight per illuminant of `spectra/illuminants/` (0.5 m × 0.4 m, 100 nits) and the
/// prim → illuminant map.
fn illuminant_stage() -> (String, Vec<(String, &'static str)>) {
    let mut s = header();
    let mut prims = Vec::new();
    for (i, name) in data::illuminant_names().iter().enumerate() {
        let prim = format!("L{i}_{}", name.replace('-', "_"));
        s += &format!(
            "def RectLight \"{prim}\"\n{{\n    float inputs:width = 0.5\n    float inputs:height = 0.4\n    float inputs:intensity = 100\n    token spectral:emission = \"{name}\"\n    double3 xformOp:translate = ({i}, 0, 0)\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n"
        );
        prims.push((format!("/{prim}"), *name));
    }
    (s, prims)
}

#[test]
fn photometry_matches_colour_science() {
    colour_science_venv();
    let dir = temp_dir("photometry-colour");

    let illuminants: Vec<String> = data::illuminant_names()
        .iter()
        .map(|name| {
            let s = photometry::summarize(data::illuminant(name).unwrap());
            let [x, y] = s.xy.unwrap();
            format!(
                "\"{name}\": {{\"luminous_flux\": {}, \"efficacy\": {}, \"xy\": [{x}, {y}], \"cct\": {}, \"duv\": {}}}",
                photometry::luminous(data::illuminant(name).unwrap()),
                s.efficacy.unwrap(),
                json_num(s.cct.map(|c| c.kelvin)),
                json_num(s.cct.map(|c| c.duv)),
            )
        })
        .collect();

    let bb = DenseSpectrum::from_fn(|l| blackbody::planck_f64(l as f64, 2042.0) as f32);
    let bb_luminance = photometry::luminous(&bb);

    let temps: Vec<String> = [1000.0, 1900.0, 2700.0, 4000.0, 6500.0, 8000.0, 10000.0]
        .iter()
        .map(|&t: &f32| {
            let [r, g, b] = color_temperature_rgb(t);
            format!("\"{t}\": [{r}, {g}, {b}]")
        })
        .collect();

    let (stage, prims) = illuminant_stage();
    write(&dir, "illuminants.usda", &stage);
    let out = spectral_render(&["lights", "illuminants.usda", "--json"], &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report_path = write(&dir, "report.json", &String::from_utf8_lossy(&out.stdout));
    let emission: Vec<String> = prims
        .iter()
        .map(|(p, n)| format!("\"{p}\": \"{n}\""))
        .collect();

    let json = format!(
        "{{\"illuminants\": {{{}}}, \"blackbody_2042_luminance\": {bb_luminance}, \"color_temperature_rgb\": {{{}}}, \"report\": \"{}\", \"report_emission\": {{{}}}}}",
        illuminants.join(", "),
        temps.join(", "),
        report_path.display(),
        emission.join(", ")
    );
    let json_path = write(&dir, "photometry.json", &json);
    let (passed, text) = colour_science_check("check_lights.py", &json_path);
    println!("{text}");
    assert!(passed, "photometry check failed:\n{text}");

    // The report's own numbers for the same lights: luminance as authored, Φ = π A L.
    let scene = scene::load(&dir.join("illuminants.usda"), None).unwrap();
    for r in report::report(&scene.lights) {
        assert!(close(r.luminance.unwrap(), 100.0, 1e-5), "{r:?}");
        assert!(
            close(r.luminous_flux.unwrap(), PI * 0.2 * 100.0, 1e-5),
            "{r:?}"
        );
        assert!(close(r.peak_intensity.unwrap(), 0.2 * 100.0, 1e-5), "{r:?}");
    }
}

// ---------------------------------------------------------------------------------------
// Geometry, photometric overrides and shaping

/// The asymmetric test profile shipped with the tests.
fn test_ies() -> PathBuf {
    root().join("tests/data/ies/asymmetric.ies")
}

/// The candela table of a well-formed type C file with horizontal angles 0–180 (our test
/// profile), read independently of the renderer's parser: (vertical°, horizontal°, cd[h][v]).
struct Table {
    v: Vec<f64>,
    h: Vec<f64>,
    cd: Vec<Vec<f64>>,
}

impl Table {
    fn read(path: &Path) -> Table {
        let text = std::fs::read_to_string(path).unwrap();
        let after = text.split("TILT=NONE").nth(1).unwrap();
        let n: Vec<f64> = after
            .split_whitespace()
            .map(|t| t.parse().unwrap())
            .collect();
        let (nv, nh) = (n[3] as usize, n[4] as usize);
        let mult = n[2] * n[10] * n[11];
        let v = n[13..13 + nv].to_vec();
        let h = n[13 + nv..13 + nv + nh].to_vec();
        let cd = (0..nh)
            .map(|j| {
                let start = 13 + nv + nh + j * nv;
                n[start..start + nv].iter().map(|c| c * mult).collect()
            })
            .collect();
        Table { v, h, cd }
    }

    fn max(&self) -> f64 {
        self.cd.iter().flatten().copied().fold(0.0, f64::max)
    }

    /// The table value at grid angles (degrees), with the 0–180 bilateral symmetry.
    fn at(&self, theta: f64, phi: f64) -> f64 {
        let phi = if phi > 180.0 { 360.0 - phi } else { phi };
        let i = self.v.iter().position(|&a| a == theta).unwrap();
        let j = self.h.iter().position(|&a| a == phi).unwrap();
        self.cd[j][i]
    }

    /// Bilinear interpolation at any (θ, φ) in degrees.
    fn interp(&self, theta: f64, phi: f64) -> f64 {
        let phi = if phi > 180.0 { 360.0 - phi } else { phi };
        let seg = |xs: &[f64], x: f64| {
            let i = xs.partition_point(|&a| a <= x).clamp(1, xs.len() - 1) - 1;
            (i, ((x - xs[i]) / (xs[i + 1] - xs[i])).clamp(0.0, 1.0))
        };
        let (i, tv) = seg(&self.v, theta);
        let (j, th) = seg(&self.h, phi);
        let col = |j: usize| self.cd[j][i] * (1.0 - tv) + self.cd[j][i + 1] * tv;
        col(j) * (1.0 - th) + col(j + 1) * th
    }

    /// ∫ I dΩ by the midpoint rule (1800 × 1440 cells over the sphere).
    fn flux(&self) -> f64 {
        let (nt, np) = (1800, 1440);
        let (dt, dp) = (180.0 / nt as f64, 360.0 / np as f64);
        let mut sum = 0.0;
        for a in 0..nt {
            let t = (a as f64 + 0.5) * dt;
            let ring: f64 = (0..np).map(|b| self.interp(t, (b as f64 + 0.5) * dp)).sum();
            sum += ring * t.to_radians().sin();
        }
        sum * dt.to_radians() * dp.to_radians()
    }
}

/// Every light type, with photometric overrides and shaping.
fn lights_stage(ies: &Path) -> String {
    let mut s = header();
    s += r#"def RectLight "Rect" {
    float inputs:width = 2
    float inputs:height = 0.5
    float spectral:luminousFlux = 1200
}
def DiskLight "Disk" {
    float inputs:radius = 0.3
    float spectral:luminousIntensity = 500
    double3 xformOp:translate = (10, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def SphereLight "Sphere" {
    float inputs:radius = 0.2
    float inputs:intensity = 1000
    double3 xformOp:translate = (20, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def CylinderLight "Tube" {
    float inputs:radius = 0.05
    float inputs:length = 1.2
    float spectral:luminousFlux = 2500
    double3 xformOp:translate = (30, 0, 0)
    float xformOp:rotateY = 30
    float3 xformOp:scale = (2, 1, 1)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateY", "xformOp:scale"]
}
def DiskLight "Spot" (
    prepend apiSchemas = ["ShapingAPI"]
)
{
    float inputs:radius = 0.1
    float inputs:shaping:cone:angle = 40
    float spectral:luminousFlux = 800
    token spectral:emission = "CIE-A"
    double3 xformOp:translate = (40, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def SphereLight "Focus" {
    float inputs:radius = 0.1
    float inputs:intensity = 50
    float inputs:shaping:focus = 3
    double3 xformOp:translate = (50, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def SphereLight "Soft" (
    prepend apiSchemas = ["ShapingAPI"]
)
{
    float inputs:radius = 0.05
    float inputs:shaping:cone:angle = 60
    float inputs:shaping:cone:softness = 0.5
    float inputs:shaping:focus = 1
    color3f inputs:shaping:focusTint = (0.2, 0.4, 0.9)
    float spectral:luminousFlux = 300
    double3 xformOp:translate = (60, 0, 0)
    float xformOp:rotateX = 70
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateX"]
}
def CylinderLight "ShapedTube" {
    float inputs:radius = 0.02
    float inputs:length = 0.6
    float inputs:shaping:cone:angle = 50
    float spectral:luminousFlux = 400
    double3 xformOp:translate = (70, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Mesh "Panel" (
    prepend apiSchemas = ["MeshLightAPI"]
)
{
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 1, 2, 3]
    point3f[] points = [(80, 0, 0), (81, 0, 0), (81, 1, 0), (80, 1, 0)]
    float inputs:intensity = 10
}
def DistantLight "Sun" {
    float inputs:angle = 0.53
    float inputs:intensity = 1000
    bool inputs:normalize = 1
}
def DomeLight "Sky" {
    float inputs:intensity = 20
}
"#;
    s += &format!(
        r#"def SphereLight "Ies" {{
    float inputs:radius = 0.01
    asset inputs:shaping:ies:file = @{}@
    float spectral:luminousIntensity = {}
    double3 xformOp:translate = (90, 0, 0)
    float xformOp:rotateZ = 25
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateZ"]
}}
"#,
        ies.display(),
        Table::read(ies).max()
    );
    s
}

fn by_prim<'a>(reports: &'a [LightReport], prim: &str) -> &'a LightReport {
    reports
        .iter()
        .find(|r| r.prim_path == prim)
        .unwrap_or_else(|| panic!("no report for {prim}"))
}

#[test]
fn report_follows_geometry_and_photometric_overrides() {
    let dir = temp_dir("photometry-report");
    let stage = write(&dir, "lights.usda", &lights_stage(&test_ies()));
    let scene = scene::load(&stage, None).unwrap();
    assert!(
        scene.summary.warnings.is_empty(),
        "{:?}",
        scene.summary.warnings
    );
    let r = report::report(&scene.lights);
    let flux = |p: &str| by_prim(&r, p).luminous_flux.unwrap();
    let peak = |p: &str| by_prim(&r, p).peak_intensity.unwrap();
    let lum = |p: &str| by_prim(&r, p).luminance.unwrap();

    // Authored flux and intensity come back, and the other quantities follow the shape.
    assert!(close(flux("/Rect"), 1200.0, 1e-5));
    assert!(close(peak("/Rect"), 1200.0 / PI, 1e-5));
    assert!(close(lum("/Rect"), 1200.0 / PI, 1e-5)); // A = 1 m²
    assert!(close(peak("/Disk"), 500.0, 1e-5));
    assert!(close(flux("/Disk"), 500.0 * PI, 1e-5));
    let a_sphere = 4.0 * PI * 0.04;
    assert!(close(flux("/Sphere"), PI * a_sphere * 1000.0, 1e-5));
    assert!(close(peak("/Sphere"), PI * 0.04 * 1000.0, 1e-5));
    // Cylinder: scale (2, 1, 1) doubles the length; Φ = π·2πrℓ·L, I_max = 2rℓ·L.
    let (r_t, l_t) = (0.05, 2.4);
    assert!(close(flux("/Tube"), 2500.0, 1e-5));
    assert!(close(
        by_prim(&r, "/Tube").area.unwrap(),
        2.0 * PI * r_t * l_t,
        1e-5
    ));
    assert!(close(
        peak("/Tube"),
        2500.0 * 2.0 * r_t * l_t / (PI * 2.0 * PI * r_t * l_t),
        1e-5
    ));
    // Hard cone of 40° on a flat emitter: Φ = π A L sin²40°.
    let a_spot = PI * 0.01;
    let l_spot = 800.0 / (PI * a_spot * 40f64.to_radians().sin().powi(2));
    assert!(close(flux("/Spot"), 800.0, 1e-5));
    assert!(
        close(lum("/Spot"), l_spot, 1e-4),
        "{} {l_spot}",
        lum("/Spot")
    );
    // Focus 3 on a sphere: Φ = L πr² ∫|cos θ|³ dω = L πr² · π.
    assert!(close(flux("/Focus"), 50.0 * PI * 0.01 * PI, 1e-4));
    assert!(close(peak("/Focus"), 50.0 * PI * 0.01, 1e-5));
    assert!(close(flux("/Soft"), 300.0, 1e-5));
    assert!(close(flux("/ShapedTube"), 400.0, 1e-5));
    // Mesh light: one-sided 1 m² of 10 nits.
    assert!(close(flux("/Panel"), 10.0 * PI, 1e-5));
    assert!(close(peak("/Panel"), 10.0, 1e-5));
    // IES on a sphere with luminousIntensity = the table's maximum: the profile itself.
    let table = Table::read(&test_ies());
    assert!(close(peak("/Ies"), table.max(), 1e-5));
    assert!(
        close(flux("/Ies"), table.flux(), 2e-4),
        "{} {}",
        flux("/Ies"),
        table.flux()
    );
    // Infinite lights: illuminance, no flux.
    let sun = by_prim(&r, "/Sun");
    assert!(close(sun.illuminance.unwrap(), 1000.0, 1e-4), "{sun:?}");
    assert_eq!((sun.luminous_flux, sun.peak_intensity), (None, None));
    let sky = by_prim(&r, "/Sky");
    assert!(close(sky.luminance.unwrap(), 20.0, 1e-5));
    assert!(close(sky.illuminance.unwrap(), 20.0 * PI, 1e-5));
    assert_eq!(sky.luminous_flux, None);
    // CCT of the CIE A spot, and no CCT for a strongly tinted one is not required here.
    let a = by_prim(&r, "/Spot").spectrum.cct.unwrap().kelvin;
    assert!((a - 2856.0).abs() < 2.0, "{a}");

    // The CLI prints the same report; JSON nulls where a quantity is not defined.
    let out = spectral_render(&["lights", "lights.usda", "--json"], &dir);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = String::from_utf8_lossy(&out.stdout);
    assert!(json.contains("\"prim\": \"/Sky\""), "{json}");
    assert!(json.contains("\"luminous_flux_lm\": null"));
    assert!(String::from_utf8_lossy(&out.stderr).starts_with("loaded "));
    let table_out = spectral_render(&["lights", "lights.usda"], &dir);
    let text = String::from_utf8_lossy(&table_out.stdout);
    assert!(
        text.contains("/Tube") && text.contains("CylinderLight"),
        "{text}"
    );
}

/// Φ through a sphere of radius `radius` around `center`: 4πR² times the mean illuminance at
/// uniformly distributed points facing the centre, each estimated with one light sample of
/// the path tracer's NEE (`Light::sample_li`) at one set of hero wavelengths. (mean, SEM) in lm.
fn flux_through_sphere(light: &Light, center: glam::Vec3, radius: f32, n: u64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for i in 0..n {
        let mut s = Sampler::new(11, i, 0);
        let [u1, u2] = s.get_2d();
        let z = 1.0 - 2.0 * u1;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2;
        let dir = glam::Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let ctx = LightSampleContext {
            p: center + radius * dir,
            n: -dir,
        };
        let lambda = SampledWavelengths::sample_visible(s.get_1d());
        let e = match light.sample_li(&ctx, s.get_2d(), &lambda) {
            Some(ls) if ls.pdf_w > 0.0 => {
                let cos = ls.wi.dot(ctx.n).max(0.0);
                xyz::sampled_to_xyz(ls.l * (cos / ls.pdf_w), &lambda)[1] as f64
            }
            _ => 0.0,
        };
        sum += e;
        sum2 += e * e;
    }
    let mean = sum / n as f64;
    let sem = ((sum2 / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
    let area = 4.0 * PI * (radius as f64).powi(2);
    (mean * area, sem * area)
}

fn light_center(l: &Light) -> glam::Vec3 {
    match l {
        Light::Rect(r) => r.corner + 0.5 * (r.edge_u + r.edge_v),
        Light::Disk(d) => d.center,
        Light::Sphere(s) => s.center,
        Light::Cylinder(c) => c.center,
        _ => panic!("not a finite light"),
    }
}

#[test]
fn emitted_flux_matches_the_report_through_light_sampling() {
    let dir = temp_dir("photometry-flux");
    let stage = write(&dir, "lights.usda", &lights_stage(&test_ies()));
    let scene = scene::load(&stage, None).unwrap();
    let reports = report::report(&scene.lights);
    for prim in [
        "/Rect",
        "/Sphere",
        "/Tube",
        "/Spot",
        "/Focus",
        "/Soft",
        "/ShapedTube",
        "/Ies",
    ] {
        let light = scene.lights.iter().find(|l| l.prim_path() == prim).unwrap();
        let expected = by_prim(&reports, prim).luminous_flux.unwrap();
        let (phi, sem) = flux_through_sphere(light, light_center(light), 3.0, 400_000);
        let z = (phi - expected) / sem;
        println!("{prim:<12} report {expected:10.3} lm  through the sphere {phi:10.3} ± {sem:.3} lm  z = {z:+.2}");
        assert!(z.abs() < 4.5, "{prim}: {phi} ± {sem} vs {expected}");
        assert!(sem / expected < 0.01, "{prim}: too noisy to mean anything");
    }
}

// ---------------------------------------------------------------------------------------
// IES read back from renders

/// Light-local emission direction at θ from the −Z axis (nadir) and azimuth φ from +X.
fn ies_direction(theta_deg: f64, phi_deg: f64) -> glam::Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    glam::Vec3::new(
        (t.sin() * p.cos()) as f32,
        (t.sin() * p.sin()) as f32,
        -t.cos() as f32,
    )
}

/// A tiny IES sphere light at the origin, as UsdLux defines it (luminance × candela, no
/// normalize): intensity 1/(π r²) makes I(ω) = πr² · L₀ · cd(ω) = cd(ω); and a camera at
/// `dist` along `w` looking back at it with a field of ±`half_tan`.
fn ies_stage(ies: &Path, radius: f64, w: glam::Vec3, dist: f64, half_tan: f64) -> String {
    let z = w.normalize();
    let up = if z.y.abs() > 0.9 {
        glam::Vec3::X
    } else {
        glam::Vec3::Y
    };
    let x = up.cross(z).normalize();
    let y = z.cross(x);
    let e = z * dist as f32;
    let row = |v: glam::Vec3, h: f32| format!("({}, {}, {}, {h})", v.x, v.y, v.z);
    let mut s = header();
    s += &format!(
        "def SphereLight \"Ies\"\n{{\n    float inputs:radius = {radius}\n    float inputs:intensity = {}\n    asset inputs:shaping:ies:file = @{}@\n}}\n",
        1.0 / (PI * radius * radius),
        ies.display()
    );
    s += &format!(
        "def Camera \"Cam\"\n{{\n    float focalLength = {}\n    float horizontalAperture = 20\n    float verticalAperture = 20\n    float2 clippingRange = (0.01, 100)\n    matrix4d xformOp:transform = ({}, {}, {}, {})\n    uniform token[] xformOpOrder = [\"xformOp:transform\"]\n}}\n",
        10.0 / half_tan,
        row(x, 0.0),
        row(y, 0.0),
        row(z, 0.0),
        row(e, 1.0)
    );
    s
}

/// I = d² Σ Y_pixel Ω_pixel over the image of the light (pinhole, pixel solid angle
/// Δ² / (1 + x² + y²)^{3/2} on the image plane at distance 1).
fn intensity_from_image(xyz: &[[f32; 3]], res: usize, half_tan: f64, dist: f64) -> f64 {
    let delta = 2.0 * half_tan / res as f64;
    let mut sum = 0.0;
    for py in 0..res {
        for px in 0..res {
            let x = (px as f64 + 0.5) * delta - half_tan;
            let y = (py as f64 + 0.5) * delta - half_tan;
            let omega = delta * delta / (1.0 + x * x + y * y).powf(1.5);
            sum += xyz[py * res + px][1] as f64 * omega;
        }
    }
    sum * dist * dist
}

#[test]
fn ies_intensity_read_back_from_renders_matches_the_candela_table() {
    let ies = test_ies();
    let table = Table::read(&ies);
    let dir = temp_dir("photometry-ies");
    // (θ, φ) on the table's grid; φ > 180° exercises the bilateral mirror.
    let directions = [
        (0.0, 0.0),
        (30.0, 0.0),
        (45.0, 60.0),
        (60.0, 150.0),
        (75.0, 90.0),
        (120.0, 30.0),
        (45.0, 300.0),
        (150.0, 210.0),
    ];
    let (radius, dist, half_tan, res) = (0.002, 1.0, 0.003, 24usize);
    let seeds = 8u64;
    for (k, &(theta, phi)) in directions.iter().enumerate() {
        let expected = table.at(theta, phi);
        let w = ies_direction(theta, phi);
        let path = write(
            &dir,
            &format!("ies{k}.usda"),
            &ies_stage(&ies, radius, w, dist, half_tan),
        );
        let scene = scene::load(&path, Some((res as u32, res as u32))).unwrap();
        let values: Vec<f64> = (0..seeds)
            .map(|seed| {
                let opts = RenderOptions {
                    spp: Some(64),
                    seed,
                    max_depth: Some(1),
                    ..Default::default()
                };
                let out = session::render(&scene, &opts).unwrap();
                assert_finite(&out);
                intensity_from_image(&out.xyz, res, half_tan, dist)
            })
            .collect();
        let (mean, sem) = mean_and_sem(values);
        // The light subtends ±0.11°: averaging the bilinear table over that disk moves it by
        // less than 3e-4 (its kinks at the nodes); the seeds share random numbers across
        // directions, so their errors are correlated.
        let tol = 4.0 * sem + 5e-4 * expected;

        // The same direction through NEE: E·d² at a point facing the light.
        let light = &scene.lights[0];
        let d_nee = 2.0f32;
        let n = 20_000u64;
        let mut e = 0.0f64;
        for i in 0..n {
            let mut s = Sampler::new(3, i, k as u64);
            let lambda = SampledWavelengths::sample_visible(s.get_1d());
            let ctx = LightSampleContext {
                p: w * d_nee,
                n: -w,
            };
            if let Some(ls) = light.sample_li(&ctx, s.get_2d(), &lambda) {
                let cos = ls.wi.dot(ctx.n).max(0.0);
                e += xyz::sampled_to_xyz(ls.l * (cos / ls.pdf_w), &lambda)[1] as f64;
            }
        }
        let i_nee = e / n as f64 * (d_nee as f64).powi(2);
        println!(
            "θ {theta:5.1}° φ {phi:5.1}°: table {expected:8.2} cd, render {mean:8.2} ± {sem:.2} cd ({:+.4}%), NEE {i_nee:8.2} cd ({:+.4}%)",
            100.0 * (mean / expected - 1.0),
            100.0 * (i_nee / expected - 1.0)
        );
        assert!(
            (mean - expected).abs() < tol,
            "render: {mean} ± {sem} vs {expected}"
        );
        assert!(close(i_nee, expected, 5e-3), "NEE: {i_nee} vs {expected}");
    }
}

#[test]
fn malformed_ies_file_is_an_error_with_path_and_line() {
    let dir = temp_dir("photometry-bad-ies");
    let bad = write(
        &dir,
        "bad.ies",
        "IESNA:LM-63-2002\n[TEST] broken\nTILT=NONE\n1 -1 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1000 abc\n",
    );
    let mut s = header();
    s += &format!(
        "def SphereLight \"Down\"\n{{\n    asset inputs:shaping:ies:file = @{}@\n}}\n",
        bad.display()
    );
    let stage = write(&dir, "bad.usda", &s);
    let e = scene::load(&stage, None)
        .err()
        .expect("must fail")
        .to_string();
    assert!(e.contains("/Down"), "{e}");
    assert!(e.contains(&format!("{}:8:", bad.display())), "{e}");
    assert!(e.contains("'abc'") && !e.contains('\n'), "{e}");
    let out = spectral_render(&["lights", "bad.usda"], &dir);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with("error: ") && err.contains("bad.ies:8:"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn room_scene_reports_its_luminaires() {
    let scene = scene::load(&root().join("scenes/room.usda"), Some((8, 6))).unwrap();
    assert!(
        scene.summary.warnings.is_empty(),
        "{:?}",
        scene.summary.warnings
    );
    let r = report::report(&scene.lights);
    let panels: Vec<&LightReport> = r.iter().filter(|l| l.kind == "RectLight").collect();
    assert_eq!(panels.len(), 4);
    for p in panels {
        assert!(close(p.luminous_flux.unwrap(), 3000.0, 1e-5), "{p:?}");
    }
    let down = by_prim(&r, "/Room/Lights/Downlight");
    let table = Table::read(&root().join("scenes/ies/downlight.ies"));
    assert!(
        close(down.peak_intensity.unwrap(), table.max(), 1e-5),
        "{down:?}"
    );
}
