//! Light meters against time: each snapshot's readings with their ci95, their relative error
//! against the reference value and whether the interval covers it. Snapshots fall at
//! multiples of the meter session's block ([`crate::session::meter::BLOCK`]), so readings
//! are those of `meter --spp N` with the same seed.

use super::{schedule, Clock, Config, Row, RunOptions, SOURCE};
use crate::error::Result;
use crate::scene::Scene;
use crate::sensor::meter::Meter;
use crate::session::meter::BLOCK;
use crate::session::{MeterOptions, MeterSession, Stop};
use std::time::Instant;

/// A meter's reference value and the half-width of its own 95 % interval (0 when exact).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceValue {
    pub value: f64,
    pub ci95: f64,
}

/// The session options of a meter configuration (snapshots drive it with `step_to`).
pub fn meter_options(config: &Config, opts: &RunOptions) -> MeterOptions {
    MeterOptions {
        stop: Stop::Samples(u64::MAX),
        seed: opts.seed,
        threads: opts.threads,
        max_depth: opts.max_depth,
        integrator: config.integrator,
        ..MeterOptions::default()
    }
}

/// Runs `config` on `meters` to its budget, one row per meter per snapshot.
pub fn run_meters(
    scene: &Scene,
    meters: &[Meter],
    config: &Config,
    opts: &RunOptions,
    references: &[ReferenceValue],
) -> Result<Vec<Row>> {
    let start = Instant::now();
    let mut clock = Clock::default();
    let mo = meter_options(config, opts);
    let mut session = clock.time(|| MeterSession::new(scene, meters, &mo))?;
    let mut rows = Vec::new();
    for n in schedule::checkpoints(BLOCK) {
        if opts.max_samples.is_some_and(|m| n > m) {
            break;
        }
        let Some(stats) = clock.time(|| session.step_to(n)) else {
            continue;
        };
        let run = session.readings();
        for (i, (r, reference)) in run.readings.iter().zip(references).enumerate() {
            let err = (r.value - reference.value).abs();
            let rel = |x: f64| x / reference.value.abs();
            rows.push(Row {
                config: config.label.clone(),
                source: SOURCE.into(),
                integrator: config.integrator.name().into(),
                samples: n,
                time_s: clock.seconds(),
                elapsed_s: Some(start.elapsed().as_secs_f64()),
                dropped: Some(stats.dropped),
                error: Some(rel(err)),
                meter: Some(i),
                value: Some(r.value),
                ci95: Some(r.ci95),
                reference: Some(reference.value),
                rel_error: Some(rel(err)),
                rel_ci95: Some(rel(r.ci95)),
                covered: Some(err <= r.ci95.hypot(reference.ci95)),
                ..Row::default()
            });
        }
        if clock.seconds() >= opts.time_s {
            break;
        }
    }
    Ok(rows)
}

/// Reference values from a long run of `config` for `time_s` seconds (its readings and
/// their ci95).
pub fn long_run(
    scene: &Scene,
    meters: &[Meter],
    config: &Config,
    time_s: f64,
    opts: &RunOptions,
) -> Result<Vec<ReferenceValue>> {
    let mo = MeterOptions {
        time_budget: Some(time_s),
        seed: opts.seed ^ 0x5eed_0000_0000_00ff,
        ..meter_options(config, opts)
    };
    let run = crate::session::measure(scene, meters, &mo)?;
    Ok(run
        .readings
        .iter()
        .map(|r| ReferenceValue {
            value: r.value,
            ci95: r.ci95,
        })
        .collect())
}
