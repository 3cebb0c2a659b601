//! The memory a session will need, estimated from its options before anything is allocated,
//! and the check against a limit ([`RenderOptions::max_memory`](super::RenderOptions),
//! `--max-memory`): a render of 30000 × 30000 pixels is refused at once with the figure and
//! the limit, instead of growing until the machine runs out.
//!
//! The estimate adds what the session allocates on top of what the process already holds (the
//! scene: meshes, BVH, textures; read as the resident set, `VmRSS` of `/proc/self/status`):
//!
//! - the film: i128 XYZ sums on the grid (`sensor::grid_sum`), the sample count and the odd
//!   samples' Y per pixel (64 B), and for splatting integrators the splat sums on the grid
//!   and the odd splats' Y (56 B more);
//! - a pass: the tiles' f64 and grid sums and odd Y (80 B per pixel) and the per-pixel
//!   variance (8 B), and
//!   for splatting integrators the splat lists of one chunk, up to max-depth + 1 splats of
//!   24 B (with their odd-sample copy) per sample, `max(splat_chunk_samples(cap), pixels)`
//!   samples (2¹⁸ at caps up to 7, fewer for deeper ones);
//! - the output: XYZ and RGB as f32, the EXR's channels and their compressed copy (72 B per
//!   pixel);
//! - strategy images (`--strategies`): per strategy, f64 weighted and unweighted sums, the
//!   tiles' copy of them and the f32 images written (96 B per pixel);
//! - VCM's light vertex store: one light subpath per pixel (images) or
//!   `meter_light_paths` (meters) of up to max-depth vertices each, held twice while the
//!   store is rebuilt, with the hash grid's index;
//! - meters: per meter its sensor, state and reading, and a map cell's share of the CSV,
//!   JSON and PNG (512 B).
//!
//! Path lengths enter as min(max-depth, [`TYPICAL_DEPTH`]) (an unlimited run's cap is the
//! safety cap): with Russian roulette a path rarely goes deeper, and a cap of 1000 (a furnace
//! test) must not count as a thousand vertices per path. Within that, the figures are
//! bounds.
//!
//! The default limit is what the process holds plus the machine's available memory
//! (`MemAvailable` of `/proc/meminfo`), or [`FALLBACK_LIMIT`] where that cannot be read.

use super::image::splat_chunk_samples;
use super::{MeterOptions, RenderOptions};
use crate::error::{Error, Result};
use crate::integrator::bidir::strategies;
use crate::integrator::bidir::LightVertexStore;
use crate::integrator::cut::depth_cap;
use crate::integrator::Integrator;
use crate::scene::Scene;

/// The limit when the machine's available memory cannot be read.
pub const FALLBACK_LIMIT: u64 = 8 << 30;

/// The path length counted per path (see the module docs).
pub const TYPICAL_DEPTH: u32 = 16;

/// Bytes per pixel of the film, a pass and the output (see the module docs).
const FILM: u64 = 64;
const FILM_SPLATS: u64 = 56;
const PASS: u64 = 88;
const OUTPUT: u64 = 72;
const STRATEGY: u64 = 96;
/// Per pixel of an adaptive render (`session::adaptive`): the pilot's moments of both
/// replicates (2 × 48 B), the allocation (8 B), the odd samples' sums and counts (56 B), the
/// sample counts' image (4 B).
const ADAPTIVE: u64 = 164;
/// Bytes of one splat and its odd-sample copy.
const SPLAT: u64 = 24;
/// Bytes per meter.
const METER: u64 = 512;

/// An estimate: named parts in bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MemoryEstimate {
    pub parts: Vec<(&'static str, u64)>,
}

impl MemoryEstimate {
    fn add(&mut self, what: &'static str, bytes: u64) {
        if bytes > 0 {
            self.parts.push((what, bytes));
        }
    }

    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |sum, (_, b)| sum.saturating_add(*b))
    }

    /// "film 57.6 GiB, output 60.3 GiB, …"
    fn describe(&self) -> String {
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|(what, b)| format!("{what} {}", bytes(*b)))
            .collect();
        parts.join(", ")
    }
}

/// What an image session of `scene` with `opts` allocates.
pub fn image(scene: &Scene, opts: &RenderOptions) -> MemoryEstimate {
    let pixels = u64::from(scene.camera.width) * u64::from(scene.camera.height);
    let caps = opts.integrator.capabilities();
    let cap = depth_cap(opts.max_depth);
    let depth = u64::from(cap.min(TYPICAL_DEPTH));
    let mut e = MemoryEstimate::default();
    let per_pixel = FILM + if caps.splats { FILM_SPLATS } else { 0 };
    e.add("film", pixels.saturating_mul(per_pixel));
    e.add("passes", pixels.saturating_mul(PASS));
    if caps.splats {
        let samples = pixels.max(splat_chunk_samples(cap));
        e.add("splat lists", samples.saturating_mul((depth + 1) * SPLAT));
    }
    e.add("output", pixels.saturating_mul(OUTPUT));
    if let Some(bins) = opts.layers.spectral {
        // i128 sums and a u64 count per pixel, and f32 images on output.
        let per_pixel = bins.count as u64 * (16 + 4) + 8;
        e.add("spectral bins", pixels.saturating_mul(per_pixel));
    }
    if opts.layers.first_hit || opts.layers.albedo {
        // Nine i128 sums and two counts per pixel, and nine f32 images on output.
        e.add(
            "first-hit layers",
            pixels.saturating_mul(9 * 16 + 16 + 9 * 4),
        );
    }
    let layers = scene.emission_layers.len() as u64;
    if layers > 0 {
        // Per layer a film and its output (XYZ and RGB), and its spectral bins.
        let bins = opts
            .layers
            .spectral
            .map_or(0, |b| b.count as u64 * (16 + 4) + 8);
        let per_pixel = layers.saturating_mul(FILM + OUTPUT + bins);
        e.add("emission layers", pixels.saturating_mul(per_pixel));
    }
    if opts.strategies {
        let n = strategies::count(cap.min(strategies::MAX_DEPTH)) as u64;
        e.add("strategy images", pixels.saturating_mul(n * STRATEGY));
    }
    if opts.adaptive {
        e.add("adaptive sampling", pixels.saturating_mul(ADAPTIVE));
    }
    e.add(
        "light vertices",
        light_vertices(&opts.integrator, pixels, depth),
    );
    e
}

/// What a meter session of `meters` meters with `opts` allocates.
pub fn meters(meters: usize, opts: &MeterOptions) -> MemoryEstimate {
    let mut e = MemoryEstimate::default();
    e.add("meters", (meters as u64).saturating_mul(METER));
    let paths = match opts.integrator {
        Integrator::Vcm(p) => p.meter_light_paths,
        _ => 0,
    };
    let depth = u64::from(depth_cap(opts.max_depth).min(TYPICAL_DEPTH));
    e.add(
        "light vertices",
        light_vertices(&opts.integrator, paths, depth),
    );
    e
}

/// VCM's light vertex store for `paths` subpaths per iteration (0 for other integrators).
fn light_vertices(integrator: &Integrator, paths: u64, depth: u64) -> u64 {
    if !matches!(integrator, Integrator::Vcm(_)) {
        return 0;
    }
    let vertex = LightVertexStore::BYTES_PER_VERTEX as u64;
    paths.saturating_mul(depth.max(1)).saturating_mul(vertex)
}

/// Refuses `estimate` when it and what the process holds exceed `limit` (None: the default
/// limit), with one line naming both figures.
pub fn check(what: &str, estimate: &MemoryEstimate, limit: Option<u64>) -> Result<()> {
    let held = resident().unwrap_or(0);
    let limit = limit.unwrap_or_else(default_limit);
    let need = estimate.total().saturating_add(held);
    if need <= limit {
        return Ok(());
    }
    Err(Error::resource(format!(
        "not enough memory: {what} needs about {} ({}) on top of {} in use, over the limit \
         of {} (--max-memory; default: the memory available)",
        bytes(estimate.total()),
        estimate.describe(),
        bytes(held),
        bytes(limit)
    )))
}

/// What the process holds plus the machine's available memory.
pub fn default_limit() -> u64 {
    match meminfo_available() {
        Some(available) => available.saturating_add(resident().unwrap_or(0)),
        None => FALLBACK_LIMIT,
    }
}

/// The resident set of this process in bytes (Linux).
fn resident() -> Option<u64> {
    kib_field(
        &std::fs::read_to_string("/proc/self/status").ok()?,
        "VmRSS:",
    )
}

/// `MemAvailable` of the machine in bytes (Linux).
fn meminfo_available() -> Option<u64> {
    kib_field(
        &std::fs::read_to_string("/proc/meminfo").ok()?,
        "MemAvailable:",
    )
}

/// The value of a `Name:   1234 kB` line, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib.saturating_mul(1024))
}

/// Bytes with a binary unit: "512 B", "3.2 MiB", "57.6 GiB".
pub fn bytes(b: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if b < 1024 {
        return format!("{b} B");
    }
    let mut v = b as f64 / 1024.0;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    format!("{v:.1} {}", UNITS[unit])
}

/// Parses a size: a whole number of bytes with an optional binary unit K, M, G or T (also
/// written KiB, MB, …; all are powers of 1024).
pub fn parse_size(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (n, unit) = t.split_at(digits);
    let n: u64 = n
        .parse()
        .map_err(|_| format!("'{s}': expected a size such as 8G, 512M or 1000000"))?;
    let shift = match unit.trim().to_ascii_uppercase().as_str() {
        "" | "B" => 0,
        "K" | "KB" | "KIB" => 10,
        "M" | "MB" | "MIB" => 20,
        "G" | "GB" | "GIB" => 30,
        "T" | "TB" | "TIB" => 40,
        _ => return Err(format!("'{s}': unknown unit (use K, M, G or T)")),
    };
    let v = n
        .checked_mul(1 << shift)
        .ok_or_else(|| format!("'{s}' is too large"))?;
    if v == 0 {
        return Err(format!("'{s}' must be positive"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_binary_units() {
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_size("1000"), Ok(1000));
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("0").is_err());
        assert!(parse_size("3X").is_err());
        assert!(parse_size("99999999999T").is_err());
    }

    #[test]
    fn figures_read_from_proc_text() {
        let text = "MemTotal:       24000000 kB\nMemAvailable:   20000000 kB\n";
        assert_eq!(kib_field(text, "MemAvailable:"), Some(20_000_000 * 1024));
        assert_eq!(kib_field(text, "VmRSS:"), None);
        assert_eq!(bytes(512), "512 B");
        assert_eq!(bytes(3 << 29), "1.5 GiB");
    }

    #[test]
    fn an_estimate_over_the_limit_is_one_line_with_both_figures() {
        let e = MemoryEstimate {
            parts: vec![("film", 60 << 30), ("output", 10 << 30)],
        };
        let msg = check("the render", &e, Some(1 << 30))
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("70.0 GiB") && msg.contains("limit of 1.0 GiB"),
            "{msg}"
        );
        assert!(
            msg.contains("film 60.0 GiB") && !msg.contains('\n'),
            "{msg}"
        );
        assert!(check("x", &MemoryEstimate::default(), Some(u64::MAX)).is_ok());
    }
}
