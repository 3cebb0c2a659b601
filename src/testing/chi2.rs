//! χ² goodness-of-fit test of a sampling routine against the pdf it claims (the method of
//! pbrt-v4's `bsdfs_test.cpp` and Mitsuba 3's `chi2.py`, written anew).
//!
//! 1. Draw N samples (default 10⁶) from the sampler under test and histogram them over a grid
//!    of cells in a 1D or 2D parameter [`Domain`] (default: 80 θ × 160 φ cells on the sphere).
//! 2. Integrate the pdf over every cell with nested adaptive Simpson quadrature (Lyness 1969,
//!    "Notes on the adaptive Simpson quadrature routine", with Richardson extrapolation), so that
//!    the expected count of a cell is N ∫_cell pdf. Cells more than 3σ off, or holding samples
//!    where the coarse integral found no density, are integrated again 8× finer per dimension,
//!    so that a feature narrower than the quadrature points (a sliver's tip) is not mistaken
//!    for a sampling error.
//! 3. One more cell, *rest*, holds the samples that failed (`None`) or fell outside the domain;
//!    it expects N (1 − ∫_domain pdf). A sampler that fails must therefore have a pdf that
//!    integrates to the success probability (as pbrt's BSDFs do: the pdf of a direction the
//!    sampler cannot produce is 0), and a sampler that fails more or less often than its pdf
//!    admits is rejected.
//! 4. Cells are sorted by expected count and those below 5 are pooled (pbrt's rule, after
//!    Cochran 1952); cells of expected count 0 must stay (almost) empty: more than N·10⁻⁵
//!    samples in them reject outright. Pearson's statistic χ² = Σ (o − e)² / e over the pooled
//!    cells has dof = cells − 1 (no parameter is fitted).
//! 5. The p-value is Q(dof/2, χ²/2), the regularized upper incomplete gamma function
//!    ([`gamma_q`], Numerical Recipes 3rd ed. §6.2), and the test rejects at significance
//!    α = 0.01 with the Šidák correction 1 − (1 − α)^(1/m) for a family of m tests
//!    ([`sidak`]), so a suite of m correct samplers fails with probability α in total.
//!
//! Besides the histogram, every sample's reported pdf (the density an estimator divides by,
//! e.g. `BsdfSample::pdf_w`) is compared with the pdf closure at the sampled point: more than
//! 10⁻⁴·N samples disagreeing by more than 0.1 % reject, because MIS weights use both.
//!
//! A rejection's report gives the statistic, dof, p-value, the rest cell and the cells with the
//! largest standardised residuals (o − e)/√e; the tables are written to the temp dir as text and
//! as a PPM (observed | expected | residual, red = too many samples). `CHI2_DUMP=1` writes them
//! for passing tests too.
//!
//! Delta lobes cannot be histogrammed against a density: a sampler returns `None` for them
//! and the pdf closure excludes them, so they land in the rest cell with the other failures.
//!
//! ```
//! use spectral_render::testing::chi2::{Chi2Test, SphericalDomain};
//! use spectral_render::sampling::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
//!
//! let outcome = Chi2Test::new("cosine hemisphere", SphericalDomain::sphere())
//!     .resolution([10, 20])
//!     .sample_count(20_000)
//!     .run(
//!         |s| {
//!             let wi = cosine_hemisphere(s.get_2d());
//!             Some((wi, cosine_hemisphere_pdf(wi.z) as f64))
//!         },
//!         |wi| cosine_hemisphere_pdf(wi.z) as f64,
//!     );
//! outcome.assert_passed();
//! ```

use crate::sampling::Sampler;
use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::PathBuf;

// ---------------------------------------------------------------------------------------------
// Domains
// ---------------------------------------------------------------------------------------------

/// A parameterisation of the space the samples live in by a rectangle of parameters
/// x = (x₀, x₁); cells are a regular grid over it. The measure of the space is
/// `jacobian · dx₀ dx₁` (e.g. sin θ dθ dφ for solid angle).
pub trait Domain: Sync {
    /// What the sampler returns and the pdf takes.
    type Point: Copy;
    /// [[x₀ min, x₀ max], [x₁ min, x₁ max]].
    fn bounds(&self) -> [[f64; 2]; 2];
    /// Grid resolution [cells along x₀, cells along x₁] used unless the test sets one.
    fn default_resolution(&self) -> [usize; 2];
    /// True when x₁ is a dummy (one cell, the pdf does not depend on it).
    fn is_1d(&self) -> bool {
        false
    }
    /// Parameters of a point, or None if it lies outside the domain.
    fn param_of(&self, p: Self::Point) -> Option<[f64; 2]>;
    /// The point at parameters `x` and the Jacobian of the measure there.
    fn point_at(&self, x: [f64; 2]) -> (Self::Point, f64);
    /// Human-readable location of parameters `x` (for failure reports).
    fn describe(&self, x: [f64; 2]) -> String;
}

/// Unit directions, parameterised by (θ, φ) around an axis (pbrt's layout: θ ∈ [0, θmax],
/// φ ∈ [0, 2π), measure = solid angle, Jacobian sin θ). φ is measured in the frame of
/// Duff et al. 2017 around the axis; for the +Z axis that is the usual φ = atan2(y, x).
#[derive(Clone, Copy, Debug)]
pub struct SphericalDomain {
    s: DVec3,
    t: DVec3,
    n: DVec3,
    theta_max: f64,
}

impl SphericalDomain {
    /// The whole sphere around +Z (the BSDF domain).
    pub fn sphere() -> SphericalDomain {
        SphericalDomain::cap(Vec3::Z, PI)
    }

    /// The whole sphere with its pole on `axis`.
    pub fn around(axis: Vec3) -> SphericalDomain {
        SphericalDomain::cap(axis, PI)
    }

    /// The cap of directions within `theta_max` radians of `axis`: full resolution over a
    /// light that subtends a small solid angle. Samples outside the cap count as failures.
    pub fn cap(axis: Vec3, theta_max: f64) -> SphericalDomain {
        let n = axis.as_dvec3().normalize();
        // Duff et al. 2017, "Building an Orthonormal Basis, Revisited", listing 3, in f64.
        let sign = 1.0f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        SphericalDomain {
            s,
            t,
            n,
            theta_max: theta_max.clamp(1e-6, PI),
        }
    }
}

impl Domain for SphericalDomain {
    type Point = Vec3;

    fn bounds(&self) -> [[f64; 2]; 2] {
        [[0.0, self.theta_max], [0.0, 2.0 * PI]]
    }

    fn default_resolution(&self) -> [usize; 2] {
        [80, 160]
    }

    fn param_of(&self, p: Vec3) -> Option<[f64; 2]> {
        let v = p.as_dvec3();
        let len = v.length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        let v = v / len;
        let theta = v.dot(self.n).clamp(-1.0, 1.0).acos();
        if theta > self.theta_max {
            return None;
        }
        let mut phi = v.dot(self.t).atan2(v.dot(self.s));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        Some([theta, phi])
    }

    fn point_at(&self, x: [f64; 2]) -> (Vec3, f64) {
        let (sin_t, cos_t) = x[0].sin_cos();
        let (sin_p, cos_p) = x[1].sin_cos();
        let d = sin_t * cos_p * self.s + sin_t * sin_p * self.t + cos_t * self.n;
        (d.as_vec3(), sin_t)
    }

    fn describe(&self, x: [f64; 2]) -> String {
        format!(
            "θ = {:.2}°, φ = {:.2}°",
            x[0].to_degrees(),
            x[1].to_degrees()
        )
    }
}

/// An interval of the real line (e.g. wavelengths in nm), measure = length.
#[derive(Clone, Copy, Debug)]
pub struct IntervalDomain {
    pub min: f64,
    pub max: f64,
}

impl IntervalDomain {
    pub fn new(min: f64, max: f64) -> IntervalDomain {
        IntervalDomain { min, max }
    }
}

impl Domain for IntervalDomain {
    type Point = f32;

    fn bounds(&self) -> [[f64; 2]; 2] {
        [[self.min, self.max], [0.0, 1.0]]
    }

    fn default_resolution(&self) -> [usize; 2] {
        [200, 1]
    }

    fn is_1d(&self) -> bool {
        true
    }

    fn param_of(&self, p: f32) -> Option<[f64; 2]> {
        let x = p as f64;
        (x >= self.min && x <= self.max).then_some([x, 0.5])
    }

    fn point_at(&self, x: [f64; 2]) -> (f32, f64) {
        (x[0] as f32, 1.0)
    }

    fn describe(&self, x: [f64; 2]) -> String {
        format!("x = {:.4}", x[0])
    }
}

/// An axis-aligned rectangle of the plane, measure = area (for area warps: disks, triangles,
/// 2D distributions).
#[derive(Clone, Copy, Debug)]
pub struct PlanarDomain {
    pub min: Vec2,
    pub max: Vec2,
}

impl PlanarDomain {
    pub fn new(min: Vec2, max: Vec2) -> PlanarDomain {
        PlanarDomain { min, max }
    }
}

impl Domain for PlanarDomain {
    type Point = Vec2;

    fn bounds(&self) -> [[f64; 2]; 2] {
        [
            [self.min.x as f64, self.max.x as f64],
            [self.min.y as f64, self.max.y as f64],
        ]
    }

    fn default_resolution(&self) -> [usize; 2] {
        [100, 100]
    }

    fn param_of(&self, p: Vec2) -> Option<[f64; 2]> {
        let inside = p.cmpge(self.min).all() && p.cmple(self.max).all();
        inside.then_some([p.x as f64, p.y as f64])
    }

    fn point_at(&self, x: [f64; 2]) -> (Vec2, f64) {
        (Vec2::new(x[0] as f32, x[1] as f32), 1.0)
    }

    fn describe(&self, x: [f64; 2]) -> String {
        format!("(x, y) = ({:.4}, {:.4})", x[0], x[1])
    }
}

// ---------------------------------------------------------------------------------------------
// The test
// ---------------------------------------------------------------------------------------------

/// Accuracy of the per-cell pdf integral (nested adaptive Simpson).
#[derive(Clone, Copy, Debug)]
pub struct Quadrature {
    /// Subdivisions forced in each dimension before the error test may stop (2 = 9 points per
    /// cell and dimension), so that features smaller than a cell are not missed.
    pub min_depth: u32,
    /// Subdivision limit in each dimension (reached only along discontinuities).
    pub max_depth: u32,
    /// Target absolute error of a cell's expected count (in samples).
    pub count_tolerance: f64,
}

impl Default for Quadrature {
    fn default() -> Quadrature {
        Quadrature {
            min_depth: 2,
            max_depth: 14,
            count_tolerance: 0.01,
        }
    }
}

/// A configured χ² test; [`Chi2Test::run`] performs it.
#[derive(Clone, Debug)]
pub struct Chi2Test<D: Domain> {
    name: String,
    domain: D,
    res: [usize; 2],
    sample_count: usize,
    significance: f64,
    test_count: usize,
    min_expected: f64,
    seed: u64,
    quadrature: Quadrature,
    pdf_tolerance: f64,
    max_pdf_mismatch: f64,
}

impl<D: Domain> Chi2Test<D> {
    /// A test with pbrt's defaults: 10⁶ samples, α = 0.01, one test in the family, pooling
    /// below 5 expected samples, the domain's default grid, a seed derived from `name`.
    pub fn new(name: impl Into<String>, domain: D) -> Chi2Test<D> {
        let name = name.into();
        Chi2Test {
            seed: fnv1a(name.as_bytes()),
            res: domain.default_resolution(),
            name,
            domain,
            sample_count: 1_000_000,
            significance: 0.01,
            test_count: 1,
            min_expected: 5.0,
            quadrature: Quadrature::default(),
            pdf_tolerance: 1e-3,
            max_pdf_mismatch: 1e-4,
        }
    }

    /// Cells along each parameter (for a 1D domain the second must be 1).
    pub fn resolution(mut self, res: [usize; 2]) -> Self {
        assert!(res[0] > 0 && res[1] > 0, "χ² resolution must be positive");
        self.res = res;
        self
    }

    pub fn sample_count(mut self, n: usize) -> Self {
        self.sample_count = n;
        self
    }

    /// Significance level α of the whole family (before the Šidák correction).
    pub fn significance(mut self, alpha: f64) -> Self {
        self.significance = alpha;
        self
    }

    /// Number m of tests in the family this one belongs to (Šidák correction).
    pub fn test_count(mut self, m: usize) -> Self {
        self.test_count = m.max(1);
        self
    }

    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    pub fn quadrature(mut self, q: Quadrature) -> Self {
        self.quadrature = q;
        self
    }

    /// Relative tolerance of the per-sample pdf check and the largest fraction of samples
    /// allowed to exceed it (defaults 10⁻³ and 10⁻⁴).
    pub fn pdf_check(mut self, tolerance: f64, max_fraction: f64) -> Self {
        self.pdf_tolerance = tolerance;
        self.max_pdf_mismatch = max_fraction;
        self
    }

    /// Runs the test. `sample` draws one sample from the sampler stream, returning the point
    /// and the pdf the routine reports for it, or None when the routine fails (or produces a
    /// delta sample). `pdf` is the claimed density with respect to the domain's measure.
    pub fn run<S, F>(&self, mut sample: S, pdf: F) -> Chi2Outcome
    where
        S: FnMut(&mut Sampler) -> Option<(D::Point, f64)>,
        F: Fn(D::Point) -> f64 + Sync,
    {
        let hist = self.histogram(&mut sample, &pdf);
        let mut expected = self.expected(&pdf);
        self.refine_suspicious(&pdf, &hist.counts, &mut expected);
        self.evaluate(hist, expected)
    }

    // --- step 1: histogram and per-sample pdf check -------------------------------------

    fn histogram<S, F>(&self, sample: &mut S, pdf: &F) -> Histogram
    where
        S: FnMut(&mut Sampler) -> Option<(D::Point, f64)>,
        F: Fn(D::Point) -> f64,
    {
        let [nx, ny] = self.res;
        let [[x0, x1], [y0, y1]] = self.domain.bounds();
        let mut h = Histogram {
            counts: vec![0.0; nx * ny],
            ..Histogram::default()
        };
        let mut rng = Sampler::new(self.seed, 0, 0);
        for _ in 0..self.sample_count {
            let Some((p, reported)) = sample(&mut rng) else {
                h.failed += 1;
                continue;
            };
            self.check_pdf(&mut h, p, reported, pdf(p));
            let Some(x) = self.domain.param_of(p) else {
                h.outside += 1;
                continue;
            };
            let ix = bin(x[0], x0, x1, nx);
            let iy = bin(x[1], y0, y1, ny);
            h.counts[ix * ny + iy] += 1.0;
        }
        h
    }

    fn check_pdf(&self, h: &mut Histogram, p: D::Point, reported: f64, reference: f64) {
        let diff = (reported - reference).abs();
        let scale = reported.abs().max(reference.abs());
        let ok = reported.is_finite() && (diff == 0.0 || diff <= self.pdf_tolerance * scale);
        if ok {
            return;
        }
        h.pdf_mismatches += 1;
        if h.first_mismatch.is_none() {
            let at = match self.domain.param_of(p) {
                Some(x) => self.domain.describe(x),
                None => "a point outside the domain".into(),
            };
            h.first_mismatch = Some(format!(
                "at {at}: sampler reports {reported:.6e}, pdf gives {reference:.6e}"
            ));
        }
    }

    // --- step 2: expected counts ----------------------------------------------------------

    fn expected<F: Fn(D::Point) -> f64 + Sync>(&self, pdf: &F) -> Vec<f64> {
        let [nx, ny] = self.res;
        let mut expected = vec![0.0; nx * ny];
        expected
            .par_chunks_mut(ny)
            .enumerate()
            .for_each(|(ix, row)| {
                for (iy, e) in row.iter_mut().enumerate() {
                    *e = self.sample_count as f64 * self.cell_integral(pdf, ix, iy);
                }
            });
        expected
    }

    /// Integrates again, with 3 more forced subdivisions per dimension, every cell whose count
    /// is more than 3σ from its expectation or that has samples but expects none. The coarse
    /// quadrature can miss a feature narrower than its point spacing (the tip of a sliver
    /// triangle); a finer integral only makes the expectation more exact, so this cannot hide
    /// a wrong sampler.
    fn refine_suspicious<F>(&self, pdf: &F, observed: &[f64], expected: &mut [f64])
    where
        F: Fn(D::Point) -> f64 + Sync,
    {
        let ny = self.res[1];
        let suspicious: Vec<usize> = (0..expected.len())
            .filter(|&i| {
                let (o, e) = (observed[i], expected[i]);
                (e == 0.0 && o > 0.0) || (o - e).abs() > 3.0 * e.max(1.0).sqrt()
            })
            .collect();
        let fine = Quadrature {
            min_depth: self.quadrature.min_depth + 3,
            max_depth: self.quadrature.max_depth + 3,
            ..self.quadrature
        };
        let refined: Vec<f64> = suspicious
            .par_iter()
            .map(|&i| {
                let integral = self.cell_integral_with(pdf, i / ny, i % ny, &fine);
                self.sample_count as f64 * integral
            })
            .collect();
        for (&i, e) in suspicious.iter().zip(refined) {
            expected[i] = e;
        }
    }

    /// ∫_cell pdf dμ. Evaluation points are kept 10⁻⁶ of a cell inside the cell, so that a
    /// discontinuity of the pdf on a cell edge (a hemisphere boundary at θ = 90°, a texel
    /// edge) is attributed to the correct side.
    fn cell_integral<F: Fn(D::Point) -> f64>(&self, pdf: &F, ix: usize, iy: usize) -> f64 {
        self.cell_integral_with(pdf, ix, iy, &self.quadrature)
    }

    fn cell_integral_with<F: Fn(D::Point) -> f64>(
        &self,
        pdf: &F,
        ix: usize,
        iy: usize,
        q: &Quadrature,
    ) -> f64 {
        let [[x0, x1], [y0, y1]] = self.domain.bounds();
        let dx = (x1 - x0) / self.res[0] as f64;
        let dy = (y1 - y0) / self.res[1] as f64;
        let (xa, ya) = (x0 + ix as f64 * dx, y0 + iy as f64 * dy);
        let (xb, yb) = (xa + dx, ya + dy);
        let g = |x: f64, y: f64| {
            let x = x.clamp(xa + 1e-6 * dx, xb - 1e-6 * dx);
            let y = y.clamp(ya + 1e-6 * dy, yb - 1e-6 * dy);
            let (p, jacobian) = self.domain.point_at([x, y]);
            pdf(p) * jacobian
        };
        let eps = q.count_tolerance / self.sample_count as f64;
        if self.domain.is_1d() {
            let ym = 0.5 * (ya + yb);
            return dy * adaptive_simpson(|x| g(x, ym), xa, xb, eps / dy, q);
        }
        // The inner integral is 10× tighter so that its noise does not drive the outer one.
        let inner_eps = 0.1 * eps / dy;
        adaptive_simpson(
            |y| adaptive_simpson(|x| g(x, y), xa, xb, inner_eps, q),
            ya,
            yb,
            eps,
            q,
        )
    }

    // --- steps 3–5: statistic, p-value, verdict, report ------------------------------------

    fn evaluate(&self, hist: Histogram, expected: Vec<f64>) -> Chi2Outcome {
        let n = self.sample_count as f64;
        let mut outcome = Chi2Outcome {
            name: self.name.clone(),
            statistic: 0.0,
            dof: 0,
            p_value: f64::NAN,
            alpha: sidak(self.significance, self.test_count),
            passed: false,
            sample_count: self.sample_count,
            failed: hist.failed,
            outside: hist.outside,
            pdf_mismatches: hist.pdf_mismatches,
            pdf_integral: expected.iter().sum::<f64>() / n,
            resolution: self.res,
            observed: hist.counts,
            expected,
            report: String::new(),
        };
        let (rest_o, rest_e) = outcome.rest();
        let observed: Vec<f64> = outcome.observed.iter().copied().chain([rest_o]).collect();
        let expected: Vec<f64> = outcome.expected.iter().copied().chain([rest_e]).collect();
        let pearson = pearson_chi2(&observed, &expected, self.min_expected);
        let mismatches = (hist.pdf_mismatches, hist.first_mismatch);
        let problems = self.problems(&observed, &expected, &pearson, mismatches);
        outcome.statistic = pearson.statistic;
        outcome.dof = pearson.dof.max(0) as usize;
        outcome.p_value = chi2_p_value(pearson.statistic, pearson.dof.max(1) as f64);
        outcome.passed =
            problems.is_empty() && outcome.p_value.is_finite() && outcome.p_value >= outcome.alpha;
        let dumped = if !outcome.passed || std::env::var_os("CHI2_DUMP").is_some() {
            self.dump(&outcome)
        } else {
            None
        };
        outcome.report = self.report(&outcome, &pearson, &problems, dumped);
        outcome
    }

    /// Reasons to reject regardless of the p-value (cells include the rest cell).
    fn problems(
        &self,
        observed: &[f64],
        expected: &[f64],
        pearson: &Pearson,
        (mismatches, first_mismatch): (usize, Option<String>),
    ) -> Vec<String> {
        let n = self.sample_count as f64;
        let mut problems = Vec::new();
        if let Some(i) = expected.iter().position(|e| !(e.is_finite() && *e >= 0.0)) {
            problems.push(format!(
                "the pdf integrates to {} over the cell at {} (non-finite or negative pdf)",
                expected[i],
                self.describe_cell(i)
            ));
        }
        if pearson.zero_cell_samples > n * 1e-5 {
            problems.push(format!(
                "{} samples fell in cells where the pdf is zero (largest: {} at {})",
                pearson.zero_cell_samples,
                observed[pearson.worst_zero_cell],
                self.describe_cell(pearson.worst_zero_cell)
            ));
        }
        if pearson.dof < 1 {
            let dof = pearson.dof;
            problems.push(format!("too few degrees of freedom ({dof}) for a test"));
        }
        if mismatches as f64 > self.max_pdf_mismatch * n {
            problems.push(format!(
                "{mismatches} samples report a pdf that differs from the pdf closure by more \
                 than {}; first {}",
                self.pdf_tolerance,
                first_mismatch.unwrap_or_default()
            ));
        }
        problems
    }

    fn describe_cell(&self, i: usize) -> String {
        let [nx, ny] = self.res;
        if i >= nx * ny {
            return "the rest cell (failed or outside the domain)".into();
        }
        self.domain.describe(self.cell_center(i / ny, i % ny))
    }

    fn cell_center(&self, ix: usize, iy: usize) -> [f64; 2] {
        let [[x0, x1], [y0, y1]] = self.domain.bounds();
        [
            x0 + (ix as f64 + 0.5) * (x1 - x0) / self.res[0] as f64,
            y0 + (iy as f64 + 0.5) * (y1 - y0) / self.res[1] as f64,
        ]
    }

    fn report(
        &self,
        o: &Chi2Outcome,
        pearson: &Pearson,
        problems: &[String],
        dumped: Option<[PathBuf; 2]>,
    ) -> String {
        let verdict = if o.passed { "accepted" } else { "REJECTED" };
        let mut r = format!(
            "χ² test `{}` {verdict}: χ² = {:.1}, dof = {}, p = {:.3e} (reject below {:.3e}: \
             α = {} Šidák-corrected for {} tests)\n",
            o.name, o.statistic, o.dof, o.p_value, o.alpha, self.significance, self.test_count
        );
        let binned = o.sample_count - o.failed - o.outside;
        let _ = writeln!(
            r,
            "  {} samples: {binned} binned, {} failed, {} outside the domain; ∫pdf over the \
             domain = {:.6} → rest cell expects {:.1}, has {}",
            o.sample_count,
            o.failed,
            o.outside,
            o.pdf_integral,
            o.rest().1,
            o.rest().0
        );
        let _ = writeln!(
            r,
            "  {} of {} cells pooled (expected < {}); pdf check: {} mismatching samples",
            pearson.pooled_cells,
            o.observed.len() + 1,
            self.min_expected,
            o.pdf_mismatches
        );
        for p in problems {
            let _ = writeln!(r, "  problem: {p}");
        }
        if !o.passed {
            let _ = writeln!(r, "  largest residuals (observed vs expected, (o − e)/√e):");
            for (i, z) in self.largest_residuals(o, 6) {
                let (obs, exp) = if i < o.observed.len() {
                    (o.observed[i], o.expected[i])
                } else {
                    o.rest()
                };
                let _ = writeln!(
                    r,
                    "    {}: {obs} vs {exp:.1} ({z:+.1}σ)",
                    self.describe_cell(i)
                );
            }
        }
        if let Some([txt, ppm]) = dumped {
            let _ = writeln!(r, "  tables: {} and {}", txt.display(), ppm.display());
        }
        r
    }

    /// The cells (rest cell = index `observed.len()`) with the largest |o − e|/√e among those
    /// expecting at least `min_expected` samples.
    fn largest_residuals(&self, o: &Chi2Outcome, k: usize) -> Vec<(usize, f64)> {
        let cells = o
            .observed
            .iter()
            .zip(&o.expected)
            .map(|(&ob, &e)| (ob, e))
            .chain([o.rest()]);
        let mut z: Vec<(usize, f64)> = cells
            .enumerate()
            .filter(|(_, (_, e))| *e >= self.min_expected)
            .map(|(i, (ob, e))| (i, (ob - e) / e.sqrt()))
            .collect();
        z.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        z.truncate(k);
        z
    }

    /// Writes `chi2_<name>.txt` (one line per cell) and `chi2_<name>.ppm` to the temp dir.
    fn dump(&self, o: &Chi2Outcome) -> Option<[PathBuf; 2]> {
        let stem: String = o
            .name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let dir = std::env::temp_dir();
        let txt = dir.join(format!("chi2_{stem}.txt"));
        let ppm = dir.join(format!("chi2_{stem}.ppm"));
        let mut t = format!("# {}\n# ix iy x0 x1 observed expected\n", o.name);
        let ny = self.res[1];
        for (i, (ob, e)) in o.observed.iter().zip(&o.expected).enumerate() {
            let c = self.cell_center(i / ny, i % ny);
            let _ = writeln!(
                t,
                "{} {} {:.6} {:.6} {ob} {e:.4}",
                i / ny,
                i % ny,
                c[0],
                c[1]
            );
        }
        std::fs::write(&txt, t).ok()?;
        std::fs::write(&ppm, residual_image(o)).ok()?;
        Some([txt, ppm])
    }
}

/// What a χ² test found. `report` is the full text (also given by `Display`).
#[derive(Clone, Debug)]
pub struct Chi2Outcome {
    pub name: String,
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// The Šidák-corrected significance level the p-value was compared with.
    pub alpha: f64,
    pub passed: bool,
    pub sample_count: usize,
    /// Samples for which the sampler returned None.
    pub failed: usize,
    /// Samples outside the domain (counted with the failures in the rest cell).
    pub outside: usize,
    /// Samples whose reported pdf disagrees with the pdf closure.
    pub pdf_mismatches: usize,
    /// ∫ pdf over the domain (numerically).
    pub pdf_integral: f64,
    pub resolution: [usize; 2],
    /// Observed and expected counts per cell, row-major: index = i₀ · res[1] + i₁.
    pub observed: Vec<f64>,
    pub expected: Vec<f64>,
    pub report: String,
}

impl Chi2Outcome {
    /// Panics with the report when the test rejected the sampler.
    #[track_caller]
    pub fn assert_passed(&self) {
        assert!(self.passed, "{}", self.report);
    }

    /// The rest cell: (samples that failed or fell outside the domain, the number expected,
    /// N (1 − ∫pdf), clamped at 0).
    pub fn rest(&self) -> (f64, f64) {
        let n = self.sample_count as f64;
        (
            (self.failed + self.outside) as f64,
            (n * (1.0 - self.pdf_integral)).max(0.0),
        )
    }

    /// One line: name, statistic, dof, p-value, rest cell, pdf mismatches.
    pub fn summary(&self) -> String {
        format!(
            "{:<52} χ² = {:>9.1}  dof = {:>5}  p = {:.3e}  rest {:>6} vs {:>8.1}  pdf≠ {:>4}  {}",
            self.name,
            self.statistic,
            self.dof,
            self.p_value,
            self.rest().0,
            self.rest().1,
            self.pdf_mismatches,
            if self.passed { "ok" } else { "REJECTED" }
        )
    }
}

impl std::fmt::Display for Chi2Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.report)
    }
}

#[derive(Default)]
struct Histogram {
    counts: Vec<f64>,
    failed: usize,
    outside: usize,
    pdf_mismatches: usize,
    first_mismatch: Option<String>,
}

#[inline]
fn bin(x: f64, lo: f64, hi: f64, n: usize) -> usize {
    let f = ((x - lo) / (hi - lo) * n as f64).floor();
    (f.max(0.0) as usize).min(n - 1)
}

/// FNV-1a, 64 bit: a stable seed from a test's name.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// PPM (binary P6) of three panels, each one pixel per cell (x₁ across, x₀ down, columns
/// repeated for narrow grids): observed and expected on a common square-root grey scale, and the
/// standardised residual (o − e)/√e from blue (−4σ) through white to red (+4σ).
fn residual_image(o: &Chi2Outcome) -> Vec<u8> {
    let [nx, ny] = o.resolution;
    let rep = 64usize.div_ceil(ny).max(1);
    let (w, gap) = (ny * rep, 4);
    let width = 3 * w + 2 * gap;
    let max = o
        .expected
        .iter()
        .chain(&o.observed)
        .fold(1e-30f64, |m, &v| m.max(v));
    let mut img = format!("P6\n{width} {nx}\n255\n").into_bytes();
    let grey = |v: f64| {
        let g = (255.0 * (v / max).clamp(0.0, 1.0).sqrt()) as u8;
        [g, g, g]
    };
    for ix in 0..nx {
        for px in 0..width {
            let (panel, col) = (px / (w + gap), px % (w + gap));
            let rgb = if col >= w {
                [0, 0, 0]
            } else {
                let i = ix * ny + col / rep;
                let (ob, e) = (o.observed[i], o.expected[i]);
                match panel {
                    0 => grey(ob),
                    1 => grey(e),
                    _ => {
                        let z = ((ob - e) / e.max(1.0).sqrt() / 4.0).clamp(-1.0, 1.0);
                        let fade = (255.0 * (1.0 - z.abs())) as u8;
                        if z >= 0.0 {
                            [255, fade, fade]
                        } else {
                            [fade, fade, 255]
                        }
                    }
                }
            };
            img.extend_from_slice(&rgb);
        }
    }
    img
}

// ---------------------------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------------------------

/// Pearson's statistic with pooling of sparse cells (see [`pearson_chi2`]).
#[derive(Clone, Copy, Debug)]
pub struct Pearson {
    pub statistic: f64,
    /// Pooled cells − 1; below 1 the test is meaningless.
    pub dof: i64,
    /// How many cells went into the pooled cell.
    pub pooled_cells: usize,
    /// Samples found in cells whose expected count is exactly 0.
    pub zero_cell_samples: f64,
    /// Index of the zero-expectation cell holding the most samples.
    pub worst_zero_cell: usize,
}

/// χ² = Σ (o − e)²/e after pooling (pbrt-v4 `Chi2Test`): cells sorted by expected count;
/// those expecting fewer than `min_expected` are merged into one cell, which keeps absorbing
/// cells until it expects at least `min_expected`. Cells expecting exactly 0 are left out and
/// their samples counted in `zero_cell_samples`.
pub fn pearson_chi2(observed: &[f64], expected: &[f64], min_expected: f64) -> Pearson {
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pooled_o, mut pooled_e, mut pooled_cells) = (0.0, 0.0, 0usize);
    let (mut stat, mut cells) = (0.0, 0i64);
    let (mut zero, mut worst) = (0.0, 0usize);
    for &i in &order {
        let (o, e) = (observed[i], expected[i]);
        if e == 0.0 {
            zero += o;
            if o > observed[worst] || expected[worst] != 0.0 {
                worst = i;
            }
        } else if e < min_expected || (pooled_e > 0.0 && pooled_e < min_expected) {
            pooled_o += o;
            pooled_e += e;
            pooled_cells += 1;
        } else {
            stat += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pooled_e > 0.0 {
        stat += (pooled_o - pooled_e) * (pooled_o - pooled_e) / pooled_e;
        cells += 1;
    }
    Pearson {
        statistic: stat,
        dof: cells - 1,
        pooled_cells,
        zero_cell_samples: zero,
        worst_zero_cell: worst,
    }
}

/// P(X ≥ `statistic`) for X ~ χ²(`dof`): Q(dof/2, statistic/2).
pub fn chi2_p_value(statistic: f64, dof: f64) -> f64 {
    if statistic <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * dof, 0.5 * statistic)
}

/// Per-test significance level so that m independent tests together reject a true null
/// hypothesis with probability α (Šidák 1967): 1 − (1 − α)^(1/m).
pub fn sidak(alpha: f64, m: usize) -> f64 {
    -((-alpha).ln_1p() / m.max(1) as f64).exp_m1()
}

/// ln Γ(x) for x > 0 by the Lanczos approximation (Lanczos 1964, "A Precision Approximation
/// of the Gamma Function", SIAM J. Numer. Anal. B 1) with g = 7 and the 9 coefficients
/// computed by P. Godfrey (2001); relative error about 10⁻¹⁵ for x ≥ 1/2, and the reflection
/// formula below that.
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + G + 0.5;
    let series = C[1..]
        .iter()
        .enumerate()
        .fold(C[0], |acc, (i, &c)| acc + c / (x + (i + 1) as f64));
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + series.ln()
}

/// Regularized lower incomplete gamma function P(a, x) = γ(a, x)/Γ(a).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_p({a}, {x}) outside its domain");
    if x == 0.0 {
        0.0
    } else if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_continued_fraction(a, x)
    }
}

/// Regularized upper incomplete gamma function Q(a, x) = 1 − P(a, x), computed directly in
/// the tail so that small p-values keep their relative precision.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "gamma_q({a}, {x}) outside its domain");
    if x == 0.0 {
        1.0
    } else if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_continued_fraction(a, x)
    }
}

/// e^(−x) x^a / Γ(a), the common prefactor of the series and the continued fraction.
fn gamma_prefactor(a: f64, x: f64) -> f64 {
    (a * x.ln() - x - ln_gamma(a)).exp()
}

/// P(a, x) by the series γ(a, x) = e^(−x) x^a Σ x^n / (a (a+1) … (a+n)) (Numerical Recipes
/// 3rd ed. §6.2), for x < a + 1. Converges in O(√a) terms near x ≈ a.
fn gamma_series(a: f64, x: f64) -> f64 {
    let (mut ap, mut term) = (a, 1.0 / a);
    let mut sum = term;
    for _ in 0..100_000 {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    sum * gamma_prefactor(a, x)
}

/// Q(a, x) by the even part of Legendre's continued fraction for Γ(a, x) (Numerical Recipes
/// 3rd ed. §6.2), evaluated with the modified Lentz method (§5.2), for x ≥ a + 1.
fn gamma_continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..100_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-16 {
            break;
        }
    }
    gamma_prefactor(a, x) * h
}

// ---------------------------------------------------------------------------------------------
// Quadrature
// ---------------------------------------------------------------------------------------------

/// ∫ₐᵇ f by adaptive Simpson quadrature with absolute tolerance `eps`: a panel is accepted
/// when its two halves change the estimate by at most 15·eps (Lyness 1969), and the accepted
/// value is Richardson-extrapolated. `q.min_depth` subdivisions are always made;
/// `q.max_depth` bounds the recursion.
pub fn adaptive_simpson<F: FnMut(f64) -> f64>(
    mut f: F,
    a: f64,
    b: f64,
    eps: f64,
    q: &Quadrature,
) -> f64 {
    let m = 0.5 * (a + b);
    let (fa, fm, fb) = (f(a), f(m), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    simpson_refine(&mut f, [a, m, b], [fa, fm, fb], whole, eps, 0, q)
}

fn simpson_refine<F: FnMut(f64) -> f64>(
    f: &mut F,
    [a, m, b]: [f64; 3],
    [fa, fm, fb]: [f64; 3],
    whole: f64,
    eps: f64,
    depth: u32,
    q: &Quadrature,
) -> f64 {
    let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
    let (flm, frm) = (f(lm), f(rm));
    let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
    let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
    let both = left + right;
    let converged = (both - whole).abs() <= 15.0 * eps;
    if depth + 1 >= q.max_depth || (depth + 1 >= q.min_depth && converged) {
        return both + (both - whole) / 15.0;
    }
    simpson_refine(f, [a, lm, m], [fa, flm, fm], left, 0.5 * eps, depth + 1, q)
        + simpson_refine(f, [m, rm, b], [fm, frm, fb], right, 0.5 * eps, depth + 1, q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Directions with pdf (n + 1)/(2π) cosⁿθ on the upper hemisphere (inversion of the
    /// cdf 1 − cos^(n+1)θ).
    fn cosine_power(u: [f32; 2], n: f64) -> Vec3 {
        let cos_t = (u[0] as f64).powf(1.0 / (n + 1.0));
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1] as f64;
        DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t).as_vec3()
    }

    fn cosine_power_pdf(w: Vec3, n: f64) -> f64 {
        if w.z <= 0.0 {
            return 0.0;
        }
        (n + 1.0) / (2.0 * PI) * (w.z as f64).powf(n)
    }

    fn cosine_power_test(sampled: f64, claimed: f64) -> Chi2Outcome {
        let o = Chi2Test::new(
            format!("cosine power {sampled} vs {claimed}"),
            SphericalDomain::sphere(),
        )
        .run(
            |s| {
                let w = cosine_power(s.get_2d(), sampled);
                Some((w, cosine_power_pdf(w, claimed)))
            },
            |w| cosine_power_pdf(w, claimed),
        );
        println!("{o}");
        o
    }

    #[test]
    fn chi2_gamma_functions_match_reference_values() {
        // Γ(5) = 24, Γ(1/2) = √π, Γ(10.5) from the recurrence.
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-13);
        assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
        let g105 = (0..10).fold(PI.sqrt(), |g, k| g * (k as f64 + 0.5));
        assert!((ln_gamma(10.5) - g105.ln()).abs() < 1e-12);
        // Q(1, x) = e^{-x}; P(3, 2) = 1 − 5e^{-2}; Q(1/2, 1) = erfc(1).
        for x in [0.1, 1.0, 5.0, 40.0] {
            assert!((gamma_q(1.0, x) / (-x).exp() - 1.0).abs() < 1e-12, "{x}");
        }
        assert!((gamma_p(3.0, 2.0) - (1.0 - 5.0 * (-2.0f64).exp())).abs() < 1e-14);
        assert!((gamma_q(0.5, 1.0) - 0.157_299_207_050_285_1).abs() < 1e-14);
        // χ² quantiles: 3.841459 (dof 1, 0.05), 23.209251 (dof 10, 0.01).
        assert!((chi2_p_value(3.841_458_820_694_124, 1.0) - 0.05).abs() < 1e-9);
        assert!((chi2_p_value(23.209_251_158_954_36, 10.0) - 0.01).abs() < 1e-9);
        // Large dof (a 80 × 160 grid): Wilson–Hilferty gives the 1 % point to ~1e-4.
        let k = 12_799.0f64;
        let wh = k * (1.0 - 2.0 / (9.0 * k) + 2.326_347_874 * (2.0 / (9.0 * k)).sqrt()).powi(3);
        assert!((chi2_p_value(wh, k) - 0.01).abs() < 2e-4);
        assert!((chi2_p_value(k, k) - 0.497).abs() < 0.003);
        assert!((gamma_p(6400.0, 6500.0) + gamma_q(6400.0, 6500.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn chi2_sidak_correction() {
        assert!((sidak(0.01, 1) - 0.01).abs() < 1e-15);
        let s = sidak(0.01, 5);
        assert!(((1.0 - s).powi(5) - 0.99).abs() < 1e-14);
    }

    #[test]
    fn chi2_adaptive_simpson_is_accurate() {
        let q = Quadrature::default();
        let v = adaptive_simpson(f64::sin, 0.0, PI, 1e-12, &q);
        assert!((v - 2.0).abs() < 1e-11, "{v}");
        // A step inside the interval: error bounded by the finest panel.
        let step = adaptive_simpson(|x| if x < 0.3 { 1.0 } else { 0.0 }, 0.0, 1.0, 1e-12, &q);
        assert!((step - 0.3).abs() < 1.0 / 256.0, "{step}");
    }

    #[test]
    fn chi2_pooling_and_zero_cells() {
        let p = pearson_chi2(&[10.0, 1.0, 2.0, 3.0], &[10.0, 1.0, 2.0, 2.5], 5.0);
        // Cells 1..3 pool to o = 6, e = 5.5; with cell 0 that is 2 cells, dof 1.
        assert_eq!((p.dof, p.pooled_cells), (1, 3));
        assert!((p.statistic - 0.25 / 5.5).abs() < 1e-12);
        let z = pearson_chi2(&[10.0, 4.0], &[10.0, 0.0], 5.0);
        assert_eq!((z.zero_cell_samples, z.worst_zero_cell), (4.0, 1));
    }

    #[test]
    fn chi2_accepts_a_matching_sampler() {
        let o = cosine_power_test(1.0, 1.0);
        o.assert_passed();
        // The pdf integrates to 1 and the rest cell is empty: the quadrature is accurate.
        assert!((o.pdf_integral - 1.0).abs() < 1e-6, "{}", o.pdf_integral);
        assert!(o.p_value > 0.01, "{o}");
    }

    #[test]
    fn chi2_rejects_cosine_power_1_against_1_05() {
        let o = cosine_power_test(1.0, 1.05);
        assert!(!o.passed, "{o}");
        assert_eq!(
            o.pdf_mismatches, 0,
            "reported pdfs come from the same closure"
        );
        assert!(o.report.contains("largest residuals"), "{o}");
    }

    #[test]
    fn chi2_rejects_a_sampler_that_fails_more_than_its_pdf_admits() {
        // 2 % of the samples fail but the pdf still integrates to 1.
        let o = Chi2Test::new("cosine, 2% silent failures", SphericalDomain::sphere()).run(
            |s| {
                let w = cosine_power(s.get_2d(), 1.0);
                (s.get_1d() >= 0.02).then_some((w, cosine_power_pdf(w, 1.0)))
            },
            |w| cosine_power_pdf(w, 1.0),
        );
        assert!(!o.passed && o.failed > 19_000, "{o}");
        // With the failure probability in the pdf, the same sampler is accepted.
        Chi2Test::new("cosine, 2% declared failures", SphericalDomain::sphere())
            .run(
                |s| {
                    let w = cosine_power(s.get_2d(), 1.0);
                    (s.get_1d() >= 0.02).then_some((w, 0.98 * cosine_power_pdf(w, 1.0)))
                },
                |w| 0.98 * cosine_power_pdf(w, 1.0),
            )
            .assert_passed();
    }

    #[test]
    fn chi2_rejects_samples_where_the_pdf_is_zero() {
        // Samples on the whole sphere, pdf claims the upper hemisphere only.
        let o = Chi2Test::new("sphere vs hemisphere", SphericalDomain::sphere()).run(
            |s| {
                let mut w = cosine_power(s.get_2d(), 1.0);
                if s.get_1d() < 0.001 {
                    w.z = -w.z;
                }
                Some((w, cosine_power_pdf(w, 1.0)))
            },
            |w| cosine_power_pdf(w, 1.0),
        );
        assert!(!o.passed && o.report.contains("pdf is zero"), "{o}");
    }

    #[test]
    fn chi2_rejects_a_wrong_reported_pdf() {
        let o = Chi2Test::new("wrong reported pdf", SphericalDomain::sphere()).run(
            |s| {
                let w = cosine_power(s.get_2d(), 1.0);
                Some((w, 1.01 * cosine_power_pdf(w, 1.0)))
            },
            |w| cosine_power_pdf(w, 1.0),
        );
        assert!(!o.passed && o.pdf_mismatches > 900_000, "{o}");
    }

    #[test]
    fn chi2_interval_and_planar_domains() {
        // p(x) = 2x on [0, 1] by inversion.
        Chi2Test::new("linear ramp", IntervalDomain::new(0.0, 1.0))
            .run(
                |s| {
                    let x = s.get_1d().sqrt();
                    Some((x, 2.0 * x as f64))
                },
                |x| 2.0 * x as f64,
            )
            .assert_passed();
        // Rejection-sampled unit disk (uniform, pdf 1/π).
        let inside = |p: Vec2| p.length_squared() <= 1.0;
        Chi2Test::new("rejection disk", PlanarDomain::new(-Vec2::ONE, Vec2::ONE))
            .run(
                |s| loop {
                    let p = Vec2::new(2.0 * s.get_1d() - 1.0, 2.0 * s.get_1d() - 1.0);
                    if inside(p) {
                        return Some((p, 1.0 / PI));
                    }
                },
                |p| if inside(p) { 1.0 / PI } else { 0.0 },
            )
            .assert_passed();
    }
}
