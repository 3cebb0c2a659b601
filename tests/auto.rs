//! `--integrator auto` and `spectral-render info` (issue 11, "Choices"): the choice and the
//! features `info --json` gives on the project's stages; that `auto` is deterministic for a
//! seed and that its result under `--spp` is bit for bit the chosen integrator's (the winner's
//! pilot samples are its first samples, the losers' are discarded), for images and meters.
//! The "Pilot" benchmark (auto against the best fixed integrator, mean error over many seeds
//! at equal samples, CPU time per render) is `tools/bench_auto.sh`, not a test.

mod common;
use common::*;
use spectral_render::scene::{self, Scene};
use spectral_render::session::{self, MeterOptions, RenderOptions, RenderOutput, Stop};
use spectral_render::{Integrator, Meter, MisHeuristic};
use std::path::{Path, PathBuf};

fn stage(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// `info --json` on a stage: the document, checked for the shape.
fn info(path: &Path) -> serde_json::Value {
    info_with(path, &[])
}

/// `info --json` with more options.
fn info_with(path: &Path, options: &[&str]) -> serde_json::Value {
    let dir = temp_dir("auto-info");
    let mut args = vec!["info", path.to_str().unwrap(), "--json"];
    args.extend_from_slice(options);
    let o = spectral_render(&args, &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let keys: Vec<&String> = doc.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["features", "integrator", "max_depth"], "{doc}");
    for name in [
        "dispersion",
        "caustics",
        "sds",
        "textures",
        "opacity",
        "delta_lights",
        "infinite_lights",
    ] {
        let f = &doc["features"][name];
        assert!(f["on"].is_boolean(), "{name}: {f}");
        assert!(!f["reason"].as_str().unwrap().is_empty(), "{name}: {f}");
        assert!(f["prims"].is_array(), "{name}: {f}");
        assert_eq!(
            f["on"].as_bool(),
            Some(!f["prims"].as_array().unwrap().is_empty())
        );
    }
    assert!(doc["integrator"]["reasons"].as_array().unwrap().len() >= 2);
    assert!(doc["max_depth"].get("value").is_some() && doc["max_depth"].get("bound_cut").is_some());
    doc
}

fn on(doc: &serde_json::Value, feature: &str) -> bool {
    doc["features"][feature]["on"].as_bool().unwrap()
}

fn choice(doc: &serde_json::Value) -> &str {
    doc["integrator"]["choice"].as_str().unwrap()
}

/// The pilot's lines among the reasons (one per candidate), e.g. `pilot bdpt: 3 spp, …`.
fn piloted(doc: &serde_json::Value) -> usize {
    let reasons = doc["integrator"]["reasons"].as_array().unwrap();
    reasons
        .iter()
        .filter(|r| r.as_str().unwrap().starts_with("pilot "))
        .count()
}

#[test]
fn cornell_boxes_have_no_caustics_and_the_pilot_chooses() {
    // The lamps' pixels are left out of the pilot (their rims' noise is the pixel filter's,
    // which zsobol's samples remove far faster than a 2-spp variance says), and path, the
    // simpler, is kept on both boxes, as at the benchmark's 96 × 72 (where counting the lamp
    // made bdpt "5.9×" path's efficiency; docs/design.md, "The criterion in the `converge`
    // report's measure").
    for (path, expected) in [
        (stage("cornell-box.usda"), Some("path")),
        (cbox_path(), None),
    ] {
        let bench = ["--resolution", "96x72", "--spp", "32", "--seed", "1"];
        assert_eq!(
            choice(&info_with(&path, &bench)),
            "path",
            "{}",
            path.display()
        );
        let doc = info(&path);
        assert!(!on(&doc, "caustics") && !on(&doc, "sds"), "{doc}");
        assert!(
            !on(&doc, "dispersion") && !on(&doc, "delta_lights"),
            "{doc}"
        );
        assert_eq!(piloted(&doc), 2, "{doc}");
        if let Some(c) = expected {
            assert_eq!(choice(&doc), c, "{}: {doc}", path.display());
        }
        // The path tracer's roulette start, as `--rr-depth auto` chose it, ends the reasons.
        if choice(&doc) == "path" {
            let reasons = doc["integrator"]["reasons"].as_array().unwrap();
            let last = reasons.last().unwrap().as_str().unwrap();
            assert!(last.starts_with("Russian roulette from bounce "), "{doc}");
        }
        // No cap by default: only the safety cap's ρ^1024 / (1 − ρ), nothing.
        assert!(doc["max_depth"]["value"].is_null(), "{doc}");
        let bound = doc["max_depth"]["bound_cut"].as_f64().unwrap();
        assert!(bound < 1e-100, "{doc}");
        // ρ_max = 0.74 (the white walls' luminous albedo): a cap of 7 cuts at most
        // ρ^7 / (1 − ρ) of the direct light.
        let small = ["--max-depth", "7", "--resolution", "32x32", "--spp", "4"];
        let doc = info_with(&path, &small);
        assert_eq!(doc["max_depth"]["value"], 7, "{doc}");
        let bound = doc["max_depth"]["bound_cut"].as_f64().unwrap();
        assert!(bound > 0.3 && bound < 0.7, "{doc}");
    }
}

#[test]
fn the_pilot_leaves_out_every_pixel_a_lamp_is_seen_in() {
    // emitter_pixels (one ray per pixel, dilated by a pixel) covers the converge report's
    // mask (16 rays per pixel), the lamp's rim included, and little more.
    let scene = spectral_render::scene::load(&stage("cornell-box.usda"), Some((96, 72))).unwrap();
    let pilot = spectral_render::scene::analysis::emitter_pixels(&scene);
    let report = spectral_render::converge::mask::emitter_mask(&scene);
    let count = |m: &[bool]| m.iter().filter(|x| **x).count();
    assert!(count(&report) > 0);
    assert!(pilot.iter().zip(&report).all(|(p, r)| *p || !r));
    assert!(
        count(&pilot) < 2 * count(&report),
        "{} {}",
        count(&pilot),
        count(&report)
    );
}

#[test]
fn the_prism_disperses_and_casts_a_caustic() {
    let doc = info(&stage("prism.usda"));
    assert!(on(&doc, "dispersion") && on(&doc, "caustics"), "{doc}");
    let prims = doc["features"]["dispersion"]["prims"].to_string();
    assert!(prims.contains("/Prism/Looks/BK7"), "{doc}");
    // The caustic falls on the satin screen, whose narrow lobe finds the light: not the
    // point-like-caustic rule, so path and bdpt go to the pilot.
    assert_eq!(piloted(&doc), 2, "{doc}");
    // Glass scatters all it receives: no bound on what a cap cuts.
    assert!(doc["max_depth"]["bound_cut"].is_null(), "{doc}");
    // At 96 × 72 and seed 2 path's 2-spp pilot finds no light and bdpt's draws a few samples
    // of the beam: nothing shows bdpt ahead, and path, the simpler, is kept (over 8 seeds path's
    // MSE × CPU time is 0.45× bdpt's). Since bdpt's camera subpaths draw from the zsobol
    // sequence (session 27) seed 1's bdpt pilot finds no light either; seeds 1–8 all keep path.
    let small = ["--resolution", "96x72", "--spp", "32", "--seed", "2"];
    let doc = info_with(&stage("prism.usda"), &small);
    let pilot = |name: &str| {
        let reasons = doc["integrator"]["reasons"].as_array().unwrap();
        let line = reasons.iter().filter_map(|r| r.as_str());
        line.into_iter()
            .find(|r| r.starts_with(&format!("pilot {name}: ")))
            .unwrap()
            .to_string()
    };
    assert!(pilot("path").contains("variance inf"), "{doc}");
    assert!(!pilot("bdpt").contains("variance inf"), "{doc}");
    assert_eq!(choice(&doc), "path", "{doc}");
}

#[test]
fn a_glass_ball_on_a_floor_under_a_small_lamp_is_bidirectional() {
    // The lamp is point-like (0.018 % of the hemisphere): path tracing reaches the caustic only
    // by rare hits on it through the ball, whose variance a 2-spp pilot mostly misses (it
    // picked path at 8 of 8 seeds, where path's MSE × CPU time without the lamp's glints is
    // 136× vcm's; docs/design.md, "The pilot against the best fixed integrator"). So only bdpt
    // and vcm go to the pilot, at the stage's resolution and at the benchmark's.
    for options in [&[][..], &["--resolution", "96x72", "--seed", "1"][..]] {
        let doc = info_with(&stage("caustic.usda"), options);
        assert!(on(&doc, "caustics") && on(&doc, "delta_lights"), "{doc}");
        assert_eq!(piloted(&doc), 2, "{doc}");
        assert!(["bdpt", "vcm"].contains(&choice(&doc)), "{doc}");
    }
}

#[test]
fn bdpt_must_show_itself_ahead_of_vcm_on_a_caustic() {
    // vcm comes first for point-like caustics, and bdpt is taken only when the 95 % interval
    // of its efficiency ratio lies above 1.1 (session::auto::efficiency_interval). On the
    // point estimate alone, bdpt was ahead at 9 of these 16 seeds; its interval cleared 1.1
    // at one (docs/design.md, "Shown ahead").
    let mut bdpt = 0;
    let mut not_shown = 0;
    for seed in 1..=16 {
        let seed = seed.to_string();
        let options = ["--resolution", "96x72", "--spp", "32", "--seed", &seed];
        let doc = info_with(&stage("caustic.usda"), &options);
        let reasons = doc["integrator"]["reasons"].as_array().unwrap();
        let summary = reasons.last().unwrap().as_str().unwrap();
        match choice(&doc) {
            "vcm" => not_shown += usize::from(summary.contains("bdpt's lead not shown")),
            "bdpt" => {
                bdpt += 1;
                assert!(summary.contains("95 % interval"), "{summary}");
            }
            other => panic!("seed {seed}: {other}"),
        }
    }
    assert!(bdpt <= 2, "bdpt at {bdpt} of 16 seeds");
    assert!(
        not_shown >= 4,
        "bdpt's lead unproven at only {not_shown} seeds"
    );
}

#[test]
fn a_glass_ball_under_a_point_lamp_is_bidirectional() {
    // The same ball under a true point lamp (`treatAsPoint`): no BSDF-sampled ray ever hits
    // it, so path tracing never finds the caustic; bdpt and vcm go to the pilot, as behind
    // the lamp of 3 cm.
    let text = std::fs::read_to_string(stage("caustic.usda")).unwrap();
    let point = text.replace(
        "float inputs:radius = 0.03",
        "float inputs:radius = 0.03\n        bool treatAsPoint = 1",
    );
    assert_ne!(point, text);
    let path = temp_dir("auto-point-caustic").join("point-caustic.usda");
    std::fs::write(&path, point).unwrap();
    let doc = info_with(&path, &["--resolution", "160x120"]);
    assert!(on(&doc, "caustics") && on(&doc, "delta_lights"), "{doc}");
    assert_eq!(piloted(&doc), 2, "{doc}");
    assert!(["bdpt", "vcm"].contains(&choice(&doc)), "{doc}");
}

#[test]
fn a_caustic_seen_in_a_mirror_is_merged() {
    let doc = info(&stage("caustic-mirror.usda"));
    assert!(on(&doc, "sds"), "{doc}");
    let seen = doc["features"]["sds"]["prims"].to_string();
    assert!(seen.contains("/Scene/Mirror"), "{doc}");
    assert_eq!(choice(&doc), "vcm", "{doc}");
}

#[test]
fn light_through_a_door_gap_is_bidirectional_by_the_pilot() {
    let doc = info(&stage("gap.usda"));
    assert!(!on(&doc, "caustics"), "{doc}");
    assert_eq!(piloted(&doc), 2, "{doc}");
    assert_eq!(choice(&doc), "bdpt", "{doc}");
    let summary = doc["integrator"]["reasons"]
        .as_array()
        .unwrap()
        .last()
        .unwrap();
    assert!(
        summary
            .as_str()
            .unwrap()
            .starts_with("auto: bdpt (efficiency "),
        "{doc}"
    );
}

fn auto() -> Integrator {
    Integrator::Auto {
        mis: MisHeuristic::Power,
    }
}

fn render(scene: &Scene, integrator: Integrator, spp: u32, threads: usize) -> RenderOutput {
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 5,
        threads: Some(threads),
        integrator,
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap();
    assert_finite(&out);
    out
}

/// auto's image is the chosen integrator's, bit for bit, whatever the threads; `spp` is
/// chosen above a splatting chunk so that the winner is paused and resumed.
fn auto_is_its_choice(path: &Path, res: (u32, u32), spp: u32, expected: &str) {
    let scene = scene::load(path, Some(res)).unwrap();
    let a = render(&scene, auto(), spp, 2);
    let report = a.auto.clone().expect("auto reports its choice");
    assert_eq!(report.choice.name(), expected, "{}", report.summary());
    assert_eq!(report.pilot.len(), 2, "{report:?}");
    assert!(
        report.pilot.iter().all(|p| p.samples < u64::from(spp)),
        "{report:?}"
    );
    let fixed = render(&scene, report.choice, spp, 2);
    assert_eq!(a.spp, fixed.spp);
    assert!(a.xyz == fixed.xyz, "auto's image differs from {expected}'s");
    let one_thread = render(&scene, auto(), spp, 1);
    assert_eq!(one_thread.auto.unwrap().choice, report.choice);
    assert!(one_thread.xyz == a.xyz, "auto depends on the thread count");
}

#[test]
fn auto_renders_exactly_what_its_choice_renders() {
    // bdpt wins here. At the default unlimited depth a splatting chunk is one sample per
    // pixel at these sizes (`splat_chunk_samples`): a pilot of 2, then 62 more.
    auto_is_its_choice(&stage("gap.usda"), (80, 60), 64, "bdpt");
    // path wins here (a pilot of 2, then 30 more): a chart under a uniform dome, where
    // next-event estimation from every patch is all it takes and BDPT's light subpaths from
    // the dome add little. (The prism no longer serves: since BDPT's camera subpaths survive
    // roulette inside glass as the path tracer's do, issue 17, its pilot finds the light
    // through the prism as often as the path tracer's.)
    auto_is_its_choice(&stage("colorchecker.usda"), (120, 80), 32, "path");
}

#[test]
fn auto_meters_read_what_their_choice_reads() {
    let scene = scene::load(&cbox_path(), Some((1, 1))).unwrap();
    let meters = [
        Meter::illuminance(glam::Vec3::new(0.0, 0.0, 0.0), glam::Vec3::Y).unwrap(),
        Meter::illuminance(glam::Vec3::new(0.3, 0.5, 0.2), glam::Vec3::Z).unwrap(),
    ];
    for stop in [Stop::Samples(4096), Stop::RelError(0.02)] {
        let opts = |integrator| MeterOptions {
            stop,
            seed: 2,
            threads: Some(2),
            integrator,
            ..Default::default()
        };
        let a = session::measure(&scene, &meters, &opts(auto())).unwrap();
        let report = a.auto.clone().expect("auto reports its choice");
        assert_eq!(report.pilot.len(), 2, "{report:?}");
        let fixed = session::measure(&scene, &meters, &opts(report.choice)).unwrap();
        assert_eq!(a.readings, fixed.readings, "{stop:?}: {}", report.summary());
    }
}

#[test]
fn auto_has_no_estimator_of_its_own() {
    let scene = scene::load(&cbox_path(), Some((4, 4))).unwrap();
    let settings = spectral_render::integrator::Settings {
        max_depth: 7,
        rr_depth: spectral_render::integrator::roulette::DEFAULT_RR_DEPTH,
        split: 1,
        filter: spectral_render::texture::TextureFilter::Finest,
        meters: false,
    };
    assert!(auto().estimator(&scene, settings).is_err());
}

#[test]
fn the_command_line_says_what_auto_chose_and_records_it() {
    let dir = temp_dir("auto-cli");
    let gap = stage("gap.usda");
    let o = spectral_render(
        &[
            gap.to_str().unwrap(),
            "--resolution",
            "40x30",
            "--spp",
            "8",
            "-o",
            "g.exr",
        ],
        &dir,
    );
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    let line = err.lines().find(|l| l.starts_with("auto: ")).expect(&err);
    assert!(
        line.contains("efficiency") && line.contains("% pilot"),
        "{line}"
    );
    let chosen = line[6..].split(' ').next().unwrap();
    let img = spectral_render::output::exr::read(&dir.join("g.exr")).unwrap();
    let recorded = &img.attributes[spectral_render::output::exr::INTEGRATOR_ATTRIBUTE];
    assert_eq!(recorded, &format!("auto→{chosen}"));
    // The human report names every feature and the choice.
    let o = spectral_render(
        &["info", gap.to_str().unwrap(), "--resolution", "40x30"],
        &dir,
    );
    let text = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    for needle in [
        "features:",
        "caustics",
        "integrator: ",
        "max depth: unlimited",
        "expected cost",
    ] {
        assert!(text.contains(needle), "{needle} not in {text}");
    }
}
