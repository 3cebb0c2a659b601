//! Opening a stage and reading its metadata (units, up axis, time).

use glam::{DMat4, DVec3, DVec4};
use openusd::{sdf, usd, usda};
use std::path::Path;
use std::sync::{Arc, Mutex};

use super::{resolver, values};
use crate::desc::{ContentHash, TimeOrigin};
use crate::error::{Error, Result};

/// `metersPerUnit` when the stage does not author it (USD's fallback: centimetres).
const DEFAULT_METERS_PER_UNIT: f64 = 0.01;

/// Opens the stage at `path`, turning every failure into a one-line [`Error::file`]; also
/// returns the hash of the bytes of every layer composed, in the order read.
pub(super) fn open(path: &Path) -> Result<(usd::Stage, u64)> {
    if !path.exists() {
        return Err(Error::io(path, "no such file"));
    }
    if !path.is_file() {
        return Err(Error::io(path, "not a regular file"));
    }
    let absolute = std::fs::canonicalize(path).map_err(|e| Error::io(path, e.to_string()))?;
    let Some(name) = absolute.to_str() else {
        return Err(Error::usd(path, "the path is not valid UTF-8"));
    };
    let bytes = std::fs::read(&absolute).map_err(|e| Error::io(path, e.to_string()))?;
    resolver::check_layer(&bytes).map_err(|e| Error::usd(path, e))?;
    let mut root = ContentHash::default();
    root.add(&bytes);
    let digest = Arc::new(Mutex::new(root));
    let stage = usd::Stage::builder()
        .resolver(resolver::CheckedResolver::recording(digest.clone()))
        .open(name)
        .map_err(|e| Error::usd(path, open_failure(&absolute, &e)))?;
    let hash = digest.lock().map_or(0, |d| d.0);
    Ok((stage, hash))
}

/// Describes why opening failed; for a text layer the parser is re-run to locate the line.
fn open_failure(path: &Path, e: &dyn std::fmt::Display) -> String {
    let message = format!("{e:#}");
    match parse_error_location(path) {
        Some(location) => format!("{location}: {message}"),
        None => message,
    }
}

/// "line L column C" of the first syntax error when `path` is a `.usda` text layer.
fn parse_error_location(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    if !text.starts_with("#usda") {
        return None;
    }
    let mut parser = usda::parser::Parser::new(&text);
    if parser.parse().is_ok() {
        return None;
    }
    let highlight = parser.last_error_highlight()?;
    Some(format!(
        "line {} column {}",
        highlight.line, highlight.column
    ))
}

/// Composition problems (unresolved or malformed references, cycles): the stage is incomplete,
/// so the first one is an error.
pub(super) fn check_composition(path: &Path, stage: &usd::Stage) -> Result<()> {
    match stage.composition_errors().first() {
        Some(e) => Err(Error::usd(path, format!("composition error: {e}"))),
        None => Ok(()),
    }
}

/// The stage's `metersPerUnit`, positive and finite.
pub(super) fn meters_per_unit(path: &Path, stage: &usd::Stage) -> Result<f64> {
    let value = stage
        .stage_metadata("metersPerUnit")
        .map_err(|e| Error::usd(path, format!("reading metersPerUnit: {e:#}")))?;
    let Some(value) = value else {
        return Ok(DEFAULT_METERS_PER_UNIT);
    };
    match values::to_f64(&value) {
        Some(m) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(Error::usd(
            path,
            format!("metersPerUnit must be a positive number, got {value:?}"),
        )),
    }
}

/// The stage's up axis: `true` for Z up, `false` for Y up (the default).
pub(super) fn z_up(path: &Path, stage: &usd::Stage) -> Result<bool> {
    let value = stage
        .stage_metadata("upAxis")
        .map_err(|e| Error::usd(path, format!("reading upAxis: {e:#}")))?;
    let token = value.as_ref().and_then(values::to_token);
    match token.as_deref() {
        None if value.is_none() => Ok(false),
        Some("Y") => Ok(false),
        Some("Z") => Ok(true),
        Some(other) => Err(Error::usd(
            path,
            format!("upAxis must be \"Y\" or \"Z\" (UsdGeom allows no other), got \"{other}\""),
        )),
        None => Err(Error::usd(
            path,
            format!("upAxis must be the token \"Y\" or \"Z\", got {value:?}"),
        )),
    }
}

/// Stage space to world space (metres, Y up): `S(metersPerUnit) * R_up`, where a Z-up stage
/// is rotated so that (x, y, z) becomes (x, z, -y).
pub(super) fn stage_to_world(meters_per_unit: f64, z_up: bool) -> DMat4 {
    // Exact columns (images of X, Y, Z) rather than a rotation with cos(pi/2) round-off.
    let up = if z_up {
        DMat4::from_cols(DVec4::X, DVec4::NEG_Z, DVec4::Y, DVec4::W)
    } else {
        DMat4::IDENTITY
    };
    DMat4::from_scale(DVec3::splat(meters_per_unit)) * up
}

/// The time values are read at when none is given: the stage's `startTimeCode` when it
/// authors a time range, else the earliest time sample (a value without samples is its
/// default then).
pub(super) fn read_time(stage: &usd::Stage) -> (usd::TimeCode, TimeOrigin) {
    if stage.has_authored_time_code_range() {
        (
            usd::TimeCode::new(stage.start_time_code()),
            TimeOrigin::StartTimeCode,
        )
    } else {
        (usd::TimeCode::EARLIEST, TimeOrigin::Earliest)
    }
}

/// A number in the stage's metadata (`framesPerSecond`, `timeCodesPerSecond`) when it is
/// authored as a finite number of any numeric type.
pub(super) fn metadata_number(stage: &usd::Stage, field: &str) -> Option<f64> {
    let v = match stage.stage_metadata(field).ok()?? {
        sdf::Value::Double(v) => v,
        sdf::Value::Float(v) => f64::from(v),
        sdf::Value::Int(v) => f64::from(v),
        sdf::Value::Int64(v) => v as f64,
        sdf::Value::Uint(v) => f64::from(v),
        sdf::Value::Uint64(v) => v as f64,
        _ => return None,
    };
    v.is_finite().then_some(v)
}
