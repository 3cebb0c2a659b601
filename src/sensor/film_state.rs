//! The raw state of a [`Film`](super::film::Film): every sum and count it holds, in f64 and
//! u64 as held, so that a film saved and read back continues bit for bit (checkpoints,
//! `--resume`; later, partial renders merged exactly). [`FilmState::encode`] and
//! [`FilmState::decode`] give its byte form (`raw_bytes`: little-endian, length-prefixed,
//! bounds-checked); [`FilmState::check`] validates one read from a file before a film is
//! built from it.
//!
//! Layout: width, height, light paths, then the per-pixel sequences closed, open (f64 XYZ
//! triples), samples (u64), odd Y (f64), splat (triples) and odd splat Y (f64); the splat
//! sequences are empty for a film that was never splatted.

use super::raw_bytes::{ByteReader, ByteWriter};
use crate::error::Reason;

/// A film's sums and counts (see `sensor::film` for what each means).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmState {
    pub width: usize,
    pub height: usize,
    /// XYZ sums of the closed chunks, per pixel.
    pub closed: Vec<[f64; 3]>,
    /// XYZ sums of the open chunk, per pixel.
    pub open: Vec<[f64; 3]>,
    /// Samples per pixel.
    pub samples: Vec<u64>,
    /// Y of the odd-numbered samples, per pixel.
    pub odd_y: Vec<f64>,
    /// Splat XYZ sums per pixel (empty when nothing splatted).
    pub splat: Vec<[f64; 3]>,
    /// Y of the odd-numbered samples' splats (empty with `splat`).
    pub odd_splat_y: Vec<f64>,
    /// Light paths traced over the whole image.
    pub light_paths: u64,
}

impl FilmState {
    pub fn encode(&self, w: &mut ByteWriter) {
        w.u64(self.width as u64);
        w.u64(self.height as u64);
        w.u64(self.light_paths);
        w.triples(&self.closed);
        w.triples(&self.open);
        w.u64s(&self.samples);
        w.f64s(&self.odd_y);
        w.triples(&self.splat);
        w.f64s(&self.odd_splat_y);
    }

    pub fn decode(r: &mut ByteReader) -> Reason<FilmState> {
        let width = r.u64()? as usize;
        let height = r.u64()? as usize;
        let light_paths = r.u64()?;
        let state = FilmState {
            width,
            height,
            light_paths,
            closed: r.triples()?,
            open: r.triples()?,
            samples: r.u64s()?,
            odd_y: r.f64s()?,
            splat: r.triples()?,
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
        let full = [
            self.closed.len(),
            self.open.len(),
            self.samples.len(),
            self.odd_y.len(),
        ];
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
            closed: vec![[1.0, 2.0, 3.0], [0.1, 0.2, 0.3]],
            open: vec![[4.0; 3], [-0.0; 3]],
            samples: vec![5, 5],
            odd_y: vec![1.5, 0.25],
            splat: vec![],
            odd_splat_y: vec![],
            light_paths: 0,
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
        bad.splat = vec![[0.0; 3]];
        let mut w = ByteWriter::default();
        bad.encode(&mut w);
        assert!(FilmState::decode(&mut ByteReader::new(&w.bytes)).is_err());
    }
}
