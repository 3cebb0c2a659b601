//! Redraws a `converge` report's plot from its `report.csv`, e.g. after the plot's drawing
//! changed, without rendering again:
//!
//! ```text
//! cargo run --release --example replot_convergence -- docs/convergence/cornell-box [--meters]
//! ```
//!
//! The title names the stage as `converge` does (the file name on the first line of
//! `report.md`); `--meters` labels the y axis for a meters report.

use spectral_render::output::{plot, report};
use std::path::PathBuf;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(dir) = args
        .iter()
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
    else {
        eprintln!("usage: replot_convergence DIR [--meters]");
        std::process::exit(2);
    };
    let y_label = if args.iter().any(|a| a == "--meters") {
        "relative error of the reading"
    } else {
        "relRMSE (emitters masked)"
    };
    if let Err(e) = replot(&dir, y_label) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn replot(dir: &std::path::Path, y_label: &str) -> spectral_render::error::Result<()> {
    let rows = report::read_csv(&dir.join("report.csv"))?;
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap_or_default();
    let stage = md
        .lines()
        .next()
        .and_then(|l| l.rsplit('/').next())
        .unwrap_or("stage")
        .trim()
        .to_string();
    let out = dir.join("convergence.png");
    plot::write(
        &out,
        &format!("{stage}: error against time"),
        y_label,
        &rows,
    )?;
    eprintln!("wrote {} ({} rows)", out.display(), rows.len());
    Ok(())
}
