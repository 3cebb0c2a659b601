//! Where VCM's merging technique exists: at every non-specular vertex ([`MergeRule::All`],
//! Georgiev et al. 2012), or only after a near-specular vertex ([`MergeRule::Caustic`]).
//!
//! **The rule.** Merging at a path vertex x_i (1 ≤ i ≤ n − 2, or at an irradiance meter's
//! point x_{n−1}) is available only when its light-order predecessor x_{i−1} — the vertex the
//! light subpath came from — is near-specular ([`near_specular`]: a delta BSDF, or a material
//! with a delta or near-specular lobe, `scene::analysis::lobes`, the path classes' S). The
//! light source x_0 is never near-specular, so x_1 never merges. This is Jensen's caustic
//! photon map (Jensen 1996, "Global illumination using photon maps", §3: photons stored after
//! a specular bounce, L S+ D) inside VCM: on L D D paths the connections sample the diffuse
//! interreflection well and the power heuristic gives merges little weight, yet every merge
//! candidate costs a BSDF evaluation.
//!
//! **Why MIS stays exact.** The availability a(x_i) ∈ {0, 1} is a function of the path's
//! vertices (their materials) alone, the same whichever technique sampled the path. So the
//! set of techniques of a path is fixed, and the balance or power heuristic over that set is
//! a partition of unity for the path (Veach 1997 §9.2: any set of techniques whose weights sum
//! to 1 per path). The brute-force check in `tests/bidir.rs` zeroes merge i where the rule
//! says so and compares every weight.
//!
//! **The recurrences with a(x_i)** (`mis.rs`; Georgiev 2012 tech. rep. (34)–(41), with
//! p_s the density of connection s, F_i / R_i the light / camera side's density of x_i per
//! area and p_{M,i} = η F_0 … F_i R_i … R_{n−1} that of merging at x_i). Writing out the
//! tech. report's sums with each merge term times its a:
//!
//! - Connection s (light end y = x_{s−1}, camera end z = x_s), (40)–(41):
//!   p_{M,s−1} / p_s = η R_{s−1}, so the η of w_light is merging at y: a(x_{s−1}), decided
//!   by x_{s−2}, y's predecessor on its own subpath, known when y is reached and kept with it
//!   ([`super::PathVertex::merges`]); p_{M,s} / p_s = η F_s, so the η of w_camera is merging
//!   at z: a(x_s), decided by x_{s−1} = y ([`super::PathVertex::near_specular`]).
//! - t = 1 (46): the η of w_light is merging at y, a(y) as above; the merge at an irradiance
//!   meter's point (x_{n−1}) relative to it is decided by the light vertex y = x_{n−2}.
//! - s = 1 (44)–(45): the η of w_camera is merging at x_1, whose predecessor is the light:
//!   0 under the caustic rule.
//! - s = 0 (42)–(43): no η term of its own; dVC carries the rest.
//! - The light recurrence (35)–(36), stepping from y_{i−1} to y_i: dVC_i gains
//!   m(R_{i−1}/F_i) m(η) a(x_{i−1}) and dVM_i gains m(R_{i−1}/F_i) · 1 · a(x_{i−1}) — both
//!   are merging at y_{i−1}, the vertex being left, whose availability (decided by y_{i−2})
//!   the walk already knows: [`super::mis::SubpathMis::scatter`] takes it as `merge`.
//! - The camera recurrence, stepping from x_{i+1} to x_i (towards the light): the same terms
//!   stand for merging at x_{i+1}, the vertex being left, but its predecessor in light order
//!   is x_i, the vertex not yet found. So the camera walk scatters with `merge` = 0, keeps the
//!   term's factor m(|cos| / p_fwd) (divided by x_i's m(|cos θ|) on arrival, as dVC and dVM
//!   are) and adds it once x_i's material is known ([`super::mis::SubpathMis::add_merge`],
//!   [`super::Walk::vertex`]); at an emitter (x_0, never near-specular) or an escape it is
//!   dropped. An irradiance meter's start (the merge at its own point, dVC = m(cos/p) m(η),
//!   dVM = m(cos/p)) is such a term too, decided at z_1.
//! - A merge at x_i itself (38)–(39): w_light and w_camera read dVCM and dVM only, whose merge
//!   terms carry their a already; the merge happens only where a(x_i) = 1, so the store keeps
//!   (and its grid holds) only light vertices whose predecessor is near-specular.
//!
//! With [`MergeRule::All`] every a is 1 and the arithmetic is that of before (SmallVCM's): the
//! same images bit for bit (`examples/exr_diff`).

use crate::bxdf::Bsdf;
use crate::scene::{Scene, SurfaceHit};

/// Which vertices VCM merges at (`--vcm-merge`). No `Default`: VCM's default is
/// `vcm::DEFAULT_MERGE_RULE`, and a second one here could disagree with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeRule {
    /// Every non-specular vertex (Georgiev et al. 2012; SmallVCM).
    All,
    /// Only vertices whose light-order predecessor is near-specular: caustics (L S+ D …).
    Caustic,
}

impl MergeRule {
    pub const ALL: [MergeRule; 2] = [MergeRule::All, MergeRule::Caustic];

    pub fn name(&self) -> &'static str {
        match self {
            MergeRule::All => "all",
            MergeRule::Caustic => "caustic",
        }
    }
}

/// The vertex at `si` with BSDF `bsdf` is near-specular: its BSDF is a delta, or its material
/// has a delta or near-specular lobe (`scene::analysis::lobes`, the one definition the scene
/// analysis' path classes use: GGX α < `NEAR_SPECULAR_ALPHA`; per material in
/// `Scene::specular_like`).
#[inline]
pub fn near_specular(scene: &Scene, si: &SurfaceHit, bsdf: &Bsdf) -> bool {
    bsdf.is_specular() || scene.specular_like[si.material as usize]
}
