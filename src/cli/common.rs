//! What the commands share: the integrator flags (clap's `ValueEnum` for [`Integrator`] and
//! [`MisHeuristic`], from the integrator's own table of names, parsed by [`named`] so that a
//! wrong name says which names there are), the one-line load summary, and warnings.

use crate::error::{Error, Result};
use crate::integrator::bidir::MergeRule;
use crate::integrator::cut;
use crate::integrator::roulette::RrStart;
use crate::integrator::split::Split;
use crate::integrator::vcm::{VcmMode, VcmParams};
use crate::integrator::{Integrator, MisHeuristic};
use crate::output::exr::{ExrMetadata, TimeMetadata};
use crate::sampling::SamplerKind;
use crate::scene::{Machinery, Scene};
use crate::session::{AutoReport, DepthCut};
use clap::builder::{PossibleValue, TypedValueParser};
use clap::ValueEnum;
use std::ffi::OsStr;
use std::marker::PhantomData;
use std::path::Path;

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

impl ValueEnum for VcmMode {
    fn value_variants<'a>() -> &'a [Self] {
        &VcmMode::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self {
            VcmMode::Vcm => "connections and merges",
            VcmMode::Vc => "connections only: exactly BDPT",
            VcmMode::Vm => "merges only: bidirectional photon mapping",
        };
        Some(PossibleValue::new(self.name()).help(help))
    }
}

impl ValueEnum for MergeRule {
    fn value_variants<'a>() -> &'a [Self] {
        &MergeRule::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self {
            MergeRule::All => "at every non-specular vertex (Georgiev et al. 2012)",
            MergeRule::Caustic => {
                "only after a specular or near-specular vertex in light order (L S+ D: \
                 caustics, Jensen's caustic photon map); diffuse light is left to the \
                 connections"
            }
        };
        Some(PossibleValue::new(self.name()).help(help))
    }
}

impl ValueEnum for SamplerKind {
    fn value_variants<'a>() -> &'a [Self] {
        &SamplerKind::ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let help = match self {
            SamplerKind::ZSobol => {
                "Owen-scrambled Sobol' points in Morton order over the image (path, and the \
                 camera subpaths of bdpt and vcm; light tracing and meters draw independent \
                 numbers)"
            }
            SamplerKind::Independent => "independent uniform numbers (PCG32)",
        };
        Some(PossibleValue::new(self.name()).help(help))
    }
}

/// The flags that set an integrator's settings, as the commands take them.
#[derive(clap::Args, Debug, Clone)]
pub struct IntegratorArgs {
    /// Light-transport algorithm (auto: chosen from the scene analysis and a short pilot).
    #[arg(long, default_value = "auto", value_parser = named::<Integrator>("integrator"))]
    pub integrator: Integrator,
    /// MIS heuristic of the integrators that combine techniques (bdpt, vcm).
    #[arg(long, default_value = "power", value_parser = named::<MisHeuristic>("MIS heuristic"))]
    pub mis: MisHeuristic,
    /// What VCM does at a vertex.
    #[arg(long = "vcm-mode", value_parser = named::<VcmMode>("VCM mode"))]
    pub vcm_mode: Option<VcmMode>,
    /// Where VCM (mode vcm) merges (default caustic: equal error for 20–30 % less CPU time on
    /// diffuse scenes, the same on caustics; vm merges everywhere).
    #[arg(long = "vcm-merge", value_parser = named::<MergeRule>("VCM merge rule"))]
    pub vcm_merge: Option<MergeRule>,
    /// VCM's base merging radius r0 in metres (default: 0.75 pixel footprints at the first
    /// hit for images, 0.003 × the scene's radius for meters).
    #[arg(long = "vcm-radius", allow_negative_numbers = true)]
    pub vcm_radius: Option<f32>,
    /// α of VCM's radius schedule r_i = r0 · i^((α−1)/2), in (0, 1] (default 0.75).
    #[arg(long = "vcm-alpha", allow_negative_numbers = true)]
    pub vcm_alpha: Option<f32>,
    /// Light subpaths VCM stores per iteration of meter readings (default 4096; images
    /// store one per pixel).
    #[arg(long = "vcm-light-paths", allow_negative_numbers = true, value_parser = at_least::<u64>(1))]
    pub vcm_light_paths: Option<u64>,
    /// The path tracer's first bounce at which Russian roulette may end a path (Mitsuba's
    /// rr_depth; 2 is pbrt-v4's rule); survival max β·η², at most 1. `auto` (images): chosen
    /// per scene by a pilot of a few thousand paths, as the start that reaches a given error
    /// soonest; meters take 2. BDPT and VCM keep pbrt-v4's.
    #[arg(long = "rr-depth", default_value = "auto", allow_negative_numbers = true,
          value_parser = parse_rr_start)]
    pub rr_depth: RrStart,
    /// The continuations the path tracer splits each image path into at its first vertex
    /// (a power of two up to 16: 1 is no splitting): they share the camera ray and the first
    /// vertex's light sample, each weighted 1/n, which is unbiased. `auto` (images): chosen
    /// per scene with the roulette start by the same pilot; meters, BDPT and VCM do not split.
    #[arg(long = "split", default_value = "auto", allow_negative_numbers = true,
          value_parser = parse_split)]
    pub split: Split,
}

impl IntegratorArgs {
    /// The integrator with its settings, for meters or an image; VCM flags without
    /// `--integrator vcm` are an error.
    pub fn integrator(&self, meters: bool) -> Result<Integrator> {
        let integrator = self.integrator.with_mis(self.mis);
        let Integrator::Vcm(p) = integrator else {
            for (given, flag) in [
                (self.vcm_mode.is_some(), "--vcm-mode"),
                (self.vcm_merge.is_some(), "--vcm-merge"),
                (self.vcm_radius.is_some(), "--vcm-radius"),
                (self.vcm_alpha.is_some(), "--vcm-alpha"),
                (self.vcm_light_paths.is_some(), "--vcm-light-paths"),
            ] {
                if given {
                    return Err(Error::option(format!("{flag} needs --integrator vcm")));
                }
            }
            return Ok(integrator);
        };
        if let Some(r) = self.vcm_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::option(format!(
                    "--vcm-radius {r} must be a positive number of metres"
                )));
            }
        }
        match self.vcm_light_paths {
            Some(_) if !meters => {
                return Err(Error::option(
                    "--vcm-light-paths is for meters; images store one light subpath per pixel",
                ))
            }
            Some(0) => return Err(Error::option("--vcm-light-paths must be at least 1")),
            _ => {}
        }
        if let Some(a) = self.vcm_alpha {
            if !(a > 0.0 && a <= 1.0) {
                return Err(Error::option(format!("--vcm-alpha {a} must be in (0, 1]")));
            }
        }
        Ok(Integrator::Vcm(VcmParams {
            mode: self.vcm_mode.unwrap_or(p.mode),
            merges: self.vcm_merge.unwrap_or(p.merges),
            radius: self.vcm_radius.or(p.radius),
            alpha: self.vcm_alpha.unwrap_or(p.alpha),
            meter_light_paths: self.vcm_light_paths.unwrap_or(p.meter_light_paths),
            ..p
        }))
    }
}

/// Prints what `--integrator auto` chose (`AutoReport::summary`), when it was asked for.
pub fn print_auto(auto: Option<&AutoReport>) {
    if let Some(a) = auto {
        eprintln!("{}", a.summary());
    }
}

/// The integrator's name for the EXR metadata: `auto→bdpt` when auto chose it.
pub fn metadata_name(integrator: &Integrator, auto: Option<&AutoReport>) -> String {
    match auto {
        Some(a) => format!("auto→{}", a.choice.name()),
        None => integrator.name().into(),
    }
}

/// Machinery the scene does not need, forced on: a hidden flag for the tests and
/// `tools/bench_pruning.sh`, which show that it changes only time (`scene::machinery`).
#[derive(clap::Args, Debug, Clone)]
pub struct MachineryArgs {
    /// Keep machinery the scene does not need: all, lobes, light-table, dispersion.
    #[arg(long = "force-machinery", hide = true, value_name = "LIST", value_parser = Machinery::parse)]
    pub force_machinery: Option<Machinery>,
}

impl MachineryArgs {
    pub fn machinery(&self) -> Machinery {
        self.force_machinery.unwrap_or_default()
    }
}

/// Prints the integrator's report (`Estimator::report`) as a note.
pub fn print_report(report: &Option<String>) {
    for line in report.iter().flat_map(|r| r.lines()) {
        eprintln!("note: {line}");
    }
}

/// `--rr-depth`: `auto` or a whole number of at least 1 (`RrStart`).
fn parse_rr_start(s: &str) -> std::result::Result<RrStart, String> {
    s.trim().parse()
}

/// `--split`: `auto` or a power of two from 1 to 16 (`Split`).
fn parse_split(s: &str) -> std::result::Result<Split, String> {
    s.trim().parse()
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
    ) -> std::result::Result<T, clap::Error> {
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
    if let Some(note) = s.time.note() {
        eprintln!("note: {note}");
    }
    if !scene.emission_layers.is_empty() {
        eprintln!(
            "emission layers: {}",
            scene.emission_layers.names().join(", ")
        );
    }
}

/// Prints what `integrator` will not render in `scene` (`Integrator::warnings`).
pub fn warn_limits(integrator: &Integrator, scene: &Scene, images: bool) {
    for w in integrator.warnings(scene, images) {
        eprintln!("warning: {w}");
    }
}

/// Warns about what a depth cap cut of `what` ("the image's mean luminance", "the reading"),
/// when a path reached it (`session::DepthCut`).
pub fn warn_depth_cut(cut: Option<&DepthCut>, what: &str) {
    if let Some(c) = cut {
        eprintln!("warning: {}", depth_cut_message(c, what));
    }
}

/// The line [`warn_depth_cut`] prints.
pub fn depth_cut_message(c: &DepthCut, what: &str) -> String {
    let amount = format!(
        "{}{} ± {} of {what}",
        if c.lower_bound { "at least " } else { "" },
        percent(c.fraction),
        percent(c.ci95)
    );
    if c.user {
        format!(
            "--max-depth {} cut {amount} ({} paths reached it; estimated by continuing a \
             random {} of them past it)",
            c.max_depth,
            c.capped,
            fraction_name(cut::Q)
        )
    } else {
        format!(
            "{} paths reached the safety cap of {} bounces (no --max-depth was given), which \
             cut {amount}: Russian roulette does not end paths whose throughput does not \
             fall (reflectances of 1)",
            c.capped, c.max_depth
        )
    }
}

/// A fraction as a percentage with a precision that shows small values.
fn percent(x: f64) -> String {
    let p = 100.0 * x;
    if !p.is_finite() {
        return "? %".into();
    }
    if p.abs() >= 0.1 || p == 0.0 {
        return format!("{p:.1} %");
    }
    // Two significant digits.
    let decimals = (1.0 - p.abs().log10().floor()).min(12.0) as usize;
    format!("{p:.decimals$} %")
}

/// "1/8" for q = 0.125.
fn fraction_name(q: f32) -> String {
    let inv = 1.0 / q;
    if inv.fract() == 0.0 {
        format!("1/{inv}")
    } else {
        format!("{:.1} %", 100.0 * q)
    }
}

/// Warns about samples dropped for a non-finite value.
pub fn warn_dropped(dropped: u64) {
    if dropped > 0 {
        eprintln!("warning: {dropped} samples had a non-finite value and were dropped");
    }
}

/// Warns about contributions clamped to the film's range (`sensor::grid_sum`).
pub fn warn_clamped(clamped: u64) {
    if clamped > 0 {
        eprintln!(
            "warning: {clamped} contributions exceeded the film's range (2^50 × the output's \
             white in one sample) and were clamped"
        );
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

/// A value parser for whole numbers of at least `min` whose error says so, negative numbers
/// included (give the argument `allow_negative_numbers`, or clap suggests `-- -1`).
pub fn at_least<T: TryFrom<u64>>(
    min: u64,
) -> impl Fn(&str) -> std::result::Result<T, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        let n: i128 = s
            .trim()
            .parse()
            .map_err(|_| format!("'{s}' is not a whole number"))?;
        if n < i128::from(min) {
            return Err(match min {
                0 => format!("{n} must not be negative"),
                1 => format!("{n} must be positive (at least 1)"),
                _ => format!("{n} must be at least {min}"),
            });
        }
        u64::try_from(n)
            .ok()
            .and_then(|v| T::try_from(v).ok())
            .ok_or_else(|| format!("{n} is too large"))
    }
}

/// `--max-memory SIZE`: bytes with an optional K, M, G or T (powers of 1024).
pub fn max_memory(s: &str) -> std::result::Result<u64, String> {
    crate::session::memory::parse_size(s)
}

/// The metadata of an EXR rendered from `stage` (as the user named it) with `integrator`: what
/// made it (spp, seed, depth, integrator and MIS heuristic, time, version) and the camera's
/// exposure and matrices.
pub struct Made<'a> {
    pub stage: &'a Path,
    pub scene: &'a Scene,
    pub integrator: &'a Integrator,
    pub seed: u64,
    pub max_depth: Option<u32>,
    /// The path tracer's first bounce of Russian roulette (`--rr-depth`, as resolved:
    /// `RenderOutput::rr_depth`); None for the other integrators, which it does not apply to.
    pub rr_depth: Option<u32>,
    /// The path tracer's split at the first vertex (`--split`, as resolved); None for the
    /// other integrators.
    pub split: Option<u32>,
    pub spp: u64,
    pub wall_time_s: f64,
    /// The sampler the samples drew from (`RenderOutput::sampler`), when known.
    pub sampler: Option<SamplerKind>,
}

impl Made<'_> {
    pub fn metadata(&self) -> ExrMetadata {
        let camera = &self.scene.camera;
        ExrMetadata {
            spp: self.spp,
            integrator: self.integrator.name().into(),
            mis: mis_name(self.integrator),
            sampler: self.sampler.map(|s| s.name().into()),
            seed: self.seed,
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            split: self.split,
            exposure: camera.exposure,
            wall_time_s: self.wall_time_s,
            version: env!("CARGO_PKG_VERSION").into(),
            scene: self.stage.display().to_string(),
            world_to_camera: Some(camera.world_to_exr_camera().to_cols_array()),
            world_to_ndc: Some(camera.world_to_ndc().to_cols_array()),
            working_space: Default::default(),
            time: time_metadata(&self.scene.summary.time),
        }
    }
}

/// The EXR's time attributes from the time the stage was read at.
fn time_metadata(t: &crate::desc::TimeDesc) -> TimeMetadata {
    TimeMetadata {
        time_code: t.code,
        frames_per_second: t.frames_per_second,
        time_codes_per_second: t.time_codes_per_second,
    }
}

/// The MIS heuristic an integrator combines its techniques with (the path tracer's NEE and
/// BSDF sampling use the power heuristic); None for light tracing, which has one technique.
fn mis_name(integrator: &Integrator) -> Option<String> {
    match integrator {
        Integrator::Path => Some("power".into()),
        Integrator::Light => None,
        Integrator::Bdpt { mis } => Some(mis.name().into()),
        Integrator::Vcm(p) => Some(p.mis.name().into()),
        Integrator::Auto { mis } => Some(mis.name().into()),
    }
}
