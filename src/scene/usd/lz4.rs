//! LZ4 block decompression (the block format of the LZ4 specification, as USD's
//! `TfFastCompression` stores it in `.usdc` files), bounded: it never produces more than the
//! caller's limit, so a corrupt block costs at most that much memory.

use crate::error::Reason;

/// The most an LZ4 block of `n` bytes can expand to: a sequence of a token byte, a two-byte
/// offset and length bytes of 255 each yields at most 255 output bytes per input byte.
pub(super) fn max_expansion(n: usize) -> usize {
    n.saturating_mul(255).saturating_add(64)
}

/// Decompresses the block `input` into at most `limit` bytes.
pub(super) fn decompress(input: &[u8], limit: usize) -> Reason<Vec<u8>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < input.len() {
        let token = input[i];
        i += 1;
        let literals = length(input, &mut i, usize::from(token >> 4))?;
        let end = i
            .checked_add(literals)
            .filter(|&e| e <= input.len())
            .ok_or("an LZ4 literal run passes the end of its block")?;
        push(&mut out, &input[i..end], limit)?;
        i = end;
        if i == input.len() {
            break;
        }
        let offset = match input.get(i..i + 2) {
            Some(b) => usize::from(u16::from_le_bytes([b[0], b[1]])),
            None => return Err("an LZ4 match offset passes the end of its block".into()),
        };
        i += 2;
        if offset == 0 || offset > out.len() {
            return Err("an LZ4 match refers to data before the start of its block".into());
        }
        let matched = length(input, &mut i, usize::from(token & 15))? + 4;
        if out.len() + matched > limit {
            return Err(too_long(limit));
        }
        let start = out.len() - offset;
        for k in 0..matched {
            out.push(out[start + k]);
        }
    }
    Ok(out)
}

/// A literal or match length: the token's nibble, extended by bytes while they are 255.
fn length(input: &[u8], i: &mut usize, nibble: usize) -> Reason<usize> {
    let mut n = nibble;
    if nibble == 15 {
        loop {
            let b = *input
                .get(*i)
                .ok_or("an LZ4 length passes the end of its block")?;
            *i += 1;
            n = n.saturating_add(usize::from(b));
            if b != 255 {
                break;
            }
        }
    }
    Ok(n)
}

fn push(out: &mut Vec<u8>, bytes: &[u8], limit: usize) -> Reason<()> {
    if out.len() + bytes.len() > limit {
        return Err(too_long(limit));
    }
    out.extend_from_slice(bytes);
    Ok(())
}

fn too_long(limit: usize) -> String {
    format!("an LZ4 block decompresses to more than the {limit} bytes declared for it")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_and_overlapping_matches() {
        // "abc" then a match of 6 at offset 3 → "abcabcabc", then the literal "!".
        let block = [0x32, b'a', b'b', b'c', 3, 0, 0x10, b'!'];
        assert_eq!(decompress(&block, 100).unwrap(), b"abcabcabc!");
        assert!(decompress(&block, 5).is_err());
    }

    #[test]
    fn corrupt_blocks_are_errors() {
        assert!(decompress(&[0x50, b'a'], 100).is_err()); // literals past the end
        assert!(decompress(&[0x10, b'a', 9, 0, 0], 100).is_err()); // offset before start
        assert!(decompress(&[0x10, b'a', 1], 100).is_err()); // truncated offset
    }
}
