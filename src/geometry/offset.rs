//! Robust spawning of rays from surface points (PBR 4ed §6.8).
//!
//! A computed surface point `p` carries a per-axis absolute error bound `p_error`
//! (for triangles: [`crate::geometry::triangle::hit_point_error`]); the true surface passes through
//! the box `p ± p_error`. Rays leaving the surface start from `p` pushed along the geometric normal
//! just past that box (to the side the ray leaves towards), so they cannot re-intersect the surface
//! they start on — no fixed "ray epsilon" (PBR 4ed §6.8.6, "Robust Spawned Ray Origins").
//!
//! Conventions: `n` is the geometric normal (any length; normalised here), `w` the direction the
//! new ray leaves in (any length). Shadow rays between two points use an unnormalised direction
//! `d = to − from` and the parametric range `(0, 1 − SHADOW_EPSILON)`.

use glam::Vec3;

use super::ray::Ray;

/// Half the machine epsilon: the unit roundoff of f32 under round-to-nearest (PBR 4ed §6.8.1).
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// Parametric fraction of a shadow segment left untested at the far end, so that the surface the
/// segment ends on is never reported as an occluder (pbrt-v4 `ShadowEpsilon`, PBR 4ed §6.8.6).
pub const SHADOW_EPSILON: f32 = 1e-4;

/// γ(n) = nε / (1 − nε), ε = f32::EPSILON / 2: the bound on the relative error accumulated by
/// n successive floating-point operations, |∏(1 ± ε) − 1| ≤ γ(n) (PBR 4ed §6.8.1;
/// Higham 2002, *Accuracy and Stability of Numerical Algorithms*, Lemma 3.1).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let ne = n as f32 * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

/// Smallest f32 strictly greater than `v` (+∞ stays +∞, −0 and +0 both step to the smallest
/// positive subnormal, NaN stays NaN) — pbrt-v4 `NextFloatUp` (PBR 4ed §6.8.1).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    v.next_up()
}

/// Largest f32 strictly less than `v` (mirror image of [`next_float_up`]).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    v.next_down()
}

/// Offsets `p` (absolute error `p_error` per axis) along the geometric normal `n` to the side of
/// `w`, by `d = |n|·p_error` — the distance from `p` to the plane (orthogonal to `n`) through the
/// farthest corner of the error box — and then rounds each moved coordinate one more ulp away
/// from `p` so that the rounding of `p + offset` cannot bring it back into the box
/// (PBR 4ed §6.8.6, pbrt-v4 `OffsetRayOrigin`).
///
/// `n` need not be unit length; a zero or non-finite `n` gives no offset. If `w` is tangent to
/// the surface (`w·n = 0`) the point moves to the `+n` side. [`SpawnPoint`] is the same
/// computation with the per-point part done once for every ray leaving the point.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    SpawnPoint::new(p, p_error, n).origin(w)
}

/// A surface point that rays leave from: [`offset_ray_origin`]'s unit normal, offset vector and
/// the origin on the `+n` side computed once, so that the rays a vertex spawns (next event
/// estimation's shadow ray and the BSDF-sampled ray, PBR 4ed §6.8.6) share them. The origins
/// are `offset_ray_origin`'s, bit for bit: the same operations in the same order.
#[derive(Clone, Copy, Debug)]
pub struct SpawnPoint {
    p: Vec3,
    /// `n` normalised (zero when it cannot be).
    n: Vec3,
    /// `n · (|n|·p_error)`: the move to the `+n` side before rounding.
    offset: Vec3,
    /// The origin of rays leaving to the `+n` side (w·n ≥ 0).
    above: Vec3,
}

impl SpawnPoint {
    /// The point `p` with absolute error `p_error` on a surface of geometric normal `n` (any
    /// length).
    #[inline(always)]
    pub fn new(p: Vec3, p_error: Vec3, n: Vec3) -> SpawnPoint {
        let n = n.normalize_or_zero();
        let d = n.abs().dot(p_error);
        let offset = n * d;
        SpawnPoint {
            p,
            n,
            offset,
            above: rounded(p + offset, offset),
        }
    }

    /// The origin of a ray leaving in direction `w` (any length): `offset_ray_origin(p,
    /// p_error, n, w)`.
    /// Inlined: the common case is the precomputed `above`; the rounding to the `−n` side
    /// (transmission, shadow rays to lights behind the surface) is a call of its own.
    #[inline(always)]
    pub fn origin(&self, w: Vec3) -> Vec3 {
        if w.dot(self.n) < 0.0 {
            self.below()
        } else {
            self.above
        }
    }

    /// The origin of rays leaving to the `−n` side (w·n < 0).
    #[inline(never)]
    fn below(&self) -> Vec3 {
        let offset = -self.offset;
        rounded(self.p + offset, offset)
    }

    /// A ray leaving in direction `w` ([`spawn_ray`]).
    #[inline]
    pub fn ray(&self, w: Vec3) -> Ray {
        Ray::new(self.origin(w), w)
    }

    /// A shadow ray to a point `p_to` of error 0 (a light sample's point):
    /// [`spawn_ray_to`] with `err_to` = 0, or [`spawn_ray_to_point`].
    #[inline]
    pub fn ray_to_exact(&self, p_to: Vec3) -> (Ray, f32) {
        let from = self.origin(p_to - self.p);
        (Ray::new(from, p_to - from), 1.0 - SHADOW_EPSILON)
    }
}

/// `po` with each coordinate moved one ulp further in the direction of `offset`'s.
#[inline(always)]
fn rounded(po: Vec3, offset: Vec3) -> Vec3 {
    Vec3::new(
        round_away(po.x, offset.x),
        round_away(po.y, offset.y),
        round_away(po.z, offset.z),
    )
}

/// Moves `v` one ulp further in the direction of `offset` (unchanged when `offset` is zero or
/// NaN): [`next_float_up`] for a positive offset, [`next_float_down`] for a negative one. For a
/// finite non-zero `v` that is one step of its bit pattern: up in magnitude when `v` and the
/// offset have the same sign, down otherwise (±0, the infinities and NaN take the std
/// functions; tested against them).
#[inline]
#[allow(clippy::double_comparisons)]
fn round_away(v: f32, offset: f32) -> f32 {
    // Not `offset != 0.0` (clippy's double_comparisons): a NaN offset leaves `v` as it is.
    if !(offset > 0.0 || offset < 0.0) {
        return v;
    }
    let bits = v.to_bits();
    let magnitude = bits & 0x7fff_ffff;
    if magnitude.wrapping_sub(1) < 0x7f80_0000 - 1 {
        let same_sign = (bits ^ offset.to_bits()) & 0x8000_0000 == 0;
        return f32::from_bits(if same_sign { bits + 1 } else { bits - 1 });
    }
    if offset > 0.0 {
        next_float_up(v)
    } else {
        next_float_down(v)
    }
}

/// A ray from the surface point `p` (error `p_error`, geometric normal `n`) in direction `w`
/// (pbrt-v4 `SpawnRay`, PBR 4ed §6.8.6). The direction is kept as given.
#[inline]
pub fn spawn_ray(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Ray {
    Ray::new(offset_ray_origin(p, p_error, n, w), w)
}

/// A shadow ray between two surface points: both ends are offset off their surfaces towards each
/// other, the direction is the unnormalised `d = to' − from'` and the returned `t_max` is
/// `1 − SHADOW_EPSILON`, so neither endpoint's surface can occlude the segment
/// (pbrt-v4 `SpawnRayTo(Point3fi, Normal3f, Float, Point3fi, Normal3f)`, PBR 4ed §6.8.6).
#[inline]
pub fn spawn_ray_to(
    p_from: Vec3,
    err_from: Vec3,
    n_from: Vec3,
    p_to: Vec3,
    err_to: Vec3,
    n_to: Vec3,
) -> (Ray, f32) {
    let from = offset_ray_origin(p_from, err_from, n_from, p_to - p_from);
    let to = if err_to == Vec3::ZERO {
        // An exact end (a light sample's point) does not move: `offset_ray_origin` would add
        // an offset of ±0 and round no coordinate (the same point, up to the sign of a zero
        // coordinate; tested), so its normalisation and tests are skipped per shadow ray.
        p_to
    } else {
        offset_ray_origin(p_to, err_to, n_to, from - p_to)
    };
    (Ray::new(from, to - from), 1.0 - SHADOW_EPSILON)
}

/// A shadow ray from a surface point to a point not on a surface (a point light, or a far point
/// standing in for a light at infinity): [`spawn_ray_to`] with zero error and no normal at `p_to`.
#[inline]
pub fn spawn_ray_to_point(p_from: Vec3, err_from: Vec3, n_from: Vec3, p_to: Vec3) -> (Ray, f32) {
    let from = offset_ray_origin(p_from, err_from, n_from, p_to - p_from);
    (Ray::new(from, p_to - from), 1.0 - SHADOW_EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::{hit_point_error, intersect, is_degenerate};
    use crate::testing::rng::Rng;

    #[test]
    fn gamma_matches_its_definition() {
        let eps = f32::EPSILON as f64 / 2.0;
        for n in [1, 2, 3, 5, 7, 12] {
            let exact = n as f64 * eps / (1.0 - n as f64 * eps);
            assert!(
                (gamma(n) as f64 - exact).abs() <= exact * 1e-6,
                "gamma({n})"
            );
        }
        assert_eq!(gamma(0), 0.0);
        assert!(gamma(3) > 3.0 * MACHINE_EPSILON && gamma(3) < gamma(4));
    }

    #[test]
    fn next_float_steps_one_ulp() {
        assert_eq!(next_float_up(1.0), 1.0 + f32::EPSILON);
        assert_eq!(next_float_down(1.0), 1.0 - f32::EPSILON / 2.0);
        assert_eq!(next_float_up(-0.0), f32::from_bits(1));
        assert_eq!(next_float_up(0.0), f32::from_bits(1));
        assert_eq!(next_float_down(0.0), -f32::from_bits(1));
        assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
        assert_eq!(next_float_down(f32::NEG_INFINITY), f32::NEG_INFINITY);
        assert_eq!(next_float_up(f32::MAX), f32::INFINITY);
        assert_eq!(next_float_up(-1.0), -1.0 + f32::EPSILON / 2.0);
        assert!(next_float_up(f32::NAN).is_nan());
    }

    /// A random non-degenerate triangle of size `scale`, translated up to 10·scale from the origin.
    fn random_triangle(rng: &mut Rng, scale: f32) -> [Vec3; 3] {
        loop {
            let c = rng.vec3(-10.0, 10.0) * scale;
            let t = [0, 1, 2].map(|_| c + rng.vec3(-1.0, 1.0) * scale);
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            // Reasonably shaped (not a sliver), so the hit points are well inside.
            if !is_degenerate(t[0], t[1], t[2])
                && n.length()
                    > 0.05
                        * (t[1] - t[0])
                            .length_squared()
                            .max((t[2] - t[0]).length_squared())
            {
                return t;
            }
        }
    }

    /// A surface point on `tri` found by tracing a ray at it: (p, p_error, geometric normal).
    fn surface_point(rng: &mut Rng, tri: &[Vec3; 3], scale: f32) -> Option<(Vec3, Vec3, Vec3)> {
        let (u, v) = (rng.range(0.0, 1.0), rng.range(0.0, 1.0));
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let target = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
        let o = target + rng.unit_vector() * scale * rng.range(0.1, 30.0);
        let hit = intersect(
            &Ray::new(o, target - o),
            tri[0],
            tri[1],
            tri[2],
            f32::INFINITY,
        )?;
        let p = hit.point(tri[0], tri[1], tri[2]);
        let err = hit_point_error(&hit, tri[0], tri[1], tri[2]);
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
        Some((p, err, n))
    }

    /// A random direction on the side `side` of `n`, including nearly tangent ones.
    fn direction_on_side(rng: &mut Rng, n: Vec3, side: f32) -> Vec3 {
        let w = rng.unit_vector();
        let w = if w.dot(n) * side < 0.0 {
            w - 2.0 * w.dot(n) * n
        } else {
            w
        };
        if rng.below(10) == 0 {
            // Within ~0.006° of the tangent plane.
            let tangent = (w - w.dot(n) * n).normalize_or_zero();
            return (tangent + n * side * 1e-4).normalize();
        }
        w
    }

    #[test]
    fn spawned_rays_never_rehit_their_triangle() {
        let mut rng = Rng::new(21);
        for scale in [1e-4f32, 1e-2, 1.0, 1e2, 1e5] {
            let mut spawned = 0;
            for _ in 0..6_000 {
                let tri = random_triangle(&mut rng, scale);
                let Some((p, err, n)) = surface_point(&mut rng, &tri, scale) else {
                    continue;
                };
                for side in [1.0, -1.0] {
                    let w = direction_on_side(&mut rng, n, side);
                    let ray = spawn_ray(p, err, n, w);
                    spawned += 1;
                    let rehit = intersect(&ray, tri[0], tri[1], tri[2], f32::INFINITY);
                    assert!(rehit.is_none(), "scale {scale}: {ray:?} re-hit {rehit:?}");
                    check_offset(p, err, n, w, ray.o, &tri);
                }
            }
            assert!(spawned > 11_000, "scale {scale}: {spawned}");
        }
    }

    /// The offset moves along ±n by d = |n|·err (plus a final ulp per axis), to the side of w,
    /// and leaves the point within that distance (plus rounding) of the triangle's plane.
    fn check_offset(p: Vec3, err: Vec3, n: Vec3, w: Vec3, po: Vec3, tri: &[Vec3; 3]) {
        let d = n.abs().dot(err);
        let moved = po - p;
        for k in 0..3 {
            let ulp = |x: f32| next_float_up(x.abs()) - x.abs();
            let bound = n[k].abs() * d * (1.0 + 4.0 * MACHINE_EPSILON)
                + 2.0 * ulp(p[k].abs().max(po[k].abs()));
            assert!(
                moved[k].abs() <= bound,
                "axis {k}: moved {} > {bound}",
                moved[k]
            );
        }
        assert!(moved.dot(n) * w.dot(n) >= 0.0, "offset to the wrong side");
        let to_plane = n.dot(po - tri[0]).abs() as f64;
        let slack = 4.0 * (po - tri[0]).abs().max_element() as f64 * f32::EPSILON as f64;
        assert!(
            to_plane <= 2.0 * d as f64 + (err.max_element() as f64) + slack,
            "{to_plane} vs {d}"
        );
    }

    #[test]
    fn shadow_rays_between_facing_triangles_are_unoccluded_by_their_ends() {
        let mut rng = Rng::new(22);
        for scale in [1e-4f32, 1.0, 1e5] {
            let mut tested = 0;
            for _ in 0..5_000 {
                let a = random_triangle(&mut rng, scale);
                let na = (a[1] - a[0]).cross(a[2] - a[0]).normalize();
                // b: a's mirror image a random distance along ±na, so the two face each other.
                let gap = na * scale * rng.range(0.01, 3.0);
                let b = a.map(|p| p + gap + rng.vec3(-0.2, 0.2) * scale);
                if is_degenerate(b[0], b[1], b[2]) {
                    continue;
                }
                let (Some((pa, ea, na)), Some((pb, eb, nb))) = (
                    surface_point(&mut rng, &a, scale),
                    surface_point(&mut rng, &b, scale),
                ) else {
                    continue;
                };
                // Normals in either orientation: the offsets pick the side from the direction.
                let (na, nb) = (na * sign(&mut rng), nb * sign(&mut rng));
                let (ray, t_max) = spawn_ray_to(pa, ea, na, pb, eb, nb);
                let (to_point, t_point) = spawn_ray_to_point(pa, ea, na, pb + nb * scale);
                for tri in [&a, &b] {
                    assert!(
                        intersect(&ray, tri[0], tri[1], tri[2], t_max).is_none(),
                        "scale {scale}: {ray:?}"
                    );
                }
                assert!(intersect(&to_point, a[0], a[1], a[2], t_point).is_none());
                assert_eq!(t_max, 1.0 - SHADOW_EPSILON);
                // The reverse direction too.
                let (back, t_back) = spawn_ray_to(pb, eb, nb, pa, ea, na);
                for tri in [&a, &b] {
                    assert!(intersect(&back, tri[0], tri[1], tri[2], t_back).is_none());
                }
                tested += 1;
            }
            assert!(tested > 4_000, "scale {scale}: {tested}");
        }
    }

    fn sign(rng: &mut Rng) -> f32 {
        if rng.below(2) == 0 {
            1.0
        } else {
            -1.0
        }
    }

    /// `offset_ray_origin` as first written (PBR 4ed §6.8.6): the std ulp steps per axis.
    fn reference_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
        let n = n.normalize_or_zero();
        let d = n.abs().dot(p_error);
        let mut offset = n * d;
        if w.dot(n) < 0.0 {
            offset = -offset;
        }
        let po = p + offset;
        let step = |v: f32, o: f32| {
            if o > 0.0 {
                next_float_up(v)
            } else if o < 0.0 {
                next_float_down(v)
            } else {
                v
            }
        };
        Vec3::new(
            step(po.x, offset.x),
            step(po.y, offset.y),
            step(po.z, offset.z),
        )
    }

    #[test]
    fn round_away_is_the_std_ulp_step() {
        let mut rng = Rng::new(24);
        let special = [
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0,
            -1.0,
        ];
        let offsets = [
            1e-7,
            -1e-7,
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut values: Vec<f32> = special.to_vec();
        values.extend((0..100_000).map(|_| f32::from_bits(rng.next_u64() as u32)));
        for &v in &values {
            for &o in &offsets {
                let want = if o > 0.0 {
                    next_float_up(v)
                } else if o < 0.0 {
                    next_float_down(v)
                } else {
                    v
                };
                let got = round_away(v, o);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "round_away({v:e}, {o:e}) = {got:e}, not {want:e}"
                );
            }
        }
    }

    #[test]
    fn spawn_points_give_the_reference_origins_bit_for_bit() {
        let mut rng = Rng::new(25);
        for scale in [1e-4f32, 1.0, 1e5] {
            for _ in 0..50_000 {
                let p = rng.vec3(-10.0, 10.0) * scale;
                let err = rng.vec3(0.0, 1e-6) * scale;
                let n = match rng.below(8) {
                    0 => Vec3::Z,
                    1 => -Vec3::X,
                    2 => rng.unit_vector() * 3.0,
                    _ => rng.unit_vector(),
                };
                let sp = SpawnPoint::new(p, err, n);
                for w in [rng.unit_vector(), n, -n, Vec3::ZERO, rng.vec3(-1.0, 1.0)] {
                    let want = reference_origin(p, err, n, w);
                    assert_eq!(
                        sp.origin(w).to_array().map(f32::to_bits),
                        want.to_array().map(f32::to_bits)
                    );
                    assert_eq!(
                        offset_ray_origin(p, err, n, w).to_array().map(f32::to_bits),
                        want.to_array().map(f32::to_bits)
                    );
                    assert_eq!(sp.ray(w).o, spawn_ray(p, err, n, w).o);
                }
                let to = rng.vec3(-10.0, 10.0) * scale;
                let (a, ta) = sp.ray_to_exact(to);
                let (b, tb) = spawn_ray_to(p, err, n, to, Vec3::ZERO, rng.unit_vector());
                let (c, tc) = spawn_ray_to_point(p, err, n, to);
                assert_eq!((a.o, a.d, ta), (b.o, b.d, tb));
                assert_eq!((a.o, a.d, ta), (c.o, c.d, tc));
            }
        }
    }

    #[test]
    fn zero_normal_or_error_gives_no_offset() {
        let p = Vec3::new(1.0, -2.0, 3.0);
        assert_eq!(
            offset_ray_origin(p, Vec3::splat(1e-3), Vec3::ZERO, Vec3::X),
            p
        );
        assert_eq!(offset_ray_origin(p, Vec3::ZERO, Vec3::Y, Vec3::X), p);
        let (ray, t_max) = spawn_ray_to_point(p, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        assert_eq!((ray.o, ray.d, t_max), (p, -p, 1.0 - SHADOW_EPSILON));
        // Non-unit normals give the same offset as unit ones.
        let e = Vec3::new(1e-6, 2e-6, 3e-6);
        let w = Vec3::new(0.3, 0.4, -0.2);
        let n = Vec3::new(0.2, -0.7, 0.4);
        assert_eq!(
            offset_ray_origin(p, e, n * 37.0, w),
            offset_ray_origin(p, e, n.normalize(), w)
        );
    }

    #[test]
    fn an_exact_end_is_the_offset_of_zero_error() {
        // `spawn_ray_to` leaves an end with zero error where it is: the same point as
        // `offset_ray_origin` gives it (== treats a zero's sign as equal), and so the same ray.
        let mut rng = Rng::new(23);
        for scale in [1e-3f32, 1.0, 1e4] {
            for _ in 0..20_000 {
                let (a, b) = (rng.vec3(-10.0, 10.0) * scale, rng.vec3(-10.0, 10.0) * scale);
                let (ea, na, nb) = (
                    Vec3::splat(1e-6 * scale),
                    rng.unit_vector(),
                    rng.unit_vector(),
                );
                let (ray, t) = spawn_ray_to(a, ea, na, b, Vec3::ZERO, nb);
                let from = offset_ray_origin(a, ea, na, b - a);
                assert_eq!(offset_ray_origin(b, Vec3::ZERO, nb, from - b), b);
                assert_eq!((ray.o, ray.d, t), (from, b - from, 1.0 - SHADOW_EPSILON));
            }
        }
        for b in [
            Vec3::ZERO,
            Vec3::new(-0.0, 0.0, -0.0),
            Vec3::new(0.0, -2.5, 0.0),
        ] {
            for nb in [Vec3::X, -Vec3::Y, Vec3::ZERO, Vec3::new(-0.0, 1.0, -0.0)] {
                assert_eq!(offset_ray_origin(b, Vec3::ZERO, nb, Vec3::ONE), b);
                assert_eq!(offset_ray_origin(b, Vec3::ZERO, nb, -Vec3::ONE), b);
            }
        }
    }
}
