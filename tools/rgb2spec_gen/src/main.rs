//! Generates the RGB→spectrum coefficient table that `spectral-render` embeds
//! (`spectra/rgb2spec/srgb_64.bin`), with the `rgb2spec` crate (BSD-3-Clause), a Rust port of
//! Jakob & Hanika's reference optimiser (W. Jakob, J. Hanika, "A Low-Dimensional Function Space
//! for Efficient Spectral Upsampling", Computer Graphics Forum 38(2), 2019).
//!
//! ```text
//! cd tools/rgb2spec_gen && cargo run --release [-- [--no-refine] [<resolution> [<output>]]]
//! cd tools/rgb2spec_gen && cargo run --release -- --diagnose <table.bin>
//! ```
//!
//! Defaults: resolution 64, output `<repo>/spectra/rgb2spec/srgb_<resolution>.bin`.
//!
//! Two steps: (1) `rgb2spec::optimize::optimize(Gamut::SRGB, res)` (the crate's Gauss–Newton
//! fit in CIELAB against its built-in 5 nm CIE/D65 tables, ~45 s at 64³); (2) unless
//! `--no-refine`, every node is polished by Newton's method against the renderer's own 1 nm
//! `spectra/` tables and Rec.709 matrix (see `refine.rs` for why), so that the nodes round-trip
//! to ~1e-6 (f32) instead of up to ~1e-2; near white the crate's bounded solutions are kept, and
//! the black plane is set to s ≈ 0. `--diagnose` reports a table's round-trip errors.
//! `spectra/rgb2spec/srgb_64.md` records the numbers.
//!
//! File format (all little-endian; identical to the original rgb2spec `.coeff` files):
//!
//! | bytes                 | content                                                         |
//! |-----------------------|-----------------------------------------------------------------|
//! | 4                     | magic `b"SPEC"`                                                 |
//! | 4                     | `u32` resolution `res`                                          |
//! | 4·res                 | `f32` scale[res]: the z (max component) grid, smoothstep²(k/(res−1)) |
//! | 4·3·res³·3            | `f32` data[l][z][y][x][3]: coefficients (c0, c1, c2)            |
//!
//! `l` is the index of the largest RGB component, `z` indexes its value through `scale`, and
//! `x`, `y` are the other two components (in the cyclic order l+1, l+2) divided by it, on a uniform
//! grid over [0, 1]. The coefficients define s(λ) = S(c0·λ² + c1·λ + c2) with λ in nm and
//! S(x) = ½ + x / (2·√(1 + x²)). Gamut: sRGB / Rec.709 primaries with illuminant D65.

mod diagnose;
mod refine;

use refine::Colorimetry;
use rgb2spec::optimize::{gamut::Gamut, optimize};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

struct Table {
    res: usize,
    scale: Vec<f32>,
    data: Vec<f32>,
}

impl Table {
    fn from_bytes(b: &[u8]) -> Table {
        let word = |i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
        assert_eq!(&b[..4], b"SPEC");
        let res = u32::from_le_bytes(b[4..8].try_into().unwrap()) as usize;
        let n = 9 * res * res * res;
        assert_eq!(b.len(), 4 * (2 + res + n));
        Table {
            res,
            scale: (2..2 + res).map(word).collect(),
            data: (2 + res..2 + res + n).map(word).collect(),
        }
    }

    fn to_bytes(&self) -> Vec<u8> {
        let mut out = b"SPEC".to_vec();
        out.extend((self.res as u32).to_le_bytes());
        for v in self.scale.iter().chain(&self.data) {
            out.extend(v.to_le_bytes());
        }
        out
    }

    /// The RGB a node stands for: rgb[l] = z, rgb[l+1] = x·z, rgb[l+2] = y·z.
    fn node_rgb(&self, node: usize) -> [f64; 3] {
        let r = self.res;
        let (i, j, k, l) = (
            node % r,
            node / r % r,
            node / (r * r) % r,
            node / (r * r * r),
        );
        let z = self.scale[k] as f64;
        let mut rgb = [0.0; 3];
        rgb[l] = z;
        rgb[(l + 1) % 3] = (i as f64 / (r - 1) as f64) as f32 as f64 * z;
        rgb[(l + 2) % 3] = (j as f64 / (r - 1) as f64) as f32 as f64 * z;
        rgb.map(|v| v as f32 as f64)
    }
}

/// What refinement did, as max RGB errors relative to the node's largest component.
struct Stats {
    /// Before, over the refined nodes with z ≥ 0.05 (dark nodes have larger relative errors).
    before_bright: f64,
    /// After, over the refined nodes.
    after: f64,
    /// Nodes near white whose crate solution was kept, and their largest error.
    kept: usize,
    kept_err: f64,
}

/// Refines every node with z > 0 in parallel (keeping the crate's solution near white where
/// the refined one would exceed [`refine::MAX_COEFF`]) and sets the black plane z = 0 to
/// s(λ) ≈ 0.
fn refine_table(table: &mut Table, cm: &Colorimetry) -> Stats {
    let nodes = table.data.len() / 3;
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let chunk = nodes.div_ceil(threads);
    let src = &*table;
    let results: Vec<Vec<([f32; 3], f64, f64)>> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    (t * chunk..((t + 1) * chunk).min(nodes))
                        .map(|n| {
                            let c = [0, 1, 2].map(|k| src.data[3 * n + k] as f64);
                            let rgb = src.node_rgb(n);
                            if rgb.iter().all(|&v| v == 0.0) {
                                // Black (the z = 0 plane): the crate's Gauss-Newton leaves a
                                // spectrum of RGB ~(0.001, 0.004, 0.0007) here; use s(λ) = S(-1e4)
                                // = 2.5e-9 instead.
                                return ([0.0, 0.0, -1e4], 0.0, 0.0);
                            }
                            let start = refine::to_normalised(c);
                            let e0 = cm.error(start, rgb);
                            let (a, e1) = cm.solve(rgb, start);
                            let near_white = rgb.iter().all(|&v| v > 0.5);
                            let too_big =
                                a.iter().copied().fold(f64::MIN, f64::max) > refine::MAX_COEFF;
                            if (near_white && too_big) || e1 >= e0 {
                                // Towards the white corner the exact solution runs off to
                                // infinity; keep the crate's bounded one, which interpolates sanely.
                                return (c.map(|v| v as f32), e0, e0);
                            }
                            (refine::to_nm(a).map(|v| v as f32), e0, e1)
                        })
                        .collect()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("refinement thread"))
            .collect()
    });
    let mut st = Stats {
        before_bright: 0.0,
        after: 0.0,
        kept: 0,
        kept_err: 0.0,
    };
    for (n, (c, e0, e1)) in results.into_iter().flatten().enumerate() {
        let crate_c = [0, 1, 2].map(|k| table.data[3 * n + k]);
        if c == crate_c && e0 > 0.0 {
            st.kept += 1;
            st.kept_err = st.kept_err.max(e0);
        } else {
            st.after = st.after.max(e1);
            if table.node_rgb(n).iter().copied().fold(0.0, f64::max) >= 0.05 {
                st.before_bright = st.before_bright.max(e0);
            }
        }
        table.data[3 * n..3 * n + 3].copy_from_slice(&c);
    }
    st
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rgb2spec_gen: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    if args.first().map(String::as_str) == Some("--diagnose") {
        let path = args.get(1).ok_or("--diagnose needs a table path")?;
        let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
        diagnose::run(
            &Table::from_bytes(&bytes),
            &Colorimetry::load(&repo.join("spectra"))?,
        );
        return Ok(());
    }
    let refine = !args.iter().any(|a| a == "--no-refine");
    args.retain(|a| a != "--no-refine");
    let res: usize = match args.first().map(|s| s.parse()) {
        None => 64,
        Some(Ok(r)) if (10..=1024).contains(&r) => r,
        Some(_) => {
            return Err(
                "usage: rgb2spec_gen [--no-refine] [<resolution 10..1024> [<output>]]".into(),
            )
        }
    };
    let out = args
        .get(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| repo.join(format!("spectra/rgb2spec/srgb_{res}.bin")));

    let start = Instant::now();
    eprintln!("optimising the sRGB table at resolution {res} with rgb2spec ...");
    let model = optimize(Gamut::SRGB, res).map_err(|e| format!("optimisation failed: {e}"))?;
    let mut bytes = Vec::new();
    model.to_writer(&mut bytes).map_err(|e| e.to_string())?;
    let mut table = Table::from_bytes(&bytes);
    eprintln!("  done in {:.1} s", start.elapsed().as_secs_f64());

    if refine {
        let t = Instant::now();
        let cm = Colorimetry::load(&repo.join("spectra"))?;
        let st = refine_table(&mut table, &cm);
        eprintln!(
            "refined {} nodes against spectra/ in {:.1} s; node RGB error relative to the largest component: \
             {:.2e} before (refined nodes with z >= 0.05), {:.2e} after; {} nodes near white kept as the crate \
             made them (error up to {:.2e})",
            table.data.len() / 3,
            t.elapsed().as_secs_f64(),
            st.before_bright,
            st.after,
            st.kept,
            st.kept_err
        );
    }

    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    std::fs::write(&out, table.to_bytes())
        .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    eprintln!(
        "wrote {} ({:.1} s in all)",
        out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
