//! USD time codes on the command line: `--frame` and `--interpolation` (render, meter,
//! lights) and `--frames A..B[:step]` with its output pattern (render).

use crate::error::{Error, Result};
use crate::scene::ReadTime;
use std::path::{Path, PathBuf};

/// At most this many frames in one `--frames` sequence.
const MAX_FRAMES: usize = 100_000;

/// How values between two time samples are read.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum Interpolation {
    /// Numeric samples interpolated linearly (USD's default); other types hold.
    Linear,
    /// Every value is the sample at or before the time code.
    Held,
}

/// `--frame` and `--interpolation`.
#[derive(clap::Args, Debug, Clone)]
pub struct FrameArgs {
    /// The USD time code to read the stage at (default: the stage's startTimeCode, else
    /// each attribute's earliest time sample).
    #[arg(long, allow_negative_numbers = true, value_parser = finite_time)]
    pub frame: Option<f64>,
    /// How time samples are read between two authored ones: linear (USD's default; values
    /// that are not numbers hold the earlier sample) or held.
    #[arg(long, value_enum, default_value_t = Interpolation::Linear)]
    pub interpolation: Interpolation,
}

impl FrameArgs {
    /// The time to read the stage at.
    pub fn read_time(&self) -> ReadTime {
        self.at(self.frame)
    }

    /// The time to read the stage at for frame `frame`.
    pub fn at(&self, frame: Option<f64>) -> ReadTime {
        ReadTime {
            frame,
            held: self.interpolation == Interpolation::Held,
        }
    }
}

/// A time code: a finite number.
fn finite_time(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() => Ok(t),
        _ => Err(format!("'{s}' is not a finite time code")),
    }
}

/// `--frames A..B[:step]`: the time codes A, A + step, ... up to B inclusive.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameRange {
    pub start: f64,
    pub end: f64,
    pub step: f64,
}

impl FrameRange {
    /// The time codes of the sequence, in order.
    pub fn times(&self) -> Vec<f64> {
        let n = ((self.end - self.start) / self.step + 1e-9).floor() as usize + 1;
        (0..n).map(|i| self.start + i as f64 * self.step).collect()
    }
}

/// Parses `A..B` or `A..B:step` (step 1 by default).
pub fn parse_frames(s: &str) -> std::result::Result<FrameRange, String> {
    let (range, step) = match s.rsplit_once(':') {
        Some((r, step)) => (r, finite_time(step)?),
        None => (s, 1.0),
    };
    let (a, b) = range
        .split_once("..")
        .ok_or("expected A..B or A..B:step, e.g. 1..24 or 0..10:0.5")?;
    let (start, end) = (finite_time(a)?, finite_time(b)?);
    if step <= 0.0 {
        return Err(format!("the step {step} must be positive"));
    }
    if end < start {
        return Err(format!("the range {start}..{end} is empty (B < A)"));
    }
    let range = FrameRange { start, end, step };
    if (end - start) / step >= MAX_FRAMES as f64 {
        return Err(format!("more than {MAX_FRAMES} frames"));
    }
    Ok(range)
}

/// `pattern` with its frame placeholder replaced by `frame`: a run of `#` (pbrt's
/// convention: as many digits as `#`s) or a printf `%0Nd` / `%d`. A fractional frame keeps
/// its fraction after the padded integer part (`out.0001.5.exr`).
pub fn frame_path(pattern: &Path, frame: f64) -> Result<PathBuf> {
    let text = pattern.to_string_lossy();
    let Some((at, len, width)) = placeholder(&text) else {
        return Err(Error::option(format!(
            "--frames needs a frame placeholder in '{}' (#### or %04d)",
            pattern.display()
        )));
    };
    let digits = frame_digits(frame, width);
    let name = format!("{}{digits}{}", &text[..at], &text[at + len..]);
    Ok(PathBuf::from(name))
}

/// The first placeholder of `text` in its file name: (byte offset, length, digits).
fn placeholder(text: &str) -> Option<(usize, usize, usize)> {
    let name_start = text.rfind('/').map_or(0, |i| i + 1);
    let name = &text[name_start..];
    if let Some(i) = name.find('#') {
        let run = name[i..].chars().take_while(|&c| c == '#').count();
        return Some((name_start + i, run, run));
    }
    let i = name.find('%')?;
    let rest = &name[i + 1..];
    let spec: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
    if !rest[spec.len()..].starts_with('d') {
        return None;
    }
    let width = spec.trim_start_matches('0').parse().unwrap_or(1);
    Some((name_start + i, spec.len() + 2, width))
}

/// `frame` with its integer part zero-padded to `width` digits.
fn frame_digits(frame: f64, width: usize) -> String {
    let sign = if frame < 0.0 { "-" } else { "" };
    let whole = frame.abs().trunc();
    let fraction = frame.abs() - whole;
    let mut s = format!("{sign}{:0width$}", whole as u64);
    if fraction > 0.0 {
        let f = format!("{fraction}");
        s.push_str(f.trim_start_matches('0'));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_list_their_frames() {
        let r = parse_frames("1..3").unwrap();
        assert_eq!(r.times(), vec![1.0, 2.0, 3.0]);
        assert_eq!(parse_frames("0..1:0.25").unwrap().times().len(), 5);
        assert_eq!(
            parse_frames("-2..2:2").unwrap().times(),
            vec![-2.0, 0.0, 2.0]
        );
        assert_eq!(
            parse_frames("1..10:4").unwrap().times(),
            vec![1.0, 5.0, 9.0]
        );
        for bad in ["1", "3..1", "1..3:0", "1..3:-1", "a..b", "1..inf", "0..1e9"] {
            assert!(parse_frames(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn placeholders_are_replaced_by_padded_frames() {
        let p = |pattern: &str, f: f64| frame_path(Path::new(pattern), f).unwrap();
        assert_eq!(p("out.####.exr", 7.0), PathBuf::from("out.0007.exr"));
        assert_eq!(
            p("dir.#/out.%04d.exr", 12.0),
            PathBuf::from("dir.#/out.0012.exr")
        );
        assert_eq!(p("out.%d.exr", 12.0), PathBuf::from("out.12.exr"));
        assert_eq!(p("out.##.exr", 123.0), PathBuf::from("out.123.exr"));
        assert_eq!(p("out.####.exr", 1.5), PathBuf::from("out.0001.5.exr"));
        assert_eq!(p("out.####.exr", -3.0), PathBuf::from("out.-0003.exr"));
        assert!(frame_path(Path::new("out.exr"), 1.0).is_err());
        assert!(frame_path(Path::new("out.%s.exr"), 1.0).is_err());
    }
}
