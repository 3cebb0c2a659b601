//! `meter … --part K/N -o PART.json`: part K of N of a light-meter study, and the merge of a
//! study's parts (`spectral-render merge PART.json… -o OUT`).
//!
//! A study of M readings (points or grid cells, in their order) is split by readings: part K
//! measures readings [K·M/N, (K+1)·M/N), each with the random numbers it has in the whole
//! study (the sampler is keyed by seed, reading index and sample:
//! `MeterSession::start_part`). A reading depends on its own samples only — its rounds, its
//! relative-error target and its blocks are its own — so every reading of a part is the whole
//! study's, bit for bit, and the merged readings are the single run's: same values, same
//! ci95, same sample counts. (Splitting the samples of each reading instead would change the
//! ci95's blocks and, under --rel-error, the stopping point; a readings split needs neither.)
//! A time budget makes readings depend on the machine's speed and is refused, as is `auto`
//! (each part would run its own pilot).
//!
//! The part file is JSON: the study's identity (request, sampling options, stage content),
//! the command's arguments (merge reads the request back from them), and each reading with
//! its f64 values as their 16 hex digits of bits, so nothing is lost to decimal. `merge`
//! checks that the parts are of one study, complete and none twice, and writes what the
//! single run writes: the `--json` document for points, the map files for a grid.

use super::interrupt;
use super::meter::{self, MeterArgs, Request};
use crate::error::{Error, Result};
use crate::integrator::Integrator;
use crate::output::atomic::write_atomically;
use crate::output::json;
use crate::output::target::{self, Format, Target};
use crate::session::part::Part;
use crate::session::{Cap, DepthCut, MeterOptions, MeterRun, MeterSession, Reading};
use clap::Parser;
use serde::{Deserialize, Serialize};
use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The `format` of a meter part file.
pub const FORMAT: &str = "spectral-render meter part 1";

/// The meter command's part flag.
#[derive(clap::Args, Debug, Clone)]
pub struct MeterPartArgs {
    /// Measure only part K of N of the readings (readings [K·M/N, (K+1)·M/N) of the M points
    /// or grid cells) and write them to -o PART.json for `spectral-render merge`.
    #[arg(long, value_name = "K/N", value_parser = Part::parse)]
    pub part: Option<Part>,
}

#[derive(Serialize, Deserialize)]
struct MeterPart {
    format: String,
    part: String,
    /// The study: request, sampling options, frame, machinery and stage content.
    identity: String,
    /// The meter command's arguments without --part, -o, --threads, --max-memory, --json.
    args: Vec<String>,
    /// Readings of the whole study, and this part's first.
    readings: u64,
    first: u64,
    dropped: u64,
    wall_time_s: f64,
    /// The stage's metres per unit (the map's axes).
    meters_per_unit: f64,
    values: Vec<PartReading>,
}

/// A reading, exactly: f64 values as the hex digits of their bits.
#[derive(Serialize, Deserialize)]
struct PartReading {
    value: String,
    ci95: String,
    samples: u64,
    /// --max-spp stopped it before --rel-error was met.
    capped: bool,
    depth_cut: Option<PartCut>,
}

#[derive(Serialize, Deserialize)]
struct PartCut {
    max_depth: u32,
    user: bool,
    capped: u64,
    fraction: String,
    ci95: String,
    lower_bound: bool,
}

fn bits(v: f64) -> String {
    format!("{:016x}", v.to_bits())
}

fn from_bits(s: &str) -> Option<f64> {
    u64::from_str_radix(s, 16).ok().map(f64::from_bits)
}

/// Measures the part's readings and writes its file.
pub(super) fn run(args: &MeterArgs, argv: &[OsString]) -> Result<()> {
    let part = args.part.part.expect("a part");
    let out = args
        .output
        .clone()
        .filter(|o| o.extension().is_some_and(|e| e == "json"))
        .ok_or_else(|| Error::option("--part needs -o PART.json: the part's readings go there"))?;
    let mut asked = args.clone();
    asked.output = None;
    let request = meter::request(&asked)?;
    let opts = meter::options(args)?;
    if args.time.is_some() {
        return Err(Error::option(
            "--part does not take --time: a time cap makes readings depend on the machine",
        ));
    }
    if let Integrator::Auto { .. } = opts.integrator {
        return Err(Error::option(format!(
            "--part needs a named --integrator ({}): auto would run its pilot in every part",
            Integrator::names_with(|_| true)
        )));
    }
    if let Request::Points(kind, _) = &request {
        opts.integrator.check_meter(*kind)?;
    }
    let kept = kept_args(argv)?;
    target::check(&[Target::new("-o", &out, Format::Any)])?;
    let Some(scene) = meter::load(args, &opts)? else {
        return Ok(());
    };
    let meters = meter::request_meters(&scene, &request)?;
    let total = meters.len() as u64;
    let (first, end) = part.samples(total);
    let mut session = MeterSession::new(&scene, &meters[first as usize..end as usize], &opts)?;
    session.start_part(first).map_err(Error::option)?;
    let run = meter::measure_session(&mut session)?;
    if let Some(signal) = interrupt::received() {
        eprintln!("interrupted by {signal}: part {} not written", part.label());
        return Ok(());
    }
    let doc = MeterPart {
        format: FORMAT.into(),
        part: part.label(),
        identity: identity(args, &request, &opts, scene.content_hash),
        args: kept,
        readings: total,
        first,
        dropped: run.dropped,
        wall_time_s: run.wall_time_s,
        meters_per_unit: meter::meters_per_unit(&scene),
        values: run.readings.iter().map(part_reading).collect(),
    };
    let text = json::pretty(&doc)?;
    write_atomically(&out, |f| f.write_all(text.as_bytes()))
        .map_err(|e| Error::io(&out, format!("cannot write the part: {e}")))?;
    eprintln!(
        "wrote part {} (readings {first}..{end} of {total}, {:.2} s) to {}",
        part.label(),
        run.wall_time_s,
        out.display()
    );
    Ok(())
}

/// What makes two parts parts of one study.
fn identity(args: &MeterArgs, request: &Request, opts: &MeterOptions, content: u64) -> String {
    let opts = MeterOptions {
        threads: None,
        max_memory: None,
        ..opts.clone()
    };
    format!(
        "request {request:?}; options {opts:?}; frame {:?}; machinery {:?}; \
         stage content {content:016x}",
        args.when, args.machinery
    )
}

/// The command's arguments without those that do not change the readings or name the part.
fn kept_args(argv: &[OsString]) -> Result<Vec<String>> {
    let mut kept = Vec::new();
    let mut skip_next = false;
    for a in argv {
        let a = a
            .to_str()
            .ok_or_else(|| Error::option("--part: an argument is not UTF-8"))?;
        if std::mem::take(&mut skip_next) {
            continue;
        }
        let valued = ["--part", "-o", "--output", "--threads", "--max-memory"];
        if valued.contains(&a) {
            skip_next = true;
        } else if a != "--json"
            && !valued
                .iter()
                .any(|f| a.starts_with(&format!("{f}=")) || (f == &"-o" && a.starts_with("-o")))
        {
            kept.push(a.to_string());
        }
    }
    Ok(kept)
}

fn part_reading(r: &Reading) -> PartReading {
    PartReading {
        value: bits(r.value),
        ci95: bits(r.ci95),
        samples: r.samples,
        capped: r.capped == Some(Cap::Samples),
        depth_cut: r.depth_cut.map(|c| PartCut {
            max_depth: c.max_depth,
            user: c.user,
            capped: c.capped,
            fraction: bits(c.fraction),
            ci95: bits(c.ci95),
            lower_bound: c.lower_bound,
        }),
    }
}

fn reading(p: &PartReading) -> Option<Reading> {
    let depth_cut = match &p.depth_cut {
        None => None,
        Some(c) => Some(DepthCut {
            max_depth: c.max_depth,
            user: c.user,
            capped: c.capped,
            fraction: from_bits(&c.fraction)?,
            ci95: from_bits(&c.ci95)?,
            lower_bound: c.lower_bound,
        }),
    };
    Some(Reading {
        value: from_bits(&p.value)?,
        ci95: from_bits(&p.ci95)?,
        samples: p.samples,
        capped: p.capped.then_some(Cap::Samples),
        depth_cut,
    })
}

/// True when `paths` are meter parts (JSON files) rather than a render's.
pub(super) fn are_meter_parts(paths: &[PathBuf]) -> bool {
    paths
        .iter()
        .all(|p| p.extension().is_some_and(|e| e == "json"))
}

/// Merges a study's parts: `output` gets the points' `--json` document, or is the base name
/// of a grid's map files.
pub(super) fn merge(paths: &[PathBuf], output: &Path) -> Result<()> {
    let docs = paths.iter().map(|p| read(p)).collect::<Result<Vec<_>>>()?;
    let order = check(paths, &docs)?;
    let first = &docs[order[0]];
    let args = MeterArgs::try_parse_from(&first.args)
        .map_err(|e| Error::io(&paths[order[0]], format!("its arguments: {e}")))?;
    let request = meter::request(&args)?;
    let opts = meter::options(&args)?;
    let mut run = MeterRun {
        readings: Vec::new(),
        dropped: 0,
        wall_time_s: 0.0,
        report: None,
        auto: None,
    };
    for &i in &order {
        for v in &docs[i].values {
            let r = reading(v).ok_or_else(|| Error::io(&paths[i], "a reading's bits are bad"))?;
            run.readings.push(r);
        }
        run.dropped += docs[i].dropped;
        run.wall_time_s += docs[i].wall_time_s;
    }
    match request {
        Request::Points(kind, points) => {
            target::check(&[Target::new("-o", output, Format::Any)])?;
            let text = meter::points_output(true, &opts, kind, &points, &run)?;
            write_atomically(output, |f| f.write_all(text.as_bytes()))
                .map_err(|e| Error::io(output, format!("cannot write: {e}")))?;
            eprintln!(
                "merged {} parts into {} ({} readings)",
                docs.len(),
                output.display(),
                run.readings.len()
            );
            Ok(())
        }
        Request::Grid(g) => {
            let base = meter::output_base(Some(output));
            meter::check_map_targets(&base)?;
            let scale = (args.range, first.meters_per_unit);
            meter::grid_output(false, &opts, &g, &run, &base, scale)
        }
    }
}

fn read(path: &Path) -> Result<MeterPart> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::io(path, format!("cannot read the part: {e}")))?;
    let doc: MeterPart =
        json::parse(&text).map_err(|e| Error::io(path, format!("not a meter part: {e}")))?;
    if doc.format != FORMAT {
        return Err(Error::io(
            path,
            format!("not a meter part ({})", doc.format),
        ));
    }
    Ok(doc)
}

/// The parts' order by part index, after checking that they are of one study, each whole,
/// none missing and none twice.
fn check(paths: &[PathBuf], docs: &[MeterPart]) -> Result<Vec<usize>> {
    let mut labelled = Vec::new();
    for (i, d) in docs.iter().enumerate() {
        let part = Part::parse(&d.part).map_err(|e| Error::io(&paths[i], e))?;
        labelled.push((part, i));
    }
    let Some(&(p0, i0)) = labelled.first() else {
        return Err(Error::option("merge: no parts given"));
    };
    let d0 = &docs[i0];
    for &(p, i) in &labelled {
        let d = &docs[i];
        let fail = |why: String| Err(Error::io(&paths[i], why));
        if p.count != p0.count {
            return fail(format!(
                "part {} of a split into {}, not {} as the first part's",
                p.label(),
                p.count,
                p0.count
            ));
        }
        if d.identity != d0.identity || d.args != d0.args || d.readings != d0.readings {
            return fail(format!(
                "part {} is of another study (its request, options or stage differ from the \
                 first part's)",
                p.label()
            ));
        }
        let (a, b) = p.samples(d.readings);
        if d.first != a || d.values.len() as u64 != b - a {
            return fail(format!(
                "part {} holds {} readings from {}, not readings {a}..{b}",
                p.label(),
                d.values.len(),
                d.first
            ));
        }
    }
    labelled.sort_by_key(|&(p, _)| p.index);
    for w in labelled.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(Error::io(
                &paths[w[1].1],
                format!("part {} given twice", w[1].0.label()),
            ));
        }
    }
    let missing: Vec<String> = (0..p0.count)
        .filter(|k| !labelled.iter().any(|(p, _)| p.index == *k))
        .map(|k| format!("{k}/{}", p0.count))
        .collect();
    if !missing.is_empty() {
        return Err(Error::option(format!(
            "merge: missing part {}",
            missing.join(", ")
        )));
    }
    Ok(labelled.into_iter().map(|(_, i)| i).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kept_arguments_leave_out_the_part_and_the_machine() {
        let argv: Vec<OsString> = [
            "meter",
            "s.usda",
            "--part",
            "1/4",
            "-o",
            "p.json",
            "--threads=2",
            "--json",
            "--spp",
            "64",
            "--max-memory",
            "8G",
            "--output=q.json",
            "-ox.json",
        ]
        .iter()
        .map(OsString::from)
        .collect();
        assert_eq!(
            kept_args(&argv).unwrap(),
            vec!["meter", "s.usda", "--spp", "64"]
        );
    }

    #[test]
    fn readings_round_trip_exactly() {
        let r = Reading {
            value: 0.1 + 0.2,
            ci95: 1e-300,
            samples: 7,
            capped: Some(Cap::Samples),
            depth_cut: Some(DepthCut {
                max_depth: 3,
                user: true,
                capped: 2,
                fraction: std::f64::consts::PI,
                ci95: f64::MIN_POSITIVE,
                lower_bound: false,
            }),
        };
        let text = json::pretty(&part_reading(&r)).unwrap();
        let back: PartReading = json::parse(&text).unwrap();
        assert_eq!(reading(&back), Some(r));
    }
}
