//! The path tracer's `--rr-depth` (issue 18): where roulette starts changes the variance, never
//! the mean, and a start beyond the depth cap is no roulette at all.

mod common;
use common::*;
use glam::Vec3;
use spectral_render::integrator::roulette::RrStart;
use spectral_render::integrator::roulette_pilot::Fixed;
use spectral_render::integrator::split::Split;
use spectral_render::scene::{self, Scene};
use spectral_render::session::{self, measure, MeterOptions, Reading, RenderOptions, Stop};
use spectral_render::{Integrator, Meter};

const CAP: u32 = 7;

fn render(scene: &Scene, rr_depth: u32) -> Vec<f32> {
    let opts = RenderOptions {
        spp: Some(8),
        seed: 3,
        max_depth: Some(CAP),
        rr_depth: RrStart::At(rr_depth),
        integrator: Integrator::Path,
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap();
    assert_finite(&out);
    out.xyz.iter().flatten().copied().collect()
}

/// A path scatters at most CAP times, so roulette from bounce CAP + 1 is never played: the
/// image is bit for bit that of no roulette (any later start); from bounce CAP it is played
/// at the last scattering event and the image changes.
#[test]
fn a_start_beyond_the_cap_is_no_roulette_bit_for_bit() {
    let scene = scene::load(&cbox_path(), Some((16, 16))).unwrap();
    let none = render(&scene, u32::MAX);
    assert_eq!(render(&scene, CAP + 1), none);
    assert_ne!(render(&scene, CAP), none);
}

/// z = (a − b)/√(σa² + σb²) from the readings' 95 % intervals.
fn z_score(a: &Reading, b: &Reading) -> f64 {
    let var = (a.ci95 / 1.96).powi(2) + (b.ci95 / 1.96).powi(2);
    (a.value - b.value) / var.sqrt()
}

/// Illuminance on the Cornell box's ceiling beside the lamp (all of it indirect) and on its
/// red wall, unlimited depth, with roulette from bounce 1, pbrt-v4's 2 and Mitsuba's 5: the
/// same means. Six z-tests at a family-wise 1 % (Šidák): |z| < 3.2.
#[test]
fn where_roulette_starts_does_not_move_the_mean() {
    let scene = scene::load(&cbox_path(), Some((1, 1))).unwrap();
    let meters = [
        Meter::illuminance(Vec3::new(0.6, 0.995, 0.6), Vec3::NEG_Y).unwrap(),
        Meter::illuminance(Vec3::new(-0.99, 0.2, 0.5), Vec3::X).unwrap(),
    ];
    let read = |rr_depth, seed| {
        let opts = MeterOptions {
            stop: Stop::RelError(0.01),
            seed,
            rr_depth,
            integrator: Integrator::Path,
            ..Default::default()
        };
        let run = measure(&scene, &meters, &opts).unwrap();
        assert_eq!(run.dropped, 0);
        run.readings
    };
    let starts = [1, 2, 5];
    let runs: Vec<Vec<Reading>> = starts.iter().zip(31..).map(|(&d, s)| read(d, s)).collect();
    for (i, m) in meters.iter().enumerate() {
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            let (ra, rb) = (&runs[a][i], &runs[b][i]);
            let z = z_score(ra, rb);
            eprintln!(
                "at {}: rr {} {:.4} ± {:.4}, rr {} {:.4} ± {:.4}, z = {z:.2}",
                m.p, starts[a], ra.value, ra.ci95, starts[b], rb.value, rb.ci95
            );
            assert!(
                z.abs() < 3.2,
                "rr {} vs {} at {}: z = {z:.2}",
                starts[a],
                starts[b],
                m.p
            );
        }
    }
}

/// The roulette pilot (`--rr-depth auto`, `integrator::roulette_pilot`) predicts the ray
/// queries a sample makes under each start and split from paths traced without roulette, split
/// in two. Against the path tracer's own roulette and splitting on the box (independent
/// numbers, 48², 64 spp, no depth cap, so that no path is continued past a cap): the measured
/// queries per sample within 5 standard errors of the prediction at starts 1, 3 and 8 unsplit
/// and (2, split 2), (3, split 4). The prediction's error is the pilot's; the
/// render's, with the same per-sample spread over 147 456 samples against the pilot's 2 per
/// pixel over 2 304 pixels, is added.
#[test]
fn the_pilot_predicts_the_rays_roulette_costs() {
    use spectral_render::integrator::roulette_pilot::choose;
    use spectral_render::sampling::SamplerKind;
    use spectral_render::session::ImageSession;
    let scene = scene::load(&cbox_path(), Some((48, 48))).unwrap();
    let filter = spectral_render::texture::TextureFilter::Finest;
    let cap = spectral_render::integrator::cut::SAFETY_DEPTH;
    let choice = choose(&scene, cap, filter, 5, Fixed::default()).expect("the pilot finds light");
    assert_eq!(choice.paths, 2 * 48 * 48);
    for (start, split) in [(1, 1), (3, 1), (8, 1), (2, 2), (3, 4)] {
        let c = choice
            .candidates
            .iter()
            .find(|c| c.start == start && c.split == split)
            .unwrap();
        let opts = RenderOptions {
            spp: Some(64),
            seed: 9,
            max_depth: None,
            rr_depth: RrStart::At(start),
            split: Split::At(split),
            integrator: Integrator::Path,
            sampler: SamplerKind::Independent,
            threads: Some(2),
            ..Default::default()
        };
        let mut s = ImageSession::new(&scene, &opts).unwrap();
        session::run(&mut s, &mut session::quiet);
        let pixels = 48.0 * 48.0;
        let measured = s.ray_queries() as f64 / (s.samples() as f64 * pixels);
        let predicted = c.cost;
        let se = c.cost_se * (1.0 + 2.0 * pixels / (pixels * 64.0)).sqrt();
        let case = format!("start {start} split {split}");
        eprintln!("{case}: {measured:.4} rays a sample, predicted {predicted:.4} ± {se:.4}");
        assert!(
            (measured - predicted).abs() < 5.0 * se,
            "{case}: {measured} rays a sample, the pilot predicted {predicted} ± {se}"
        );
    }
}

/// The pilot's choice and figures do not depend on the number of threads: its pixels and
/// numbers are fixed by the image and the seed, its sums taken in pixel order.
#[test]
fn the_pilot_is_the_same_on_any_thread_count() {
    use spectral_render::integrator::roulette_pilot::{choose, SPLITS};
    let scene = scene::load(&cbox_path(), Some((40, 30))).unwrap();
    let filter = spectral_render::texture::TextureFilter::Finest;
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| choose(&scene, 1024, filter, 2, Fixed::default()))
    };
    let one = on(1).expect("the box's pilot finds light");
    assert_eq!(Some(&one), on(2).as_ref());
    assert_eq!(one.candidates.len(), 8 * SPLITS.len());
    assert!((1..=8).contains(&one.start));
    assert!(SPLITS.contains(&one.split));
}
