//! Issue 13, the output and resource side: output targets checked before any work, memory
//! refused before it is allocated, interrupts that keep the image, checkpoints that resume
//! bit for bit, honest EXR metadata, and the command line's help and number errors.

mod common;

use common::{cbox_path, spectral_render, stderr, stdout, temp_dir};
use spectral_render::integrator::vcm::VcmParams;
use spectral_render::integrator::{Integrator, MisHeuristic};
use spectral_render::output::exr;
use spectral_render::scene;
use spectral_render::session::checkpoint::Checkpoint;
use spectral_render::session::{ImageSession, Progressive, RenderOptions};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_spectral-render"))
}

fn stage() -> String {
    cbox_path().display().to_string()
}

/// Asserts a run failed with exit code 1 and one `error:` line that contains `want`, before
/// the stage was read; returns the line.
fn assert_refused(args: &[&str], cwd: &Path, want: &str) -> String {
    let start = Instant::now();
    let out = spectral_render(args, cwd);
    let took = start.elapsed();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(
        err.starts_with("error: ") && err.contains(want),
        "{args:?}: {err}"
    );
    assert!(
        !err.contains("loaded"),
        "{args:?} read the stage first: {err}"
    );
    assert!(took < Duration::from_secs(1), "{args:?} took {took:?}");
    err
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn output_problems_fail_in_under_a_second_before_rendering() {
    let dir = temp_dir("outputs");
    let s = stage();
    let cases: &[(&[&str], &str)] = &[
        (&["-o", "no/such/dir/x.exr"], "the directory does not exist"),
        (&["-o", "."], "is a directory"),
        (&["-o", "x.png"], "ending in .exr"),
        (
            &["-o", "a.exr", "--preview", "a.exr"],
            "-o names the same file",
        ),
        (
            &["-o", "a.exr", "--checkpoint", "./a.exr"],
            "-o names the same file",
        ),
        (&["-o", "a.exr", "--preview", "p.exr"], "ending in .png"),
        (&["-o", "a.exr", "--preview", "no/p.png"], "--preview"),
        (&["-o", "/proc/x.exr"], "cannot write in /proc"),
        (&["-o", "a.exr", "--strategies", "a.exr/s"], "--strategies"),
    ];
    std::fs::write(dir.join("a.exr"), b"not yet").unwrap();
    for (args, want) in cases {
        let mut all = vec![s.as_str()];
        all.extend_from_slice(args);
        assert_refused(&all, &dir, want);
    }
    // A FIFO is never replaced by a regular file.
    let fifo = dir.join("fifo.exr");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    assert_refused(&[&s, "-o", "fifo.exr"], &dir, "is a FIFO");
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    // The meter's map files are checked alike.
    let grid = [
        "meter", &s, "--grid", "0,0,0", "--u", "1,0,0", "--v", "0,0,1", "--n", "2,2", "--normal",
        "0,1,0", "-o", "none/map",
    ];
    assert_refused(&grid, &dir, "the directory does not exist");
    assert_eq!(entries(&dir), ["a.exr", "fifo.exr"]);
}

#[test]
fn a_symlink_is_written_through_as_cp_does() {
    let dir = temp_dir("symlink");
    std::os::unix::fs::symlink("real.exr", dir.join("link.exr")).unwrap();
    let out = spectral_render(
        &[
            &stage(),
            "--resolution",
            "8x8",
            "--spp",
            "1",
            "-o",
            "link.exr",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let meta = std::fs::symlink_metadata(dir.join("link.exr")).unwrap();
    assert!(meta.file_type().is_symlink());
    assert_eq!(exr::read(&dir.join("real.exr")).unwrap().width, 8);
    assert_eq!(entries(&dir), ["link.exr", "real.exr"]);
}

#[test]
fn memory_is_refused_before_it_is_allocated() {
    let dir = temp_dir("memory");
    let s = stage();
    let start = Instant::now();
    let out = spectral_render(
        &[
            &s,
            "--resolution",
            "30000x30000",
            "--spp",
            "1",
            "-o",
            "x.exr",
        ],
        &dir,
    );
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    let line = err.lines().last().unwrap();
    assert!(
        line.contains("not enough memory") && line.contains("over the limit of"),
        "{err}"
    );
    assert!(
        start.elapsed() < Duration::from_secs(5),
        "{:?}",
        start.elapsed()
    );
    // RenderSettings asking for 100000² pixels.
    let text = std::fs::read_to_string(cbox_path()).unwrap()
        + "\ndef RenderSettings \"R\" {\n    uniform int2 resolution = (100000, 100000)\n}\n";
    let huge = common::write(&dir, "huge.usda", &text);
    let out = spectral_render(&[huge.to_str().unwrap(), "--spp", "1"], &dir);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("not enough memory"),
        "{}",
        stderr(&out)
    );
    // An explicit limit below a small render's need.
    let out = spectral_render(&[&s, "--spp", "1", "--max-memory", "1M"], &dir);
    assert!(
        stderr(&out).contains("limit of 1.0 MiB"),
        "{}",
        stderr(&out)
    );
    assert_eq!(entries(&dir), ["huge.usda"]);
}

#[test]
fn the_exr_says_how_it_was_made_in_typed_attributes() {
    let dir = temp_dir("metadata");
    let room = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/room.usda");
    let args = [
        room.to_str().unwrap(),
        "--resolution",
        "32x21",
        "--spp",
        "2",
        "--seed",
        "5",
        "-o",
        "room.exr",
    ];
    let out = spectral_render(&args, &dir);
    assert!(out.status.success(), "{}", stderr(&out));
    let img = exr::read(&dir.join("room.exr")).unwrap();
    // room.usda's camera has exposure −8: RGB (1, 1, 1) is 256 cd/m².
    assert_eq!(img.attributes["whiteLuminance"], "256");
    assert_eq!(img.attributes[exr::EXPOSURE_ATTRIBUTE], "-8");
    assert_eq!(img.attributes[exr::SPP_ATTRIBUTE], "2");
    assert_eq!(img.attributes[exr::SEED_ATTRIBUTE], "5");
    // No --max-depth: unlimited, written as −1.
    assert_eq!(img.attributes[exr::MAX_DEPTH_ATTRIBUTE], "-1");
    // The default integrator is auto, whose pilot chooses between path and bdpt here.
    let integrator = &img.attributes[exr::INTEGRATOR_ATTRIBUTE];
    assert!(
        ["auto→path", "auto→bdpt"].contains(&integrator.as_str()),
        "{integrator}"
    );
    assert_eq!(img.attributes[exr::MIS_ATTRIBUTE], "power");
    // Path and bdpt both draw from the default zsobol.
    assert_eq!(img.attributes[exr::SAMPLER_ATTRIBUTE], "zsobol");
    for (name, ty) in [
        ("whiteLuminance", "float"),
        (exr::EXPOSURE_ATTRIBUTE, "float"),
        (exr::SPP_ATTRIBUTE, "int"),
        (exr::SEED_ATTRIBUTE, "int"),
        (exr::MAX_DEPTH_ATTRIBUTE, "int"),
        (exr::WALL_TIME_ATTRIBUTE, "double"),
        ("worldToCamera", "m44f"),
        ("worldToNDC", "m44f"),
    ] {
        assert_eq!(img.types[name], ty, "{name}");
    }
}

#[test]
fn the_exr_names_the_sampler_its_samples_drew_from() {
    let dir = temp_dir("sampler-attribute");
    let stage = stage();
    // (integrator, --sampler or none, the sampler named): --sampler steers the path tracer and
    // BDPT's and VCM's camera subpaths; light tracing draws independent numbers whatever it says.
    for (k, (integrator, asked, named)) in [
        ("path", None, "zsobol"),
        ("path", Some("independent"), "independent"),
        ("path", Some("zsobol"), "zsobol"),
        ("light", Some("zsobol"), "independent"),
        ("bdpt", None, "zsobol"),
        ("bdpt", Some("independent"), "independent"),
        ("vcm", None, "zsobol"),
        ("light", None, "independent"),
    ]
    .into_iter()
    .enumerate()
    {
        let out = format!("s{k}.exr");
        let mut args = vec![
            stage.as_str(),
            "--resolution",
            "8x8",
            "--spp",
            "1",
            "--integrator",
            integrator,
            "-o",
            &out,
        ];
        if let Some(s) = asked {
            args.extend(["--sampler", s]);
        }
        let o = spectral_render(&args, &dir);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let img = exr::read(&dir.join(&out)).unwrap();
        assert_eq!(
            img.attributes[exr::SAMPLER_ATTRIBUTE],
            named,
            "{integrator} {asked:?}"
        );
        assert_eq!(img.types[exr::SAMPLER_ATTRIBUTE], "string");
    }
}

/// The settings of [`spawn_render`]'s run, which a resume must repeat.
const INTERRUPTED_RUN: [&str; 6] = [
    "--sampler",
    "independent",
    "--resolution",
    "16x16",
    "--threads",
    "1",
];

/// A render of the Cornell box at 16 × 16 on one thread, with a checkpoint after every pass,
/// on independent numbers: the first k samples of a zsobol run depend on its sample count
/// (the sequence's block, `sampling/zsobol.rs`), so an interrupted run's image equals a run of
/// k samples only with the independent sampler.
fn spawn_render(dir: &Path, spp: u32, extra: &[&str]) -> Child {
    bin()
        .arg(stage())
        .args(INTERRUPTED_RUN)
        .args(["-o", "out.exr"])
        .args(["--spp", &spp.to_string()])
        .args(["--checkpoint", "ck", "--checkpoint-interval", "0.001"])
        .args(extra)
        .current_dir(dir)
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn spectral-render")
}

/// Waits for the first checkpoint (the first pass is done), then sends `signal`.
fn interrupt_after_first_pass(
    child: &mut Child,
    dir: &Path,
    signal: &str,
) -> (Option<i32>, String) {
    let start = Instant::now();
    while !dir.join("ck").exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args([signal, &pid])
        .status()
        .unwrap()
        .success());
    let mut err = String::new();
    for line in BufReader::new(child.stderr.take().unwrap()).lines() {
        err.push_str(&line.unwrap());
        err.push('\n');
    }
    (child.wait().unwrap().code(), err)
}

fn pixels(path: &Path) -> Vec<u32> {
    let img = exr::read(path).unwrap();
    img.channels
        .values()
        .flatten()
        .map(|v| v.to_bits())
        .collect()
}

fn spp_of(path: &Path) -> u32 {
    exr::read(path).unwrap().attributes[exr::SPP_ATTRIBUTE]
        .parse()
        .unwrap()
}

/// The uninterrupted render at `spp` samples, its pixels.
fn reference(spp: u32) -> Vec<u32> {
    let dir = temp_dir("reference");
    let out = spectral_render(
        &[
            &stage(),
            "--sampler",
            "independent",
            "--resolution",
            "16x16",
            "--spp",
            &spp.to_string(),
            "-o",
            "ref.exr",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    pixels(&dir.join("ref.exr"))
}

#[test]
fn sigint_writes_the_image_so_far_and_its_checkpoint_resumes_bit_for_bit() {
    const SPP: u32 = 4000;
    let dir = temp_dir("sigint");
    let mut child = spawn_render(&dir, SPP, &[]);
    let (code, err) = interrupt_after_first_pass(&mut child, &dir, "-INT");
    assert_eq!(code, Some(130), "{err}");
    assert!(err.contains("interrupted by SIGINT"), "{err}");
    assert_eq!(entries(&dir), ["ck", "out.exr"], "temp files left: {err}");
    let k = spp_of(&dir.join("out.exr"));
    assert!(k > 0 && k < SPP, "{k}");
    assert_eq!(
        pixels(&dir.join("out.exr")),
        reference(k),
        "the EXR is not {k} spp"
    );
    // Resumed to the end: the uninterrupted render, bit for bit; the checkpoint is removed.
    let out = spectral_render(
        &[
            &stage(),
            "--sampler",
            "independent",
            "--resolution",
            "16x16",
            "--spp",
            &SPP.to_string(),
            "--resume",
            "ck",
            "--checkpoint",
            "ck",
            "-o",
            "resumed.exr",
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(&format!("at {k} spp")),
        "{}",
        stderr(&out)
    );
    assert_eq!(spp_of(&dir.join("resumed.exr")), SPP);
    assert_eq!(pixels(&dir.join("resumed.exr")), reference(SPP));
    assert_eq!(entries(&dir), ["out.exr", "resumed.exr"]);
}

#[test]
fn sigterm_writes_the_image_and_exits_143() {
    let dir = temp_dir("sigterm");
    let mut child = spawn_render(&dir, 4000, &["--preview", "out.png"]);
    let (code, err) = interrupt_after_first_pass(&mut child, &dir, "-TERM");
    assert_eq!(code, Some(143), "{err}");
    assert_eq!(entries(&dir), ["ck", "out.exr", "out.png"], "{err}");
    assert!(spp_of(&dir.join("out.exr")) > 0);
}

#[test]
fn a_resume_of_another_run_is_one_line() {
    let dir = temp_dir("resume-other");
    let s = stage();
    let mut child = spawn_render(&dir, 4000, &[]);
    let (code, err) = interrupt_after_first_pass(&mut child, &dir, "-INT");
    assert_eq!(code, Some(130), "{err}");
    let other = spectral_render(
        &[
            &s,
            "--resolution",
            "16x16",
            "--spp",
            "4000",
            "--seed",
            "9",
            "--resume",
            "ck",
        ],
        &dir,
    );
    let err = stderr(&other);
    assert_eq!(other.status.code(), Some(1), "{err}");
    assert!(err.contains("another run: seed 0 there, 9 here"), "{err}");
    // The roulette's start is part of the run: `auto`, the default, is named; 2, the default
    // before it, is not, so checkpoints written before `--rr-depth` existed still resume with
    // `--rr-depth 2`.
    let mut args = vec![s.as_str()];
    args.extend(INTERRUPTED_RUN);
    args.extend(["--spp", "4000", "--rr-depth", "5", "--resume", "ck"]);
    let rr = spectral_render(&args, &dir);
    let err = stderr(&rr);
    assert_eq!(rr.status.code(), Some(1), "{err}");
    assert!(
        err.contains("another run: rr depth auto there, 5 here"),
        "{err}"
    );
    std::fs::write(dir.join("junk"), b"spectral-render checkpoint\nxx").unwrap();
    let out = spectral_render(&[&s, "--resume", "junk"], &dir);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("junk: --resume"), "{}", stderr(&out));
}

#[test]
fn an_interrupted_meter_prints_its_readings_marked() {
    let dir = temp_dir("meter-int");
    let mut child = bin()
        .args([
            "meter",
            &stage(),
            "--at",
            "0,1,0",
            "--normal",
            "0,1,0",
            "--spp",
            "100000000",
        ])
        .args(["--threads", "1"])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = lines.next().unwrap().unwrap();
    assert!(first.starts_with("loaded"), "{first}");
    std::thread::sleep(Duration::from_millis(200));
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
    let rest: Vec<String> = lines.map(|l| l.unwrap()).collect();
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{rest:?}");
    let text = stdout(&out);
    assert!(
        text.contains("[interrupted]") && text.contains("lx"),
        "{text}"
    );
    assert!(rest.iter().any(|l| l.contains("interrupt")), "{rest:?}");
}

#[test]
fn help_lists_the_commands_and_negative_numbers_say_so() {
    let dir = temp_dir("help");
    let help = stdout(&spectral_render(&["--help"], &dir));
    assert!(
        help.contains("lights") && help.contains("meter") && help.contains("help"),
        "{help}"
    );
    let meter = spectral_render(&["help", "meter"], &dir);
    assert!(meter.status.success() && stdout(&meter).contains("spectral-render meter"));
    assert!(stdout(&spectral_render(&["help", "render"], &dir)).contains("--checkpoint"));
    let unknown = spectral_render(&["help", "nope"], &dir);
    assert_eq!(unknown.status.code(), Some(1));
    let listed = stderr(&unknown);
    assert!(
        listed.contains("available: render, ")
            && ["lights", "meter", "converge"]
                .iter()
                .all(|c| listed.contains(c)),
        "{listed}"
    );
    for args in [
        &["x.usda", "--spp", "-1"][..],
        &["x.usda", "--threads", "-2"],
        &["x.usda", "--max-depth", "-1"],
        &["x.usda", "--resolution", "-5x3"],
        &["meter", "x.usda", "--spp", "-4"],
        &["meter", "x.usda", "--seed", "-1"],
    ] {
        let out = spectral_render(args, &dir);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        assert!(
            err.contains("must be positive") || err.contains("must not be negative"),
            "{err}"
        );
        assert!(!err.contains("-- -"), "{err}");
    }
}

/// Renders `opts` in one go, and again stopped after its first pass, saved, read back and
/// resumed in a new session: the two images are equal bit for bit.
fn assert_resumes_exactly(scene: &scene::Scene, opts: &RenderOptions) {
    let whole = spectral_render::session::render(scene, opts).unwrap();
    let mut first = ImageSession::new(scene, opts).unwrap();
    let stats = first.step().unwrap();
    let target = u64::from(opts.spp.unwrap());
    assert!(
        stats.samples < target,
        "{:?}: one pass did it all",
        opts.integrator
    );
    let bytes = first.checkpoint().encode();
    drop(first);
    let mut second = ImageSession::new(scene, opts).unwrap();
    second.resume(Checkpoint::decode(&bytes).unwrap()).unwrap();
    while second.step().is_some() {}
    let resumed = second.output();
    assert_eq!(resumed.spp, target);
    let bits = |v: &[[f32; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    let what = format!("{:?}", opts.integrator);
    assert_eq!(bits(&resumed.xyz), bits(&whole.xyz), "{what}");
    // The depth cap's report resumes too (its f64 sums are grouped by pass, so to round-off).
    match (resumed.depth_cut, whole.depth_cut) {
        (Some(a), Some(b)) => {
            assert_eq!(a.capped, b.capped, "{what}");
            assert!(
                (a.fraction - b.fraction).abs() <= 1e-9 * b.fraction,
                "{what}"
            );
        }
        (a, b) => assert_eq!(a, b, "{what}"),
    }
    match (&resumed.strategies, &whole.strategies) {
        (Some(a), Some(b)) => {
            for (x, y) in a.iter().zip(b) {
                assert_eq!(bits(&x.weighted), bits(&y.weighted), "{what}");
            }
        }
        (None, None) => {}
        _ => panic!("{what}: strategy images differ"),
    }
}

#[test]
fn checkpoints_resume_bit_for_bit_for_path_bdpt_and_vcm() {
    let path = cbox_path();
    // Splatting integrators take whole chunks of 2^18 samples per pass: at 128² a chunk is
    // 16 spp, so 17 spp take two passes. (Light tracing shares BDPT's splat machinery.)
    let small = scene::load(&path, Some((32, 32))).unwrap();
    let large = scene::load(&path, Some((128, 128))).unwrap();
    let cases = [
        (&small, Integrator::Path, 6, false),
        (
            &large,
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
            17,
            true,
        ),
        (&large, Integrator::Vcm(VcmParams::default()), 17, false),
    ];
    for (scene, integrator, spp, strategies) in cases {
        let opts = RenderOptions {
            spp: Some(spp),
            seed: 11,
            max_depth: Some(2),
            integrator,
            strategies,
            ..Default::default()
        };
        assert_resumes_exactly(scene, &opts);
    }
    // Another seed is another run.
    let opts = RenderOptions {
        spp: Some(4),
        ..Default::default()
    };
    let mut s = ImageSession::new(&small, &opts).unwrap();
    s.step();
    let c = s.checkpoint();
    let other = RenderOptions { seed: 1, ..opts };
    let e = ImageSession::new(&small, &other)
        .unwrap()
        .resume(c)
        .unwrap_err();
    assert!(e.contains("seed"), "{e}");
}

#[test]
fn the_stage_content_hash_tells_stages_apart() {
    let dir = temp_dir("hash");
    let text = std::fs::read_to_string(cbox_path()).unwrap();
    let a = common::write(&dir, "a.usda", &text);
    let b = common::write(&dir, "b.usda", &format!("{text}\n# another stage\n"));
    let load = |p: &PathBuf| scene::load(p, Some((4, 4))).unwrap().content_hash;
    assert_eq!(
        load(&a),
        scene::load(&cbox_path(), Some((4, 4)))
            .unwrap()
            .content_hash
    );
    assert_ne!(load(&a), load(&b));
}
