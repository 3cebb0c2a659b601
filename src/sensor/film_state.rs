//! The raw state of a [`Film`](super::film::Film): every sum and count it holds, in f64 and
//! u64 as held, so that a film saved and read back continues bit for bit (checkpoints,
//! `--resume`; later, partial renders merged exactly). [`FilmState::encode`] and
//! [`FilmState::decode`] give its byte form (`raw_bytes`: little-endian, length-prefixed,
//! bounds-checked); [`FilmState::check`] validates one read from a file before a film is
//! built from it.
//!
//! Layout: width, height, the grid's exponent (as u64 of its i64), light paths, terms
//! clamped, then the per-pixel sequences sums (i128 XYZ triples on the grid, `grid_sum`),
//! samples (u64), odd Y (f64), splat (i128 triples) and odd splat Y (f64); the splat
//! sequences are empty for a film that was never splatted.

use super::raw_bytes::{ByteReader, ByteWriter};
use crate::error::Reason;

/// A film's sums and counts (see `sensor::film` for what each means).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmState {
    pub width: usize,
    pub height: usize,
    /// The exponent e of the grid 2^−e the sums are held on (`grid_sum`).
    pub grid_exponent: i32,
    /// Own-pixel XYZ sums on the grid, per pixel.
    pub sums: Vec<[i128; 3]>,
    /// Samples per pixel.
    pub samples: Vec<u64>,
    /// Y of the odd-numbered samples, per pixel.
    pub odd_y: Vec<f64>,
    /// Splat XYZ sums on the grid per pixel (empty when nothing splatted).
    pub splat: Vec<[i128; 3]>,
    /// Y of the odd-numbered samples' splats (empty with `splat`).
    pub odd_splat_y: Vec<f64>,
    /// Light paths traced over the whole image.
    pub light_paths: u64,
    /// Terms clamped and sums saturated.
    pub clamped: u64,
}

impl FilmState {
    pub fn encode(&self, w: &mut ByteWriter) {
        w.u64(self.width as u64);
        w.u64(self.height as u64);
        w.u64(i64::from(self.grid_exponent) as u64);
        w.u64(self.light_paths);
        w.u64(self.clamped);
        w.fixed_triples(&self.sums);
        w.u64s(&self.samples);
        w.f64s(&self.odd_y);
        w.fixed_triples(&self.splat);
        w.f64s(&self.odd_splat_y);
    }

    pub fn decode(r: &mut ByteReader) -> Reason<FilmState> {
        let width = r.u64()? as usize;
        let height = r.u64()? as usize;
        let grid_exponent = i32::try_from(r.u64()? as i64)
            .map_err(|_| "the film's grid exponent is out of range")?;
        let light_paths = r.u64()?;
        let clamped = r.u64()?;
        let state = FilmState {
            width,
            height,
            grid_exponent,
            light_paths,
            clamped,
            sums: r.fixed_triples()?,
            samples: r.u64s()?,
            odd_y: r.f64s()?,
            splat: r.fixed_triples()?,
            odd_splat_y: r.f64s()?,
        };
        state.check()?;
        Ok(state)
    }

    /// Every per-pixel sequence has one entry per pixel (the splat ones may be empty).
    pub fn check(&self) -> Reason<()> {
        let n = self
            .width
            .checked_mul(self.height)
            .ok_or("the film's size overflows")?;
        let full = [self.sums.len(), self.samples.len(), self.odd_y.len()];
        let splats = [self.splat.len(), self.odd_splat_y.len()];
        if full.iter().any(|&l| l != n) || !(splats == [0, 0] || splats == [n, n]) {
            return Err(format!(
                "the film's sums do not match its {}×{} pixels",
                self.width, self.height
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> FilmState {
        FilmState {
            width: 2,
            height: 1,
            grid_exponent: -3,
            sums: vec![[1, 2, i128::MIN], [-1, 0, i128::MAX]],
            samples: vec![5, 5],
            odd_y: vec![1.5, 0.25],
            splat: vec![],
            odd_splat_y: vec![],
            light_paths: 0,
            clamped: 2,
        }
    }

    #[test]
    fn a_state_round_trips_and_a_damaged_one_is_refused() {
        let s = state();
        let mut w = ByteWriter::default();
        s.encode(&mut w);
        assert_eq!(
            FilmState::decode(&mut ByteReader::new(&w.bytes)),
            Ok(s.clone())
        );
        let cut = &w.bytes[..w.bytes.len() - 4];
        assert!(FilmState::decode(&mut ByteReader::new(cut)).is_err());
        let mut bad = s;
        bad.splat = vec![[0; 3]];
        let mut w = ByteWriter::default();
        bad.encode(&mut w);
        assert!(FilmState::decode(&mut ByteReader::new(&w.bytes)).is_err());
    }
}
