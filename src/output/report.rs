//! The files of a `converge` report: `report.json` (everything), `report.csv` (one row per
//! snapshot and configuration, [`COLUMNS`]) and `report.md` (the table of times to the
//! target errors, slopes and efficiencies). Peers' CSV files (`tools/converge_peers.py`)
//! have the same columns and are read back by [`read_csv`].

use super::atomic::write_atomically;
use super::json;
use crate::converge::fit::{Summary, TARGETS};
use crate::converge::Row;
use crate::error::{Error, Result};
use serde::Serialize;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// A whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// The command that made it, as typed.
    pub command: String,
    pub stage: String,
    /// "image" or "meters".
    pub kind: String,
    pub resolution: Option<[usize; 2]>,
    pub time_budget_s: f64,
    pub seed: u64,
    /// None: unlimited.
    pub max_depth: Option<u32>,
    /// How the reference was made or where it came from, one sentence.
    pub reference: String,
    /// Pixels masked as emitters seen directly (images).
    pub masked_pixels: Option<usize>,
    /// Lines a reader should know (what was not measured, what was left out).
    pub notes: Vec<String>,
    pub summaries: Vec<Summary>,
    pub rows: Vec<Row>,
}

/// The CSV columns, in order (the names of [`Row`]'s fields).
pub const COLUMNS: [&str; 25] = [
    "config",
    "source",
    "integrator",
    "wavelengths",
    "samples",
    "time_s",
    "elapsed_s",
    "dropped",
    "rel_mse",
    "rel_rmse",
    "rel_rmse_masked",
    "rel_mse_corrected",
    "rel_rmse_corrected",
    "rel_rmse_masked_corrected",
    "bias_masked",
    "bias_masked_bound",
    "error",
    "meter",
    "value",
    "ci95",
    "reference",
    "rel_error",
    "rel_ci95",
    "covered",
    "image",
];

/// Writes report.json, report.csv and report.md into `dir`.
pub fn write(dir: &Path, report: &Report) -> Result<()> {
    text_file(&dir.join("report.json"), &json::pretty(report)?)?;
    text_file(&dir.join("report.csv"), &csv(&report.rows))?;
    text_file(&dir.join("report.md"), &markdown(report))
}

fn text_file(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |f| f.write_all(text.as_bytes()))
        .map_err(|e| Error::io(path, format!("cannot write: {e}")))
}

/// The rows as CSV with a header line; empty fields for what a row does not have.
pub fn csv(rows: &[Row]) -> String {
    let mut out = COLUMNS.join(",") + "\n";
    for r in rows {
        let fields: Vec<String> = COLUMNS.iter().map(|c| field(r, c)).collect();
        out += &fields.join(",");
        out.push('\n');
    }
    out
}

fn opt<T: ToString>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

/// A row's value of `column` as CSV text (names must not hold commas or quotes).
fn field(r: &Row, column: &str) -> String {
    match column {
        "config" => r.config.clone(),
        "source" => r.source.clone(),
        "integrator" => r.integrator.clone(),
        "wavelengths" => opt(r.wavelengths),
        "samples" => r.samples.to_string(),
        "time_s" => r.time_s.to_string(),
        "elapsed_s" => opt(r.elapsed_s),
        "dropped" => opt(r.dropped),
        "rel_mse" => opt(r.rel_mse),
        "rel_rmse" => opt(r.rel_rmse),
        "rel_rmse_masked" => opt(r.rel_rmse_masked),
        "rel_mse_corrected" => opt(r.rel_mse_corrected),
        "rel_rmse_corrected" => opt(r.rel_rmse_corrected),
        "rel_rmse_masked_corrected" => opt(r.rel_rmse_masked_corrected),
        "bias_masked" => opt(r.bias_masked),
        "bias_masked_bound" => opt(r.bias_masked_bound),
        "error" => opt(r.error),
        "meter" => opt(r.meter),
        "value" => opt(r.value),
        "ci95" => opt(r.ci95),
        "reference" => opt(r.reference),
        "rel_error" => opt(r.rel_error),
        "rel_ci95" => opt(r.rel_ci95),
        "covered" => opt(r.covered),
        "image" => opt(r.image.clone()),
        _ => String::new(),
    }
}

/// Reads rows from a CSV with a header naming (some of) [`COLUMNS`]; `config`, `samples` and
/// `time_s` are required. One line `FILE: line N: reason` on a bad value.
pub fn read_csv(path: &Path) -> Result<Vec<Row>> {
    let text =
        std::fs::read_to_string(path).map_err(|e| Error::io(path, format!("cannot read: {e}")))?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let fail =
        |line: usize, reason: String| Error::io(path, format!("line {}: {reason}", line + 1));
    let Some((_, header)) = lines.next() else {
        return Err(fail(0, "the file is empty".into()));
    };
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    for need in ["config", "samples", "time_s"] {
        if !names.contains(&need) {
            return Err(fail(0, format!("the header has no '{need}' column")));
        }
    }
    let mut rows = Vec::new();
    for (i, line) in lines {
        let values: Vec<&str> = line.split(',').map(str::trim).collect();
        if values.len() != names.len() {
            return Err(fail(
                i,
                format!("{} fields, the header has {}", values.len(), names.len()),
            ));
        }
        let mut row = Row::default();
        for (name, value) in names.iter().zip(values) {
            set(&mut row, name, value).map_err(|reason| fail(i, format!("{name}: {reason}")))?;
        }
        if !(row.time_s.is_finite() && row.time_s > 0.0) {
            return Err(fail(
                i,
                format!("time_s {} is not a positive time", row.time_s),
            ));
        }
        rows.push(row);
    }
    Ok(rows)
}

fn parse<T: std::str::FromStr>(v: &str) -> std::result::Result<T, String> {
    v.parse().map_err(|_| format!("'{v}' is not a valid value"))
}

fn parse_opt<T: std::str::FromStr>(v: &str) -> std::result::Result<Option<T>, String> {
    if v.is_empty() {
        Ok(None)
    } else {
        parse(v).map(Some)
    }
}

/// A finite number or nothing.
fn number(v: &str) -> std::result::Result<Option<f64>, String> {
    match parse_opt::<f64>(v)? {
        Some(x) if !x.is_finite() => Err(format!("'{v}' is not finite")),
        x => Ok(x),
    }
}

fn set(r: &mut Row, name: &str, v: &str) -> std::result::Result<(), String> {
    match name {
        "config" => r.config = v.to_string(),
        "source" => r.source = v.to_string(),
        "integrator" => r.integrator = v.to_string(),
        "wavelengths" => r.wavelengths = parse_opt(v)?,
        "samples" => r.samples = parse(v)?,
        "time_s" => r.time_s = number(v)?.unwrap_or(f64::NAN),
        "elapsed_s" => r.elapsed_s = number(v)?,
        "dropped" => r.dropped = parse_opt(v)?,
        "rel_mse" => r.rel_mse = number(v)?,
        "rel_rmse" => r.rel_rmse = number(v)?,
        "rel_rmse_masked" => r.rel_rmse_masked = number(v)?,
        "rel_mse_corrected" => r.rel_mse_corrected = number(v)?,
        "rel_rmse_corrected" => r.rel_rmse_corrected = number(v)?,
        "rel_rmse_masked_corrected" => r.rel_rmse_masked_corrected = number(v)?,
        "bias_masked" => r.bias_masked = number(v)?,
        "bias_masked_bound" => r.bias_masked_bound = number(v)?,
        "error" => r.error = number(v)?,
        "meter" => r.meter = parse_opt(v)?,
        "value" => r.value = number(v)?,
        "ci95" => r.ci95 = number(v)?,
        "reference" => r.reference = number(v)?,
        "rel_error" => r.rel_error = number(v)?,
        "rel_ci95" => r.rel_ci95 = number(v)?,
        "covered" => r.covered = parse_opt(v)?,
        "image" => r.image = (!v.is_empty()).then(|| v.to_string()),
        _ => {}
    }
    Ok(())
}

/// Seconds as the table shows them: 3 significant digits.
fn seconds(t: Option<f64>) -> String {
    match t {
        Some(t) if t >= 100.0 => format!("{t:.0}"),
        Some(t) if t >= 10.0 => format!("{t:.1}"),
        Some(t) => format!("{t:.2}"),
        None => "—".into(),
    }
}

fn percent(e: f64) -> String {
    format!("{:.2} %", 100.0 * e)
}

/// report.md: what was compared, the table, the notes.
pub fn markdown(report: &Report) -> String {
    let mut s = String::new();
    let what = if report.kind == "meters" {
        "relative error of each reading"
    } else {
        "relRMSE (pbrt-v4's relMSE, square-rooted; emitters seen directly masked; the reference's noise subtracted when known)"
    };
    let _ = writeln!(s, "# Convergence: {}\n", report.stage);
    let _ = writeln!(s, "```bash\n{}\n```\n", report.command);
    let mut facts = vec![format!(
        "{} s of integrator wall time per configuration (measured; metrics and snapshot I/O \
         excluded)",
        report.time_budget_s
    )];
    if let Some([w, h]) = report.resolution {
        facts.push(format!("{w}×{h} pixels"));
    }
    let depth = report
        .max_depth
        .map_or("unlimited".to_string(), |d| d.to_string());
    facts.push(format!("seed {}, max depth {depth}", report.seed));
    let _ = writeln!(s, "{}.\n", facts.join(", "));
    let _ = writeln!(s, "Reference: {}\n", report.reference);
    if let Some(m) = report.masked_pixels {
        let _ = writeln!(s, "Emitter mask: {m} pixels see a light source directly.\n");
    }
    let _ = writeln!(
        s,
        "Error: {what}. Times to a target are the measured time of the \
        first snapshot from which on the error stays at or below it (— : not within the \
        budget); the slope is fitted to ln error against ln time over the last two decades \
        of time; efficiency = 1/(error² · time) at the last snapshot, over the best.\n"
    );
    let targets: Vec<String> = TARGETS
        .iter()
        .map(|t| format!("to {:.0} %", 100.0 * t))
        .collect();
    let _ = writeln!(
        s,
        "| configuration | source | samples | time (s) | samples/s | error | slope | {} | efficiency | bias (95 % bound) |",
        targets.join(" | ")
    );
    let _ = writeln!(
        s,
        "|---|---|---:|---:|---:|---:|---:|{}---:|---:|",
        "---:|".repeat(TARGETS.len())
    );
    for x in &report.summaries {
        let name = match x.meter {
            Some(m) => format!("{} (meter {m})", x.config),
            None => x.config.clone(),
        };
        let slope = match (x.slope, x.slope_stderr) {
            (Some(a), Some(e)) => format!("{a:.2} ± {e:.2}"),
            _ => "—".into(),
        };
        let times: Vec<String> = x.time_to.iter().map(|t| seconds(*t)).collect();
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {:.4e} | {} | {slope} | {} | {} | {} |",
            x.source,
            x.samples,
            seconds(Some(x.time_s)),
            x.samples_per_s,
            percent(x.error),
            times.join(" | "),
            x.efficiency_ratio.map_or("—".into(), |r| format!("{r:.2}")),
            match (x.bias, x.bias_bound) {
                (Some(b), Some(u)) => format!("{} (≤ {})", percent(b), percent(u)),
                (Some(b), None) => percent(b),
                _ => "—".into(),
            },
        );
    }
    if !report.notes.is_empty() {
        let _ = writeln!(s, "\nNotes:\n");
        for n in &report.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips() {
        let rows = vec![
            Row {
                config: "path".into(),
                source: "spectral-render".into(),
                integrator: "path".into(),
                wavelengths: Some(4),
                samples: 12,
                time_s: 0.25,
                rel_mse: Some(0.01),
                error: Some(0.1),
                ..Row::default()
            },
            Row {
                config: "bdpt".into(),
                samples: 256,
                time_s: 1.5,
                meter: Some(0),
                value: Some(512.5),
                covered: Some(true),
                image: Some("a.exr".into()),
                ..Row::default()
            },
        ];
        let dir = std::env::temp_dir().join(format!("spectral-render-csv-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("r.csv");
        std::fs::write(&p, csv(&rows)).unwrap();
        assert_eq!(read_csv(&p).unwrap(), rows);
        std::fs::write(&p, "config,samples,time_s\npath,4,-1\n").unwrap();
        let e = read_csv(&p).unwrap_err().to_string();
        assert!(e.contains("line 2") && !e.contains('\n'), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
