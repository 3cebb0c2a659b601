//! Collecting one sample's contributions and turning them into film sums.
//!
//! A sample's contributions stay spectral ([`SampleRecord`]) until the sample is finished, and
//! are converted to XYZ with the sample's *final* wavelengths: a secondary-wavelength
//! termination at a dispersive event on either subpath then applies to everything the path
//! contributed, camera-side and splatted alike (docs/design.md §5). A sample with any non-finite
//! value is dropped whole and counted. [`TileAccumulator`] keeps a tile's sums and its splat
//! list, which the render loop merges in tile order (deterministic for any thread count).

use super::connect::Contribution;
use super::strategies;
use crate::integrator::cut::{BatchedRatio, CutSample};
use crate::sensor::film::Splat;
use crate::spectral::xyz::sampled_to_xyz;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

/// A contribution to a sensor bin other than the sample's pixel (t = 1), kept spectral.
#[derive(Clone, Copy, Debug)]
pub struct PendingSplat {
    pub bin: u32,
    /// Strategy index (`strategies::index`), or 0 when strategies are not recorded.
    pub strategy: u16,
    pub c: Contribution,
}

/// Everything one (pixel, sample) produced; reused from sample to sample.
#[derive(Clone, Debug, Default)]
pub struct SampleRecord {
    /// The weighted sum of the contributions to the sample's own pixel (t ≥ 2, merges).
    pub camera: Contribution,
    /// Own-pixel contributions valid on the hero wavelength only, whatever the sample's final
    /// wavelengths (merges with a light vertex whose subpath terminated the secondary
    /// wavelengths, by a camera subpath that had not): see [`SampleRecord::own`].
    pub hero_only: SampledSpectrum,
    pub splats: Vec<PendingSplat>,
    /// Per strategy (s, t), the sample's own-pixel contributions; empty when not recorded.
    pub strategies: Vec<Contribution>,
    /// What the sample's continuations past the depth cap found (`integrator::cut`), over
    /// all the bins it reached.
    pub cut: CutSample,
    /// Per emission layer (`light::emission_layers`), the sample's own-pixel radiance with
    /// that layer's emission (path tracing only); empty without layers.
    pub layers: Vec<SampledSpectrum>,
    /// Scratch of twice the layers' length for a path split at its first vertex
    /// (`PathIntegrator::li_split`: the layers' shared sums and their running total), kept so
    /// that a split sample allocates nothing.
    pub split_layers: Vec<SampledSpectrum>,
}

impl SampleRecord {
    /// `strategy_count` 0 records no decomposition.
    pub fn new(strategy_count: usize) -> SampleRecord {
        SampleRecord {
            camera: Contribution::default(),
            hero_only: SampledSpectrum::ZERO,
            splats: Vec::new(),
            strategies: vec![Contribution::default(); strategy_count],
            cut: CutSample::default(),
            layers: Vec::new(),
            split_layers: Vec::new(),
        }
    }

    pub fn clear(&mut self) {
        self.camera = Contribution::default();
        self.hero_only = SampledSpectrum::ZERO;
        self.splats.clear();
        self.strategies.fill(Contribution::default());
        self.cut = CutSample::default();
        self.layers.fill(SampledSpectrum::ZERO);
    }

    /// The weighted sum of everything the sample contributed, whatever the bin: a meter's
    /// estimate (its contributions all go to its one reading).
    pub fn total(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        self.splats
            .iter()
            .fold(self.own(lambda), |acc, s| acc + s.c.weighted)
    }

    /// The weighted own-pixel sum relative to the sample's final wavelengths `lambda`:
    /// `camera` plus the hero-only part as the single-wavelength estimate it is — its hero
    /// lane alone, × N when the secondary wavelengths still count (so that the conversion's
    /// average over N lanes leaves it whole).
    pub fn own(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        if self.hero_only.is_black() {
            return self.camera.weighted;
        }
        let scale = if lambda.secondary_terminated() {
            1.0
        } else {
            crate::spectral::N_LAMBDA as f32
        };
        let mut hero = SampledSpectrum::ZERO;
        hero.0[0] = self.hero_only.0[0] * scale;
        self.camera.weighted + hero
    }

    /// A technique (s, t ≥ 2) contributing to the sample's own pixel.
    #[inline]
    pub fn add_camera(&mut self, s: u32, t: u32, c: Contribution) {
        self.camera += c;
        if !self.strategies.is_empty() {
            self.strategies[strategies::index(s, t)] += c;
        }
    }

    /// A technique (s, 1) splatting into `bin`.
    #[inline]
    pub fn add_splat(&mut self, bin: u32, s: u32, c: Contribution) {
        let strategy = if self.strategies.is_empty() {
            0
        } else {
            strategies::index(s, 1) as u16
        };
        self.splats.push(PendingSplat { bin, strategy, c });
    }
}

/// The sums of one tile: per-pixel XYZ, splats in sample order, dropped samples, the odd
/// samples' luminance apart (for the film's variance estimate), and the per-strategy
/// decomposition when asked for.
#[derive(Clone, Debug, Default)]
pub struct TileAccumulator {
    pub sums: Vec<[f64; 3]>,
    pub splats: Vec<Splat>,
    pub dropped: u64,
    /// Per pixel, the summed Y of the odd-numbered samples' own-pixel values.
    pub odd_y: Vec<f64>,
    /// (pixel, Y) of the odd-numbered samples' splats.
    pub odd_splats: Vec<(u32, f32)>,
    pub strategies: Option<StrategyTile>,
    /// The luminance the samples' continuations found past the depth cap, and theirs within
    /// it, in batches (`integrator::cut`).
    pub cut: BatchedRatio,
}

/// Per-strategy sums of a tile: `weighted[strategy * pixels + k]`, and tagged splats.
#[derive(Clone, Debug, Default)]
pub struct StrategyTile {
    pub pixels: usize,
    pub weighted: Vec<[f64; 3]>,
    pub unweighted: Vec<[f64; 3]>,
    pub splats: Vec<StrategySplat>,
}

/// A splat of one strategy, weighted and unweighted.
#[derive(Clone, Copy, Debug)]
pub struct StrategySplat {
    pub pixel: u32,
    pub strategy: u16,
    pub weighted: [f32; 3],
    pub unweighted: [f32; 3],
}

impl TileAccumulator {
    #[cfg(any(test, feature = "testing"))]
    pub fn new(pixels: usize, strategy_count: usize) -> TileAccumulator {
        TileAccumulator::continuing(vec![[0.0; 3]; pixels], strategy_count)
    }

    /// A tile whose per-pixel sums continue `sums` (the film's open chunk).
    pub fn continuing(sums: Vec<[f64; 3]>, strategy_count: usize) -> TileAccumulator {
        let pixels = sums.len();
        TileAccumulator {
            sums,
            splats: Vec::new(),
            dropped: 0,
            odd_y: vec![0.0; pixels],
            odd_splats: Vec::new(),
            strategies: (strategy_count > 0).then(|| StrategyTile {
                pixels,
                weighted: vec![[0.0; 3]; pixels * strategy_count],
                unweighted: vec![[0.0; 3]; pixels * strategy_count],
                splats: Vec::new(),
            }),
            cut: BatchedRatio::default(),
        }
    }

    /// Adds the finished sample `s` of tile pixel `k` (see the module docs).
    pub fn add(&mut self, k: usize, rec: &SampleRecord, lambda: &SampledWavelengths, s: u64) {
        let odd = s % 2 == 1;
        let xyz = |s| sampled_to_xyz(s, lambda);
        let own = xyz(rec.own(lambda));
        let mut ok = finite(&own);
        let first_splat = self.splats.len();
        let mut total_y = f64::from(own[1]);
        for sp in &rec.splats {
            let v = xyz(sp.c.weighted);
            ok &= finite(&v);
            total_y += f64::from(v[1]);
            self.splats.push(Splat {
                pixel: sp.bin,
                xyz: v,
            });
        }
        if self.strategies.is_some() {
            ok &= rec
                .strategies
                .iter()
                .chain(rec.splats.iter().map(|s| &s.c))
                .all(|c| finite(&xyz(c.unweighted)) && finite(&xyz(c.weighted)));
        }
        if !ok {
            self.splats.truncate(first_splat);
            self.dropped += 1;
            return;
        }
        add3(&mut self.sums[k], own);
        // A non-finite continuation leaves the capped estimate alone and counts as 0.
        let cut_y = if rec.cut.light.is_black() {
            0.0
        } else {
            f64::from(xyz(rec.cut.light)[1])
        };
        let cut_y = if cut_y.is_finite() { cut_y } else { 0.0 };
        self.cut.push(s, total_y, &rec.cut, cut_y);
        if odd {
            self.odd_y[k] += f64::from(own[1]);
            let new = &self.splats[first_splat..];
            self.odd_splats
                .extend(new.iter().map(|s| (s.pixel, s.xyz[1])));
        }
        if let Some(st) = &mut self.strategies {
            st.add(k, rec, lambda);
        }
    }
}

impl StrategyTile {
    /// A finished (finite) sample's contributions, per strategy.
    fn add(&mut self, k: usize, rec: &SampleRecord, lambda: &SampledWavelengths) {
        let xyz = |s| sampled_to_xyz(s, lambda);
        for (i, c) in rec.strategies.iter().enumerate() {
            if c.unweighted.is_black() {
                continue;
            }
            add3(&mut self.weighted[i * self.pixels + k], xyz(c.weighted));
            add3(&mut self.unweighted[i * self.pixels + k], xyz(c.unweighted));
        }
        for s in &rec.splats {
            self.splats.push(StrategySplat {
                pixel: s.bin,
                strategy: s.strategy,
                weighted: xyz(s.c.weighted),
                unweighted: xyz(s.c.unweighted),
            });
        }
    }
}

#[inline]
fn finite(v: &[f32; 3]) -> bool {
    v.iter().all(|c| c.is_finite())
}

#[inline]
fn add3(acc: &mut [f64; 3], v: [f32; 3]) {
    for (a, x) in acc.iter_mut().zip(v) {
        *a += x as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terminated_wavelengths_apply_to_every_contribution_of_the_sample() {
        // A contribution recorded before the termination (a splat from the light subpath) and
        // one after (the camera subpath's) are both converted with the final wavelengths.
        let mut rec = SampleRecord::new(0);
        let c = Contribution::new(SampledSpectrum([1.0, 2.0, 3.0, 4.0]), 1.0);
        rec.add_splat(5, 2, c);
        rec.add_camera(1, 2, c);
        let mut lambda = SampledWavelengths::sample_visible(0.37);
        lambda.terminate_secondary();
        let mut acc = TileAccumulator::new(1, 0);
        acc.add(0, &rec, &lambda, 0);
        let hero = sampled_to_xyz(SampledSpectrum([1.0, 0.0, 0.0, 0.0]), &lambda);
        assert_eq!(acc.splats[0].xyz, hero);
        assert_eq!(acc.sums[0], hero.map(f64::from));
        assert_eq!(acc.dropped, 0);
    }

    #[test]
    fn a_non_finite_contribution_drops_the_whole_sample() {
        let mut rec = SampleRecord::new(0);
        rec.add_camera(0, 2, Contribution::new(SampledSpectrum::ONE, 1.0));
        rec.add_splat(
            1,
            3,
            Contribution::new(SampledSpectrum::splat(f32::NAN), 1.0),
        );
        let mut acc = TileAccumulator::new(1, 0);
        acc.add(0, &rec, &SampledWavelengths::sample_visible(0.5), 1);
        assert_eq!(
            (acc.dropped, acc.splats.len(), acc.sums[0]),
            (1, 0, [0.0; 3])
        );
        assert!(acc.odd_splats.is_empty() && acc.odd_y[0] == 0.0);
    }
}
