//! Where each decision of a camera path draws its numbers: the same dimensions of the
//! low-discrepancy sequence for the same decision in every sample, whatever branches the
//! path took before (a skipped light sample or roulette test leaves its dimensions unused
//! rather than shifting the ones after it). The camera's come first, then a block per
//! bounce; the sequence pads every dimension beyond by hashing (`zsobol.rs`), so depth is
//! unbounded. The independent sampler ignores the layout and draws in order.
//!
//! BDPT's and VCM's camera subpaths take the same blocks (their s = 1 connection at `LIGHT`,
//! the BSDF at `BSDF`, roulette at `ROULETTE`); their light subpaths and splats draw from
//! the sample's independent stream (`Sampler::detached`), outside the layout.

/// The hero wavelength's u (1D).
pub const WAVELENGTH: u32 = 0;
/// The position in the pixel (2D).
pub const FILM: u32 = 1;
/// The point on the lens (2D).
pub const LENS: u32 = 3;
/// The first bounce's block.
const FIRST_BOUNCE: u32 = 5;
/// Next-event estimation: the light's selection (1D), then the point on it (2D).
pub const LIGHT: u32 = 0;
/// BSDF sampling: the lobe (1D), then the direction (2D).
pub const BSDF: u32 = 3;
/// Russian roulette (1D).
pub const ROULETTE: u32 = 6;
/// Dimensions per bounce.
const PER_BOUNCE: u32 = 7;

/// The first dimension of bounce `b` (0 at the camera ray's first hit) plus `offset`.
#[inline]
pub fn bounce(b: u32, offset: u32) -> u32 {
    FIRST_BOUNCE
        .saturating_add(b.saturating_mul(PER_BOUNCE))
        .saturating_add(offset)
}

/// Dimension `offset` of the block that starts at `block` (`bounce(b, 0)`): `bounce(b,
/// offset)`, for a caller that draws several decisions of one bounce and computes the block's
/// start once.
#[inline]
pub fn in_block(block: u32, offset: u32) -> u32 {
    block.saturating_add(offset)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block's start plus an offset is the bounce's dimension, up to and past saturation.
    #[test]
    fn in_block_is_bounce() {
        let bounces = [
            0,
            1,
            2,
            6,
            7,
            1000,
            u32::MAX / 7,
            u32::MAX / 7 + 1,
            u32::MAX,
        ];
        for b in bounces {
            for offset in [LIGHT, BSDF, ROULETTE, PER_BOUNCE - 1] {
                assert_eq!(
                    in_block(bounce(b, 0), offset),
                    bounce(b, offset),
                    "{b} {offset}"
                );
            }
        }
    }
}
