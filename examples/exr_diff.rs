//! Compares the pixel data of two EXRs channel by channel, bit for bit.
//!
//! ```text
//! cargo run --release --example exr_diff -- A.exr B.exr
//! ```
//!
//! Prints `IDENTICAL` when every channel the two files share holds the same bits (and they
//! share all their channels), otherwise `DIFFERENT` with the largest absolute difference per
//! channel; exits 0 when identical, 1 when not, 2 on an unreadable file.

use spectral_render::output::exr;
use std::path::PathBuf;

fn main() {
    let paths: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let [a, b] = paths.as_slice() else {
        eprintln!("usage: exr_diff A.exr B.exr");
        std::process::exit(2);
    };
    let read = |p: &PathBuf| {
        exr::read(p).unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(2)
        })
    };
    let (a, b) = (read(a), read(b));
    let mut identical = a.width == b.width && a.channels.keys().eq(b.channels.keys());
    let mut report = Vec::new();
    for (name, va) in &a.channels {
        let Some(vb) = b.channels.get(name) else {
            continue;
        };
        let same =
            va.len() == vb.len() && va.iter().zip(vb).all(|(x, y)| x.to_bits() == y.to_bits());
        let max_abs = va
            .iter()
            .zip(vb)
            .map(|(x, y)| (f64::from(*x) - f64::from(*y)).abs())
            .fold(0.0, f64::max);
        identical &= same;
        report.push(format!("{name} {max_abs:.3e}"));
    }
    let verdict = if identical { "IDENTICAL" } else { "DIFFERENT" };
    println!("{verdict} (max |a − b| per channel: {})", report.join(", "));
    std::process::exit(if identical { 0 } else { 1 });
}
