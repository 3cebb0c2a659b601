//! Watertight ray–triangle intersection and the error bound of the hit point.
//!
//! The test is Woop, Benthin and Wald 2013, "Watertight Ray/Triangle Intersection" (JCGT 2(1)),
//! as written in PBR 4ed §6.5.3: the vertices are translated to the ray origin, the axes permuted
//! so that the ray's largest direction component is z, and sheared so that the ray becomes the +z
//! axis; the hit is then a 2D point-in-triangle test at the origin using the three edge functions.
//! A shared vertex or edge of two triangles transforms to bit-identical values in both, and the
//! edge function of a shared edge is the exact negation of its twin, so a ray through the interior
//! of a closed mesh cannot slip between triangles (PBR 4ed §6.8.4).
//!
//! The three vertices are processed together, one per SIMD lane ([`PackedTriangle`] stores the
//! triangle by coordinate rows, so the per-ray axis permutation is a choice of rows). Each lane
//! performs exactly the scalar operations, so the watertightness argument is unchanged.
//!
//! Precision:
//! - **Edge functions** are evaluated in f32 first. Rounding is monotonic, so
//!   fl(fl(ab) − fl(cd)) has the sign of the exact ab − cd or is zero; a zero (or a NaN from
//!   overflow) sends the test to f64, where the products of two f32 are exact and the
//!   difference is rounded once, so the sign is exact (pbrt-v4 `IntersectTriangle` falls back the
//!   same way). Either way the hit/miss decision is that of the exactly evaluated edge functions
//!   of the transformed vertices.
//! - **t** is Woop's t = Σ eᵢ zᵢ / Σ eᵢ, a convex combination of the vertices' sheared depths
//!   zᵢ (all eᵢ share one sign). The sign of each computed zᵢ = fl(fl(pᵢ − o)_z · s_z) is exact,
//!   so when all three are positive the whole triangle lies in front of the origin and t > 0 is
//!   certain, for the exact and the computed t alike. This replaces pbrt's δt bound
//!   (PBR 4ed §6.8.7), which rejects valid hits on slivers and at grazing angles. A triangle with
//!   all zᵢ ≤ 0 lies behind the origin. One that straddles the origin's plane (a spawned ray next
//!   to its own surface) takes t from the plane equation in f64 with a forward error bound that
//!   certifies t > 0 (`plane_t`).
//!
//! Barycentric convention: `p = b0 p0 + b1 p1 + b2 p2`, `b0 + b1 + b2 = 1`, `bi ≥ 0`.

use glam::{Vec3, Vec3Swizzles, Vec4, Vec4Swizzles};

use super::offset::gamma;
use super::ray::Ray;

/// A ray–triangle hit: ray parameter `t` and barycentrics (`p = b0 p0 + b1 p1 + b2 p2`).
#[derive(Clone, Copy, Debug)]
pub struct TriangleHit {
    pub t: f32,
    pub b0: f32,
    pub b1: f32,
    pub b2: f32,
}

impl TriangleHit {
    /// The hit point interpolated from the vertices, evaluated exactly as the error bound of
    /// [`hit_point_error`] assumes.
    #[inline]
    pub fn point(&self, p0: Vec3, p1: Vec3, p2: Vec3) -> Vec3 {
        self.b0 * p0 + self.b1 * p1 + self.b2 * p2
    }
}

/// True when the triangle can never be hit: zero area (`(p1 − p0) × (p2 − p0) = 0`, as pbrt-v4
/// tests it) or a non-finite vertex.
#[inline]
pub fn is_degenerate(p0: Vec3, p1: Vec3, p2: Vec3) -> bool {
    let finite = p0.is_finite() && p1.is_finite() && p2.is_finite();
    !finite || (p1 - p0).cross(p2 - p0) == Vec3::ZERO
}

/// A triangle by coordinate, borrowed from a row store ([`PackedTriangle::push_rows`]): floats
/// 0–2 are x of p0, p1, p2, floats 3–5 their y, 6–8 their z, and float 9 is the next stored one.
/// A coordinate's row is loaded as four lanes from its first float ([`Row`]); lane 3 is ignored
/// by every test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PackedTriangle<'a> {
    floats: &'a [f32; ROW_FLOATS + ROW_PADDING],
}

/// Floats per triangle in a row store ([`PackedTriangle::push_rows`]).
pub(crate) const ROW_FLOATS: usize = 9;
/// Floats read after a triangle's rows (its last row's fourth lane), so the store must hold
/// them too.
pub(crate) const ROW_PADDING: usize = 1;

/// A coordinate axis as the first float of its row in a [`PackedTriangle`]. Its values are
/// 0, 3 and 6, so a row's four floats are in bounds without a check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
enum Row {
    X = 0,
    Y = 3,
    Z = 6,
}

/// What a row store of no triangle holds: the zero triangle, which nothing hits.
const ZERO_TRIANGLE: [f32; ROW_FLOATS + ROW_PADDING] = [0.0; ROW_FLOATS + ROW_PADDING];

impl<'a> PackedTriangle<'a> {
    /// The floats of a one-triangle row store of `p0`, `p1`, `p2` (for [`PackedTriangle::from`]).
    #[cfg(any(test, feature = "testing"))]
    #[inline]
    pub fn floats(p0: Vec3, p1: Vec3, p2: Vec3) -> [f32; ROW_FLOATS + ROW_PADDING] {
        let mut floats = [0.0; ROW_FLOATS + ROW_PADDING];
        for k in 0..3 {
            floats[3 * k..3 * k + 3].copy_from_slice(&[p0[k], p1[k], p2[k]]);
        }
        floats
    }

    /// The triangle of a one-triangle row store ([`PackedTriangle::floats`]).
    #[cfg(any(test, feature = "testing"))]
    #[inline]
    pub fn from(floats: &'a [f32; ROW_FLOATS + ROW_PADDING]) -> PackedTriangle<'a> {
        PackedTriangle { floats }
    }

    /// Appends the triangle to a row store, 36 bytes: x, y, z of p0, p1, p2, by coordinate.
    pub fn push_rows(rows: &mut Vec<f32>, [p0, p1, p2]: [Vec3; 3]) {
        for k in 0..3 {
            rows.extend([p0[k], p1[k], p2[k]]);
        }
    }

    /// The triangle whose rows ([`PackedTriangle::push_rows`]) start at float `start` of
    /// `store`, which holds at least [`ROW_PADDING`] floats after them (each row is loaded as
    /// four lanes; lane 3 is ignored). Out of range (not built so): the zero triangle, which
    /// nothing hits.
    #[inline(always)]
    pub fn at(store: &'a [f32], start: usize) -> PackedTriangle<'a> {
        let stored = store.get(start..start + ROW_FLOATS + ROW_PADDING);
        let floats = stored.and_then(|r| r.try_into().ok());
        PackedTriangle {
            floats: floats.unwrap_or(&ZERO_TRIANGLE),
        }
    }

    /// The coordinate `row` of p0, p1, p2 in lanes 0–2.
    #[inline(always)]
    fn row(&self, row: Row) -> Vec4 {
        let first = row as usize;
        Vec4::from_slice(&self.floats[first..first + 4])
    }

    /// `[p0, p1, p2]`.
    #[inline]
    pub fn vertices(&self) -> [Vec3; 3] {
        let f = self.floats;
        [
            Vec3::new(f[0], f[3], f[6]),
            Vec3::new(f[1], f[4], f[7]),
            Vec3::new(f[2], f[5], f[8]),
        ]
    }
}

/// Per-ray part of the watertight test (axis permutation and shear, PBR 4ed §6.5.3), computed once
/// per ray and reused for every triangle the ray is tested against.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    o: Vec3,
    d: Vec3,
    /// Rows of a [`PackedTriangle`] that become x, y, z: the ray's largest |d| component is z.
    rows: [Row; 3],
    /// The origin's permuted coordinates, each splatted.
    o_perm: [Vec4; 3],
    /// Shear taking the permuted direction to (0, 0, 1): x' = x + sx z, y' = y + sy z,
    /// z' = sz z; `[sx, sy, sz]`, each splatted.
    shear: [Vec4; 3],
}

impl WatertightRay {
    /// None for a zero or non-finite direction or a non-finite origin (such a ray hits nothing).
    #[inline(always)]
    pub fn new(ray: &Ray) -> Option<WatertightRay> {
        let (o, d) = (ray.o, ray.d);
        // The six coordinates in two registers, one finiteness test.
        let finite = Vec4::new(o.x, o.y, o.z, d.x).is_finite_mask()
            & Vec4::new(d.y, d.z, d.y, d.z).is_finite_mask();
        if !finite.all() {
            return None;
        }
        // z is the largest |d| component (the first of equal ones), x and y its cyclic
        // successors; the permutation is a swizzle of the registers, not an index into arrays
        // stored for it.
        let (rows, o_p, d_p) = match d.abs().max_position() {
            0 => ([Row::Y, Row::Z, Row::X], o.yzx(), d.yzx()),
            1 => ([Row::Z, Row::X, Row::Y], o.zxy(), d.zxy()),
            _ => ([Row::X, Row::Y, Row::Z], o, d),
        };
        if d_p.z == 0.0 {
            return None;
        }
        // −dx/dz, −dy/dz, 1/dz: each lane one correctly rounded division, as in scalar.
        let s = Vec4::new(-d_p.x, -d_p.y, 1.0, 1.0) / d_p.z;
        Some(WatertightRay {
            o,
            d,
            rows,
            o_perm: [o_p.x, o_p.y, o_p.z].map(Vec4::splat),
            shear: [s.x, s.y, s.z].map(Vec4::splat),
        })
    }

    /// Translates, permutes and shears the three vertices; z is scaled by `sz` (a vertex's t is
    /// its z).
    #[inline(always)]
    fn transform(&self, tri: PackedTriangle) -> Sheared {
        let [kx, ky, kz] = self.rows;
        let z = tri.row(kz) - self.o_perm[2];
        Sheared {
            x: (tri.row(kx) - self.o_perm[0]) + self.shear[0] * z,
            y: (tri.row(ky) - self.o_perm[1]) + self.shear[1] * z,
            z: z * self.shear[2],
        }
    }
}

/// The transformed vertices a, b, c (= p0, p1, p2) in lanes 0–2 of each coordinate.
#[derive(Clone, Copy)]
struct Sheared {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

impl Sheared {
    /// `(edge(b, c), edge(c, a), edge(a, b), 0)` with `edge(u, v) = u.x v.y − u.y v.x` in f32,
    /// lane by lane without fused multiply-add, so `edge(v, u)` is exactly `−edge(u, v)`.
    #[inline(always)]
    fn edge_functions(&self) -> Vec4 {
        let (x1, x2) = (self.x.yzxw(), self.x.zxyw());
        let (y1, y2) = (self.y.yzxw(), self.y.zxyw());
        x1 * y2 - y1 * x2
    }

    fn vertices(&self) -> [Vec3; 3] {
        let (x, y, z) = (self.x, self.y, self.z);
        [
            Vec3::new(x.x, y.x, z.x),
            Vec3::new(x.y, y.y, z.y),
            Vec3::new(x.z, y.z, z.z),
        ]
    }
}

/// Lanes 0–2 of a comparison mask as 3 bits.
#[inline(always)]
fn mask3(m: glam::BVec4A) -> u32 {
    m.bitmask() & 0b111
}

/// Watertight ray–triangle test (Woop, Benthin, Wald 2013; PBR 4ed §6.5.3) that never reports a
/// hit at t ≤ 0 (see the module docs). `t_max` is exclusive. Returns None for degenerate
/// (zero-area) triangles and never a NaN. The BVH runs the same test on its packed
/// triangles; this one-triangle form is the reference of the tests.
#[cfg(any(test, feature = "testing"))]
#[inline]
pub fn intersect(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3, t_max: f32) -> Option<TriangleHit> {
    if (p1 - p0).cross(p2 - p0) == Vec3::ZERO {
        return None;
    }
    let floats = PackedTriangle::floats(p0, p1, p2);
    intersect_packed(
        &WatertightRay::new(ray)?,
        PackedTriangle::from(&floats),
        t_max,
    )
}

/// [`intersect_prepared`] for triangles already known not to be degenerate, packed (the BVH
/// filters and packs them at build time). Not for degenerate triangles: rounded by the shear,
/// their vertices need not stay collinear, and Woop's t does not look at the plane normal.
#[inline(always)]
pub(crate) fn intersect_packed(
    ray: &WatertightRay,
    tri: PackedTriangle,
    t_max: f32,
) -> Option<TriangleHit> {
    let v = ray.transform(tri);
    let e = v.edge_functions();
    let (neg, pos) = (mask3(e.cmplt(Vec4::ZERO)), mask3(e.cmpgt(Vec4::ZERO)));
    if neg != 0 && pos != 0 {
        // Nonzero f32 edge functions have exact signs: certainly outside.
        return None;
    }
    let det = e.x + e.y + e.z;
    if neg | pos != 0b111 || !det.is_finite() {
        return intersect_f64((ray.o, ray.d), tri, v, t_max);
    }
    let t = woop_t(ray, tri, &v, (e, det), t_max)?;
    // |eᵢ| ≤ |det| (same signs), so the correctly rounded quotients lie in [0, 1].
    let b = e / det;
    Some(TriangleHit {
        t,
        b0: b.x,
        b1: b.y,
        b2: b.z,
    })
}

/// Woop's t = Σ eᵢ zᵢ / det when all three vertices lie in front of the origin (t > 0 is then
/// certain, see the module docs), None when none does, else the f64 plane t; None unless
/// 0 < t < `t_max` (exclusive; a NaN `t_max` rejects).
#[inline(always)]
fn woop_t(
    ray: &WatertightRay,
    tri: PackedTriangle,
    v: &Sheared,
    (e, det): (Vec4, f32),
    t_max: f32,
) -> Option<f32> {
    if mask3(v.z.cmpgt(Vec4::ZERO)) == 0b111 {
        let ez = e * v.z;
        let t = (ez.x + ez.y + ez.z) / det;
        // The common case first, two comparisons: t_max ≤ +∞, so such a t is also finite.
        if t > 0.0 && t < t_max {
            return Some(t);
        }
        // A finite positive t at or beyond t_max is a miss; a zero (underflow) or infinite
        // (overflow) t goes to the f64 path.
        if t > 0.0 && t < f32::INFINITY {
            return None;
        }
    } else if mask3(v.z.cmple(Vec4::ZERO)) == 0b111 {
        return None;
    }
    let t = plane_t((ray.o, ray.d), tri)? as f32;
    (t > 0.0 && t < t_max).then_some(t)
}

/// The test with f64 edge functions (pbrt-v4's fallback when an f32 edge function is zero) and
/// the f64 plane t: rays through an edge or a vertex, overflow, and the reference the f32 path
/// is checked against in the tests.
#[cold]
#[inline(never)]
fn intersect_f64(
    ray: (Vec3, Vec3),
    tri: PackedTriangle,
    v: Sheared,
    t_max: f32,
) -> Option<TriangleHit> {
    let [a, b, c] = v.vertices();
    let e = [edge_f64(b, c), edge_f64(c, a), edge_f64(a, b)];
    let has_neg = e[0] < 0.0 || e[1] < 0.0 || e[2] < 0.0;
    let has_pos = e[0] > 0.0 || e[1] > 0.0 || e[2] > 0.0;
    if has_neg && has_pos {
        return None;
    }
    let det = e[0] + e[1] + e[2];
    if det == 0.0 {
        return None;
    }
    let t = plane_t(ray, tri)? as f32;
    // Written so that a NaN rejects the hit.
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let inv_det = 1.0 / det;
    Some(TriangleHit {
        t,
        b0: (e[0] * inv_det) as f32,
        b1: (e[1] * inv_det) as f32,
        b2: (e[2] * inv_det) as f32,
    })
}

/// The test with the f64 path only: the reference the f32 path is checked against.
#[cfg(test)]
pub(crate) fn intersect_reference(
    ray: &Ray,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_max: f32,
) -> Option<TriangleHit> {
    let ray = WatertightRay::new(ray)?;
    if (p1 - p0).cross(p2 - p0) == Vec3::ZERO {
        return None;
    }
    let floats = PackedTriangle::floats(p0, p1, p2);
    let tri = PackedTriangle::from(&floats);
    intersect_f64((ray.o, ray.d), tri, ray.transform(tri), t_max)
}

/// Edge function `u.x v.y − u.y v.x` of the transformed vertices. Both products of f32 are exact
/// in f64 and the difference is rounded once, so the sign is exact and swapping `u` and `v`
/// negates the value exactly (the watertightness argument of PBR 4ed §6.8.4).
#[inline]
fn edge_f64(u: Vec3, v: Vec3) -> f64 {
    u.x as f64 * v.y as f64 - u.y as f64 * v.x as f64
}

/// γ(n) in f64 arithmetic (unit roundoff 2⁻⁵³), PBR 4ed §6.8.1.
const fn gamma64(n: i32) -> f64 {
    let ne = n as f64 * (f64::EPSILON * 0.5);
    ne / (1.0 - ne)
}

/// The ray parameter of the hit once the edge test has accepted the triangle:
/// t = n·(p0 − o) / n·d with n = (p1 − p0) × (p2 − p0), all in f64, or None unless t > 0 is
/// certain. Forward error bound (standard model of PBR 4ed §6.8.1; Higham 2002, §3.1 for the
/// dot products): each normal component carries |δn_k| ≤ γ(5)·N_k with N_k the sum of the
/// magnitudes of its two products, so |δ(n·v)| ≤ 2γ(12)·Σ N_k |v_k| for v = p0 − o and v = d.
/// The hit is kept only if both numerator and denominator exceed their bounds and agree in sign.
///
/// Deviation from pbrt-v4 (which bounds the error of Woop's t from the sheared coordinates,
/// PBR 4ed §6.8.7): that bound grows with the vertices' distance from the ray axis divided by the
/// triangle's projected area, so it rejects valid hits on slivers (area 1e-12) and at grazing
/// angles; the f64 plane equation is accurate to ~1e-15 relative in both cases.
///
/// Not inlined: its callers' hot paths take it only for triangles that straddle the origin's
/// plane, and inlined, the compiler hoisted its f64 conversions of the ray into every query's
/// set-up (about 20 instructions a ray in the BVH's queries, session 31). Cold, so that the
/// leaf test's call of it is not a hot block to lay out and allocate registers around: 1.5 %
/// fewer instructions per ray on the spheres of `../shared/limit` (session 34).
#[cold]
#[inline(never)]
fn plane_t((o, d): (Vec3, Vec3), tri: PackedTriangle) -> Option<f64> {
    let f = |v: Vec3| [v.x as f64, v.y as f64, v.z as f64];
    let [p0, p1, p2] = tri.vertices();
    let (q0, q1, q2, o, d) = (f(p0), f(p1), f(p2), f(o), f(d));
    let e1 = [q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]];
    let e2 = [q2[0] - q0[0], q2[1] - q0[1], q2[2] - q0[2]];
    let v = [q0[0] - o[0], q0[1] - o[1], q0[2] - o[2]];
    let (mut num, mut den, mut num_err, mut den_err) = (0.0, 0.0, 0.0, 0.0);
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (x, y) = (e1[i] * e2[j], e1[j] * e2[i]);
        let n_k = x - y;
        let mag_k = x.abs() + y.abs();
        num += n_k * v[k];
        den += n_k * d[k];
        num_err += mag_k * v[k].abs();
        den_err += mag_k * d[k].abs();
    }
    let g = 2.0 * gamma64(12);
    let certain = num.abs() > g * num_err && den.abs() > g * den_err;
    let t = num / den;
    (certain && t > 0.0).then_some(t)
}

/// Absolute error bound of [`TriangleHit::point`]: γ(7)·(|b0 p0| + |b1 p1| + |b2 p2|) per axis
/// (PBR 4ed §6.8.5, "Bounding Intersection Point Error", triangles; pbrt-v4
/// `Triangle::InteractionFromIntersection`).
///
/// The box `p ± error` contains a point of the triangle, which is what ray offsetting needs
/// (the barycentrics always lie in the simplex; the bound covers rounding in the interpolation
/// and in the barycentrics' sum). It does not bound the distance *along* the surface to the
/// exact ray hit, which grows as the triangle seen along the ray thins out (slivers, grazing
/// rays) — harmless for offsetting, and far below shading scales.
#[inline]
pub fn hit_point_error(hit: &TriangleHit, p0: Vec3, p1: Vec3, p2: Vec3) -> Vec3 {
    let abs_sum = (hit.b0 * p0).abs() + (hit.b1 * p1).abs() + (hit.b2 * p2).abs();
    gamma(7) * abs_sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    fn ray(o: Vec3, d: Vec3) -> Ray {
        Ray::new(o, d)
    }

    fn check_hit(h: &TriangleHit) {
        assert!(h.t.is_finite() && h.t > 0.0, "{h:?}");
        for b in [h.b0, h.b1, h.b2] {
            assert!(b.is_finite() && (0.0..=1.0).contains(&b), "{h:?}");
        }
        assert!((h.b0 + h.b1 + h.b2 - 1.0).abs() < 1e-5, "{h:?}");
    }

    const P0: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    const P1: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    const P2: Vec3 = Vec3::new(0.0, 1.0, 0.0);

    #[test]
    fn simple_hit_t_and_barycentrics() {
        let r = ray(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let h = intersect(&r, P0, P1, P2, f32::INFINITY).expect("hit");
        check_hit(&h);
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        assert!((h.point(P0, P1, P2) - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-6);
        // Both sides hit (no culling).
        let r = ray(Vec3::new(0.25, 0.5, -3.0), Vec3::new(0.0, 0.0, 2.0));
        let h = intersect(&r, P0, P1, P2, f32::INFINITY).expect("hit from below");
        assert!((h.t - 1.5).abs() < 1e-6);
    }

    #[test]
    fn misses_outside_behind_and_beyond_t_max() {
        let down = Vec3::new(0.0, 0.0, -1.0);
        let outside = ray(Vec3::new(0.75, 0.5, 2.0), down);
        assert!(intersect(&outside, P0, P1, P2, f32::INFINITY).is_none());
        let behind = ray(Vec3::new(0.25, 0.25, -1.0), down);
        assert!(intersect(&behind, P0, P1, P2, f32::INFINITY).is_none());
        let r = ray(Vec3::new(0.25, 0.25, 2.0), down);
        assert!(
            intersect(&r, P0, P1, P2, 2.0).is_none(),
            "t_max is exclusive"
        );
        assert!(intersect(&r, P0, P1, P2, 2.0f32.next_up()).is_some());
        assert!(intersect(&r, P0, P1, P2, 1.5).is_none());
        let zero_dir = ray(Vec3::new(0.25, 0.25, 0.0), Vec3::ZERO);
        assert!(intersect(&zero_dir, P0, P1, P2, f32::INFINITY).is_none());
        let nan_dir = ray(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, f32::NAN, -1.0));
        assert!(intersect(&nan_dir, P0, P1, P2, f32::INFINITY).is_none());
    }

    /// A displaced height field: `n × n` cells, two triangles each, vertices shared bit-exactly.
    struct Grid {
        n: usize,
        verts: Vec<Vec3>,
    }

    impl Grid {
        /// Displacement amplitude 0.05 against cells of about 0.4.
        fn new(n: usize, rng: &mut Rng) -> Grid {
            Grid::with_amplitude(n, 0.05, rng)
        }

        fn with_amplitude(n: usize, amplitude: f32, rng: &mut Rng) -> Grid {
            let mut verts = Vec::with_capacity((n + 1) * (n + 1));
            // A tilted frame with "ugly" coordinates, so nothing is exactly representable.
            let (u, v, w) = (
                Vec3::new(0.8, 0.1, -0.3).normalize() * 0.37,
                Vec3::new(-0.2, 0.9, 0.35).normalize() * 0.41,
                Vec3::new(0.3, -0.4, 0.85).normalize(),
            );
            let origin = Vec3::new(3.3, -1.7, 2.9);
            for j in 0..=n {
                for i in 0..=n {
                    let h = rng.range(-amplitude, amplitude);
                    verts.push(origin + u * i as f32 + v * j as f32 + w * h);
                }
            }
            Grid { n, verts }
        }

        fn vert(&self, i: usize, j: usize) -> Vec3 {
            self.verts[j * (self.n + 1) + i]
        }

        /// The two triangles of cell (i, j), consistently wound.
        fn cell(&self, i: usize, j: usize) -> [[Vec3; 3]; 2] {
            let (a, b) = (self.vert(i, j), self.vert(i + 1, j));
            let (c, d) = (self.vert(i, j + 1), self.vert(i + 1, j + 1));
            [[a, b, d], [a, d, c]]
        }

        /// Triangles of the cells around grid point (i, j).
        fn around(&self, i: usize, j: usize) -> Vec<[Vec3; 3]> {
            let mut tris = Vec::new();
            for cj in j.saturating_sub(1)..(j + 1).min(self.n) {
                for ci in i.saturating_sub(1)..(i + 1).min(self.n) {
                    tris.extend(self.cell(ci, cj));
                }
            }
            tris
        }

        fn all(&self) -> Vec<[Vec3; 3]> {
            let cells = (0..self.n).flat_map(|j| (0..self.n).map(move |i| (i, j)));
            cells.flat_map(|(i, j)| self.cell(i, j)).collect()
        }

        fn normal(&self) -> Vec3 {
            let (a, b, c) = (self.vert(0, 0), self.vert(self.n, 0), self.vert(0, self.n));
            (b - a).cross(c - a).normalize()
        }
    }

    fn count_hits(r: &Ray, tris: &[[Vec3; 3]]) -> usize {
        let mut hits = 0;
        for t in tris {
            if let Some(h) = intersect(r, t[0], t[1], t[2], f32::INFINITY) {
                check_hit(&h);
                hits += 1;
            }
        }
        hits
    }

    /// True when every triangle faces the same way as seen along `d`: the local patch is then a
    /// single sheet in the ray's projection, so a ray through it must hit. (At a silhouette
    /// fold a ray passing a rounding error beside the shared edge legitimately misses.)
    fn no_silhouette(d: Vec3, tris: &[[Vec3; 3]]) -> bool {
        let side = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).dot(d) > 0.0;
        let first = side(&tris[0]);
        tris.iter().all(|t| side(t) == first)
    }

    /// A random origin on the side `side` (±1) of the grid, at a polar angle up to `max_deg`.
    fn origin_towards(rng: &mut Rng, target: Vec3, normal: Vec3, side: f32, max_deg: f32) -> Vec3 {
        loop {
            let dir = rng.unit_vector();
            let cos = dir.dot(normal) * side;
            if cos > max_deg.to_radians().cos() {
                return target + dir * rng.range(0.05, 20.0);
            }
        }
    }

    #[test]
    fn watertight_grid_vertices_edges_and_interior() {
        let mut rng = Rng::new(7);
        let grid = Grid::new(24, &mut rng);
        let normal = grid.normal();
        let (mut rays, mut misses) = (0, 0);
        for k in 0..125_000 {
            // Interior grid point (i, j), so the whole 1-ring exists.
            let (i, j) = (1 + rng.below(grid.n - 1), 1 + rng.below(grid.n - 1));
            let p = grid.vert(i, j);
            let target = match k % 4 {
                0 => p,                                      // a shared vertex
                1 => 0.5 * (p + grid.vert(i + 1, j)),        // a shared edge
                2 => 0.5 * (p + grid.vert(i + 1, j + 1)),    // the cell diagonal
                _ => p.lerp(grid.vert(i, j + 1), rng.f32()), // anywhere on an edge
            };
            let side = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            let o = origin_towards(&mut rng, target, normal, side, 80.0);
            let r = ray(o, target - o);
            let local = grid.around(i, j);
            if !no_silhouette(r.d, &local) {
                continue;
            }
            rays += 1;
            if count_hits(&r, &local) == 0 {
                misses += 1;
            }
        }
        assert!(rays > 100_000, "only {rays} rays tested");
        assert_eq!(misses, 0, "{misses} of {rays} rays fell through the mesh");
    }

    /// Asserts that the f32 path and the f64 reference agree: same hit/miss, and when both
    /// hit, the barycentrics to f32 accuracy and t to f32 accuracy over |cos θ| (θ between ray
    /// and normal: seen edge-on, a barycentric rounding moves the hit far along the ray).
    fn assert_paths_agree(r: &Ray, tri: &[Vec3; 3]) -> bool {
        let fast = intersect(r, tri[0], tri[1], tri[2], f32::INFINITY);
        let reference = intersect_reference(r, tri[0], tri[1], tri[2], f32::INFINITY);
        match (fast, reference) {
            (None, None) => false,
            (Some(f), Some(g)) => {
                check_hit(&f);
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
                let cos = n.dot(r.d.normalize()).abs().max(1e-6);
                let tol = 1e-5 * g.t / cos;
                assert!((f.t - g.t).abs() <= tol, "{r:?} {tri:?}: {f:?} vs {g:?}");
                for (a, b) in [(f.b0, g.b0), (f.b1, g.b1), (f.b2, g.b2)] {
                    assert!((a - b).abs() <= 1e-4, "{r:?} {tri:?}: {f:?} vs {g:?}");
                }
                true
            }
            (f, g) => panic!("{r:?} {tri:?}: f32 path {f:?}, f64 reference {g:?}"),
        }
    }

    /// The f32 edge functions (with the f64 fallback on zero) decide hit/miss exactly as the f64
    /// ones for rays through shared vertices, edges and cell diagonals of a displaced grid, from
    /// every side and at angles down to 10° above the surface.
    #[test]
    fn f32_path_agrees_with_the_f64_reference() {
        let mut rng = Rng::new(19);
        let grid = Grid::new(16, &mut rng);
        let normal = grid.normal();
        let (mut tests, mut hits) = (0, 0);
        for k in 0..60_000 {
            let (i, j) = (1 + rng.below(grid.n - 1), 1 + rng.below(grid.n - 1));
            let p = grid.vert(i, j);
            let target = match k % 4 {
                0 => p,
                1 => 0.5 * (p + grid.vert(i + 1, j)),
                2 => p.lerp(grid.vert(i + 1, j + 1), rng.f32()),
                _ => p.lerp(grid.vert(i, j + 1), rng.f32()),
            };
            let side = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            let o = origin_towards(&mut rng, target, normal, side, 80.0);
            let r = ray(o, target - o);
            for tri in grid.around(i, j) {
                tests += 1;
                hits += assert_paths_agree(&r, &tri) as usize;
            }
        }
        assert!(
            hits > 60_000 && tests > 400_000,
            "{hits} hits in {tests} tests"
        );
    }

    /// A closed mesh: an icosahedron subdivided `levels` times, vertices shared by index and
    /// moved radially by up to ±3%, in a tilted frame with "ugly" coordinates. Star-shaped
    /// around `center`.
    struct Sphere {
        center: Vec3,
        verts: Vec<Vec3>,
        faces: Vec<[usize; 3]>,
    }

    impl Sphere {
        fn new(levels: usize, rng: &mut Rng) -> Sphere {
            let phi = (1.0 + 5.0f32.sqrt()) / 2.0;
            let mut dirs: Vec<Vec3> = [
                [-1.0, phi, 0.0],
                [1.0, phi, 0.0],
                [-1.0, -phi, 0.0],
                [1.0, -phi, 0.0],
                [0.0, -1.0, phi],
                [0.0, 1.0, phi],
                [0.0, -1.0, -phi],
                [0.0, 1.0, -phi],
                [phi, 0.0, -1.0],
                [phi, 0.0, 1.0],
                [-phi, 0.0, -1.0],
                [-phi, 0.0, 1.0],
            ]
            .map(|v| Vec3::from(v).normalize())
            .to_vec();
            let mut faces = vec![
                [0, 11, 5],
                [0, 5, 1],
                [0, 1, 7],
                [0, 7, 10],
                [0, 10, 11],
                [1, 5, 9],
                [5, 11, 4],
                [11, 10, 2],
                [10, 7, 6],
                [7, 1, 8],
                [3, 9, 4],
                [3, 4, 2],
                [3, 2, 6],
                [3, 6, 8],
                [3, 8, 9],
                [4, 9, 5],
                [2, 4, 11],
                [6, 2, 10],
                [8, 6, 7],
                [9, 8, 1],
            ];
            for _ in 0..levels {
                let mut midpoints = std::collections::HashMap::new();
                let mut mid = |a: usize, b: usize, dirs: &mut Vec<Vec3>| {
                    *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                        dirs.push((dirs[a] + dirs[b]).normalize());
                        dirs.len() - 1
                    })
                };
                faces = faces
                    .iter()
                    .flat_map(|&[a, b, c]| {
                        let (ab, bc, ca) = (
                            mid(a, b, &mut dirs),
                            mid(b, c, &mut dirs),
                            mid(c, a, &mut dirs),
                        );
                        [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
                    })
                    .collect();
            }
            let center = Vec3::new(-2.71, 5.33, 1.09);
            let frame = glam::Quat::from_axis_angle(Vec3::new(0.3, -0.8, 0.5).normalize(), 0.7);
            let verts = dirs
                .iter()
                .map(|&d| center + frame * d * 1.37 * rng.range(0.97, 1.03))
                .collect();
            Sphere {
                center,
                verts,
                faces,
            }
        }

        fn triangles(&self) -> Vec<[Vec3; 3]> {
            self.faces
                .iter()
                .map(|f| f.map(|i| self.verts[i]))
                .collect()
        }

        /// A random point on a shared edge (k odd) or a shared vertex (k even).
        fn edge_or_vertex(&self, k: usize, rng: &mut Rng) -> Vec3 {
            let f = self.faces[rng.below(self.faces.len())];
            let e = rng.below(3);
            let (a, b) = (self.verts[f[e]], self.verts[f[(e + 1) % 3]]);
            if k.is_multiple_of(2) {
                a
            } else {
                a.lerp(b, rng.f32())
            }
        }
    }

    /// No ray slips through a closed mesh at a shared edge or vertex: rays from inside (near the
    /// center) out through edges and vertices, and from outside in towards the center through
    /// them, all hit; and the f32 path agrees with the f64 reference on every triangle.
    #[test]
    fn closed_mesh_has_no_cracks() {
        let mut rng = Rng::new(23);
        let sphere = Sphere::new(3, &mut rng);
        let tris = sphere.triangles();
        assert_eq!(tris.len(), 1280);
        let mut misses = 0;
        for k in 0..20_000 {
            let target = sphere.edge_or_vertex(k, &mut rng);
            let r = if k % 4 < 2 {
                let o = sphere.center + rng.unit_vector() * rng.range(0.0, 0.05);
                ray(o, target - o)
            } else {
                let o = sphere.center + (target - sphere.center) * rng.range(1.5, 10.0);
                ray(o, sphere.center - o)
            };
            let hits = tris.iter().filter(|t| assert_paths_agree(&r, t)).count();
            if hits == 0 {
                misses += 1;
            }
        }
        assert_eq!(misses, 0, "{misses} rays fell through the closed mesh");
    }

    #[test]
    fn watertight_fan_around_a_vertex() {
        let mut rng = Rng::new(11);
        let center = Vec3::new(0.3137, -2.6093, 1.3271);
        let (u, v) = (
            Vec3::new(1.0, 0.2, 0.1).normalize(),
            Vec3::new(-0.1, 0.3, 1.0).normalize(),
        );
        let normal = u.cross(v).normalize();
        // 48 spokes at random angles, slightly off-plane: a non-planar closed fan.
        // Stratified angles, so no spoke gap is tiny or exceeds π.
        let angles: Vec<f32> = (0..48)
            .map(|k| (k as f32 + rng.range(0.1, 0.9)) * std::f32::consts::TAU / 48.0)
            .collect();
        let rim: Vec<Vec3> = angles
            .iter()
            .map(|a| {
                center
                    + (u * a.cos() + v * a.sin()) * rng.range(0.5, 1.5)
                    + normal * rng.range(-0.005, 0.005)
            })
            .collect();
        let fan: Vec<[Vec3; 3]> = (0..rim.len())
            .map(|k| [center, rim[k], rim[(k + 1) % rim.len()]])
            .collect();
        let (mut rays, mut misses) = (0, 0);
        for k in 0..40_000 {
            let target = match k % 2 {
                0 => center,
                _ => center.lerp(rim[rng.below(rim.len())], rng.range(0.0, 0.9)),
            };
            let side = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            let o = origin_towards(&mut rng, target, normal, side, 70.0);
            if !no_silhouette(target - o, &fan) {
                continue;
            }
            rays += 1;
            if count_hits(&ray(o, target - o), &fan) == 0 {
                misses += 1;
            }
        }
        assert!(rays > 30_000, "only {rays} rays tested");
        assert_eq!(misses, 0, "{misses} of {rays} rays fell through the fan");
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let mut rng = Rng::new(3);
        // Exactly representable, so exactly collinear in f32.
        let a = Vec3::new(0.125, 0.25, 0.375);
        let b = a + Vec3::new(1.0, 2.0, 3.0) * 0.5;
        let c = a + Vec3::new(1.0, 2.0, 3.0) * 1.5;
        let degenerate = [
            [a, b, c], // collinear
            [a, a, b], // repeated vertex
            [a, b, b],
            [a, a, a],
            [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            [Vec3::new(f32::NAN, 0.0, 0.0), Vec3::X, Vec3::Y],
            [Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::X, Vec3::Y],
            [Vec3::new(0.0, 0.0, f32::NEG_INFINITY), Vec3::X, Vec3::Y],
        ];
        for tri in &degenerate {
            assert!(is_degenerate(tri[0], tri[1], tri[2]), "{tri:?}");
            for _ in 0..2000 {
                // Rays aimed at points on the degenerate segment from every direction.
                let target = a.lerp(b, rng.range(-0.5, 1.5));
                let o = target + rng.unit_vector() * rng.range(0.01, 10.0);
                for r in [ray(o, target - o), ray(o, rng.unit_vector())] {
                    assert!(intersect(&r, tri[0], tri[1], tri[2], f32::INFINITY).is_none());
                }
            }
        }
        // Rays along the degenerate line itself.
        let along = ray(a - (b - a), b - a);
        assert!(intersect(&along, a, b, c, f32::INFINITY).is_none());
    }

    #[test]
    fn sliver_triangles_hit_where_they_should() {
        // Width 2e-12 over length 1: area 1e-12.
        let (p0, p1, p2) = (Vec3::ZERO, Vec3::X, Vec3::new(0.5, 2e-12, 0.0));
        assert!(!is_degenerate(p0, p1, p2));
        let down = Vec3::new(0.0, 0.0, -1.0);
        let inside = ray(Vec3::new(0.5, 1e-12, 1.0), down);
        let h = intersect(&inside, p0, p1, p2, f32::INFINITY).expect("sliver hit");
        check_hit(&h);
        assert!((h.t - 1.0).abs() < 1e-6);
        for y in [3e-12, -1e-12, 1e-6] {
            assert!(intersect(
                &ray(Vec3::new(0.5, y, 1.0), down),
                p0,
                p1,
                p2,
                f32::INFINITY
            )
            .is_none());
        }
        // Oblique rays through random interior points of random slivers hit; NaN never appears.
        let mut rng = Rng::new(5);
        let mut hits = 0;
        for _ in 0..20_000 {
            let a = rng.vec3(-1.0, 1.0);
            let axis = rng.unit_vector() * rng.range(0.1, 1.0);
            let bump = rng.unit_vector().cross(axis).normalize_or_zero() * 1e-5;
            let (q0, q1, q2) = (a, a + axis, a + 0.5 * axis + bump);
            if is_degenerate(q0, q1, q2) {
                continue;
            }
            // An interior point, away from the edges in barycentric terms.
            let (u, v) = (rng.range(0.2, 0.4), rng.range(0.2, 0.4));
            let target = q0 * (1.0 - u - v) + q1 * u + q2 * v;
            let n = (q1 - q0).cross(q2 - q0).normalize();
            let o = target + (n + rng.unit_vector() * 0.5).normalize() * rng.range(0.1, 10.0);
            if let Some(h) = intersect(&ray(o, target - o), q0, q1, q2, f32::INFINITY) {
                check_hit(&h);
                hits += 1;
            }
        }
        assert!(hits > 19_000, "only {hits} sliver hits");
    }

    #[test]
    fn grazing_rays_consistent_and_finite() {
        // A planar (up to vertex rounding) but not axis-aligned tessellated quad: no silhouettes.
        let mut rng = Rng::new(13);
        let grid = Grid::with_amplitude(16, 0.0, &mut rng);
        let normal = grid.normal();
        let tangent = (grid.vert(grid.n, 0) - grid.vert(0, 0)).normalize();
        let tangent = (tangent - normal * normal.dot(tangent)).normalize();
        let elevation = (90.0f32 - 89.99).to_radians();
        let all = grid.all();
        let mut misses = 0;
        for _ in 0..20_000 {
            let (i, j) = (2 + rng.below(grid.n - 4), 2 + rng.below(grid.n - 4));
            let target = grid.vert(i, j).lerp(grid.vert(i + 1, j + 1), rng.f32());
            let side = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            let azimuth = rng.range(0.0, std::f32::consts::TAU);
            let t_dir = glam::Quat::from_axis_angle(normal, azimuth) * tangent;
            let dir = (t_dir * elevation.cos() - normal * side * elevation.sin()).normalize();
            let o = target - dir * rng.range(0.01, 0.3);
            let r = ray(o, dir);
            if count_hits(&r, &grid.around(i, j)) == 0 && count_hits(&r, &all) == 0 {
                misses += 1;
            }
        }
        assert_eq!(misses, 0);
        // Same triangle, same ray, repeated: identical answers; a ray exactly in a plane misses.
        let (a, b, c) = (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 4.0, 0.0),
        );
        let in_plane = ray(Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 0.1, 0.0));
        assert!(intersect(&in_plane, a, b, c, f32::INFINITY).is_none());
        for k in 0..1000 {
            let e = (1e-4 * (k + 1) as f32).to_radians();
            let r = ray(Vec3::new(-1.0, 1.0, e.tan()), Vec3::new(1.0, 0.0, -e.tan()));
            let h = intersect(&r, a, b, c, f32::INFINITY).expect("grazing hit");
            check_hit(&h);
            assert!((h.t - 1.0).abs() < 1e-3, "{h:?} at {e}");
        }
    }

    /// What ray spawning relies on (PBR 4ed §6.8.5–6): the triangle's plane passes through the box
    /// `p ± hit_point_error`, i.e. |n̂·(p − p0)| ≤ |n̂|·err, checked in f64 at every scale. The
    /// point is also close to the exact ray–plane intersection (the barycentrics are accurate up
    /// to the foreshortening of the triangle seen along the ray).
    #[test]
    fn hit_point_error_box_contains_the_surface() {
        let mut rng = Rng::new(17);
        let mut tested = 0;
        for scale in [1e-4f32, 1e-2, 1.0, 1e2, 1e5] {
            for _ in 0..20_000 {
                let offset = rng.vec3(-10.0, 10.0) * scale;
                let p = [0, 1, 2].map(|_| offset + rng.vec3(-1.0, 1.0) * scale);
                if is_degenerate(p[0], p[1], p[2]) {
                    continue;
                }
                let (u, v) = (rng.range(0.0, 0.5), rng.range(0.0, 0.5));
                let target = p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v;
                let o = target + rng.unit_vector() * scale * rng.range(0.1, 10.0);
                let r = ray(o, target - o);
                let Some(h) = intersect(&r, p[0], p[1], p[2], f32::INFINITY) else {
                    continue;
                };
                tested += 1;
                let hp = h.point(p[0], p[1], p[2]);
                let err = hit_point_error(&h, p[0], p[1], p[2]);
                let (n, dist) = plane_distance(&p, hp);
                let allowed: f64 = (0..3).map(|k| n[k].abs() * err[k] as f64).sum();
                assert!(dist <= allowed, "scale {scale}: {dist} > {allowed}");
                // Woop's barycentrics come from the projection along the ray, so their error
                // grows as the projected triangle thins out: 1/cos θ.
                let d = f64x3(r.d);
                let d_len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                let cos = ((0..3).map(|k| n[k] * d[k]).sum::<f64>() / d_len).abs();
                let exact = exact_plane_hit(&r, &p);
                for k in 0..3 {
                    let dev = (hp[k] as f64 - exact[k]).abs();
                    assert!(
                        dev <= 1e-5 * scale as f64 / cos,
                        "scale {scale}: axis {k} off by {dev}; {p:?} {r:?} {h:?}"
                    );
                }
            }
        }
        assert!(tested > 90_000, "{tested}");
    }

    fn f64x3(a: Vec3) -> [f64; 3] {
        [a.x as f64, a.y as f64, a.z as f64]
    }

    /// Unit normal of the triangle and the distance of `q` from its plane, in f64.
    fn plane_distance(p: &[Vec3; 3], q: Vec3) -> ([f64; 3], f64) {
        let (a, b, c, q) = (f64x3(p[0]), f64x3(p[1]), f64x3(p[2]), f64x3(q));
        let (u, v) = (
            [0, 1, 2].map(|k| b[k] - a[k]),
            [0, 1, 2].map(|k| c[k] - a[k]),
        );
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        let n = n.map(|x| x / len);
        let dist: f64 = (0..3).map(|k| n[k] * (q[k] - a[k])).sum();
        (n, dist.abs())
    }

    /// Intersection of the ray with the triangle's plane in f64.
    fn exact_plane_hit(r: &Ray, p: &[Vec3; 3]) -> [f64; 3] {
        let v = |a: Vec3| [a.x as f64, a.y as f64, a.z as f64];
        let (o, d, a, b, c) = (v(r.o), v(r.d), v(p[0]), v(p[1]), v(p[2]));
        let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let cross = |x: [f64; 3], y: [f64; 3]| {
            [
                x[1] * y[2] - x[2] * y[1],
                x[2] * y[0] - x[0] * y[2],
                x[0] * y[1] - x[1] * y[0],
            ]
        };
        let n = cross(sub(b, a), sub(c, a));
        let t = dot(n, sub(a, o)) / dot(n, d);
        [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]]
    }
}
