//! Light tracing and BDPT against the path tracer and against their own definitions:
//!
//! - agreement: PT, LT and BDPT per pixel (z-tests with Šidák correction) and in the image
//!   mean, on a table of scenes (adding a scene is one entry);
//! - efficiency: BDPT's variance per sample of the image's mean luminance is at most 1.2 × the
//!   path tracer's (whose techniques it contains) on five scenes, caustics seen directly and
//!   in a mirror among them (issue 17);
//! - MIS: on random paths through a scene with every light type, a mirror, a glass pane and a
//!   glass ball (chains of 1, 2 and 3 or more specular vertices to every kind of light),
//!   from the camera and from irradiance and luminance meters, the recurrent weights equal a
//!   brute-force evaluation of m(p_s) / Σ_j m(p_j) from per-vertex densities (techniques
//!   whose connection evaluates to 0 — a delta vertex — excluded, and exactly those the
//!   integrators skip), and sum to 1;
//! - closed forms with BDPT and LT: the white furnace, a plane under a uniform dome;
//! - the strategy images (`--strategies`) sum to the BDPT image;
//! - no NaN or Inf with a point-like light against a wall and a camera inside a closed box;
//! - 1 and 2 threads give bit-identical images.

mod common;
use common::*;
use glam::Vec3;
use spectral_render::bxdf::{BsdfSample, TransportMode};
use spectral_render::geometry::offset::spawn_ray;
use spectral_render::geometry::Ray;
use spectral_render::integrator::bidir::connect::{
    connect_weight, direct_weight, emitter_weight, escaped_weight, infinite_origin_weight,
    origin_weight, sensor_weight,
};
use spectral_render::integrator::bidir::subpath::first_hit_direct;
use spectral_render::integrator::bidir::vertex::bsdf_at;
use spectral_render::integrator::roulette::{RrStart, DEFAULT_RR_DEPTH};
use spectral_render::integrator::split::Split;
use spectral_render::texture::TextureFilter;
use spectral_render::SamplerKind;

/// The bidirectional context's default (`BidirContext::new`): textures unfiltered.
const FINEST: TextureFilter = TextureFilter::Finest;
use spectral_render::integrator::bidir::merge::{merge_weight, sensor_merge_weight};
use spectral_render::integrator::bidir::merge_rule::{near_specular, MergeRule};
use spectral_render::integrator::bidir::vertex::LightOrigin;
use spectral_render::integrator::bidir::{
    BidirContext, MergeVertex, Mis, MisHeuristic, PathVertex, Walk,
};
use spectral_render::integrator::vcm::{VcmMode, VcmParams};
use spectral_render::light::emit::LightLeSample;
use spectral_render::light::{Light, LightHit, LightLiSample, LightSampleContext};
use spectral_render::sampling::Sampler;
use spectral_render::scene::{self, Hit, Scene, SurfaceHit};
use spectral_render::sensor::meter::{Meter, MeterKind, MeterSensor};
use spectral_render::sensor::{Sensor, SensorRay};
use spectral_render::session::{self, RenderOptions, RenderOutput};
use spectral_render::spectral::SampledWavelengths;
use spectral_render::Integrator;
use std::path::Path;

// ---------------------------------------------------------------------------------------------
// Stages
// ---------------------------------------------------------------------------------------------

fn mesh_light(name: &str, points: &[[f32; 3]], intensity: f32, two_sided: bool) -> String {
    let extra = format!(
        "    float inputs:intensity = {intensity}\n    uniform bool doubleSided = {}\n{}",
        two_sided as u8,
        binding("Grey")
    );
    mesh(
        name,
        MESH_LIGHT_API,
        points,
        &one_face(points.len()),
        &extra,
    )
}

fn looks() -> String {
    looks_scope(
        &(flat_diffuse("Grey", 0.6)
            + &material(
                "Red",
                "spectral:diffuse",
                "        float2[] inputs:reflectance:samples = [(360, 0.05), (560, 0.1), (620, 0.7), (830, 0.8)]\n",
            )
            + &flat_diffuse("White", 0.8)
            + &material(
                "Gold",
                "spectral:conductor",
                "        uniform token inputs:metal = \"Au\"\n        float inputs:roughness = 0.2\n",
            )
            + &material(
                "Mirror",
                "spectral:conductor",
                "        uniform token inputs:metal = \"Ag\"\n        float inputs:roughness = 0\n",
            )
            + &material(
                "Satin",
                "spectral:conductor",
                "        uniform token inputs:metal = \"Ag\"\n        float inputs:roughness = 0.06\n",
            )
            + &material(
                "Glass",
                "spectral:dielectric",
                "        float inputs:ior = 1.5\n        float inputs:roughness = 0\n",
            )),
    )
}

/// A UsdLux light with a transform.
fn lux(kind: &str, name: &str, inputs: &str, translate: [f32; 3], rotate: [f32; 3]) -> String {
    format!(
        "def {kind} \"{name}\"\n{{\n{inputs}    double3 xformOp:translate = ({}, {}, {})\n    float3 xformOp:rotateXYZ = ({}, {}, {})\n    uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:rotateXYZ\"]\n}}\n\n",
        translate[0], translate[1], translate[2], rotate[0], rotate[1], rotate[2]
    )
}

/// A quad with tilted per-vertex normals (shading normals differ from the geometric one).
fn smooth_panel() -> String {
    polygon(
        "Panel",
        &[
            [1.5, 0.0, -1.5],
            [1.5, 0.0, 1.0],
            [1.5, 1.5, 1.0],
            [1.5, 1.5, -1.5],
        ],
        Some(&[
            [-1.0, 0.3, 0.0],
            [-1.0, -0.2, 0.2],
            [-1.0, 0.1, -0.3],
            [-1.0, 0.0, 0.3],
        ]),
        &binding("Grey"),
    )
}

/// An open corner (floor, back and left walls) with every light type: a one-sided and a
/// two-sided mesh light, rect, disk and sphere lights, a dome, a distant light with an
/// angle and a delta distant light.
fn every_light_stage() -> String {
    let mut s = header();
    s += &camera_at([0.0, 1.0, 4.0], 0.6, "");
    s += &looks();
    s += &polygon(
        "Floor",
        &[
            [-2.0, 0.0, 2.0],
            [2.0, 0.0, 2.0],
            [2.0, 0.0, -2.0],
            [-2.0, 0.0, -2.0],
        ],
        None,
        &binding("White"),
    );
    s += &polygon(
        "Back",
        &[
            [-2.0, 0.0, -2.0],
            [2.0, 0.0, -2.0],
            [2.0, 2.0, -2.0],
            [-2.0, 2.0, -2.0],
        ],
        None,
        &binding("Grey"),
    );
    s += &polygon(
        "Left",
        &[
            [-2.0, 0.0, 2.0],
            [-2.0, 0.0, -2.0],
            [-2.0, 2.0, -2.0],
            [-2.0, 2.0, 2.0],
        ],
        None,
        &binding("Red"),
    );
    s += &smooth_panel();
    s += &mesh_light(
        "Lamp",
        &[
            [-0.4, 1.8, -0.4],
            [0.4, 1.8, -0.4],
            [0.4, 1.8, 0.4],
            [-0.4, 1.8, 0.4],
        ],
        5.0,
        false,
    );
    s += &mesh_light(
        "Fin",
        &[[-1.0, 0.2, 0.5], [-0.5, 0.2, 0.5], [-0.75, 0.8, 0.5]],
        4.0,
        true,
    );
    s += &lux("RectLight", "Rect", "    float inputs:width = 0.5\n    float inputs:height = 0.3\n    float inputs:intensity = 3\n", [0.5, 1.2, -1.95], [0.0, 180.0, 0.0]);
    s += &lux(
        "DiskLight",
        "Disk",
        "    float inputs:radius = 0.2\n    float inputs:intensity = 3\n",
        [-1.95, 1.0, -0.5],
        [0.0, -90.0, 0.0],
    );
    s += &lux(
        "SphereLight",
        "Bulb",
        "    float inputs:radius = 0.1\n    float inputs:intensity = 4\n",
        [0.8, 0.5, 0.3],
        [0.0, 0.0, 0.0],
    );
    s += &lux(
        "CylinderLight",
        "Tube",
        "    float inputs:radius = 0.05\n    float inputs:length = 0.6\n    float inputs:intensity = 3\n",
        [-0.5, 1.5, 0.5],
        [0.0, 30.0, 0.0],
    );
    s += "def DomeLight \"Sky\"\n{\n    float inputs:intensity = 0.5\n}\n\n";
    s += &lux(
        "DistantLight",
        "Haze",
        "    float inputs:angle = 10\n    float inputs:intensity = 1\n",
        [0.0; 3],
        [-60.0, 0.0, 0.0],
    );
    s += &lux(
        "DistantLight",
        "Sun",
        "    float inputs:angle = 0\n    float inputs:intensity = 2\n",
        [0.0; 3],
        [-40.0, 30.0, 0.0],
    );
    s
}

/// A tunnel-like room (open towards a thin-lens camera, walls long enough that every camera
/// ray enters it) lit by one small, bright sphere light only, hidden from the camera behind a
/// panel with shading normals; diffuse walls of two colours. The light is kept away from
/// walls: hot spots close to a tiny light give the path tracer heavy-tailed pixel estimates,
/// whose batch variances a z-test cannot trust.
fn small_light_stage() -> String {
    small_light_stage_with("Grey")
}

/// [`small_light_stage`] with the tilted panel made of `panel_look` (e.g. a glossy conductor).
fn small_light_stage_with(panel_look: &str) -> String {
    let mut s = header();
    s += &camera_at(
        [0.0, 1.0, 3.5],
        0.4,
        "    float fStop = 8\n    float focusDistance = 4\n",
    );
    s += &looks();
    let walls: [(&str, [[f32; 3]; 4], &str); 5] = [
        (
            "Floor",
            [
                [-1.5, 0.0, 4.0],
                [1.5, 0.0, 4.0],
                [1.5, 0.0, -2.0],
                [-1.5, 0.0, -2.0],
            ],
            "White",
        ),
        (
            "Ceiling",
            [
                [-1.5, 2.0, 2.0],
                [-1.5, 2.0, -2.0],
                [1.5, 2.0, -2.0],
                [1.5, 2.0, 2.0],
            ],
            "White",
        ),
        (
            "Back",
            [
                [-1.5, 0.0, -2.0],
                [1.5, 0.0, -2.0],
                [1.5, 2.0, -2.0],
                [-1.5, 2.0, -2.0],
            ],
            "Grey",
        ),
        (
            "Left",
            [
                [-1.5, 0.0, 2.0],
                [-1.5, 0.0, -2.0],
                [-1.5, 2.0, -2.0],
                [-1.5, 2.0, 2.0],
            ],
            "Red",
        ),
        (
            "Right",
            [
                [1.5, 0.0, -2.0],
                [1.5, 0.0, 2.0],
                [1.5, 2.0, 2.0],
                [1.5, 2.0, -2.0],
            ],
            "Grey",
        ),
    ];
    for (name, points, look) in walls {
        s += &polygon(name, &points, None, &binding(look));
    }
    s += &polygon(
        "Panel",
        &[
            [0.2, 0.0, -0.6],
            [1.0, 0.0, 0.0],
            [1.0, 1.2, 0.0],
            [0.2, 1.2, -0.6],
        ],
        Some(&[
            [-0.5, 0.2, 0.8],
            [-0.8, -0.1, 0.6],
            [-0.6, 0.0, 0.7],
            [-0.4, 0.3, 0.8],
        ]),
        &binding(panel_look),
    );
    s += &lux(
        "SphereLight",
        "Bulb",
        "    float inputs:radius = 0.02\n    float inputs:intensity = 3000\n",
        [0.6, 0.7, -1.0],
        [0.0; 3],
    );
    s
}

fn render_with(
    scene: &Scene,
    integrator: Integrator,
    spp: u32,
    seed: u64,
    max_depth: u32,
) -> RenderOutput {
    render_sampled(
        scene,
        integrator,
        SamplerKind::default(),
        spp,
        seed,
        max_depth,
    )
}

fn render_sampled(
    scene: &Scene,
    integrator: Integrator,
    sampler: SamplerKind,
    spp: u32,
    seed: u64,
    max_depth: u32,
) -> RenderOutput {
    let (rr_depth, split) = roulette_start(scene, max_depth);
    let opts = RenderOptions {
        spp: Some(spp),
        seed,
        max_depth: Some(max_depth),
        rr_depth,
        split,
        integrator,
        sampler,
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap();
    assert_finite(&out);
    out
}

/// The path tracer's roulette start and split that `--rr-depth auto` and `--split auto`
/// choose for `scene` at seed 0, given to every seed's render: the batches of a z-test must be
/// identically distributed, and auto's pilot may choose differently at other seeds
/// (docs/design.md §8, "Where roulette starts, chosen per scene").
fn roulette_start(scene: &Scene, max_depth: u32) -> (RrStart, Split) {
    let auto = (RrStart::Auto, Split::Auto);
    let pilot = session::roulette::resolve(scene, &Integrator::Path, auto, max_depth, 0);
    (
        RrStart::At(pilot.as_ref().map_or(DEFAULT_RR_DEPTH, |r| r.start)),
        Split::At(pilot.as_ref().map_or(1, |r| r.split)),
    )
}

// ---------------------------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------------------------

#[test]
fn p_values_match_tables() {
    assert!((two_sided_p(1.959_964, 1e7) - 0.05).abs() < 1e-5);
    assert!((two_sided_p(2.042_272, 30.0) - 0.05).abs() < 1e-5);
    assert!((two_sided_p(4.0, 1e7) - 6.334e-5).abs() < 1e-7);
}

/// Per-pixel means of K independent renders and the variances of those means.
struct Batches {
    k: usize,
    mean: Vec<[f64; 3]>,
    var_mean: Vec<[f64; 3]>,
    /// Mean luminance of the image and its standard error.
    image_y: (f64, f64),
}

fn batches(
    scene: &Scene,
    integrator: Integrator,
    k: usize,
    spp: u32,
    max_depth: u32,
    seed_base: u64,
) -> Batches {
    batches_sampled(
        scene,
        integrator,
        SamplerKind::default(),
        k,
        spp,
        max_depth,
        seed_base,
    )
}

/// [`batches`] with the samples drawn by `sampler` (the path tracer's low-discrepancy
/// sequence or independent numbers): k independent seeds, so the batch means are
/// independent whatever the sampler.
fn batches_sampled(
    scene: &Scene,
    integrator: Integrator,
    sampler: SamplerKind,
    k: usize,
    spp: u32,
    max_depth: u32,
    seed_base: u64,
) -> Batches {
    let outs: Vec<Vec<[f32; 3]>> = (0..k)
        .map(|i| {
            let seed = seed_base + i as u64;
            render_sampled(scene, integrator, sampler, spp, seed, max_depth).xyz
        })
        .collect();
    let n = outs[0].len();
    let mut mean = vec![[0.0; 3]; n];
    let mut var_mean = vec![[0.0; 3]; n];
    for p in 0..n {
        for c in 0..3 {
            let (m, var) = mean_and_var(outs.iter().map(|o| o[p][c] as f64));
            mean[p][c] = m;
            var_mean[p][c] = var / k as f64;
        }
    }
    let (m, var) = mean_and_var(
        outs.iter()
            .map(|o| o.iter().map(|p| p[1] as f64).sum::<f64>() / n as f64),
    );
    Batches {
        k,
        mean,
        var_mean,
        image_y: (m, (var / k as f64).sqrt()),
    }
}

/// The outcome of per-pixel z-tests between two integrators.
#[derive(Debug)]
struct ZTest {
    tests: usize,
    /// (pixel, channel) of the largest |z|.
    worst: (usize, usize),
    max_abs_z: f64,
    min_p: f64,
    sidak_alpha: f64,
    image_z: f64,
}

impl ZTest {
    /// One line for the test's log: the worst pixel of `a` against `b`, the levels, and the
    /// image means.
    fn describe(&self, a: &Batches, b: &Batches) -> String {
        let (wp, wc) = self.worst;
        format!(
            "{} tests, max |z| {:.2} (pixel {wp} channel {wc}: {:.3e} ± {:.1e} vs {:.3e} ± {:.1e}), \
             min p {:.2e}, Šidák level {:.2e}; image Y {:.5} ± {:.5} vs {:.5} ± {:.5} (z {:.2})",
            self.tests,
            self.max_abs_z,
            a.mean[wp][wc],
            a.var_mean[wp][wc].sqrt(),
            b.mean[wp][wc],
            b.var_mean[wp][wc].sqrt(),
            self.min_p,
            self.sidak_alpha,
            a.image_y.0,
            a.image_y.1,
            b.image_y.0,
            b.image_y.1,
            self.image_z
        )
    }
}

/// z = Δ / sqrt(σ²_a + σ²_b) per pixel and XYZ channel, two-sided p from Student's t with the
/// Welch–Satterthwaite degrees of freedom; Šidák-corrected level for a family-wise α.
fn z_test(a: &Batches, b: &Batches, alpha: f64) -> ZTest {
    let mut max_abs_z = 0.0f64;
    let mut min_p = 1.0f64;
    let mut tests = 0;
    let mut worst = (0, 0);
    for p in 0..a.mean.len() {
        for c in 0..3 {
            let (va, vb) = (a.var_mean[p][c], b.var_mean[p][c]);
            let d = a.mean[p][c] - b.mean[p][c];
            let v = va + vb;
            tests += 1;
            if v == 0.0 {
                assert_eq!(
                    d, 0.0,
                    "pixel {p} channel {c}: zero variance but different means"
                );
                continue;
            }
            let z = d / v.sqrt();
            let df = v * v / (va * va / (a.k - 1) as f64 + vb * vb / (b.k - 1) as f64);
            if z.abs() > max_abs_z {
                max_abs_z = z.abs();
                worst = (p, c);
            }
            min_p = min_p.min(two_sided_p(z, df));
        }
    }
    let sidak_alpha = 1.0 - (1.0 - alpha).powf(1.0 / tests as f64);
    let image_z = (a.image_y.0 - b.image_y.0) / (a.image_y.1.powi(2) + b.image_y.1.powi(2)).sqrt();
    ZTest {
        tests,
        worst,
        max_abs_z,
        min_p,
        sidak_alpha,
        image_z,
    }
}

// ---------------------------------------------------------------------------------------------
// Agreement of PT, LT and BDPT
// ---------------------------------------------------------------------------------------------

/// One scene of the agreement and efficiency tables: rendered `batches` times at `spp` per
/// pixel by each integrator, seeds fixed.
struct SceneCase {
    name: &'static str,
    scene: fn() -> Scene,
    max_depth: u32,
    batches: usize,
    spp: u32,
}

/// The agreement scenes: adding one (e.g. a glossy conductor with a small bright light, once
/// that model exists) is one entry.
const AGREEMENT: &[SceneCase] = &[
    SceneCase {
        name: "cornell box",
        scene: || scene::load(&cbox_path(), Some((20, 20))).unwrap(),
        max_depth: 7,
        batches: 32,
        spp: 32,
    },
    SceneCase {
        name: "small bright light, thin lens, shading normals",
        scene: || load_text("small-light", &small_light_stage(), (20, 20)),
        max_depth: 7,
        batches: 32,
        spp: 64,
    },
    SceneCase {
        name: "glossy conductor (rough gold, GGX α 0.2) and a small bright light",
        scene: || load_text("glossy", &small_light_stage_with("Gold"), (20, 20)),
        max_depth: 7,
        // 64 batches of 96 samples rather than 32 of 192: the gold panel's highlights make
        // heavy-tailed pixels, whose variances 32 batches estimated too poorly for a 1 %
        // family-wise level (session 39: PT against BDPT at |z| 4.96 with the new split, and
        // BDPT against BDPT, which nothing changed, at 5.22 with other seeds); with 64 both
        // seed sets pass, max |z| 3.74 and 4.10 over the seven families.
        batches: 64,
        spp: 96,
    },
];

#[test]
fn path_light_and_bdpt_agree_per_pixel() {
    let alpha = 0.01;
    for case in AGREEMENT {
        let scene = (case.scene)();
        let run = |kind, base| batches(&scene, kind, case.batches, case.spp, case.max_depth, base);
        let pt = run(Integrator::Path, 1000);
        let pt_independent = batches_sampled(
            &scene,
            Integrator::Path,
            SamplerKind::Independent,
            case.batches,
            case.spp,
            case.max_depth,
            4000,
        );
        let lt = run(Integrator::Light, 2000);
        let bdpt = Integrator::Bdpt {
            mis: MisHeuristic::Power,
        };
        let bd = run(bdpt, 3000);
        // BDPT's camera subpaths draw from the sequence too; its independent numbers are
        // tested as well.
        let bd_independent = batches_sampled(
            &scene,
            bdpt,
            SamplerKind::Independent,
            case.batches,
            case.spp,
            case.max_depth,
            5000,
        );
        for (label, a, b) in [
            ("PT-LT", &pt, &lt),
            ("PT-BDPT", &pt, &bd),
            ("LT-BDPT", &lt, &bd),
            ("PT(independent)-BDPT", &pt_independent, &bd),
            ("PT(zsobol)-PT(independent)", &pt, &pt_independent),
            ("PT-BDPT(independent)", &pt, &bd_independent),
            ("BDPT(zsobol)-BDPT(independent)", &bd, &bd_independent),
        ] {
            let z = z_test(a, b, alpha);
            eprintln!("{}: {label}: {}", case.name, z.describe(a, b));
            assert!(
                z.min_p > z.sidak_alpha,
                "{}: {label} differ per pixel: {z:?}",
                case.name
            );
            assert!(
                z.image_z.abs() < 3.3,
                "{}: {label} image means differ: {z:?}",
                case.name
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Efficiency: BDPT against the path tracer it contains
// ---------------------------------------------------------------------------------------------

/// A caustic stage of `scenes/` (`caustic.usda`, `caustic-mirror.usda`: a glass ball focusing
/// a 3 cm SphereLight of 30000 nits) with the camera's focal length `focal` mm, zooming in on
/// the caustic, and the lamp's radius × 4 at the same power (radiance ÷ 16). The caustic keeps
/// its paths (L–S–S–D–E, E–S–D–S–S–L) but the path tracer's camera paths find the lamp 16 times
/// as often, so that a few hundred batches judge a variance ratio (with the 3 cm lamp the
/// variance of a batch's variance would need millions of samples).
fn caustic_stage(file: &str, focal: (&str, &str), res: (u32, u32)) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file);
    let text = std::fs::read_to_string(path).unwrap();
    let mut edited = text.clone();
    for (from, to) in [
        (
            format!("float focalLength = {}", focal.0),
            format!("float focalLength = {}", focal.1),
        ),
        (
            "float inputs:radius = 0.03".into(),
            "float inputs:radius = 0.12".into(),
        ),
        (
            "float inputs:intensity = 30000".into(),
            "float inputs:intensity = 1875".into(),
        ),
    ] {
        assert!(edited.contains(&from), "{file}: `{from}` not found");
        edited = edited.replace(&from, &to);
    }
    load_text(&format!("eff-{file}"), &edited, res)
}

/// The scenes of issue 17: BDPT's strategies include the path tracer's (s = 0, 1), so with a
/// sound MIS its variance per sample is never much above the path tracer's. The last two are
/// the SDS scenes VCM is also measured on (`scenes/README.md`).
const EFFICIENCY: &[SceneCase] = &[
    SceneCase {
        name: "cornell box",
        scene: || scene::load(&cbox_path(), Some((16, 16))).unwrap(),
        max_depth: 5,
        batches: 400,
        spp: 2,
    },
    SceneCase {
        name: "small light behind a panel",
        scene: || load_text("eff-small-light", &small_light_stage(), (16, 16)),
        max_depth: 5,
        batches: 400,
        spp: 2,
    },
    SceneCase {
        name: "glossy gold panel",
        scene: || load_text("eff-glossy", &small_light_stage_with("Gold"), (16, 16)),
        max_depth: 5,
        batches: 400,
        spp: 2,
    },
    SceneCase {
        name: "glass ball, caustic seen directly (caustic.usda)",
        scene: || caustic_stage("caustic.usda", ("35", "70"), (32, 24)),
        max_depth: 5,
        batches: 400,
        spp: 2,
    },
    SceneCase {
        name: "caustic seen in a mirror (caustic-mirror.usda)",
        scene: || caustic_stage("caustic-mirror.usda", ("24", "72"), (32, 24)),
        max_depth: 5,
        batches: 400,
        spp: 2,
    },
];

/// The image's mean luminance, one value per render of `spp` samples per pixel (seeds
/// `seed_base` + i, independent samplers): independent batch means of the pixel-mean estimator. Also the mean over
/// pixels of each pixel's variance per sample (for the log only: BDPT's splats make pixels
/// covary, which the batch means of the image mean include and a sum of pixels' would not).
fn image_means(
    scene: &Scene,
    integrator: Integrator,
    case: &SceneCase,
    seed_base: u64,
) -> (Vec<f64>, f64) {
    let mut sums: Vec<(f64, f64)> = Vec::new();
    let means = (0..case.batches)
        .map(|i| {
            // Independent numbers for every integrator: this compares estimators, not
            // samplers (the default low-discrepancy sequence lowers the variance of the path
            // tracer and of BDPT's camera subpaths further).
            let out = render_sampled(
                scene,
                integrator,
                SamplerKind::Independent,
                case.spp,
                seed_base + i as u64,
                case.max_depth,
            );
            sums.resize(out.xyz.len(), (0.0, 0.0));
            for (s, p) in sums.iter_mut().zip(&out.xyz) {
                let y = p[1] as f64;
                *s = (s.0 + y, s.1 + y * y);
            }
            out.xyz.iter().map(|p| p[1] as f64).sum::<f64>() / out.xyz.len() as f64
        })
        .collect();
    let k = case.batches as f64;
    let pixel_var = sums
        .iter()
        .map(|(s, s2)| (s2 - s * s / k) / (k - 1.0))
        .sum::<f64>()
        / sums.len() as f64;
    (means, pixel_var * case.spp as f64)
}

/// The unbiased sample variance s² of `x` and the variance of s² itself, from the sample's
/// fourth central moment: Var(s²) = (μ₄ − σ⁴ (n − 3)/(n − 1)) / n (Cramér 1946, §27.4),
/// which does not assume normal batch means (a caustic's are skewed).
fn variance_and_its_variance(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mean, s2) = mean_and_var(x.iter().copied());
    let m4 = x.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / n;
    (s2, ((m4 - s2 * s2 * (n - 3.0) / (n - 1.0)) / n).max(0.0))
}

/// ln(s²_a / s²_b) and its standard error by the delta method (Var ln s² ≈ Var s² / s⁴).
fn log_variance_ratio(a: &[f64], b: &[f64]) -> (f64, f64) {
    let (va, vva) = variance_and_its_variance(a);
    let (vb, vvb) = variance_and_its_variance(b);
    ((va / vb).ln(), (vva / (va * va) + vvb / (vb * vb)).sqrt())
}

/// Issue 17: on every scene of [`EFFICIENCY`], BDPT's variance per sample of the image's mean
/// luminance is at most 1.2 × the path tracer's: the test fails when the ratio's one-sided
/// lower confidence bound (z = 2.88, α = 0.01 over the five scenes by Šidák) exceeds 1.2.
/// Batch means with fixed seeds; the ratio's spread from the batches' own fourth moments.
#[test]
fn bdpt_variance_per_sample_is_at_most_the_path_tracers() {
    let z = 2.88;
    let limit = 1.2f64;
    let mut failures = Vec::new();
    for case in EFFICIENCY {
        let scene = (case.scene)();
        let pt = image_means(&scene, Integrator::Path, case, 10_000);
        let bd = image_means(
            &scene,
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
            case,
            20_000,
        );
        let ((pt, pt_pixel), (bd, bd_pixel)) = (pt, bd);
        let (ln_ratio, se) = log_variance_ratio(&bd, &pt);
        let (m_pt, m_bd) = (
            mean_and_sem(pt.iter().copied()),
            mean_and_sem(bd.iter().copied()),
        );
        let lower = (ln_ratio - z * se).exp();
        eprintln!(
            "{}: variance per sample of the image mean, BDPT/PT {:.3} (×/÷ {:.3} at 1σ; lower bound {:.3}); mean pixel variance BDPT/PT {:.3}; image Y PT {:.4e} ± {:.1e}, BDPT {:.4e} ± {:.1e}",
            case.name,
            ln_ratio.exp(),
            se.exp(),
            lower,
            bd_pixel / pt_pixel,
            m_pt.0,
            m_pt.1,
            m_bd.0,
            m_bd.1
        );
        if lower > limit {
            failures.push(case.name);
        }
    }
    assert!(
        failures.is_empty(),
        "BDPT noisier per sample than 1.2 × PT on {failures:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// VCM against BDPT
// ---------------------------------------------------------------------------------------------

/// VCM in `mode` with base radius `radius` (metres; None: its default) and α = 0.75, merging
/// at every non-specular vertex (`MergeRule::All`: on these diffuse and glossy scenes the
/// default rule merges nothing; the rule has its own test,
/// [`vcm_merging_after_near_specular_vertices_agrees_with_bdpt_per_pixel`]).
fn vcm(mode: VcmMode, radius: Option<f32>) -> Integrator {
    Integrator::Vcm(VcmParams {
        mode,
        radius,
        merges: MergeRule::All,
        ..VcmParams::default()
    })
}

/// `vc` is BDPT: the same estimator, bit for bit, for the same seed and samples, with either
/// sampler (the two samplers' images differ).
#[test]
fn vcm_without_merging_is_bdpt_bit_for_bit() {
    let scene = scene::load(&cbox_path(), Some((16, 16))).unwrap();
    let bdpt = Integrator::Bdpt {
        mis: MisHeuristic::Balance,
    };
    let vc = Integrator::Vcm(VcmParams {
        mode: VcmMode::Vc,
        mis: MisHeuristic::Balance,
        ..VcmParams::default()
    });
    let bits = |k, sampler| {
        let out = render_sampled(&scene, k, sampler, 8, 11, 7);
        out.xyz
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    for sampler in SamplerKind::ALL {
        assert_eq!(bits(bdpt, sampler), bits(vc, sampler), "{sampler:?}");
    }
    assert_ne!(
        bits(bdpt, SamplerKind::ZSobol),
        bits(bdpt, SamplerKind::Independent)
    );
}

/// VCM (connections and merges) agrees with BDPT per pixel on the Cornell box and on the
/// glossy scene (rough gold, GGX α 0.2, lit by a small bright light) at 20² pixels, at a base
/// radius of 1 cm. (Photon mapping alone, `vm`, needs far more light paths per pixel at such a
/// radius than 400 per iteration; its closed-form test is the mirror caustic of
/// `tests/vcm.rs`.)
///
/// Bias bound: a merge estimates the light arriving at a camera vertex averaged over a disk
/// of radius r (the uniform kernel), which differs from its centre value by
/// r²/8 · |Δ_surface E| / E relative. In the box the irradiance varies on the scale of the
/// lamp's distance, ℓ ≳ 0.25 m, so |ΔE|/E ≲ 6/ℓ² and the bias is below
/// (0.01 m)² · 6 / (8 · 0.0625 m²) ≈ 1.2e-3 relative; in the glossy scene the small light
/// stands ℓ ≳ 0.5 m from every surface the camera sees, so the bound is ≈ 3e-4. Merges at the
/// glossy gold vertices blur the same way (the kernel is spatial; the BSDF is evaluated at the
/// camera vertex for the light vertex's direction). Both shrink as r² with the iterations'
/// radius and lie far below the per-pixel intervals here (≈ 2–5 %), so the z-tests see only
/// noise. Near edges and corners (within r of an edge, 0.5 % of a wall's width) the bound
/// does not hold; those are a few pixels' fractions and stay within the intervals.
#[test]
fn vcm_agrees_with_bdpt_per_pixel() {
    for case in [&AGREEMENT[0], &AGREEMENT[2]] {
        let scene = (case.scene)();
        // VCM and BDPT share their heavy-tailed strategies, so 64 spp per batch do here.
        let spp = case.spp.min(64);
        let run = |kind, base| batches(&scene, kind, case.batches, spp, case.max_depth, base);
        let bd = run(
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
            3000,
        );
        // VCM's camera subpaths draw from the default sequence, or from independent numbers.
        for (sampler, base) in [
            (SamplerKind::ZSobol, 4000),
            (SamplerKind::Independent, 6000),
        ] {
            let label = format!("VCM({})-BDPT, {}", sampler.name(), case.name);
            let v = batches_sampled(
                &scene,
                vcm(VcmMode::Vcm, Some(0.01)),
                sampler,
                case.batches,
                spp,
                case.max_depth,
                base,
            );
            let z = z_test(&v, &bd, 0.01);
            eprintln!("{label}: {}", z.describe(&v, &bd));
            assert!(z.min_p > z.sidak_alpha, "{label} differ per pixel: {z:?}");
            assert!(z.image_z.abs() < 3.3, "{label} image means differ: {z:?}");
        }
    }
}

/// VCM merging only after near-specular vertices (`MergeRule::Caustic`) agrees with BDPT per
/// pixel where that rule merges: the small-light scene with its tilted panel a near-specular
/// glossy silver (GGX α 0.06 < `NEAR_SPECULAR_ALPHA`), whose reflection of the light lands on
/// the diffuse walls (L S D paths: merged after the panel, connected elsewhere), at 20²
/// pixels and a base radius of 1 cm. The bias bound is that of
/// [`vcm_agrees_with_bdpt_per_pixel`], for light of the panel's spread; the store keeps
/// only the light vertices after the panel, and the camera subpaths decide their merge terms
/// one vertex late, which this checks in the renderer as the brute-force MIS check does for
/// the weights.
#[test]
fn vcm_merging_after_near_specular_vertices_agrees_with_bdpt_per_pixel() {
    let scene = load_text("satin", &small_light_stage_with("Satin"), (20, 20));
    let (batches_n, spp, depth) = (32, 32, 7);
    let bd = batches(
        &scene,
        Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
        batches_n,
        spp,
        depth,
        3000,
    );
    let caustic = Integrator::Vcm(VcmParams {
        mode: VcmMode::Vcm,
        radius: Some(0.01),
        merges: MergeRule::Caustic,
        ..VcmParams::default()
    });
    let v = batches(&scene, caustic, batches_n, spp, depth, 4000);
    let z = z_test(&v, &bd, 0.01);
    let label = "VCM (merges caustic)-BDPT, near-specular panel";
    eprintln!("{label}: {}", z.describe(&v, &bd));
    assert!(z.min_p > z.sidak_alpha, "{label} differ per pixel: {z:?}");
    assert!(z.image_z.abs() < 3.3, "{label} image means differ: {z:?}");
}

// ---------------------------------------------------------------------------------------------
// MIS: recurrence against brute force
// ---------------------------------------------------------------------------------------------

/// [`every_light_stage`] with a smooth silver mirror in front of the back wall, a smooth glass
/// pane (IOR 1.5) standing on the floor and a smooth glass ball (IOR 1.5) before the mirror:
/// paths through delta (specular) vertices, up to three and more in sequence (into the ball,
/// out of it, off the mirror).
fn specular_stage() -> String {
    let mut s = every_light_stage();
    s += &prim(
        "Sphere",
        "Ball",
        &format!(
            "    double radius = 0.35\n{}{}",
            xform(&[("translate", "(-0.9, 0.6, -1.3)".into())]),
            binding("Glass")
        ),
    )
    .replacen(
        "\n{",
        &format!(" (\n    prepend apiSchemas = [{BINDING_API}]\n)\n{{"),
        1,
    );
    s += &polygon(
        "Mirror",
        &[
            [-1.6, 0.2, -1.9],
            [-0.2, 0.2, -1.9],
            [-0.2, 1.6, -1.9],
            [-1.6, 1.6, -1.9],
        ],
        None,
        &binding("Mirror"),
    );
    s += &polygon(
        "Pane",
        &[
            [-0.4, 0.0, 0.9],
            [0.9, 0.0, 0.6],
            [0.9, 1.2, 0.6],
            [-0.4, 1.2, 0.9],
        ],
        None,
        &binding("Glass"),
    );
    // A near-specular (GGX α 0.06 < `NEAR_SPECULAR_ALPHA`) glossy silver sheet on the floor:
    // a non-delta vertex after which VCM's caustic rule merges.
    s += &polygon(
        "Satin",
        &[
            [0.5, 0.01, -0.1],
            [1.4, 0.01, -0.1],
            [1.4, 0.01, -1.4],
            [0.5, 0.01, -1.4],
        ],
        None,
        &binding("Satin"),
    );
    s
}

/// The light end x_0 of a full path.
#[derive(Clone, Copy, Debug)]
enum LightEnd {
    /// A point on a finite light with the light's geometric (front) normal.
    Point { p: Vec3, n: Vec3 },
    /// An infinite light seen along `to_light` from x_1.
    Direction { to_light: Vec3 },
}

/// The sensor end x_{n−1} of a full path: the camera's lens centre or a meter.
#[derive(Clone, Copy, Debug)]
enum SensorEnd {
    Camera(Vec3),
    Meter(MeterSensor),
}

impl SensorEnd {
    /// An irradiance meter, which VCM also merges at.
    fn merges_at_point(&self) -> bool {
        matches!(self, SensorEnd::Meter(m) if !m.delta_direction())
    }

    fn p(&self) -> Vec3 {
        match self {
            SensorEnd::Camera(p) => *p,
            SensorEnd::Meter(m) => m.p,
        }
    }

    /// Brute force: the density per solid angle with which the sensor's own rays take unit
    /// direction `w` — the camera's PDF_We, cos θ/π for an irradiance meter — or None for
    /// the delta direction of a luminance meter.
    fn pdf_dir(&self, scene: &Scene, w: Vec3) -> Option<f64> {
        match self {
            SensorEnd::Camera(p) => Some(scene.camera.pdf_we(*p, w).1 as f64),
            SensorEnd::Meter(m) if m.kind == MeterKind::Luminance => None,
            SensorEnd::Meter(m) => Some((w.dot(m.dir) as f64).max(0.0) / std::f64::consts::PI),
        }
    }

    /// (1, 1) for an infinite light exists only for an irradiance meter.
    fn connects_infinite_lights(&self) -> bool {
        matches!(self, SensorEnd::Meter(m) if m.kind == MeterKind::Illuminance)
    }

    fn delta_direction(&self) -> bool {
        matches!(self, SensorEnd::Meter(m) if m.kind == MeterKind::Luminance)
    }

    /// The production context with this sensor.
    fn context<'a>(&self, base: &BidirContext<'a>) -> BidirContext<'a> {
        match self {
            SensorEnd::Camera(_) => *base,
            SensorEnd::Meter(m) => base.with_sensor(Sensor::Meter(*m)),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            SensorEnd::Camera(_) => "camera",
            SensorEnd::Meter(m) => m.kind.name(),
        }
    }
}

/// A full path: x_0 on light `light`, surface vertices x_1 … x_{n−2} (light to sensor order)
/// and the sensor point x_{n−1}.
struct FullPath {
    light: u32,
    end: LightEnd,
    surfaces: Vec<SurfaceHit>,
    sensor: SensorEnd,
}

impl FullPath {
    fn n(&self) -> usize {
        self.surfaces.len() + 2
    }

    fn p(&self, i: usize) -> Vec3 {
        let n = self.n();
        if i == n - 1 {
            self.sensor.p()
        } else if i == 0 {
            match self.end {
                LightEnd::Point { p, .. } => p,
                LightEnd::Direction { .. } => unreachable!("x_0 at infinity"),
            }
        } else {
            self.surfaces[i - 1].p
        }
    }

    /// Unit direction from x_i to x_j (for x_0 at infinity: its direction).
    fn dir(&self, i: usize, j: usize) -> Vec3 {
        match (self.end, i, j) {
            (LightEnd::Direction { to_light }, _, 0) => to_light,
            (LightEnd::Direction { to_light }, 0, _) => -to_light,
            _ => (self.p(j) - self.p(i)).normalize(),
        }
    }

    fn infinite(&self) -> bool {
        matches!(self.end, LightEnd::Direction { .. })
    }

    /// Per vertex: true for a surface vertex whose BSDF is a pure delta (smooth mirror, glass).
    fn specular(&self, scene: &Scene) -> Vec<bool> {
        let mut lambda = SampledWavelengths::sample_visible(0.5);
        (0..self.n())
            .map(|i| {
                (1..self.n() - 1).contains(&i)
                    && bsdf_at(scene, &self.surfaces[i - 1], FINEST, &mut lambda).is_specular()
            })
            .collect()
    }

    /// Per vertex: true for a surface vertex that is near-specular (a delta BSDF, or a
    /// material with a delta or near-specular lobe: the one definition,
    /// `merge_rule::near_specular`); never the light x_0 or the sensor.
    fn near_specular(&self, scene: &Scene) -> Vec<bool> {
        let mut lambda = SampledWavelengths::sample_visible(0.5);
        (0..self.n())
            .map(|i| {
                (1..self.n() - 1).contains(&i) && {
                    let si = &self.surfaces[i - 1];
                    near_specular(scene, si, &bsdf_at(scene, si, FINEST, &mut lambda))
                }
            })
            .collect()
    }

    /// Brute force: merging at x_i (1 ≤ i ≤ n − 1; n − 1 an irradiance meter's point) exists
    /// under `rule`: at a non-specular vertex, and under the caustic rule only when x_{i−1},
    /// its light-order predecessor, is near-specular (x_0, the light, never is).
    fn merge_available(&self, scene: &Scene, rule: MergeRule, i: usize) -> bool {
        let n = self.n();
        if i == 0 || i >= n || (i < n - 1 && self.specular(scene)[i]) {
            return false;
        }
        match rule {
            MergeRule::All => true,
            MergeRule::Caustic => self.near_specular(scene)[i - 1],
        }
    }

    /// The longest run of consecutive specular surface vertices.
    fn specular_run(&self, scene: &Scene) -> usize {
        let mut run = 0;
        let mut longest = 0;
        for s in self.specular(scene) {
            run = if s { run + 1 } else { 0 };
            longest = longest.max(run);
        }
        longest
    }

    /// Brute force, from evaluation alone: technique s (1 ≤ s ≤ n − 1) cannot produce this
    /// path when joining x_{s−1} to x_s has a zero value along the path's own directions —
    /// a BSDF evaluated there is 0, as it is for every direction of a delta lobe, or the sensor
    /// (t = 1) has a delta direction — whatever `is_specular` says (Veach 1997 §10.3.5: such a
    /// technique has p_s = 0).
    fn cannot_connect(&self, scene: &Scene, s: usize) -> bool {
        let n = self.n();
        if s == 0 {
            return false;
        }
        let mut lambda = SampledWavelengths::sample_visible(0.5);
        let mut f_zero = |i: usize| {
            let b = bsdf_at(scene, &self.surfaces[i - 1], FINEST, &mut lambda);
            b.f(
                self.dir(i, i + 1),
                self.dir(i, i - 1),
                TransportMode::Radiance,
            )
            .is_black()
        };
        (s >= 2 && f_zero(s - 1))
            || (s <= n - 2 && f_zero(s))
            || (s == n - 1 && self.sensor.delta_direction())
    }

    /// True when technique s joins its subpaths at a delta vertex (a specular surface, or the
    /// delta-direction sensor for t = 1): f (or W) is 0 there for every connecting direction,
    /// so p_s = 0 (Veach 1997 §10.3.5). This is the integrators' rule (specular vertices are
    /// neither stored nor connected); [`FullPath::cannot_connect`] is the brute force's.
    fn connects_at_delta(&self, s: usize, specular: &[bool]) -> bool {
        let n = self.n();
        s >= 1
            && (specular[s - 1]
                || (s <= n - 2 && specular[s])
                || (s == n - 1 && self.sensor.delta_direction()))
    }
}

/// The light's front normal at point `p` (outward for spheres and cylinders).
fn light_normal(light: &Light, p: Vec3) -> Vec3 {
    match light {
        Light::Triangle(t) => t.n,
        Light::Rect(r) => r.n,
        Light::Disk(d) => d.frame.n,
        Light::Sphere(s) => (p - s.center).normalize(),
        Light::Cylinder(c) => {
            let v = p - c.center;
            (v - c.frame.n * v.dot(c.frame.n)).normalize()
        }
        _ => Vec3::ZERO,
    }
}

/// The sensor's first ray: through a random pixel of the camera, or the meter's own ray.
fn sensor_ray(scene: &Scene, sensor: &SensorEnd, sampler: &mut Sampler) -> Option<(Ray, f32)> {
    match sensor {
        SensorEnd::Camera(_) => {
            let cam = &scene.camera;
            let film = [
                sampler.get_1d() * cam.width as f32,
                sampler.get_1d() * cam.height as f32,
            ];
            Some(cam.generate_ray(film, [0.5; 2]))
        }
        SensorEnd::Meter(m) => Some((m.generate_ray(sampler.get_2d())?.ray, f32::INFINITY)),
    }
}

/// Follows `ray` to an emitter: a light shape, an emissive surface, or (escaping) an
/// infinite light chosen uniformly among those that shine along it.
fn trace_to_emitter(
    scene: &Scene,
    ray: &Ray,
    t: f32,
    lambda: &SampledWavelengths,
    sampler: &mut Sampler,
) -> Option<(u32, LightEnd)> {
    match scene.intersect(ray, t) {
        Some(Hit::Light { light, hit }) => Some((light, LightEnd::Point { p: hit.p, n: hit.n })),
        Some(Hit::Surface(si)) => {
            let light = si.light?;
            let hit = LightHit {
                p: si.p,
                n: si.ng,
                t: si.t,
            };
            if scene.lights[light as usize]
                .l(&hit, -ray.d, lambda)
                .is_black()
            {
                return None;
            }
            Some((light, LightEnd::Point { p: si.p, n: si.ng }))
        }
        None => {
            let d = ray.d.normalize();
            let shining: Vec<u32> = scene
                .infinite_lights
                .iter()
                .copied()
                .filter(|&i| !scene.lights[i as usize].le(d, lambda).is_black())
                .collect();
            let k = (sampler.get_1d() * shining.len() as f32) as usize;
            let light = *shining.get(k.min(shining.len().max(1) - 1))?;
            Some((light, LightEnd::Direction { to_light: d }))
        }
    }
}

/// A random full path of `k` surface vertices from `sensor` (None when this try failed): a
/// walk by BSDF sampling (specular vertices included), closed by a light point or direction
/// that illuminates the last vertex — or, when that vertex is specular (or, for k = 0, half
/// the time), by following the walk's last ray to an emitter. Visibility of a closing segment
/// found by light sampling is not required (weights do not depend on it).
fn random_path(
    scene: &Scene,
    sensor: &SensorEnd,
    k: usize,
    sampler: &mut Sampler,
) -> Option<FullPath> {
    let (mut ray, mut t) = sensor_ray(scene, sensor, sampler)?;
    let mut lambda = SampledWavelengths::sample_visible(sampler.get_1d());
    let mut surfaces = Vec::new();
    let mut last_specular = false;
    for _ in 0..k {
        let Some(Hit::Surface(si)) = scene.intersect(&ray, t) else {
            return None;
        };
        let bsdf = bsdf_at(scene, &si, FINEST, &mut lambda);
        let bs = bsdf.sample_f(
            -ray.d,
            sampler.get_1d(),
            sampler.get_2d(),
            TransportMode::Radiance,
        )?;
        surfaces.push(si);
        last_specular = bsdf.is_specular();
        ray = spawn_ray(si.p, si.p_error, si.ng, bs.wi);
        t = f32::INFINITY;
    }
    surfaces.reverse();
    let meter_normal = match sensor {
        SensorEnd::Meter(m) if m.kind == MeterKind::Illuminance => Some(m.dir),
        _ => None,
    };
    let trace = last_specular || (k == 0 && (meter_normal.is_none() || sampler.get_1d() < 0.5));
    if trace {
        let (light, end) = trace_to_emitter(scene, &ray, t, &lambda, sampler)?;
        return Some(FullPath {
            light,
            end,
            surfaces,
            sensor: *sensor,
        });
    }
    // Close on a light seen from x_1 (from the meter point when k = 0), which must illuminate
    // it from the side of its BSDF (of the meter's normal). Lights uniformly, so that weak
    // lights are checked as often as bright ones.
    let (p1, n1) = match surfaces.first() {
        Some(x1) => (x1.p, x1.ng),
        None => (sensor.p(), meter_normal?),
    };
    let li = ((sampler.get_1d() * scene.lights.len() as f32) as usize).min(scene.lights.len() - 1);
    let light = &scene.lights[li];
    let ctx = LightSampleContext { p: p1, n: n1 };
    let ls = light.sample_li(&ctx, sampler.get_2d(), &lambda)?;
    if ls.l.is_black() {
        return None;
    }
    let end = if ls.infinite {
        LightEnd::Direction { to_light: ls.wi }
    } else {
        LightEnd::Point {
            p: ls.p_light,
            n: light_normal(light, ls.p_light),
        }
    };
    let lit = match surfaces.first() {
        Some(x1) => {
            let wo = match surfaces.get(1) {
                Some(x2) => (x2.p - x1.p).normalize(),
                None => (sensor.p() - x1.p).normalize(),
            };
            let bsdf = bsdf_at(scene, x1, FINEST, &mut lambda);
            !bsdf.f(wo, ls.wi, TransportMode::Radiance).is_black()
        }
        None => ls.wi.dot(n1) > 0.0,
    };
    lit.then_some(FullPath {
        light: li as u32,
        end,
        surfaces,
        sensor: *sensor,
    })
}

/// Brute force: p_s for s = 0 … n−1 as products of per-vertex area (or, for x_0 at
/// infinity, solid-angle) densities (Veach 1997 §10.2, eq. 10.9). A delta vertex (specular
/// surface, luminance meter's direction) contributes the same Dirac factor to every technique
/// that samples through it, so its density is taken as 1 — it cancels in m(p_s)/Σ m(p_j) —
/// with the area conversion kept; techniques that connect at it have p_s = 0
/// (Veach 1997 §10.3.5; Georgiev 2012 tech. rep. (53)–(55) is the same rule as a recurrence).
fn technique_pdfs(ctx: &BidirContext, path: &FullPath) -> Techniques {
    let scene = ctx.scene;
    let n = path.n();
    let li = path.light as usize;
    let light = &scene.lights[li];
    let pmf = scene.light_sampler.pmf(li) as f64;
    let specular = path.specular(scene);
    let mut lambda = SampledWavelengths::sample_visible(0.5);
    // The BSDF density at x_i from x_{i_from} to x_{i_to}: 1 for a delta (see above).
    let bsdf_pdf = |i: usize, from: usize, to: usize, mode, lambda: &mut SampledWavelengths| {
        if specular[i] {
            return 1.0;
        }
        let b = bsdf_at(scene, &path.surfaces[i - 1], FINEST, lambda);
        b.pdf(path.dir(i, from), path.dir(i, to), mode) as f64
    };
    let ng = |i: usize| -> Vec3 {
        match (i, path.end, &path.sensor) {
            (0, LightEnd::Point { n, .. }, _) => n,
            (i, _, SensorEnd::Meter(m)) if i == n - 1 => m.dir,
            _ => path.surfaces[i - 1].ng,
        }
    };
    // Converts a direction density at x_from into a density at x_to.
    let to_area = |pdf_w: f64, from: usize, to: usize| -> f64 {
        if to == 0 && path.infinite() {
            return pdf_w;
        }
        let d = path.p(to) - path.p(from);
        pdf_w * ng(to).dot(d.normalize()).abs() as f64 / d.length_squared() as f64
    };
    let (p0, n0) = match path.end {
        LightEnd::Point { p, n } => (p, n),
        LightEnd::Direction { .. } => (Vec3::ZERO, Vec3::ZERO),
    };
    let le = light.pdf_le(p0, n0, path.dir(0, 1), &ctx.sphere);
    // Forward densities (light side) of x_i for techniques with s > i.
    let forward = |i: usize, s: usize, lambda: &mut SampledWavelengths| -> f64 {
        match i {
            0 if s == 1 && n >= 3 => {
                let wi = path.dir(1, 0);
                let rctx = LightSampleContext {
                    p: path.p(1),
                    n: ng(1),
                };
                let hit = LightHit {
                    p: p0,
                    n: n0,
                    t: 0.0,
                };
                let pdf_w = if light.is_delta() {
                    1.0
                } else {
                    light.pdf_li(&rctx, wi, &hit) as f64
                };
                to_area(pmf * pdf_w, 1, 0)
            }
            // (1, 1) for an infinite light: its emitted direction, where the sensor takes it.
            0 if path.infinite() && s == 1 && !path.sensor.connects_infinite_lights() => 0.0,
            0 if path.infinite() => pmf * le.dir_w as f64,
            0 => pmf * le.pos_a as f64,
            1 if path.infinite() => le.pos_a as f64 * ng(1).dot(path.dir(0, 1)).abs() as f64,
            1 => to_area(le.dir_w as f64, 0, 1),
            _ => {
                let pdf = bsdf_pdf(i - 1, i - 2, i, TransportMode::Importance, lambda);
                to_area(pdf, i - 1, i)
            }
        }
    };
    // Reverse densities (sensor side) of x_i for techniques with s ≤ i.
    let reverse = |i: usize, lambda: &mut SampledWavelengths| -> f64 {
        if i == n - 1 {
            return 1.0; // the sensor point: the same density for every technique with t ≥ 1
        }
        if i == 0 && light.is_delta() {
            return 0.0;
        }
        if i == n - 2 {
            let pdf_dir = path
                .sensor
                .pdf_dir(scene, path.dir(n - 1, i))
                .unwrap_or(1.0);
            return to_area(pdf_dir, n - 1, i);
        }
        let pdf = bsdf_pdf(i + 1, i + 2, i, TransportMode::Radiance, lambda);
        to_area(pdf, i + 1, i)
    };
    let connections = (0..n)
        .map(|s| {
            if path.cannot_connect(scene, s) {
                return 0.0;
            }
            let f: f64 = (0..s).map(|i| forward(i, s, &mut lambda)).product();
            let r: f64 = (s..n).map(|i| reverse(i, &mut lambda)).product();
            f * r
        })
        .collect();
    // Merging at x_i (1 ≤ i ≤ n − 2, non-specular): both subpaths sample x_i, the light one
    // forward (as technique s = i + 1) and the camera one in reverse; times η in the caller
    // [tech. rep. (19), (20)].
    let rule = ctx.mis.merge_rule;
    let merges = (0..n)
        .map(|i| {
            if i + 1 >= n || !path.merge_available(scene, rule, i) {
                return 0.0;
            }
            let f: f64 = (0..=i).map(|j| forward(j, i + 1, &mut lambda)).product();
            let r: f64 = (i..n).map(|j| reverse(j, &mut lambda)).product();
            f * r
        })
        .collect();
    // Merging at an irradiance meter's point: the light subpath covers every vertex, the
    // last one landing within the radius of the meter (its cosine at the meter's normal).
    let sensor_merge = match &path.sensor {
        // Light vertices of depth ≥ 2 only (`bidir::connect::sensor_merge`).
        SensorEnd::Meter(m)
            if !m.delta_direction() && n >= 3 && path.merge_available(scene, rule, n - 1) =>
        {
            (0..n).map(|j| forward(j, n, &mut lambda)).product()
        }
        _ => 0.0,
    };
    Techniques {
        connections,
        merges,
        sensor_merge,
    }
}

/// The densities of a path's techniques: connection s (s light vertices) at `connections[s]`,
/// merging at x_i at `merges[i]` (without the factor η).
struct Techniques {
    connections: Vec<f64>,
    merges: Vec<f64>,
    /// Merging at an irradiance meter's point (0 for other sensors), without η.
    sensor_merge: f64,
}

/// Production weights for every technique of `path`: the subpaths are replayed through the
/// integrators' own walk, MIS update and weight functions.
fn recurrent_weights(ctx: &BidirContext, path: &FullPath) -> Vec<f64> {
    let mut ctx = path.sensor.context(ctx);
    ctx.sensor_merges = path.sensor.merges_at_point() && ctx.mis.vm_weight > 0.0;
    let specular = path.specular(ctx.scene);
    (0..path.n())
        .map(|s| {
            // The integrators never evaluate these: specular vertices are neither stored on
            // light subpaths nor connected from camera subpaths, and a luminance meter's
            // `sample_wi` is None.
            if path.connects_at_delta(s, &specular) {
                0.0
            } else {
                recurrent_weight(&ctx, path, s, Replay::Connect) as f64
            }
        })
        .collect()
}

/// The production weight of merging the light subpath's last vertex at an irradiance meter's
/// point (0 for other sensors).
fn recurrent_sensor_merge_weight(ctx: &BidirContext, path: &FullPath) -> f64 {
    if !path.sensor.merges_at_point() || path.n() < 3 {
        return 0.0;
    }
    let mut ctx = path.sensor.context(ctx);
    ctx.sensor_merges = true;
    recurrent_weight(&ctx, path, path.n(), Replay::SensorMerge) as f64
}

/// Production weights of merging at every x_i of `path` (0 where no merge can happen: the
/// ends and specular vertices), index i.
fn recurrent_merge_weights(ctx: &BidirContext, path: &FullPath) -> Vec<f64> {
    let mut ctx = path.sensor.context(ctx);
    ctx.sensor_merges = path.sensor.merges_at_point() && ctx.mis.vm_weight > 0.0;
    let specular = path.specular(ctx.scene);
    let n = path.n();
    (0..n)
        .map(|i| {
            if i == 0 || i + 1 >= n || specular[i] {
                0.0
            } else {
                recurrent_weight(&ctx, path, i + 1, Replay::Merge) as f64
            }
        })
        .collect()
}

/// Which technique `recurrent_weight` replays.
#[derive(Clone, Copy, PartialEq)]
enum Replay {
    /// Connection s.
    Connect,
    /// Merging at x_{s−1}: the light walk reaches x_{s−1}, the camera walk too.
    Merge,
    /// Merging at an irradiance meter's point (s = n): the light walk reaches the meter.
    SensorMerge,
}

/// The production weight of technique s of `path` (see [`Replay`]).
fn recurrent_weight(ctx: &BidirContext, path: &FullPath, s: usize, replay: Replay) -> f32 {
    let scene = ctx.scene;
    let n = path.n();
    let t = n - s;
    let merge = replay == Replay::Merge;
    let camera_end = if merge { t + 1 } else { t };
    let li = path.light;
    let light = &scene.lights[li as usize];
    let pmf = scene.light_sampler.pmf(li as usize);
    let mut lambda = SampledWavelengths::sample_visible(0.5);
    // The vertex as the walks build it (`Walk::vertex`: its merge flags, and a camera
    // walk's pending merge term decided), along the path's own direction back.
    let vertex = |i: usize, wo: Vec3, walk: &mut Walk, lambda: &mut SampledWavelengths| {
        let si = &path.surfaces[i - 1];
        let mut v: PathVertex = walk.vertex(ctx, si, bsdf_at(scene, si, FINEST, lambda));
        v.wo = wo;
        v
    };
    // Leaves `v` towards `wi` as the walk would have sampled it (a delta lobe: specular, with
    // a density that cancels, as `Walk::advance` assumes).
    let step = |walk: &mut Walk, v: &PathVertex, wi: Vec3, mode: TransportMode| {
        let bs = if v.bsdf.is_specular() {
            BsdfSample::reflection(
                spectral_render::spectral::SampledSpectrum::ONE,
                wi,
                1.0,
                true,
            )
        } else {
            BsdfSample::reflection(
                v.bsdf.f(v.wo, wi, mode),
                wi,
                v.bsdf.pdf(v.wo, wi, mode),
                false,
            )
        };
        walk.advance(&ctx.mis, v, bs, mode);
    };
    // Light side y_0 … y_{s−1} = x_0 … x_{s−1}.
    let mut light_vertex = None;
    let mut origin = None;
    if s >= 1 {
        let (p, n0) = match path.end {
            LightEnd::Point { p, n } => (p, n),
            LightEnd::Direction { .. } => (path.p(1) + 10.0 * path.dir(1, 0), path.dir(0, 1)),
        };
        let w = path.dir(0, 1);
        let pdf = light.pdf_le(p, n0, w, &ctx.sphere);
        let le = LightLeSample {
            p,
            p_error: Vec3::ZERO,
            n: n0,
            w,
            l: spectral_render::spectral::SampledSpectrum::ONE,
            pdf_pos_a: pdf.pos_a,
            pdf_dir_w: pdf.dir_w,
            delta_dir: light.is_delta() && !light.is_delta_position(),
            delta_pos: light.is_delta_position(),
            infinite: path.infinite(),
        };
        let o =
            LightOrigin::new(li, pmf, &le).unwrap_or_else(|| panic!("emission: light {li} {le:?}"));
        let mut walk =
            Walk::light(ctx, &o, &le).unwrap_or_else(|| panic!("emission: light {li} {le:?}"));
        origin = Some(o);
        for i in 1..s {
            // The surface point x_i, or the meter's point for the last of a sensor merge.
            let (p_i, n_i) = match &path.sensor {
                SensorEnd::Meter(m) if i == n - 1 => (m.p, m.dir),
                _ => (path.surfaces[i - 1].p, path.surfaces[i - 1].ng),
            };
            if i == 1 {
                let direct = first_hit_direct(ctx, &o, p_i, n_i, walk.ray.d);
                walk.mis.light_direct(&ctx.mis, direct);
            } else {
                let prev = light_vertex.unwrap();
                step(
                    &mut walk,
                    &prev,
                    path.dir(i - 1, i),
                    TransportMode::Importance,
                );
            }
            walk.arrive(&ctx.mis, p_i, n_i);
            if replay == Replay::SensorMerge && i == n - 1 {
                let SensorEnd::Meter(m) = &path.sensor else {
                    unreachable!("a sensor merge needs a meter");
                };
                // The store keeps only vertices merging is available at.
                if !walk.arrival_merges {
                    return 0.0;
                }
                let wo = path.dir(i, i - 1);
                let y = MergeVertex {
                    p: p_i,
                    wo,
                    beta: walk.beta,
                    dvcm: walk.mis.dvcm,
                    dvm: walk.mis.dvm,
                    cos_ng: n_i.dot(wo).abs(),
                    depth: i as u32,
                    mesh: 0,
                    n: n_i,
                    hero_only: false,
                };
                return sensor_merge_weight(&ctx.mis, m, &y);
            }
            light_vertex = Some(vertex(i, path.dir(i, i - 1), &mut walk, &mut lambda));
        }
    }
    // Sensor side z_0 … z_{t−1} = x_{n−1} … x_s, and the weight.
    let sensor_p = path.sensor.p();
    let sr = SensorRay {
        ray: Ray::new(sensor_p, path.dir(n - 1, n - 2)),
        t_max: f32::INFINITY,
        p: sensor_p,
    };
    let mut walk = Walk::sensor(ctx, &sr).expect("sensor ray");
    let mut camera_vertex: Option<PathVertex> = None;
    for j in 1..camera_end {
        let i = n - 1 - j;
        if j >= 2 {
            let prev = camera_vertex.unwrap();
            step(
                &mut walk,
                &prev,
                path.dir(i + 1, i),
                TransportMode::Radiance,
            );
        }
        if i == 0 {
            // s = 0: the walk reaches the light.
            return match path.end {
                LightEnd::Point { p, n: n0 } => {
                    walk.arrive(&ctx.mis, p, n0);
                    let hit = LightHit { p, n: n0, t: 0.0 };
                    emitter_weight(ctx, &walk, li, &hit, path.dir(0, 1))
                }
                LightEnd::Direction { to_light } => escaped_weight(ctx, &walk, li, to_light),
            };
        }
        let si = &path.surfaces[i - 1];
        walk.arrive(&ctx.mis, si.p, si.ng);
        camera_vertex = Some(vertex(i, path.dir(i, i + 1), &mut walk, &mut lambda));
    }
    if merge {
        let (z, y) = (camera_vertex.unwrap(), light_vertex.unwrap());
        // The store keeps only light vertices merging is available at.
        if !y.merges {
            return 0.0;
        }
        let e = z.bsdf.eval(z.wo, y.wo, TransportMode::Radiance);
        return merge_weight(&ctx.mis, &z.mis, &MergeVertex::new(&y, 0, false), &e);
    }
    let pdf_dir = |p: Vec3| ctx.sensor.ray_pdf_dir_w((p - sensor_p).normalize());
    match (s, t) {
        (1, 1) => origin.map_or(0.0, |o| match ctx.sensor.infinite_light_meter() {
            Some(m) if o.infinite => infinite_origin_weight(ctx, &o, m.pdf_dir_w(-o.n)),
            None if o.infinite => 0.0,
            _ => origin_weight(ctx, &o, sensor_p, pdf_dir(o.p)),
        }),
        (_, 1) => {
            let y = light_vertex.unwrap();
            sensor_weight(ctx, &y, sensor_p, pdf_dir(y.p))
        }
        (1, _) => {
            let z = camera_vertex.unwrap();
            let (wi, p_light, n_light) = match path.end {
                LightEnd::Point { p, n } => ((p - z.p).normalize(), p, n),
                LightEnd::Direction { to_light } => (to_light, z.p + 1e6 * to_light, Vec3::ZERO),
            };
            let hit = LightHit {
                p: p_light,
                n: n_light,
                t: 0.0,
            };
            let lctx = LightSampleContext { p: z.p, n: z.ng };
            let ls = LightLiSample {
                l: spectral_render::spectral::SampledSpectrum::ONE,
                wi,
                pdf_w: if light.is_delta() {
                    1.0
                } else {
                    light.pdf_li(&lctx, wi, &hit)
                },
                p_light,
                n_light,
                delta: light.is_delta(),
                infinite: path.infinite(),
            };
            direct_weight(ctx, &z, li, &ls)
        }
        _ => connect_weight(ctx, &light_vertex.unwrap(), &camera_vertex.unwrap()),
    }
}

/// What the brute-force check saw for one sensor and heuristic.
#[derive(Debug, Default)]
struct MisCheck {
    /// Paths per number of surface vertices (n = 2 … 7).
    per_length: Vec<usize>,
    per_light: std::collections::BTreeMap<&'static str, usize>,
    /// Paths with at least one specular vertex, and techniques they excluded (p_s = 0).
    specular_paths: usize,
    excluded: usize,
    /// Paths by their longest run of consecutive specular vertices: 1, 2, 3 or more (index).
    runs: [usize; 4],
    /// Paths specular next to both ends (x_1 and x_{n−2}, as E–S–D–S–S–L).
    specular_at_both_ends: usize,
    /// Paths with specular vertices per light kind, by longest run (1, 2, 3 or more).
    specular_per_light: std::collections::BTreeMap<&'static str, [usize; 3]>,
    /// Non-specular interior vertices (and irradiance meter points) of the paths checked at
    /// which merging is available under the check's rule, and at which it is not.
    merges_available: usize,
    merges_unavailable: usize,
    /// Available merges after a near-specular glossy (non-delta) vertex.
    merges_after_glossy: usize,
    worst_diff: f64,
    worst_sum: f64,
}

/// Checks the recurrent weights of random paths from `sensor` against the brute-force sum.
/// Which merging techniques compete in a brute-force MIS check, with η = π r² N_L.
#[derive(Clone, Copy, Debug)]
enum Merging {
    /// BDPT: connections only.
    None,
    /// VCM: connections and merges.
    Vcm(f32),
    /// VCM with merges only after near-specular vertices (`MergeRule::Caustic`).
    Caustic(f32),
    /// Bidirectional photon mapping: merges only.
    Vm(f32),
}

fn check_mis(
    scene: &Scene,
    sensor: &SensorEnd,
    heuristic: MisHeuristic,
    merging: Merging,
    paths_per_length: usize,
    seed: u64,
) -> MisCheck {
    let kinds: Vec<&'static str> = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Triangle(_) => "mesh",
            Light::Rect(_) => "rect",
            Light::Disk(_) => "disk",
            Light::Sphere(_) => "sphere",
            Light::Cylinder(_) => "cylinder",
            Light::Distant(d) if d.is_delta() => "distant (delta)",
            Light::Distant(_) => "distant",
            Light::Dome(_) => "dome",
            Light::Point(_) => "point",
            Light::Line(_) => "line",
        })
        .collect();
    let mut ctx = BidirContext::new(scene, Mis::bdpt(heuristic), 100);
    let (eta, connect, rule) = match merging {
        Merging::None => (0.0, true, MergeRule::All),
        Merging::Vcm(eta) => (eta, true, MergeRule::All),
        Merging::Caustic(eta) => (eta, true, MergeRule::Caustic),
        Merging::Vm(eta) => (eta, false, MergeRule::All),
    };
    if eta > 0.0 {
        ctx.mis = Mis::vcm(heuristic, eta, connect, true).with_merge_rule(rule);
    }
    let mut sampler = Sampler::new(seed, 0, heuristic as u64);
    let mut out = MisCheck {
        per_length: vec![0; 6],
        ..Default::default()
    };
    for k in 0..6 {
        let mut tries = 0;
        while out.per_length[k] < paths_per_length && tries < 200_000 {
            tries += 1;
            let Some(path) = random_path(scene, sensor, k, &mut sampler) else {
                continue;
            };
            let t = technique_pdfs(&ctx, &path);
            // Every technique's density: connections (unless only merging), then merges × η.
            let mut pdfs: Vec<f64> = if connect {
                t.connections.clone()
            } else {
                vec![0.0; path.n()]
            };
            pdfs.extend(t.merges.iter().map(|&p| p * eta as f64));
            pdfs.push(t.sensor_merge * eta as f64);
            let m: Vec<f64> = pdfs.iter().map(|&p| ctx.mis.m(p as f32) as f64).collect();
            let total: f64 = m.iter().sum();
            if !(total > 0.0 && total.is_finite()) {
                continue;
            }
            let brute: Vec<f64> = m.iter().map(|x| x / total).collect();
            let mut recurrent = if connect {
                recurrent_weights(&ctx, &path)
            } else {
                vec![0.0; path.n()]
            };
            if eta > 0.0 {
                recurrent.extend(recurrent_merge_weights(&ctx, &path));
                recurrent.push(recurrent_sensor_merge_weight(&ctx, &path));
            } else {
                recurrent.extend(vec![0.0; path.n() + 1]);
            }
            for s in 0..brute.len() {
                let diff = (brute[s] - recurrent[s]).abs();
                out.worst_diff = out.worst_diff.max(diff);
                assert!(
                    diff < 2e-3,
                    "{} {heuristic:?} {merging:?}, n = {}, technique {s} (≥ n: merges), light {}, specular {:?}: recurrent {:?} vs brute force {:?} (pdfs {:?})",
                    sensor.name(),
                    path.n(),
                    kinds[path.light as usize],
                    path.specular(scene),
                    recurrent,
                    brute,
                    pdfs
                );
            }
            // Techniques that cannot produce the path (by evaluation) are exactly those the
            // integrators never evaluate (specular vertices neither stored nor connected), and
            // have weight 0; the others' weights sum to 1.
            let specular = path.specular(scene);
            for s in 0..path.n() {
                let cannot = path.cannot_connect(scene, s);
                assert_eq!(
                    cannot,
                    path.connects_at_delta(s, &specular),
                    "{}: technique {s} of a path with specular vertices {specular:?}",
                    sensor.name()
                );
                assert!(!cannot || (brute[s] == 0.0 && recurrent[s] == 0.0));
            }
            let sum: f64 = recurrent.iter().sum();
            out.worst_sum = out.worst_sum.max((sum - 1.0).abs());
            assert!(
                (sum - 1.0).abs() < 2e-3,
                "{}: weights sum to {sum}: {recurrent:?}",
                sensor.name()
            );
            if specular.iter().any(|&b| b) {
                out.specular_paths += 1;
                out.excluded += (0..path.n())
                    .filter(|&s| path.connects_at_delta(s, &specular))
                    .count();
                let run = path.specular_run(scene).min(3);
                out.runs[run] += 1;
                let n = path.n();
                if n >= 4 && specular[1] && specular[n - 2] {
                    out.specular_at_both_ends += 1;
                }
                out.specular_per_light
                    .entry(kinds[path.light as usize])
                    .or_default()[run - 1] += 1;
            }
            let near = path.near_specular(scene);
            let last = if path.sensor.merges_at_point() {
                path.n() - 1
            } else {
                path.n() - 2
            };
            for i in 1..=last {
                if i < path.n() - 1 && specular[i] {
                    continue;
                }
                if path.merge_available(scene, rule, i) {
                    out.merges_available += 1;
                    out.merges_after_glossy += usize::from(near[i - 1] && !specular[i - 1]);
                } else {
                    out.merges_unavailable += 1;
                }
            }
            out.per_length[k] += 1;
            *out.per_light.entry(kinds[path.light as usize]).or_default() += 1;
        }
    }
    out
}

/// The recurrent MIS weights (`bidir::mis`) against m(p_s) / Σ_j m(p_j) evaluated from
/// per-vertex densities, on random paths through a scene with every light type, a mirror and
/// a glass pane, for three sensors: the camera, an irradiance meter on the floor (whose
/// (1, 1) technique includes infinite lights' directions) and a luminance meter (a delta
/// direction: t = 1 has weight 0). Specular vertices exclude the techniques that would connect
/// at them; the weights of the others must still sum to 1.
#[test]
fn mis_recurrence_matches_brute_force_and_weights_sum_to_one() {
    let scene = load_text("every-light", &specular_stage(), (32, 32));
    let meter = |kind, p: Vec3, dir: Vec3| {
        let m = Meter {
            kind,
            p,
            dir: dir.normalize(),
        };
        SensorEnd::Meter(MeterSensor::new(&m, scene.point_error(p)))
    };
    let sensors = [
        SensorEnd::Camera(scene.camera.lens_point([0.5; 2])),
        meter(MeterKind::Illuminance, Vec3::new(0.3, 0.0, 0.2), Vec3::Y),
        meter(
            MeterKind::Luminance,
            Vec3::new(-1.0, 1.4, 1.5),
            Vec3::new(0.3, -0.6, -1.0),
        ),
    ];
    // BDPT, VCM at a small and a large η (merges weak and dominant), the same with merges
    // only after near-specular vertices, and merging alone.
    let modes = [
        (Merging::None, 500),
        (Merging::Vcm(0.05), 100),
        (Merging::Vcm(20.0), 100),
        (Merging::Caustic(0.05), 100),
        (Merging::Caustic(20.0), 100),
        (Merging::Vm(2.0), 100),
    ];
    const KINDS: [&str; 8] = [
        "mesh",
        "rect",
        "disk",
        "sphere",
        "cylinder",
        "dome",
        "distant",
        "distant (delta)",
    ];
    for (i, sensor) in sensors.iter().enumerate() {
        // BDPT's paths per light kind and longest specular run (1, 2, ≥ 3), both heuristics.
        let mut chains: std::collections::BTreeMap<&str, [usize; 3]> = Default::default();
        for (heuristic, (merging, paths)) in [MisHeuristic::Power, MisHeuristic::Balance]
            .into_iter()
            .flat_map(|h| modes.iter().map(move |&m| (h, m)))
        {
            let c = check_mis(&scene, sensor, heuristic, merging, paths, 11 + i as u64);
            eprintln!(
                "{} {heuristic:?} {merging:?}: paths per length (n = 2..7) {:?}, per light {:?}; {} with specular vertices ({} techniques excluded; longest specular run 1, 2, ≥3: {:?}; specular next to both ends {}; per light {:?}); merges available {} ({} after a glossy near-specular vertex), unavailable {}; max |recurrent − brute force| {:.2e}, max |Σ w − 1| {:.2e}",
                sensor.name(),
                c.per_length,
                c.per_light,
                c.specular_paths,
                c.excluded,
                &c.runs[1..],
                c.specular_at_both_ends,
                c.specular_per_light,
                c.merges_available,
                c.merges_after_glossy,
                c.merges_unavailable,
                c.worst_diff,
                c.worst_sum
            );
            // The caustic rule's check sees merges it keeps (after delta and after glossy
            // near-specular vertices) and merges it drops: a wrong flag either way shows.
            if matches!(merging, Merging::Caustic(_)) {
                assert!(
                    c.merges_available >= paths / 5
                        && c.merges_after_glossy >= paths / 20
                        && c.merges_unavailable >= paths,
                    "{}: merges available {} ({} after glossy), unavailable {}",
                    sensor.name(),
                    c.merges_available,
                    c.merges_after_glossy,
                    c.merges_unavailable
                );
            }
            // A luminance meter looking at a plain floor sees no emitter directly (n = 2),
            // and a two-vertex path has nothing to merge at.
            let first = if matches!(sensor, SensorEnd::Meter(m) if m.delta_direction())
                || matches!(merging, Merging::Vm(_))
            {
                1
            } else {
                0
            };
            for (k, &count) in c.per_length.iter().enumerate().skip(first) {
                assert!(
                    count >= paths.min(100),
                    "{}: too few paths with {k} surface vertices",
                    sensor.name()
                );
            }
            assert!(
                c.specular_paths >= paths / 3,
                "{}: few specular paths",
                sensor.name()
            );
            for kind in KINDS {
                assert!(
                    c.per_light.get(kind).copied().unwrap_or(0) >= paths / 30,
                    "{}: few paths to {kind}: {:?}",
                    sensor.name(),
                    c.per_light
                );
            }
            if matches!(merging, Merging::None) {
                for (kind, runs) in &c.specular_per_light {
                    let all = chains.entry(kind).or_default();
                    for r in 0..3 {
                        all[r] += runs[r];
                    }
                }
            }
        }
        // Chains of 1, 2 and 3 or more specular vertices (mirror, into and out of the
        // ball, glass pane) on paths to every kind of light.
        for kind in KINDS {
            let runs = chains.get(kind).copied().unwrap_or_default();
            assert!(
                runs.iter().all(|&r| r >= 3),
                "{}: paths to {kind} by longest specular run (1, 2, ≥3): {runs:?}",
                sensor.name()
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Closed forms
// ---------------------------------------------------------------------------------------------

#[test]
fn white_furnace_with_bdpt_and_light_tracing() {
    let le = 2.0f32;
    let scene = load_text("furnace", &furnace_stage(le, 0.8), (16, 16));
    let expected = le as f64 / (1.0 - 0.8);
    for (kind, spp) in [
        (
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
            256,
        ),
        (Integrator::Light, 4096),
    ] {
        let out = render_with(&scene, kind, spp, 5, 10_000);
        let (mean, sem) = mean_and_sem(out.xyz.iter().map(|p| p[1]));
        eprintln!("furnace {kind:?}: Y {mean:.4} ± {sem:.4}, expected {expected}");
        assert!(sem / expected < 3e-3, "too noisy to judge: sem {sem}");
        assert!(
            (mean / expected - 1.0).abs() < 0.01,
            "{kind:?}: furnace Y = {mean}, expected {expected}"
        );
    }
}

/// A grey plane under a uniform dome of L nits reads ρ L: the dome's emission sampling (a
/// disk at the scene's bounding sphere) carries exactly the radiance it should.
#[test]
fn plane_under_a_uniform_dome_reads_albedo_times_radiance() {
    let l = 50.0f32;
    let s = dome_plane_stage(l, &looks_scope(&flat_diffuse("Paint", 0.5)), "");
    let scene = load_text("dome-plane", &s, (12, 12));
    let expected = 0.5 * l as f64;
    // Light tracing reaches the small visible part of the plane rarely: more paths.
    for (kind, spp) in [
        (
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
            256,
        ),
        (Integrator::Light, 4096),
    ] {
        let out = render_with(&scene, kind, spp, 3, 7);
        let (mean, sem) = mean_and_sem(out.xyz.iter().map(|p| p[1]));
        eprintln!("dome plane {kind:?}: Y {mean:.4} ± {sem:.4}, expected {expected}");
        assert!(
            (mean - expected).abs() < 2e-3 * expected + 4.0 * sem,
            "{kind:?}: {mean} vs {expected} (sem {sem})"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Strategy decomposition, robustness, determinism
// ---------------------------------------------------------------------------------------------

#[test]
fn strategy_images_sum_to_the_bdpt_image() {
    let dir = temp_dir("strategies");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_spectral-render"))
        .args([
            "--integrator",
            "bdpt",
            "--spp",
            "16",
            "--resolution",
            "12x12",
            "--max-depth",
            "4",
        ])
        .arg("--strategies")
        .arg(dir.join("st"))
        .arg("-o")
        .arg(dir.join("bdpt.exr"))
        .arg(cbox_path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |p: &Path| spectral_render::output::exr::read(p).unwrap();
    let image = read(&dir.join("bdpt.exr"));
    let mut sum = vec![0.0f64; 144];
    let mut files = 0;
    for entry in std::fs::read_dir(dir.join("st")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.ends_with("_weighted.exr") {
            for (acc, v) in sum.iter_mut().zip(&read(&path).channels["XYZ.Y"]) {
                *acc += *v as f64;
            }
            files += 1;
        }
    }
    // Depths 0..=4: 2 + 3 + 4 + 5 + 6 strategies.
    assert_eq!(files, 20);
    let y = &image.channels["XYZ.Y"];
    let max_rel = sum
        .iter()
        .zip(y)
        .map(|(s, &v)| (s - v as f64).abs() / (v as f64).max(1e-3))
        .fold(0.0f64, f64::max);
    eprintln!("strategy images: max relative difference of the sum {max_rel:.2e}");
    assert!(max_rel < 1e-4, "strategy sum differs by {max_rel}");
}

#[test]
fn no_nan_with_a_point_like_light_on_a_wall_or_a_camera_inside_a_box() {
    // A 0.1 mm sphere light 0.15 mm above a floor, seen from above.
    let mut s = header();
    s += &camera_at([0.0, 0.5, 0.0], 0.3, "").replace(
        "    uniform token[] xformOpOrder = [\"xformOp:translate\"]",
        "    float3 xformOp:rotateXYZ = (-90, 0, 0)\n    uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:rotateXYZ\"]",
    );
    s += &looks();
    s += &polygon(
        "Floor",
        &[
            [-1.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, -1.0],
            [-1.0, 0.0, -1.0],
        ],
        None,
        &binding("White"),
    );
    s += &lux(
        "SphereLight",
        "Dot",
        "    bool treatAsPoint = 1\n    float inputs:intensity = 1e9\n",
        [0.01, 0.00015, 0.0],
        [0.0; 3],
    );
    let near_wall = load_text("point-light", &s, (16, 16));
    // A closed box (walls facing inwards) with a small light inside and the camera inside.
    let mut b = header();
    b += &camera(0.5, 0.8, 0.0);
    b += &looks();
    for (i, f) in cube_faces(1.0).iter().enumerate() {
        b += &polygon(&format!("Wall{i}"), f, None, &binding("Grey"));
    }
    b += &lux(
        "SphereLight",
        "Bulb",
        "    float inputs:radius = 0.05\n    float inputs:intensity = 100\n",
        [0.3, 0.6, -0.2],
        [0.0; 3],
    );
    let inside = load_text("inside-box", &b, (16, 16));
    for (name, scene) in [
        ("point-like light", &near_wall),
        ("camera inside a box", &inside),
    ] {
        for kind in [
            Integrator::Path,
            Integrator::Light,
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
        ] {
            let out = render_with(scene, kind, 64, 1, 7);
            assert!(
                out.xyz.iter().any(|p| p[1] > 0.0),
                "{name} {kind:?}: black image"
            );
        }
    }
}

#[test]
fn bidirectional_images_are_bit_identical_for_one_and_two_threads() {
    let scene = scene::load(&cbox_path(), Some((24, 24))).unwrap();
    for kind in [
        Integrator::Light,
        Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
        vcm(VcmMode::Vcm, Some(0.02)),
        vcm(VcmMode::Vm, None),
    ] {
        let run = |threads| {
            let opts = RenderOptions {
                spp: Some(4),
                seed: 3,
                threads: Some(threads),
                integrator: kind,
                ..Default::default()
            };
            let out = session::render(&scene, &opts).unwrap();
            assert_finite(&out);
            out.xyz
                .iter()
                .flatten()
                .map(|v| v.to_bits())
                .collect::<Vec<_>>()
        };
        assert_eq!(run(1), run(2), "{kind:?}");
    }
}

#[test]
fn command_line_options_of_the_bidirectional_integrators() {
    let dir = temp_dir("bidir-cli");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_spectral-render"))
            .args(args)
            .arg(cbox_path())
            .current_dir(&dir)
            .output()
            .unwrap()
    };
    for (integrator, mis, extra) in [
        ("light", "power", &[][..]),
        ("bdpt", "balance", &[][..]),
        (
            "vcm",
            "power",
            &["--vcm-mode", "vm", "--vcm-radius", "0.05"][..],
        ),
        ("vcm", "balance", &["--vcm-alpha", "0.5"][..]),
    ] {
        let base = [
            "--integrator",
            integrator,
            "--mis",
            mis,
            "--spp",
            "2",
            "--resolution",
            "8x8",
            "-o",
            "x.exr",
        ];
        let o = run(&[&base[..], extra].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert_eq!(err.contains("note: v"), integrator == "vcm", "{err}");
        let img = spectral_render::output::exr::read(&dir.join("x.exr")).unwrap();
        assert!(img.channels["XYZ.Y"].iter().all(|v| v.is_finite()));
    }
    for (args, message) in [
        (&["--integrator", "vcn"][..], "unknown integrator"),
        (
            &["--vcm-mode", "vm"][..],
            "--vcm-mode needs --integrator vcm",
        ),
        (
            &["--integrator", "vcm", "--vcm-alpha", "1.5"][..],
            "--vcm-alpha 1.5 must be in (0, 1]",
        ),
        (
            &["--integrator", "vcm", "--vcm-radius", "-1"][..],
            "must be a positive number of metres",
        ),
        (
            &["--integrator", "vcm", "--vcm-mode", "pm"][..],
            "unknown VCM mode",
        ),
        (&["--mis", "cutoff"][..], "unknown MIS heuristic"),
        (
            &["--strategies", "st"][..],
            "--strategies needs --integrator bdpt",
        ),
        (
            &[
                "--integrator",
                "bdpt",
                "--strategies",
                "st",
                "--max-depth",
                "40",
            ][..],
            "strategy images need --max-depth 15 or less",
        ),
    ] {
        let o = run(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(message),
            "{args:?}: {err}"
        );
    }
}
