//! What the commands share: the integrator flags (clap's `ValueEnum` for [`Integrator`] and
//! [`MisHeuristic`], from the integrator's own table of names, parsed by [`named`] so that a
//! wrong name says which names there are), the one-line load summary, and warnings.

use crate::integrator::{Integrator, MisHeuristic};
use crate::scene::Scene;
use clap::builder::{PossibleValue, TypedValueParser};
use clap::ValueEnum;
use std::ffi::OsStr;
use std::marker::PhantomData;

impl ValueEnum for Integrator {
    fn value_variants<'a>() -> &'a [Self] {
        &Integrator::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()).help(self.help()))
    }
}

impl ValueEnum for MisHeuristic {
    fn value_variants<'a>() -> &'a [Self] {
        &[MisHeuristic::Power, MisHeuristic::Balance]
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self {
            MisHeuristic::Power => "power heuristic, β = 2 (Veach 1997 eq. 9.13)",
            MisHeuristic::Balance => "balance heuristic (Veach 1997 eq. 9.10)",
        };
        Some(PossibleValue::new(self.name()).help(help))
    }
}

/// A value parser for a `ValueEnum` whose error names the kind of value and lists the
/// choices: `unknown integrator 'vcm' (available: path, light, bdpt)`. `--help` lists them
/// with their help as for any `ValueEnum`.
#[derive(Clone, Copy)]
pub struct Named<T> {
    what: &'static str,
    values: PhantomData<fn() -> T>,
}

/// [`Named`] for values that are a `what` (e.g. "integrator").
pub fn named<T>(what: &'static str) -> Named<T> {
    Named {
        what,
        values: PhantomData,
    }
}

impl<T: ValueEnum + Clone + Send + Sync + 'static> TypedValueParser for Named<T> {
    type Value = T;

    fn parse_ref(
        &self,
        _cmd: &clap::Command,
        _arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<T, clap::Error> {
        let text = value.to_string_lossy();
        T::from_str(&text, false).map_err(|_| {
            let names: Vec<String> = T::value_variants()
                .iter()
                .filter_map(|v| v.to_possible_value())
                .map(|p| p.get_name().to_string())
                .collect();
            clap::Error::raw(
                clap::error::ErrorKind::InvalidValue,
                format!(
                    "unknown {} '{text}' (available: {})\n",
                    self.what,
                    names.join(", ")
                ),
            )
        })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        let values = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value());
        Some(Box::new(values))
    }
}

/// The one-line summary every command that reads a scene prints.
pub fn print_summary(scene: &Scene) {
    let s = &scene.summary;
    eprintln!(
        "loaded {}: {} meshes ({} triangles), {} materials, {} lights, camera {}, {}x{}{}",
        scene.source.display(),
        s.meshes,
        s.triangles,
        s.materials,
        s.lights,
        s.camera,
        scene.camera.width,
        scene.camera.height,
        if s.warnings.is_empty() {
            String::new()
        } else {
            format!("; ignored: {}", s.warnings.join("; "))
        }
    );
}

/// Prints what `integrator` will not render in `scene` (`Integrator::warnings`).
pub fn warn_limits(integrator: &Integrator, scene: &Scene, images: bool) {
    for w in integrator.warnings(scene, images) {
        eprintln!("warning: {w}");
    }
}

/// Warns about samples dropped for a non-finite value.
pub fn warn_dropped(dropped: u64) {
    if dropped > 0 {
        eprintln!("warning: {dropped} samples had a non-finite value and were dropped");
    }
}

/// One line from a clap error: its message and the possible values, without the `error: `
/// prefix and the usage block.
pub fn clap_message(e: &clap::Error) -> String {
    let text = e.to_string();
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
        .collect();
    let first = if lines.is_empty() {
        "invalid arguments".to_string()
    } else {
        lines.join(" ")
    };
    format!("{} (see --help)", first.trim_start_matches("error: "))
}
