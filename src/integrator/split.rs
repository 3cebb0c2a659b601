//! Splitting a path at its first vertex (`--split`): the path tracer's image samples share
//! their camera ray and first vertex (its BSDF, next-event estimation there) among n
//! continuations, each weighted 1/n (`PathIntegrator::li_split`). On scenes whose noise comes
//! from the light the continuations gather, it buys more of them for a fraction of a sample's
//! time; on those whose noise is in the first vertex itself (a pixel's texture, the direct
//! light), it buys nothing (docs/design.md §8, "Splitting at the first vertex").
//!
//! `auto`, the default for images, lets the roulette pilot choose n with the roulette start
//! (`roulette_pilot.rs`); a number fixes it. n is a power of two, so that the zsobol sampler's
//! continuations of a pixel are one (0, k, 2)-net (`Stream::continuation`).

/// The largest split a user may ask for.
pub const MAX_SPLIT: u32 = 16;

/// `--split`: chosen by the pilot, or fixed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Split {
    #[default]
    Auto,
    At(u32),
}

impl Split {
    /// The split of a run without a pilot (meters, the bidirectional integrators): the given
    /// one, or none.
    pub fn or_default(self) -> u32 {
        match self {
            Split::Auto => 1,
            Split::At(n) => n,
        }
    }
}

impl std::fmt::Display for Split {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Split::Auto => f.write_str("auto"),
            Split::At(n) => write!(f, "{n}"),
        }
    }
}

impl std::str::FromStr for Split {
    type Err = String;

    /// `auto`, or a power of two from 1 to [`MAX_SPLIT`].
    fn from_str(s: &str) -> Result<Split, String> {
        if s == "auto" {
            return Ok(Split::Auto);
        }
        match s.parse::<u32>() {
            Ok(n) if n.is_power_of_two() && n <= MAX_SPLIT => Ok(Split::At(n)),
            _ => Err(format!(
                "'{s}': auto or a power of two from 1 to {MAX_SPLIT}"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_auto_and_powers_of_two() {
        for (text, split) in [
            ("auto", Split::Auto),
            ("1", Split::At(1)),
            ("8", Split::At(8)),
        ] {
            assert_eq!(text.parse::<Split>(), Ok(split));
            assert_eq!(split.to_string(), text);
        }
        for bad in ["0", "3", "32", "-2", "x", "", "Auto", "2.0"] {
            assert!(bad.parse::<Split>().is_err(), "{bad}");
        }
        assert_eq!(Split::Auto.or_default(), 1);
        assert_eq!(Split::At(4).or_default(), 4);
    }
}
