//! Validates a binary crate file (`.usdc`) before openusd reads it.
//!
//! openusd's crate reader trusts the counts a file declares: it allocates what a count asks
//! for before reading the data (so a flipped bit can ask for 9e17 bytes, an abort), follows
//! the path tree's jumps without checking that they form a tree (exponential work), and
//! recurses through dictionaries without a depth limit. This module walks the same
//! structures the reader will — the table of contents, the six structural sections, and
//! every field's value — and checks that each count fits in the bytes that must hold it
//! (with LZ4's largest expansion where the data is compressed), that the path tree visits
//! each entry once, that nesting stays shallow, and that the values together decode to at
//! most a fixed multiple of the file's size. What passes can only fail inside openusd with
//! an ordinary error (or a panic, which `guard.rs` turns into one).
//!
//! The layout is the USD crate format as openusd 0.6 reads it (`usdc/reader.rs`), versions
//! 0.4.0 to 0.12.0.

use super::lz4;
use crate::error::Reason;

const MAGIC: &[u8; 8] = b"PXR-USDC";

/// Deepest nesting of values (dictionaries, time samples) accepted.
const MAX_VALUE_DEPTH: usize = 32;

/// The decoded values of all fields together may take this many bytes per byte of file
/// (LZ4's largest expansion), plus [`DECODED_SLACK`].
const DECODED_PER_BYTE: usize = 256;
const DECODED_SLACK: usize = 64 << 20;

/// `true` when `bytes` begin like a crate file.
pub(super) fn is_crate(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// Checks a crate file held in `bytes`.
pub(super) fn check(bytes: &[u8]) -> Reason<()> {
    let mut file = Crate::open(bytes)?;
    let reps = file.structure()?;
    // Fields share deduplicated values; openusd decodes each field on its own, so a shared
    // value is charged once here (values nested in one field are charged every time).
    let mut seen = std::collections::HashSet::new();
    for rep in reps {
        if seen.insert(rep) {
            file.value(Rep(rep), 0)?;
        }
    }
    Ok(())
}

/// Crate version (major, minor, patch).
type Version = (u8, u8, u8);

struct Crate<'a> {
    bytes: &'a [u8],
    version: Version,
    sections: Vec<(String, usize, usize)>,
    /// Decoded bytes the values may still take, and value visits left.
    decoded_budget: usize,
    visits_left: usize,
}

/// A value representation: type, flags and a 48-bit payload.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
struct Rep(u64);

impl Rep {
    fn ty(self) -> u8 {
        (self.0 >> 48) as u8
    }
    fn is_array(self) -> bool {
        self.0 & (1 << 63) != 0
    }
    fn is_inlined(self) -> bool {
        self.0 & (1 << 62) != 0
    }
    fn is_compressed(self) -> bool {
        self.0 & (1 << 61) != 0
    }
    fn payload(self) -> usize {
        (self.0 & ((1 << 48) - 1)) as usize
    }
}

/// How openusd decides whether an array is compressed.
#[derive(Clone, Copy, PartialEq)]
enum ArrayKind {
    Ints,
    Floats,
    Other,
}

impl<'a> Crate<'a> {
    fn open(bytes: &'a [u8]) -> Reason<Crate<'a>> {
        if bytes.len() < 32 || !is_crate(bytes) {
            return Err("not a crate file (no PXR-USDC header)".into());
        }
        let version = (bytes[8], bytes[9], bytes[10]);
        if version.0 != 0 || !(4..=12).contains(&version.1) {
            return Err(format!(
                "crate file version {}.{}.{} is not supported (0.4.0 to 0.12.0)",
                version.0, version.1, version.2
            ));
        }
        let len = bytes.len();
        Ok(Crate {
            bytes,
            version,
            sections: Vec::new(),
            decoded_budget: len.saturating_mul(DECODED_PER_BYTE) + DECODED_SLACK,
            visits_left: len.saturating_mul(4) + 1_000_000,
        })
    }

    fn at_least(&self, minor: u8) -> bool {
        self.version.1 >= minor
    }

    // ---------------------------------------------------------------- reading primitives

    fn u64_at(&self, pos: usize) -> Reason<u64> {
        let b = self.slice(pos, 8)?;
        Ok(u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }

    fn u32_at(&self, pos: usize) -> Reason<u32> {
        let b = self.slice(pos, 4)?;
        Ok(u32::from_le_bytes(b.try_into().expect("4 bytes")))
    }

    fn slice(&self, pos: usize, n: usize) -> Reason<&'a [u8]> {
        pos.checked_add(n)
            .and_then(|end| self.bytes.get(pos..end))
            .ok_or_else(|| format!("data at byte {pos} runs past the end of the file"))
    }

    /// Bytes from `pos` to the end of the file.
    fn rest(&self, pos: usize) -> usize {
        self.bytes.len().saturating_sub(pos)
    }

    /// `count` elements of `size` bytes must fit in the file from `pos`.
    fn fits(&self, pos: usize, count: usize, size: usize, what: &str) -> Reason<()> {
        if count.saturating_mul(size) > self.rest(pos) {
            return Err(format!(
                "{what} declares {count} elements at byte {pos}, more than the file holds"
            ));
        }
        Ok(())
    }

    /// Charges `bytes` of decoded data against the file's budget.
    fn charge(&mut self, bytes: usize) -> Reason<()> {
        if bytes > self.decoded_budget {
            return Err(format!(
                "its values decode to more than {DECODED_PER_BYTE} times the file's size"
            ));
        }
        self.decoded_budget -= bytes;
        Ok(())
    }

    /// A compressed block at `pos` (u64 size, then the `TfFastCompression` data) that holds
    /// at least `least` and at most `limit` bytes (openusd allocates `limit` before it
    /// decompresses): (decompressed data, position after the block).
    fn compressed(
        &self,
        pos: usize,
        (least, limit): (usize, usize),
        what: &str,
    ) -> Reason<(Vec<u8>, usize)> {
        let size = self.u64_at(pos)? as usize;
        let data = self
            .slice(pos + 8, size)
            .map_err(|_| format!("{what}: the compressed block runs past the end of the file"))?;
        if least > lz4::max_expansion(size) {
            return Err(format!(
                "{what}: {least} bytes cannot come from a compressed block of {size} bytes"
            ));
        }
        let out = match data.split_first() {
            None => Vec::new(),
            Some((0, block)) => {
                lz4::decompress(block, limit).map_err(|e| format!("{what}: {e}"))?
            }
            Some(_) => return Err(format!("{what}: chunked LZ4 data is not supported")),
        };
        Ok((out, pos + 8 + size))
    }

    /// Integer-coded 32-bit values (USD's integerCoding) compressed at `pos`.
    fn encoded_ints(&self, pos: usize, count: usize, what: &str) -> Reason<(Vec<i64>, usize)> {
        if count == 0 {
            let size = self.u64_at(pos)? as usize;
            self.fits(pos + 8, size, 1, what)?;
            return Ok((Vec::new(), pos + 8 + size));
        }
        // The common value and two bits per integer at least, four more bytes each at most.
        let least = 4 + (2 * count).div_ceil(8);
        let (data, next) = self.compressed(pos, (least, least + 4 * count), what)?;
        Ok((
            decode_ints32(&data, count).map_err(|e| format!("{what}: {e}"))?,
            next,
        ))
    }

    // ---------------------------------------------------------------- structure

    fn section(&self, name: &str) -> Option<(usize, usize)> {
        self.sections
            .iter()
            .find(|s| s.0 == name)
            .map(|s| (s.1, s.2))
    }

    /// Checks the table of contents and the structural sections; returns every field's
    /// value representation.
    fn structure(&mut self) -> Reason<Vec<u64>> {
        self.read_toc()?;
        let tokens = self.tokens()?;
        if let Some((start, _)) = self.section("STRINGS") {
            let count = self.u64_at(start)? as usize;
            self.fits(start + 8, count, 4, "STRINGS")?;
        }
        let reps = self.fields()?;
        if let Some((start, _)) = self.section("FIELDSETS") {
            let count = self.u64_at(start)? as usize;
            self.encoded_ints(start + 8, count, "FIELDSETS")?;
        }
        self.paths(tokens)?;
        if let Some((start, _)) = self.section("SPECS") {
            let count = self.u64_at(start)? as usize;
            let mut pos = start + 8;
            for _ in 0..3 {
                pos = self.encoded_ints(pos, count, "SPECS")?.1;
            }
        }
        Ok(reps)
    }

    fn read_toc(&mut self) -> Reason<()> {
        let toc = self.u64_at(16)? as usize;
        let count = self.u64_at(toc)? as usize;
        if count == 0 || count >= 64 {
            return Err(format!("the table of contents lists {count} sections"));
        }
        for k in 0..count {
            let entry = self.slice(toc + 8 + 32 * k, 32)?;
            let name_len = entry[..16].iter().position(|&b| b == 0).unwrap_or(16);
            let name = String::from_utf8_lossy(&entry[..name_len]).into_owned();
            let start = u64::from_le_bytes(entry[16..24].try_into().expect("8 bytes")) as usize;
            let size = u64::from_le_bytes(entry[24..32].try_into().expect("8 bytes")) as usize;
            if start
                .checked_add(size)
                .is_none_or(|end| end > self.bytes.len())
            {
                return Err(format!("section {name} lies outside the file"));
            }
            self.sections.push((name, start, size));
        }
        Ok(())
    }

    /// The TOKENS section; returns the number of tokens.
    fn tokens(&self) -> Reason<usize> {
        let Some((start, _)) = self.section("TOKENS") else {
            return Ok(0);
        };
        let count = self.u64_at(start)? as usize;
        let size = self.u64_at(start + 8)? as usize;
        let (data, _) = self.compressed(start + 16, (size, size), "TOKENS")?;
        let found = data.iter().filter(|&&b| b == 0).count();
        if found != count {
            return Err(format!("TOKENS declares {count} tokens but holds {found}"));
        }
        Ok(count)
    }

    /// The FIELDS section: token indices, then the value representations.
    fn fields(&self) -> Reason<Vec<u64>> {
        let Some((start, _)) = self.section("FIELDS") else {
            return Ok(Vec::new());
        };
        let count = self.u64_at(start)? as usize;
        let (_, pos) = self.encoded_ints(start + 8, count, "FIELDS")?;
        let bytes = count.saturating_mul(8);
        let (data, _) = self.compressed(pos, (bytes, bytes), "FIELDS")?;
        Ok(data
            .chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect())
    }

    /// The PATHS section: the encoded tree must visit each entry once, with its indices in
    /// range, as openusd's `build_compressed_paths` walks it.
    fn paths(&self, tokens: usize) -> Reason<()> {
        let Some((start, _)) = self.section("PATHS") else {
            return Ok(());
        };
        let path_count = self.u64_at(start)? as usize;
        let count = self.u64_at(start + 8)? as usize;
        if path_count > count {
            return Err(format!(
                "PATHS declares {path_count} paths but encodes {count}"
            ));
        }
        let (indexes, pos) = self.encoded_ints(start + 16, count, "PATHS")?;
        let (elements, pos) = self.encoded_ints(pos, count, "PATHS")?;
        let (jumps, _) = self.encoded_ints(pos, count, "PATHS")?;
        check_path_tree(&indexes, &elements, &jumps, path_count, tokens)
    }

    // ---------------------------------------------------------------- values

    /// Checks one value as openusd's `CrateFile::value` would decode it.
    fn value(&mut self, rep: Rep, depth: usize) -> Reason<()> {
        if depth > MAX_VALUE_DEPTH {
            return Err(format!("values nest deeper than {MAX_VALUE_DEPTH} levels"));
        }
        if self.visits_left == 0 {
            return Err("its values refer to each other too often".into());
        }
        self.visits_left -= 1;
        if rep.is_inlined() {
            return Ok(());
        }
        let pos = rep.payload();
        match rep.ty() {
            1 | 2 if rep.is_array() => self.array(rep, 1, ArrayKind::Other),
            3 | 4 if rep.is_array() => self.array(rep, 4, ArrayKind::Ints),
            5 | 6 if rep.is_array() => self.array(rep, 8, ArrayKind::Ints),
            7 if rep.is_array() => self.array(rep, 2, ArrayKind::Floats),
            8 if rep.is_array() => self.array(rep, 4, ArrayKind::Floats),
            9 | 56 if rep.is_array() => self.array(rep, 8, ArrayKind::Floats),
            48 => self.array(rep, 8, ArrayKind::Floats),
            11 if rep.is_array() => self.array(rep, 4, ArrayKind::Other),
            // An empty array has payload 0 (openusd 0.6 misread it; vendor/openusd/PATCHES.md).
            10 | 12 | 57 if rep.is_array() && pos == 0 => Ok(()),
            10 | 12 | 57 if rep.is_array() => self.indexed(pos, "a string array").map(|_| ()),
            13..=30 if rep.is_array() => {
                let size = element_size(rep.ty());
                self.array(rep, size, ArrayKind::Other)
            }
            40 | 41 | 50 => self.indexed(pos, "a vector").map(|_| ()),
            31 => self.dictionary(pos, depth),
            32..=34 | 54 => self.list_op(pos, depth, ListItems::Indexed),
            35 => self.list_op(pos, depth, ListItems::References),
            36 | 38 => self.list_op(pos, depth, ListItems::Pods(4)),
            37 | 39 => self.list_op(pos, depth, ListItems::Pods(8)),
            55 => self.list_op(pos, depth, ListItems::Payloads),
            49 => self.counted(pos, 16, "a layer offset vector").map(|_| ()),
            45 => self.counted(pos, 8, "a variant selection map").map(|_| ()),
            58 => self.counted(pos, 8, "relocates").map(|_| ()),
            46 => self.time_samples(pos, depth),
            _ => Ok(()),
        }
    }

    /// An array value (`unpack_array_len` and the reads after it).
    fn array(&mut self, rep: Rep, size: usize, kind: ArrayKind) -> Reason<()> {
        if rep.payload() == 0 {
            return Ok(());
        }
        let mut pos = rep.payload();
        if !self.at_least(5) {
            pos += 4;
        }
        let (count, mut pos) = if self.at_least(7) {
            (self.u64_at(pos)? as usize, pos + 8)
        } else {
            (self.u32_at(pos)? as usize, pos + 4)
        };
        let compressed = count >= 4
            && rep.is_compressed()
            && match kind {
                ArrayKind::Ints => self.at_least(5),
                ArrayKind::Floats => self.at_least(6),
                ArrayKind::Other => false,
            };
        let what = "an array";
        if !compressed {
            self.fits(pos, count, size, what)?;
        } else if kind == ArrayKind::Floats {
            let code = self.slice(pos, 1)?[0];
            pos += 1;
            if code == b't' {
                let lut = self.u32_at(pos)? as usize;
                self.fits(pos + 4, lut, size, what)?;
                pos += 4 + lut * size;
            } else if code != b'i' {
                return Err(format!(
                    "an array at byte {pos} has compression code {code}"
                ));
            }
            self.encoded_ints(pos, count, what)?;
        } else {
            self.encoded_ints(pos, count, what)?;
        }
        self.charge(count.saturating_mul(size.max(4)))
    }

    /// A count-prefixed vector of `size`-byte items at `pos`; returns the position after it.
    fn counted(&mut self, pos: usize, size: usize, what: &str) -> Reason<usize> {
        let count = self.u64_at(pos)? as usize;
        self.fits(pos + 8, count, size, what)?;
        self.charge(count.saturating_mul(size.max(24)))?;
        Ok(pos + 8 + count * size)
    }

    /// A count-prefixed vector of 4-byte table indices (strings, tokens, paths).
    fn indexed(&mut self, pos: usize, what: &str) -> Reason<usize> {
        self.counted(pos, 4, what)
    }

    /// A dictionary (`read_custom_data`): entries of a key, a forward offset to the value's
    /// representation, and the value. Returns the position after the last entry.
    fn dictionary(&mut self, pos: usize, depth: usize) -> Reason<()> {
        self.dictionary_at(pos, depth).map(|_| ())
    }

    fn dictionary_at(&mut self, pos: usize, depth: usize) -> Reason<usize> {
        let count = self.u64_at(pos)? as usize;
        // Each entry takes at least a key, an offset and a representation.
        self.fits(pos + 8, count, 20, "a dictionary")?;
        let mut pos = pos + 8;
        for _ in 0..count {
            let rep_at = self.forward(pos + 4)?;
            let rep = Rep(self.u64_at(rep_at)?);
            self.value(rep, depth + 1)?;
            pos = rep_at + 8;
        }
        Ok(pos)
    }

    /// Where the forward offset stored at `pos` leads (openusd's `apply_recursive_offset`).
    fn forward(&self, pos: usize) -> Reason<usize> {
        let offset = self.u64_at(pos)? as i64;
        if offset < 8 {
            return Err(format!(
                "a value offset at byte {pos} does not point forward"
            ));
        }
        Ok(pos.saturating_add(offset as usize))
    }

    /// A list op: a header byte, then each list it has, in openusd's order.
    fn list_op(&mut self, pos: usize, depth: usize, items: ListItems) -> Reason<()> {
        let header = self.slice(pos, 1)?[0];
        let mut pos = pos + 1;
        // explicit, added, prepended, appended, deleted, ordered
        for bit in [1, 2, 5, 6, 3, 4] {
            if header & (1 << bit) == 0 {
                continue;
            }
            pos = match items {
                ListItems::Indexed => self.indexed(pos, "a list op")?,
                ListItems::Pods(size) => self.counted(pos, size, "a list op")?,
                ListItems::Payloads => {
                    let size = if self.at_least(8) { 24 } else { 8 };
                    self.counted(pos, size, "a payload list op")?
                }
                ListItems::References => self.references(pos, depth)?,
            };
        }
        Ok(())
    }

    /// A reference list: each a string, a path, a layer offset and a dictionary.
    fn references(&mut self, pos: usize, depth: usize) -> Reason<usize> {
        let count = self.u64_at(pos)? as usize;
        self.fits(pos + 8, count, 32, "a reference list")?;
        self.charge(count.saturating_mul(128))?;
        let mut pos = pos + 8;
        for _ in 0..count {
            pos = self.dictionary_at(pos + 24, depth)?;
        }
        Ok(pos)
    }

    /// Time samples: an offset to the times' representation, then an offset to the count
    /// and the values' representations.
    fn time_samples(&mut self, pos: usize, depth: usize) -> Reason<()> {
        let times_at = self.forward(pos)?;
        let times = Rep(self.u64_at(times_at)?);
        self.value(times, depth + 1)?;
        let count_at = self.forward(times_at + 8)?;
        let count = self.u64_at(count_at)? as usize;
        self.fits(count_at + 8, count, 8, "time samples")?;
        self.charge(count.saturating_mul(64))?;
        for k in 0..count {
            let rep = Rep(self.u64_at(count_at + 8 + 8 * k)?);
            self.value(rep, depth + 1)?;
        }
        Ok(())
    }
}

/// What a list op holds.
#[derive(Clone, Copy)]
enum ListItems {
    /// Table indices (tokens, strings, paths).
    Indexed,
    /// Plain numbers of this size.
    Pods(usize),
    Payloads,
    References,
}

/// The size of one element of the fixed-size array types 13–30 (matrices, quaternions,
/// vectors).
fn element_size(ty: u8) -> usize {
    match ty {
        13 => 32,
        14 => 72,
        15 => 128,
        16 | 27 => 32,
        17 | 28 | 30 => 16,
        18 | 29 => 8,
        19 => 16,
        20 | 22 => 8,
        21 => 4,
        23 => 24,
        24 | 26 => 12,
        _ => 6, // 25: Vec3h
    }
}

/// Decodes `count` 32-bit integers of USD's integer coding: a common delta, two bits per
/// value saying whether its delta is the common one or an 8-, 16- or 32-bit number, then
/// the deltas.
fn decode_ints32(data: &[u8], count: usize) -> Reason<Vec<i64>> {
    let codes_len = (2 * count).div_ceil(8);
    let (common, rest) = data
        .split_first_chunk::<4>()
        .ok_or("integer-coded data is too short")?;
    let common = i64::from(i32::from_le_bytes(*common));
    let codes = rest
        .get(..codes_len)
        .ok_or("integer-coded data is too short")?;
    let mut deltas = &rest[codes_len..];
    let mut take = |n: usize| -> Reason<i64> {
        let (b, tail) = deltas
            .split_at_checked(n)
            .ok_or("integer-coded data is too short")?;
        deltas = tail;
        Ok(match n {
            1 => i64::from(b[0] as i8),
            2 => i64::from(i16::from_le_bytes([b[0], b[1]])),
            _ => i64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        })
    };
    let mut out = Vec::with_capacity(count);
    let mut prev = 0i64;
    for k in 0..count {
        let code = (codes[k / 4] >> (2 * (k % 4))) & 3;
        let delta = match code {
            0 => common,
            1 => take(1)?,
            2 => take(2)?,
            _ => take(4)?,
        };
        prev = i64::from(prev.wrapping_add(delta) as i32);
        out.push(prev);
    }
    Ok(out)
}

/// The path tree as `build_compressed_paths` walks it: from entry 0, each entry's jump says
/// whether a child follows (the next entry) and where its next sibling is. Every entry must
/// be reached once, and its path and token indices must be in range.
fn check_path_tree(
    indexes: &[i64],
    elements: &[i64],
    jumps: &[i64],
    path_count: usize,
    tokens: usize,
) -> Reason<()> {
    let n = jumps.len();
    if n == 0 {
        return Ok(());
    }
    let mut seen = vec![false; n];
    let mut pending = vec![0usize];
    while let Some(mut index) = pending.pop() {
        loop {
            if index >= n || std::mem::replace(&mut seen[index], true) {
                return Err(
                    "the PATHS tree is malformed (an entry is reached twice or lies outside it)"
                        .into(),
                );
            }
            let in_range = usize::try_from(indexes[index]).is_ok_and(|i| i < path_count)
                && (index == 0 || (elements[index].unsigned_abs() as usize) < tokens);
            if !in_range {
                return Err(format!("PATHS entry {index} has an index out of range"));
            }
            let jump = jumps[index];
            let has_child = jump > 0 || jump == -1;
            let has_sibling = jump >= 0;
            if has_child && has_sibling {
                pending.push(index.saturating_add(jump as usize));
            }
            if !has_child && !has_sibling {
                break;
            }
            index += 1;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_coding_round_trip() {
        // common delta 1; codes: common, 8-bit, common, 16-bit → 1, 1 + (-3), -1, -1 + 300.
        let mut data = 1i32.to_le_bytes().to_vec();
        data.push(0b10_00_01_00);
        data.push((-3i8) as u8);
        data.extend_from_slice(&300i16.to_le_bytes());
        assert_eq!(decode_ints32(&data, 4).unwrap(), vec![1, -2, -1, 299]);
        assert!(decode_ints32(&data[..6], 4).is_err());
    }

    #[test]
    fn path_trees_must_visit_each_entry_once() {
        // Jumps: −1 a child follows, 0 a sibling follows, k > 0 a child follows and the
        // sibling is k entries on, −2 neither. / → A → (B, then its sibling C).
        assert!(check_path_tree(&[0, 1, 2, 3], &[0, 1, 2, 3], &[-1, -1, 0, -2], 4, 4).is_ok());
        // A's sibling pointer lands on its own child: entry 2 is reached twice.
        assert!(check_path_tree(&[0, 1, 2], &[0, 1, 2], &[-1, 1, -2], 3, 3).is_err());
        // A token index out of range.
        assert!(check_path_tree(&[0, 1], &[0, 7], &[-1, -2], 2, 3).is_err());
    }

    #[test]
    fn garbage_is_refused_without_allocating() {
        let mut bytes = MAGIC.to_vec();
        bytes.extend_from_slice(&[0, 8, 0, 0, 0, 0, 0, 0]);
        bytes.extend_from_slice(&32u64.to_le_bytes());
        bytes.extend_from_slice(&[0; 8]);
        // A table of contents with one TOKENS section claiming 2^60 bytes.
        bytes.extend_from_slice(&1u64.to_le_bytes());
        let mut name = [0u8; 16];
        name[..6].copy_from_slice(b"TOKENS");
        bytes.extend_from_slice(&name);
        bytes.extend_from_slice(&72u64.to_le_bytes());
        bytes.extend_from_slice(&24u64.to_le_bytes());
        bytes.extend_from_slice(&1u64.to_le_bytes());
        bytes.extend_from_slice(&(1u64 << 60).to_le_bytes());
        bytes.extend_from_slice(&8u64.to_le_bytes());
        let e = check(&bytes).unwrap_err();
        assert!(e.contains("TOKENS"), "{e}");
    }
}
