//! ANSI/IES LM-63 photometric files (LM-63-1995, -2002 and -2019 share the data layout),
//! type C photometry only, for UsdLux `shaping:ies:file`.
//!
//! Layout: an optional version line (`IESNA:LM-63-2002`, `IES:LM-63-2019`, …), keyword lines
//! (`[TEST] …`), the `TILT=` line, then whitespace- or comma-separated numbers that may wrap
//! across lines: number of lamps, lumens per lamp, candela multiplier, number of vertical and
//! horizontal angles, photometric type (1 = C), units type, width, length, height; ballast
//! factor, ballast-lamp photometric factor ("future use" since 2002, 1 in valid files), input
//! watts; the vertical angles, the horizontal angles, and the candela values (for each
//! horizontal angle, all vertical angles).
//!
//! Conventions (type C, LM-63-2019 §5): vertical angle 0° is nadir — for a UsdLux light its
//! emission axis, local −Z — and 180° zenith; horizontal angle 0° is the C0 half-plane, which
//! we put along the light's local +X, with 90° along local +Y. The horizontal range tells the
//! symmetry and is expanded to a full 0–360° table here: one angle (rotationally symmetric),
//! 0–90 (quadrant symmetric), 0–180 (bilateral about the 0–180 plane), 90–270 (bilateral about
//! the 90–270 plane, LM-63-2002 §3.23) or 0–360. Vertical angles run 0–90, 0–180 or 90–180;
//! outside them the intensity is zero. Intensities are interpolated bilinearly in (θ, φ).
//!
//! Every candela value is multiplied by the candela multiplier, the ballast factor and the
//! ballast-lamp photometric factor (as Cycles and hdEmbree do). `TILT=NONE` is required:
//! tilt tables (`TILT=INCLUDE` or a tilt file) describe output changes with the luminaire's
//! mounting tilt, which a renderer placing the luminaire as photometered does not model.
//!
//! Errors name the file and the line: `downlight.ies:14: expected 37 vertical angles …`.
//!
//! ```text
//! IESNA:LM-63-2002
//! [TEST] synthetic
//! TILT=NONE
//! 1 -1 1 3 1 1 2 0.1 0.1 0
//! 1 1 10
//! 0 45 90
//! 0
//! 1000 700 0
//! ```

use crate::error::Reason;
use std::f64::consts::PI as PI64;
use std::path::Path;

/// The largest IES file read (real LM-63 files hold at most a few hundred kB: 361 × 181
/// candela values are about 400 kB).
pub const MAX_FILE_BYTES: u64 = 4 << 20;

/// A parsed type C profile, expanded to horizontal angles 0–360°.
#[derive(Clone, Debug, PartialEq)]
pub struct IesProfile {
    /// Vertical angles θ (radians, strictly increasing; 0 = nadir).
    vertical: Vec<f32>,
    /// Horizontal angles φ (radians, strictly increasing from 0 to 2π).
    horizontal: Vec<f32>,
    /// Candela with the multipliers applied, `candela[h * vertical.len() + v]`.
    candela: Vec<f32>,
    /// The largest candela value.
    pub max_candela: f32,
    /// ∫ I dΩ of the bilinear interpolant over the sphere, in lumens.
    pub flux: f64,
    /// Solid angle the profile is spread over for `shaping:ies:normalize`: 4π when the vertical
    /// angles span more than a hemisphere, else 2π (hdEmbree's `pxrIES.cpp` rule).
    pub solid_angle: f64,
}

/// A number token and the 1-based line it is on.
struct Token<'a> {
    text: &'a str,
    line: usize,
}

/// Reads the numbers after the `TILT=` line, with their line numbers for messages.
struct Numbers<'a> {
    tokens: std::vec::IntoIter<Token<'a>>,
    path: &'a Path,
    last_line: usize,
}

impl<'a> Numbers<'a> {
    fn err(&self, line: usize, reason: impl std::fmt::Display) -> String {
        format!("{}:{line}: {reason}", self.path.display())
    }

    /// The next number; `what` names it for the message when it is missing or malformed.
    fn next(&mut self, what: &str) -> Reason<(f64, usize)> {
        let Some(t) = self.tokens.next() else {
            return Err(self.err(
                self.last_line,
                format!("the file ends where {what} was expected"),
            ));
        };
        match t.text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok((v, t.line)),
            _ => Err(self.err(
                t.line,
                format!("expected {what} (a number), found '{}'", t.text),
            )),
        }
    }

    /// The next number as a positive count.
    fn count(&mut self, what: &str) -> Reason<(usize, usize)> {
        let (v, line) = self.next(what)?;
        if v.fract() != 0.0 || !(1.0..=100_000.0).contains(&v) {
            return Err(self.err(line, format!("{what} must be a positive integer, not {v}")));
        }
        Ok((v as usize, line))
    }

    /// `n` numbers as angles in degrees, strictly increasing.
    fn angles(&mut self, n: usize, what: &str) -> Reason<Vec<(f64, usize)>> {
        // Never more room than the numbers left can fill: a count is not an allocation.
        let mut out: Vec<(f64, usize)> = Vec::with_capacity(n.min(self.tokens.len()));
        for i in 0..n {
            let (a, line) = self.next(&format!("{what} {} of {n}", i + 1))?;
            if let Some(&(prev, _)) = out.last() {
                if a <= prev {
                    return Err(self.err(
                        line,
                        format!("{what}s must increase strictly ({a} after {prev})"),
                    ));
                }
            }
            out.push((a, line));
        }
        Ok(out)
    }
}

impl IesProfile {
    /// Reads and parses `path`: a regular file of at most [`MAX_FILE_BYTES`].
    pub fn read(path: &Path) -> Reason<IesProfile> {
        let cannot = |e: &dyn std::fmt::Display| {
            format!("{}: cannot read the IES file: {e}", path.display())
        };
        let meta = std::fs::metadata(path).map_err(|e| cannot(&e))?;
        if !meta.is_file() {
            return Err(cannot(&"not a regular file"));
        }
        if meta.len() > MAX_FILE_BYTES {
            return Err(cannot(&format!(
                "it has {} bytes; IES files of more than {MAX_FILE_BYTES} bytes are refused",
                meta.len()
            )));
        }
        let mut bytes = Vec::new();
        std::fs::File::open(path)
            .and_then(|f| {
                std::io::Read::read_to_end(
                    &mut std::io::Read::take(f, MAX_FILE_BYTES + 1),
                    &mut bytes,
                )
            })
            .map_err(|e| cannot(&e))?;
        // LM-63 files are ASCII; older ones are often Latin-1 in their keyword lines.
        let text: String = bytes.iter().map(|&b| b as char).collect();
        IesProfile::parse(&text, path)
    }

    /// Parses the text of an LM-63 file; `path` is only used in messages.
    pub fn parse(text: &str, path: &Path) -> Reason<IesProfile> {
        let mut numbers = numbers_after_tilt(text, path)?;
        let header = Header::read(&mut numbers)?;
        let vertical = numbers.angles(header.n_vertical, "vertical angle")?;
        let horizontal = numbers.angles(header.n_horizontal, "horizontal angle")?;
        check_vertical_range(&numbers, &vertical)?;
        check_horizontal_range(&numbers, &horizontal)?;
        let mut columns = Vec::with_capacity(horizontal.len());
        for (h, _) in &horizontal {
            let mut column = Vec::with_capacity(vertical.len());
            for (v, _) in &vertical {
                let what = format!("the candela value at horizontal {h}°, vertical {v}°");
                let (cd, line) = numbers.next(&what)?;
                if cd < 0.0 {
                    return Err(numbers.err(line, format!("{what} is negative ({cd})")));
                }
                let scaled = (cd * header.multiplier) as f32;
                if !scaled.is_finite() {
                    let reason = format!(
                        "{what} times the multipliers ({cd} × {}) overflows",
                        header.multiplier
                    );
                    return Err(numbers.err(line, reason));
                }
                column.push(scaled);
            }
            columns.push(column);
        }
        if let Some(t) = numbers.tokens.next() {
            return Err(numbers.err(
                t.line,
                format!("unexpected '{}' after the candela table", t.text),
            ));
        }
        let h_deg: Vec<f64> = horizontal.iter().map(|a| a.0).collect();
        let (h_full, columns) = expand_horizontal(&h_deg, columns);
        Ok(IesProfile::new(
            vertical.iter().map(|a| a.0).collect(),
            h_full,
            columns,
        ))
    }

    /// A profile from full tables: vertical and horizontal (0–360) angles in degrees and one
    /// column of candela per horizontal angle.
    fn new(v_deg: Vec<f64>, h_deg: Vec<f64>, columns: Vec<Vec<f32>>) -> IesProfile {
        let vertical: Vec<f32> = v_deg.iter().map(|a| a.to_radians() as f32).collect();
        let horizontal: Vec<f32> = h_deg.iter().map(|a| a.to_radians() as f32).collect();
        let candela: Vec<f32> = columns.into_iter().flatten().collect();
        let max_candela = candela.iter().copied().fold(0.0, f32::max);
        let span = (v_deg[v_deg.len() - 1] - v_deg[0]).to_radians();
        let mut p = IesProfile {
            vertical,
            horizontal,
            candela,
            max_candela,
            flux: 0.0,
            solid_angle: if span > 0.5 * PI64 + 0.1 {
                4.0 * PI64
            } else {
                2.0 * PI64
            },
        };
        p.flux = p.integrate();
        p
    }

    /// The mean intensity over [`IesProfile::solid_angle`] (cd): what `shaping:ies:normalize`
    /// divides by, so that an isotropic profile leaves the light unchanged.
    pub fn mean_intensity(&self) -> f64 {
        self.flux / self.solid_angle
    }

    fn at(&self, h: usize, v: usize) -> f32 {
        self.candela[h * self.vertical.len() + v]
    }

    /// Luminous intensity (cd) at vertical angle `theta` (0 = nadir) and horizontal angle
    /// `phi` (radians, any value; taken modulo 2π), interpolated bilinearly.
    pub fn candela(&self, theta: f32, phi: f32) -> f32 {
        let v = &self.vertical;
        if !(theta >= v[0] && theta <= v[v.len() - 1]) {
            return 0.0;
        }
        let phi = phi.rem_euclid(std::f32::consts::TAU);
        let (i, tv) = interval(v, theta);
        let (j, th) = interval(&self.horizontal, phi);
        let lerp = |h: usize| self.at(h, i) * (1.0 - tv) + self.at(h, i + 1) * tv;
        lerp(j) * (1.0 - th) + lerp(j + 1) * th
    }

    /// The table's grid directions (θ, φ) in radians, for searches of the peak.
    pub fn nodes(&self) -> impl Iterator<Item = (f32, f32)> + '_ {
        self.horizontal
            .iter()
            .flat_map(|&phi| self.vertical.iter().map(move |&theta| (theta, phi)))
    }

    /// The vertical angles (radians).
    pub fn vertical_angles(&self) -> &[f32] {
        &self.vertical
    }

    /// The horizontal angles (radians, 0 to 2π).
    pub fn horizontal_angles(&self) -> &[f32] {
        &self.horizontal
    }

    /// ∫ I dΩ of the bilinear interpolant, exactly, patch by patch: over a patch the mean over
    /// φ is linear in θ, a(θ) = a₀ + (a₁ − a₀)(θ − θ₀)/Δθ, and
    /// ∫ a(θ) sin θ dθ = a₀ (cos θ₀ − cos θ₁) + (a₁ − a₀)/Δθ · (sin θ₁ − sin θ₀ − Δθ cos θ₁).
    fn integrate(&self) -> f64 {
        let (v, h) = (&self.vertical, &self.horizontal);
        let mut sum = 0.0f64;
        for j in 0..h.len() - 1 {
            let dphi = (h[j + 1] - h[j]) as f64;
            for i in 0..v.len() - 1 {
                let (t0, t1) = (v[i] as f64, v[i + 1] as f64);
                let dt = t1 - t0;
                let a0 = 0.5 * (self.at(j, i) + self.at(j + 1, i)) as f64;
                let a1 = 0.5 * (self.at(j, i + 1) + self.at(j + 1, i + 1)) as f64;
                let f0 = t0.cos() - t1.cos();
                let f1 = t1.sin() - t0.sin() - dt * t1.cos();
                sum += dphi * (a0 * f0 + (a1 - a0) / dt * f1);
            }
        }
        sum
    }
}

/// The index i with xs[i] ≤ x ≤ xs[i+1] and the fraction of the way from xs[i] to xs[i+1];
/// `xs` has at least two entries and contains x.
fn interval(xs: &[f32], x: f32) -> (usize, f32) {
    let i = xs.partition_point(|&a| a <= x).clamp(1, xs.len() - 1) - 1;
    let t = ((x - xs[i]) / (xs[i + 1] - xs[i])).clamp(0.0, 1.0);
    (i, t)
}

/// The tokens after `TILT=NONE`, or an error naming the line.
fn numbers_after_tilt<'a>(text: &'a str, path: &'a Path) -> Reason<Numbers<'a>> {
    let at = |line: usize, reason: &str| format!("{}:{line}: {reason}", path.display());
    let mut lines = text.lines().enumerate();
    let tilt_line = loop {
        let Some((i, line)) = lines.next() else {
            return Err(format!(
                "{}: not an LM-63 photometric file (no TILT= line)",
                path.display()
            ));
        };
        let line = line.trim();
        if let Some(tilt) = line.strip_prefix("TILT=").or(line.strip_prefix("TILT =")) {
            match tilt.trim() {
                "NONE" => break i + 1,
                "INCLUDE" => {
                    return Err(at(i + 1, "TILT=INCLUDE is not supported (only TILT=NONE)"))
                }
                other => {
                    return Err(at(
                        i + 1,
                        &format!("tilt file '{other}' is not supported (only TILT=NONE)"),
                    ))
                }
            }
        }
    };
    let tokens: Vec<Token> = lines
        .flat_map(|(i, line)| {
            line.split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .map(move |text| Token { text, line: i + 1 })
        })
        .collect();
    let last_line = tokens.last().map_or(tilt_line, |t| t.line);
    Ok(Numbers {
        tokens: tokens.into_iter(),
        path,
        last_line,
    })
}

/// The thirteen numbers before the angle tables.
struct Header {
    multiplier: f64,
    n_vertical: usize,
    n_horizontal: usize,
}

impl Header {
    fn read(n: &mut Numbers) -> Reason<Header> {
        n.count("the number of lamps")?;
        n.next("lumens per lamp")?;
        let (candela_multiplier, line) = n.next("the candela multiplier")?;
        if candela_multiplier <= 0.0 {
            return Err(n.err(line, "the candela multiplier must be positive"));
        }
        let (n_vertical, line) = n.count("the number of vertical angles")?;
        if n_vertical < 2 {
            return Err(n.err(line, "at least two vertical angles are needed"));
        }
        let (n_horizontal, _) = n.count("the number of horizontal angles")?;
        let (kind, line) = n.next("the photometric type")?;
        if kind != 1.0 {
            let name = match kind {
                2.0 => "type B",
                3.0 => "type A",
                _ => "unknown",
            };
            return Err(n.err(
                line,
                format!("photometric type {kind} ({name}) is not supported; only type C (1)"),
            ));
        }
        let (units, line) = n.next("the units type")?;
        if units != 1.0 && units != 2.0 {
            return Err(n.err(
                line,
                format!("units type {units} is not 1 (feet) or 2 (metres)"),
            ));
        }
        for what in [
            "the luminous width",
            "the luminous length",
            "the luminous height",
        ] {
            n.next(what)?;
        }
        let (ballast, line) = n.next("the ballast factor")?;
        let (ballast_lamp, _) = n.next("the ballast-lamp photometric factor")?;
        n.next("the input watts")?;
        let multiplier = candela_multiplier * ballast * ballast_lamp;
        if multiplier <= 0.0 {
            return Err(n.err(line, "the ballast factors must be positive"));
        }
        Ok(Header {
            multiplier,
            n_vertical,
            n_horizontal,
        })
    }
}

/// Type C vertical angles start at 0 or 90 and end at 90 or 180 (LM-63-2002 §3.22).
fn check_vertical_range(n: &Numbers, v: &[(f64, usize)]) -> Reason<()> {
    let (first, last) = (v[0], v[v.len() - 1]);
    if first.0 != 0.0 && first.0 != 90.0 {
        return Err(n.err(
            first.1,
            format!(
                "type C vertical angles must start at 0 or 90 degrees, not {}",
                first.0
            ),
        ));
    }
    if last.0 != 90.0 && last.0 != 180.0 {
        return Err(n.err(
            last.1,
            format!(
                "type C vertical angles must end at 90 or 180 degrees, not {}",
                last.0
            ),
        ));
    }
    Ok(())
}

/// Type C horizontal angles: 0; 0–90; 0–180; 0–360; or 90–270 (LM-63-2002 §3.23).
fn check_horizontal_range(n: &Numbers, h: &[(f64, usize)]) -> Reason<()> {
    let (first, last) = (h[0].0, h[h.len() - 1].0);
    let ok = match first {
        0.0 => matches!(last, 0.0 | 90.0 | 180.0 | 360.0),
        90.0 => last == 270.0,
        _ => false,
    };
    if ok {
        return Ok(());
    }
    Err(n.err(
        h[h.len() - 1].1,
        format!(
            "type C horizontal angles must be 0, 0–90, 0–180, 0–360 or 90–270 degrees, \
             not {first}–{last}"
        ),
    ))
}

/// Expands a symmetric horizontal table to 0–360° by mirroring.
fn expand_horizontal(h: &[f64], columns: Vec<Vec<f32>>) -> (Vec<f64>, Vec<Vec<f32>>) {
    let (first, last) = (h[0], h[h.len() - 1]);
    let pairs: Vec<(f64, Vec<f32>)> = h.iter().copied().zip(columns).collect();
    let mut full: Vec<(f64, Vec<f32>)> = if h.len() == 1 {
        let c = pairs[0].1.clone();
        vec![(0.0, c.clone()), (360.0, c)]
    } else if first == 90.0 {
        // Bilateral about the 90–270 plane: φ ↦ 180 − φ below 90, 540 − φ above 270.
        let mut out: Vec<(f64, Vec<f32>)> = Vec::new();
        for (a, c) in pairs.iter().rev().filter(|(a, _)| *a > 90.0 && *a <= 180.0) {
            out.push((180.0 - a, c.clone()));
        }
        out.extend(pairs.iter().cloned());
        for (a, c) in pairs
            .iter()
            .rev()
            .filter(|(a, _)| *a >= 180.0 && *a < 270.0)
        {
            out.push((540.0 - a, c.clone()));
        }
        out
    } else {
        let mut out = pairs.clone();
        if last == 90.0 {
            for (a, c) in pairs.iter().rev().skip(1) {
                out.push((180.0 - a, c.clone()));
            }
        }
        if last == 90.0 || last == 180.0 {
            let half = out.clone();
            for (a, c) in half.iter().rev().skip(1) {
                out.push((360.0 - a, c.clone()));
            }
        }
        out
    };
    full.dedup_by(|b, a| (a.0 - b.0).abs() < 1e-9);
    full.into_iter().unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Reason<IesProfile> {
        IesProfile::parse(text, Path::new("t.ies"))
    }

    const HEADER: &str = "IESNA:LM-63-2002\n[TEST] unit\nTILT=NONE\n";

    #[test]
    fn rotationally_symmetric_profile_interpolates_and_integrates() {
        let p = parse(&format!(
            "{HEADER}1 -1 2 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n500 350 0\n"
        ))
        .unwrap();
        assert_eq!(p.max_candela, 1000.0);
        assert_eq!(p.candela(0.0, 1.0), 1000.0);
        assert!((p.candela(22.5f32.to_radians(), 3.0) - 850.0).abs() < 1e-2);
        assert_eq!(p.candela(100f32.to_radians(), 0.0), 0.0);
        // Exact integral of I(θ) piecewise linear: 2π ∫ I sin θ dθ.
        let n = 200_000;
        let mut sum = 0.0f64;
        for k in 0..n {
            let t = (k as f64 + 0.5) / n as f64 * 0.5 * PI64;
            sum += p.candela(t as f32, 0.0) as f64 * t.sin();
        }
        let expected = 2.0 * PI64 * sum * 0.5 * PI64 / n as f64;
        assert!(
            (p.flux / expected - 1.0).abs() < 1e-5,
            "{} {expected}",
            p.flux
        );
        assert_eq!(p.solid_angle, 2.0 * PI64);
    }

    #[test]
    fn quadrant_and_bilateral_symmetry_expand_to_the_full_circle() {
        let quadrant = parse(&format!(
            "{HEADER}1 1000 1 2 3 1 1 0 0 0\n1 1 0\n0 90\n0 45 90\n100 0\n200 0\n400 0\n"
        ))
        .unwrap();
        for (phi, cd) in [(0.0, 100.0), (90.0, 400.0), (180.0, 100.0), (270.0, 400.0)] {
            assert!((quadrant.candela(0.0, f32::to_radians(phi)) - cd).abs() < 1e-3);
        }
        assert!((quadrant.candela(0.0, 135f32.to_radians()) - 200.0).abs() < 1e-3);
        assert!((quadrant.candela(0.0, 315f32.to_radians()) - 200.0).abs() < 1e-3);

        let bilateral_90 = parse(&format!(
            "{HEADER}1 1000 1 2 3 1 1 0 0 0\n1 1 0\n0 90\n90 180 270\n100 0\n200 0\n300 0\n"
        ))
        .unwrap();
        // Mirror of 0° about the 90–270 plane is 180°; of 300° is 240°.
        assert!((bilateral_90.candela(0.0, 0.0) - 200.0).abs() < 1e-3);
        let at_240 = 200.0 + 100.0 * 60.0 / 90.0;
        assert!((bilateral_90.candela(0.0, 300f32.to_radians()) - at_240).abs() < 1e-3);
        assert!((bilateral_90.candela(0.0, 45f32.to_radians()) - 150.0).abs() < 1e-3);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases = [
            ("IESNA:LM-63-2002\nTILT=INCLUDE\n", "t.ies:2: TILT=INCLUDE"),
            (
                &format!("{HEADER}1 1000 1 2 1 2 1 0 0 0\n1 1 0\n"),
                "t.ies:4: photometric type 2",
            ),
            (
                &format!("{HEADER}1 1000 1 2 1 1 1 0 0 0\n1 1 0\n0 x\n"),
                "t.ies:6: expected vertical angle 2 of 2",
            ),
            (
                &format!("{HEADER}1 1000 1 2 1 1 1 0 0 0\n1 1 0\n0 90\n0\n5\n"),
                "t.ies:8: the file ends",
            ),
            (
                &format!("{HEADER}1 1000 1 2 1 1 1 0 0 0\n1 1 0\n0 90\n0\n5 -1\n"),
                "t.ies:8: the candela value",
            ),
            (
                &format!("{HEADER}1 1000 1 2 1 1 1 0 0 0\n1 1 0\n0 80\n0\n5 1\n"),
                "t.ies:6: type C vertical",
            ),
            (
                &format!("{HEADER}1 1000 1 2 2 1 1 0 0 0\n1 1 0\n0 90\n0 120\n5 1 5 1\n"),
                "t.ies:7: type C horizontal",
            ),
            (
                &format!("{HEADER}1 1000 1 2 1 1 1 0 0 0\n1 1 0\n0 90\n0\n5 1\n7\n"),
                "t.ies:9: unexpected '7'",
            ),
            ("no tilt here\n", "t.ies: not an LM-63"),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err();
            assert!(e.starts_with(want), "{e:?} does not start with {want:?}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn multipliers_and_commas() {
        let p = parse(&format!(
            "{HEADER}1,1000,2,2,1,1,2,0,0,0\n0.5,1,10\n0,90\n0\n10,20\n"
        ))
        .unwrap();
        assert_eq!(p.candela(0.0, 0.0), 10.0);
        assert_eq!(p.max_candela, 20.0);
    }
}
