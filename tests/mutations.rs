//! A deterministic, seeded mutation test of the input side (issue 13): the stages of
//! `scenes/`, the IES fixtures and the texture fixtures, each mutated a few hundred ways
//! (extreme numbers, deleted, doubled and truncated text, stray brackets, deep nesting,
//! inherits cycles, bad asset paths, flipped bytes, oversized image headers), and run through
//! the binary (`meter`, or an 8×8 render with one sample per pixel).
//!
//! Every case must end in exit 0 with finite output (no "non-finite" warning), or exit 1
//! with exactly one `error: ` line on stderr, its last: never a panic, an abort, a signal, a
//! hang past [`TIMEOUT`] or memory past [`MEMORY_CAP_KB`] (`ulimit -v` on the child).
//!
//! Cases that once failed are kept as fixtures in `tests/data/mutations/` and run first.
//! A failing case is written to `target/mutations/` to be added there.

mod common;

use common::cbox_path;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Cases per kind of input.
const STAGE_CASES: usize = 240;
const IES_CASES: usize = 60;
const TEXTURE_CASES: usize = 60;

/// Wall-clock limit of one case.
const TIMEOUT: Duration = Duration::from_secs(20);

/// Address-space limit of the child, in KiB (the renderer needs about 200 MB of address
/// space for its threads and these small scenes).
const MEMORY_CAP_KB: u64 = 2_000_000;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// SplitMix64: one u64 of state, fixed seeds.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

/// Numbers that break naive arithmetic.
const EXTREMES: [&str; 20] = [
    "1e19",
    "-1e19",
    "1e38",
    "-1e38",
    "3.4e38",
    "1e308",
    "nan",
    "inf",
    "-inf",
    "0",
    "-0",
    "1e-38",
    "1e-45",
    "-1",
    "65536",
    "2147483648",
    "-2147483649",
    "18446744073709551616",
    "1e-300",
    "130",
];

/// The spans of number tokens in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if starts {
            let s = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            let mut e = i;
            while e < b.len() && (b[e].is_ascii_digit() || b".eE+-".contains(&b[e])) {
                e += 1;
            }
            out.push((s, e));
            i = e;
        } else {
            i += 1;
        }
    }
    out
}

/// One mutation of a text file (a stage or an IES profile).
fn mutate_text(text: &str, rng: &mut Rng) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let nums = numbers(text);
    let at = |rng: &mut Rng| {
        let mut k = rng.below(text.len());
        while !text.is_char_boundary(k) {
            k -= 1;
        }
        k
    };
    match rng.below(12) {
        0..=3 if !nums.is_empty() => {
            // Up to three numbers replaced by extremes.
            let mut out = text.to_string();
            let mut picks: Vec<(usize, usize)> =
                (0..1 + rng.below(3)).map(|_| rng.pick(&nums)).collect();
            picks.sort();
            picks.dedup();
            for (s, e) in picks.into_iter().rev() {
                out.replace_range(s..e, rng.pick(&EXTREMES));
            }
            out
        }
        4 => {
            let k = rng.below(lines.len());
            lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| format!("{l}\n"))
                .collect()
        }
        5 => {
            let k = rng.below(lines.len());
            let mut out: Vec<&str> = lines.clone();
            out.insert(k, lines[k]);
            out.iter().map(|l| format!("{l}\n")).collect()
        }
        6 => text[..at(rng)].to_string(),
        7 => {
            let k = at(rng);
            let stray = rng.pick(&[
                "{", "}", "(", ")", "[", "]", "\"", "@", "<", ",", "=", "\n", "#",
            ]);
            format!("{}{stray}{}", &text[..k], &text[k..])
        }
        8 if !nums.is_empty() => {
            // A tuple loses a component, or a number becomes a word.
            let (s, e) = rng.pick(&nums);
            let mut out = text.to_string();
            let cut = if out[e..].starts_with(", ") { e + 2 } else { e };
            out.replace_range(s..cut, "");
            out
        }
        9 => {
            // Numbers near the end of the file scaled by a huge factor (IES candela tables).
            let mut out = text.to_string();
            for &(s, e) in nums.iter().rev().take(1 + rng.below(8)) {
                let v: f64 = out[s..e].parse().unwrap_or(1.0);
                out.replace_range(s..e, &format!("{:e}", v * 1e37));
            }
            out
        }
        _ => {
            // A byte of a line swapped with a byte of another.
            let mut b = text.as_bytes().to_vec();
            let (i, j) = (rng.below(b.len()), rng.below(b.len()));
            b.swap(i, j);
            String::from_utf8_lossy(&b).into_owned()
        }
    }
}

/// Mutations only a stage has: composition and paths.
fn mutate_stage(text: &str, rng: &mut Rng) -> String {
    let insert_after_header = |extra: &str| match text.find("\n)\n") {
        Some(k) => format!("{}{extra}{}", &text[..k + 3], &text[k + 3..]),
        None => format!("{text}{extra}"),
    };
    match rng.below(10) {
        0 => {
            let n = [100, 300, 330, 2000][rng.below(4)];
            let open: String = (0..n).map(|i| format!("def Xform \"N{i}\" {{\n")).collect();
            insert_after_header(&format!("{open}{}", "}\n".repeat(n)))
        }
        1 => insert_after_header(
            "def Xform \"Cyc\" ( inherits = </K1> ) {}\nclass \"K1\" ( inherits = </K2> ) {}\nclass \"K2\" ( inherits = </K1> ) {}\n",
        ),
        2 => insert_after_header(&format!(
            "def Xform \"Ref\" ( references = {} ) {{}}\n",
            rng.pick(&["</Missing>", "@/dev/zero@", "@missing.usda@</A>", "@.@</A>", "</Ref>"])
        )),
        3 => {
            let mpu = rng.pick(&["1e19", "1e-30", "0", "-1", "nan", "1e300"]);
            text.replacen("metersPerUnit = 1", &format!("metersPerUnit = {mpu}"), 1)
        }
        4 => {
            let typo = rng.pick(&["inputs:intensty", "inputs:exposure", "inputs:color"]);
            text.replacen("inputs:intensity", typo, 1)
        }
        _ => mutate_text(text, rng),
    }
}

/// One mutation of a binary image.
fn mutate_image(bytes: &[u8], png: bool, rng: &mut Rng) -> Vec<u8> {
    let mut b = bytes.to_vec();
    match rng.below(4) {
        0 if png => {
            // IHDR width and height (bytes 16..24) made large, with a correct CRC, so that
            // only the size checks stand in the way.
            let w = rng.pick(&[8192u32, 65535, 1 << 30, 4096]);
            let h = rng.pick(&[8192u32, 65535, 1, 4096]);
            b[16..20].copy_from_slice(&w.to_be_bytes());
            b[20..24].copy_from_slice(&h.to_be_bytes());
            let crc = crc32(&b[12..29]);
            b[29..33].copy_from_slice(&crc.to_be_bytes());
            b
        }
        1 => {
            b.truncate(rng.below(b.len()));
            b
        }
        _ => {
            for _ in 0..1 + rng.below(4) {
                let k = rng.below(b.len());
                b[k] = rng.pick(&[0x00, 0xff, 0x7f, 0x80, 0x01]);
            }
            b
        }
    }
}

/// CRC-32 (ISO-HDLC, as PNG chunks use).
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &byte in data {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A stage lighting a floor with a SphereLight shaped by `ies`.
fn ies_stage(ies: &str) -> String {
    format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n
def Mesh \"Floor\" {{
    point3f[] points = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)]
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 3, 2, 1]
}}
def SphereLight \"Lamp\" (prepend apiSchemas = [\"ShapingAPI\"]) {{
    float inputs:radius = 0.05
    float inputs:intensity = 1000
    asset inputs:shaping:ies:file = @{ies}@
    double3 xformOp:translate = (0, 2, 0)
    float xformOp:rotateX = -90
    uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:rotateX\"]
}}
def Camera \"Cam\" {{
    double3 xformOp:translate = (0, 1, 5)
    uniform token[] xformOpOrder = [\"xformOp:translate\"]
}}
"
    )
}

/// A stage with the floor textured by `png` under a dome lit by `exr`.
fn texture_stage(png: &str, exr: &str) -> String {
    format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n
def Mesh \"Floor\" (prepend apiSchemas = [\"MaterialBindingAPI\"]) {{
    point3f[] points = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)]
    int[] faceVertexCounts = [4]
    int[] faceVertexIndices = [0, 3, 2, 1]
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (interpolation = \"vertex\")
    rel material:binding = </M>
}}
def Material \"M\" {{
    token outputs:surface.connect = </M/S.outputs:surface>
    def Shader \"S\" {{
        uniform token info:id = \"UsdPreviewSurface\"
        color3f inputs:diffuseColor.connect = </M/T.outputs:rgb>
        token outputs:surface
    }}
    def Shader \"T\" {{
        uniform token info:id = \"UsdUVTexture\"
        asset inputs:file = @{png}@
        float3 outputs:rgb
    }}
}}
def DomeLight \"Sky\" {{
    asset inputs:texture:file = @{exr}@
}}
def Camera \"Cam\" {{
    double3 xformOp:translate = (0, 1, 5)
    uniform token[] xformOpOrder = [\"xformOp:translate\"]
}}
"
    )
}

/// How a case ended.
#[derive(Debug, PartialEq)]
enum Outcome {
    Rendered,
    Refused,
    /// What it did wrong.
    Failed(String),
}

/// Runs the binary on `stage` (a meter reading or an 8×8 render) and classifies the end.
fn run_case(stage: &Path, meter: bool) -> Outcome {
    let exe = env!("CARGO_BIN_EXE_spectral-render");
    let dir = stage.parent().unwrap();
    let mut args: Vec<String> = vec![exe.into()];
    if meter {
        args.extend(
            [
                "meter", "STAGE", "--at", "0,1,0", "--normal", "0,1,0", "--spp", "16",
            ]
            .map(String::from),
        );
    } else {
        args.extend(["STAGE", "--resolution", "8x8", "--spp", "1", "-o"].map(String::from));
        args.push(dir.join("out.exr").display().to_string());
    }
    let k = args.iter().position(|a| a == "STAGE").unwrap();
    args[k] = stage.display().to_string();
    let mut child = Command::new("bash")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_CAP_KB}; exec \"$@\""))
        .arg("bash")
        .args(&args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run bash");
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Outcome::Failed(format!("hung for more than {TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    let lines: Vec<&str> = stderr.lines().collect();
    let errors = lines.iter().filter(|l| l.starts_with("error: ")).count();
    let bad = match status.code() {
        Some(0) if stderr.contains("non-finite") => "exit 0 with non-finite samples",
        Some(0) => return Outcome::Rendered,
        Some(1) if errors == 1 && lines.last().is_some_and(|l| l.starts_with("error: ")) => {
            return Outcome::Refused
        }
        Some(1) => "exit 1 without exactly one final error line",
        Some(_) => "an exit code other than 0 or 1 (a panic?)",
        None => "killed by a signal (an abort or a stack overflow?)",
    };
    Outcome::Failed(format!("{bad}: {status}; stderr: {}", stderr.trim()))
}

/// Writes `files` (paths relative to `dir`) into `dir`.
fn write_files(dir: &Path, files: &[(String, Vec<u8>)]) {
    for (file, bytes) in files {
        let path = dir.join(file);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
}

/// The outcomes so far.
#[derive(Default)]
struct Tally {
    rendered: usize,
    refused: usize,
    failures: Vec<String>,
}

impl Tally {
    fn add(&mut self, name: &str, outcome: Outcome) {
        match outcome {
            Outcome::Rendered => self.rendered += 1,
            Outcome::Refused => self.refused += 1,
            Outcome::Failed(what) => self.failures.push(format!("{name}: {what}")),
        }
    }
}

/// Runs one generated case in a fresh directory; on failure keeps a copy for the corpus.
fn check_case(name: &str, files: &[(String, Vec<u8>)], meter: bool, tally: &mut Tally) {
    let dir = common::temp_dir(&format!("mutation-{name}"));
    write_files(&dir, files);
    let outcome = run_case(&dir.join(&files[0].0), meter);
    if matches!(outcome, Outcome::Failed(_)) {
        let keep = root().join("target/mutations").join(name);
        write_files(&keep, files);
    }
    tally.add(name, outcome);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The unmutated inputs render: the mutations start from working stages.
#[test]
fn the_unmutated_fixtures_render() {
    let dir = common::temp_dir("mutation-fixtures");
    let ies = std::fs::read(root().join("scenes/ies/downlight.ies")).unwrap();
    let png = std::fs::read(root().join("tests/data/textures/checker.png")).unwrap();
    let exr = std::fs::read(root().join("tests/data/textures/sky.exr")).unwrap();
    let files = [
        ("ies.usda".to_string(), ies_stage("lamp.ies").into_bytes()),
        ("lamp.ies".to_string(), ies),
        (
            "tex.usda".to_string(),
            texture_stage("t.png", "sky.exr").into_bytes(),
        ),
        ("t.png".to_string(), png),
        ("sky.exr".to_string(), exr),
    ];
    write_files(&dir, &files);
    for stage in ["ies.usda", "tex.usda"] {
        for meter in [false, true] {
            assert_eq!(
                run_case(&dir.join(stage), meter),
                Outcome::Rendered,
                "{stage}"
            );
        }
    }
}

#[test]
fn mutated_inputs_never_crash_hang_or_leak_non_finite_values() {
    let start = Instant::now();
    let mut tally = Tally::default();

    // The corpus of cases that once failed.
    let corpus = root().join("tests/data/mutations");
    let mut kept: Vec<PathBuf> = std::fs::read_dir(&corpus)
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    kept.sort();
    for case in kept.iter().filter(|p| p.is_dir()) {
        for meter in [false, true] {
            let name = format!("corpus {}", case.display());
            tally.add(&name, run_case(&case.join("stage.usda"), meter));
        }
    }

    let mut stages: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "usda"))
        .collect();
    stages.push(cbox_path());
    stages.sort();
    let sources: Vec<String> = stages
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    let mut rng = Rng(13);
    for k in 0..STAGE_CASES {
        let i = rng.below(sources.len());
        let text = mutate_stage(&sources[i], &mut rng);
        // Stages that name assets (the room's IES file) find them next to the copy.
        let mut files = vec![("stage.usda".to_string(), text.into_bytes())];
        if sources[i].contains("ies/downlight.ies") {
            let ies = std::fs::read(root().join("scenes/ies/downlight.ies")).unwrap();
            files.push(("ies/downlight.ies".into(), ies));
        }
        check_case(&format!("stage-{k:03}"), &files, k % 2 == 0, &mut tally);
    }

    let ies_sources = ["scenes/ies/downlight.ies", "tests/data/ies/asymmetric.ies"]
        .map(|p| std::fs::read_to_string(root().join(p)).unwrap());
    for k in 0..IES_CASES {
        let source = &ies_sources[rng.below(ies_sources.len())];
        let ies = mutate_text(source, &mut rng);
        // The first case names a device instead of a file (once read forever).
        let file = if k == 0 { "/dev/zero" } else { "lamp.ies" };
        let files = [
            ("stage.usda".to_string(), ies_stage(file).into_bytes()),
            ("lamp.ies".to_string(), ies.into_bytes()),
        ];
        check_case(&format!("ies-{k:03}"), &files, k % 2 == 0, &mut tally);
    }

    let png = std::fs::read(root().join("tests/data/textures/checker.png")).unwrap();
    let exr = std::fs::read(root().join("tests/data/textures/sky.exr")).unwrap();
    for k in 0..TEXTURE_CASES {
        let (png, exr) = if k % 2 == 0 {
            (mutate_image(&png, true, &mut rng), exr.clone())
        } else {
            (png.clone(), mutate_image(&exr, false, &mut rng))
        };
        let files = [
            (
                "stage.usda".to_string(),
                texture_stage("t.png", "sky.exr").into_bytes(),
            ),
            ("t.png".to_string(), png),
            ("sky.exr".to_string(), exr),
        ];
        check_case(&format!("texture-{k:03}"), &files, k % 4 < 2, &mut tally);
    }

    eprintln!(
        "{} rendered, {} refused, {} failed, in {:.1} s",
        tally.rendered,
        tally.refused,
        tally.failures.len(),
        start.elapsed().as_secs_f64()
    );
    let n = tally.failures.len();
    assert!(
        n == 0,
        "{n} cases failed (copies in target/mutations/):\n{}",
        tally.failures.join("\n")
    );
    // Both outcomes occur: the mutations neither all miss nor all break the input.
    assert!(
        tally.rendered > 50 && tally.refused > 50,
        "{} rendered, {} refused",
        tally.rendered,
        tally.refused
    );
}
