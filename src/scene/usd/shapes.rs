//! UsdGeom intrinsic shapes (Sphere, Cube, Cylinder, Cone, Plane) tessellated into polygon
//! meshes with analytic normals, in the prim's local space, outward faces counter-clockwise.

use glam::DVec3;
use openusd::usd;
use std::f64::consts::TAU;

use super::values::Ctx;
use crate::error::Result;

/// Segments around the axis of round shapes.
const SEGMENTS: u32 = 64;
/// Rings from pole to pole of a sphere.
const RINGS: u32 = 32;

/// The intrinsic shape types that are tessellated.
pub(super) const SHAPE_TYPES: [&str; 5] = ["Sphere", "Cube", "Cylinder", "Cone", "Plane"];

/// A tessellated shape: polygons over `points`, with one normal per point.
#[derive(Debug, Default)]
pub(super) struct Shape {
    pub points: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    pub counts: Vec<usize>,
    pub indices: Vec<u32>,
}

impl Shape {
    /// Adds a point with its normal; returns its index.
    fn point(&mut self, p: DVec3, n: DVec3) -> u32 {
        self.points.push(p);
        self.normals.push(n);
        (self.points.len() - 1) as u32
    }

    /// Adds a polygon (counter-clockwise seen from the front).
    fn face(&mut self, corners: &[u32]) {
        self.counts.push(corners.len());
        self.indices.extend_from_slice(corners);
    }

    /// Maps a shape built along +Z onto `axis` by a cyclic permutation (a rotation).
    fn along(mut self, axis: Axis) -> Shape {
        let permute = |v: DVec3| match axis {
            Axis::X => DVec3::new(v.z, v.x, v.y),
            Axis::Y => DVec3::new(v.y, v.z, v.x),
            Axis::Z => v,
        };
        self.points.iter_mut().for_each(|p| *p = permute(*p));
        self.normals.iter_mut().for_each(|n| *n = permute(*n));
        self
    }
}

/// A shape's `axis`.
#[derive(Clone, Copy, Debug)]
enum Axis {
    X,
    Y,
    Z,
}

/// Tessellates the shape prim of type `type_name`.
pub(super) fn tessellate(ctx: &Ctx, prim: &usd::Prim, type_name: &str) -> Result<Shape> {
    Ok(match type_name {
        "Sphere" => sphere(dimension(ctx, prim, "radius", 1.0)?),
        "Cube" => cube(dimension(ctx, prim, "size", 2.0)?),
        "Cylinder" => {
            let (radius, height) = (
                dimension(ctx, prim, "radius", 1.0)?,
                dimension(ctx, prim, "height", 2.0)?,
            );
            cone(radius, radius, height).along(axis(ctx, prim)?)
        }
        "Cone" => {
            let (radius, height) = (
                dimension(ctx, prim, "radius", 1.0)?,
                dimension(ctx, prim, "height", 2.0)?,
            );
            cone(radius, 0.0, height).along(axis(ctx, prim)?)
        }
        _ => {
            let (width, length) = (
                dimension(ctx, prim, "width", 2.0)?,
                dimension(ctx, prim, "length", 2.0)?,
            );
            plane(width, length, axis(ctx, prim)?)
        }
    })
}

/// A positive size attribute with its schema default.
fn dimension(ctx: &Ctx, prim: &usd::Prim, name: &str, default: f64) -> Result<f64> {
    let value = ctx.f64(prim, name)?.unwrap_or(default);
    if value <= 0.0 {
        return Err(ctx.err(prim, format!("{name} must be positive")));
    }
    Ok(value)
}

/// The `axis` token (default Z).
fn axis(ctx: &Ctx, prim: &usd::Prim) -> Result<Axis> {
    match ctx.token(prim, "axis")?.as_deref() {
        None | Some("Z") => Ok(Axis::Z),
        Some("X") => Ok(Axis::X),
        Some("Y") => Ok(Axis::Y),
        Some(other) => Err(ctx.err(prim, format!("axis '{other}' is not X, Y or Z"))),
    }
}

/// A point on the unit circle in the XY plane at segment `i`.
fn circle(i: u32) -> DVec3 {
    let phi = TAU * f64::from(i % SEGMENTS) / f64::from(SEGMENTS);
    DVec3::new(phi.cos(), phi.sin(), 0.0)
}

/// A UV sphere around the origin (poles on Z), with smooth normals and triangle fans at the
/// poles (no degenerate triangles).
fn sphere(radius: f64) -> Shape {
    let mut s = Shape::default();
    let south = s.point(DVec3::NEG_Z * radius, DVec3::NEG_Z);
    for ring in 1..RINGS {
        let theta = std::f64::consts::PI * f64::from(ring) / f64::from(RINGS);
        for i in 0..SEGMENTS {
            let n = circle(i) * theta.sin() + DVec3::Z * -theta.cos();
            s.point(n * radius, n);
        }
    }
    let north = s.point(DVec3::Z * radius, DVec3::Z);
    // Point of segment i on ring r (1..RINGS-1).
    let at = |ring: u32, i: u32| 1 + (ring - 1) * SEGMENTS + i % SEGMENTS;
    for i in 0..SEGMENTS {
        s.face(&[south, at(1, i + 1), at(1, i)]);
        s.face(&[at(RINGS - 1, i), at(RINGS - 1, i + 1), north]);
    }
    for ring in 1..RINGS - 1 {
        for i in 0..SEGMENTS {
            s.face(&[
                at(ring, i),
                at(ring, i + 1),
                at(ring + 1, i + 1),
                at(ring + 1, i),
            ]);
        }
    }
    s
}

/// An axis-aligned cube of edge `size` centred on the origin, with flat normals.
fn cube(size: f64) -> Shape {
    let mut s = Shape::default();
    let h = size / 2.0;
    for n in [
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ] {
        // (u, v, n) is right-handed, so u, v, -u, -v walks counter-clockwise seen from n.
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let corners = [-u - v, u - v, u + v, v - u].map(|c| s.point((n + c) * h, n));
        s.face(&corners);
    }
    s
}

/// A capped cone frustum along Z from `-height/2` (radius `bottom`) to `height/2` (radius
/// `top`, 0 for a cone), with smooth side normals and flat caps.
fn cone(bottom: f64, top: f64, height: f64) -> Shape {
    let mut s = Shape::default();
    let h = height / 2.0;
    let slope = (bottom - top) / height;
    let side_normal = |i: u32| (circle(i) + DVec3::Z * slope).normalize();
    let base = s.points.len() as u32;
    for i in 0..SEGMENTS {
        s.point(circle(i) * bottom - DVec3::Z * h, side_normal(i));
        s.point(circle(i) * top + DVec3::Z * h, side_normal(i));
    }
    for i in 0..SEGMENTS {
        let (b0, t0) = (base + 2 * i, base + 2 * i + 1);
        let (b1, t1) = (
            base + 2 * ((i + 1) % SEGMENTS),
            base + 2 * ((i + 1) % SEGMENTS) + 1,
        );
        if top > 0.0 {
            s.face(&[b0, b1, t1, t0]);
        } else {
            s.face(&[b0, b1, t0]);
        }
    }
    cap(&mut s, bottom, -h, DVec3::NEG_Z);
    cap(&mut s, top, h, DVec3::Z);
    s
}

/// A flat disk cap of `radius` at height `z` facing `normal` (nothing for radius 0).
fn cap(s: &mut Shape, radius: f64, z: f64, normal: DVec3) {
    if radius <= 0.0 {
        return;
    }
    let ring: Vec<u32> = (0..SEGMENTS)
        .map(|i| s.point(circle(i) * radius + DVec3::Z * z, normal))
        .collect();
    if normal.z > 0.0 {
        s.face(&ring);
    } else {
        s.face(&ring.iter().rev().copied().collect::<Vec<_>>());
    }
}

/// A `width` x `length` rectangle facing +`axis`. As UsdGeomPlane, `width` runs along X (along
/// Z when the axis is X) and `length` along Y (along Z when the axis is Y).
fn plane(width: f64, length: f64, axis: Axis) -> Shape {
    let mut s = Shape::default();
    let (w, l) = (width / 2.0, length / 2.0);
    let (place, normal): (fn(f64, f64) -> DVec3, DVec3) = match axis {
        Axis::X => (|u, v| DVec3::new(0.0, v, u), DVec3::X),
        Axis::Y => (|u, v| DVec3::new(u, 0.0, v), DVec3::Y),
        Axis::Z => (|u, v| DVec3::new(u, v, 0.0), DVec3::Z),
    };
    let mut corners =
        [(-w, -l), (w, -l), (w, l), (-w, l)].map(|(u, v)| s.point(place(u, v), normal));
    // (width, length) directions are right-handed about the normal only for Z.
    if !matches!(axis, Axis::Z) {
        corners.reverse();
    }
    s.face(&corners);
    s
}
