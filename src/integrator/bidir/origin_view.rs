//! Which lights' points can reach the camera's image: a light subpath's origin y_0 is
//! connected to the camera (t = 1, `splat.rs`) only through `Camera::sample_wi`, which finds
//! its raster position; for a lamp outside the view it always finds none. Found once per
//! render here, so that a sample skips the projection (its 2D number is still drawn, so the
//! sampler's stream and every image stay the same).
//!
//! Conservative: a light counts as unseen only when a sphere bounding every point its
//! `sample_le` can emit from lies wholly outside one face of the pinhole camera's viewing
//! frustum (PBR 4ed §5.2; the sides through the centre of projection and the raster's edges,
//! the near and far clipping planes), by a margin well above the round-off of
//! `Camera::sample_wi`. A thin-lens camera, an infinite light, and lights past the 64th are
//! always taken as seen.

use crate::light::Light;
use crate::sensor::camera::Camera;
use glam::Vec3;

/// Bit i set: light i may be seen by `camera` (every bit for lights past the 64th).
pub fn lights_in_view(camera: &Camera, lights: &[Light]) -> u64 {
    let mut mask = !0u64;
    for (i, light) in lights.iter().take(64).enumerate() {
        if bounding_sphere(light).is_some_and(|(c, r)| !may_see(camera, c, r)) {
            mask &= !(1u64 << i);
        }
    }
    mask
}

/// Whether bit `light` of `mask` ([`lights_in_view`]) says its points may be seen.
#[inline]
pub fn may_be_seen(mask: u64, light: u32) -> bool {
    light >= 64 || mask & (1 << light) != 0
}

/// A sphere (centre, radius) holding every point light subpaths start from on `light`; None
/// for infinite lights, whose origins lie on the scene's bounding disk.
fn bounding_sphere(light: &Light) -> Option<(Vec3, f32)> {
    Some(match light {
        Light::Sphere(s) => (
            s.center,
            s.ellipsoid
                .as_ref()
                .map_or(s.radius, |e| e.bounding_radius()),
        ),
        Light::Point(p) => (p.p(), 0.0),
        // |x a + y b| ≤ √(|a|² + |b|²) over the unit disk (Cauchy–Schwarz), sheared or not.
        Light::Disk(d) => (d.center, d.axes[0].length().hypot(d.axes[1].length())),
        Light::Rect(r) => (
            r.corner + 0.5 * (r.edge_u + r.edge_v),
            0.5 * (r.edge_u.length() + r.edge_v.length()),
        ),
        Light::Cylinder(c) => (c.center, c.radius + 0.5 * c.length),
        Light::Line(l) => (l.cylinder.center, 0.5 * l.length()),
        Light::Triangle(t) => {
            let c = (t.p[0] + t.p[1] + t.p[2]) / 3.0;
            (c, t.p.iter().map(|p| p.distance(c)).fold(0.0, f32::max))
        }
        Light::Distant(_) | Light::Dome(_) => return None,
    })
}

/// Whether any point of the sphere (world `centre`, `radius`) may project into `camera`'s
/// image; false only when the sphere lies beyond one face of the frustum by more than the
/// margin.
fn may_see(camera: &Camera, centre: Vec3, radius: f32) -> bool {
    if camera.lens_radius > 0.0 || !(centre.is_finite() && radius.is_finite()) {
        return true;
    }
    // Camera space: looking down −Z; from_world is rigid, so the radius is unchanged.
    let c = camera.from_world.transform_point3(centre);
    let margin = 1e-3 * (c.length() + radius) + 1e-6;
    let r = radius + margin;
    // Depths −z of the sphere's points: [−c.z − radius, −c.z + radius].
    if -c.z + r < camera.clip_near || -c.z - r > camera.clip_far {
        return false;
    }
    // The four sides x = ±half_w·depth, y = ±half_h·depth: the sphere wholly outside one.
    let outside = |offset: f32, half: f32| (offset + half * c.z) / (1.0 + half * half).sqrt() > r;
    let (hw, hh) = (camera.half_w, camera.half_h);
    !(outside(c.x, hw) || outside(-c.x, hw) || outside(c.y, hh) || outside(-c.y, hh))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::CameraDesc;
    use crate::testing::rng::Rng;
    use glam::Mat4;

    /// A pinhole camera turned and moved off the origin, 64 × 48, seeing 0.1–8 m.
    fn camera() -> Camera {
        let desc = CameraDesc {
            prim_path: "/cam".into(),
            to_world: Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
                * Mat4::from_rotation_y(0.7)
                * Mat4::from_rotation_x(-0.3),
            focal_length: 35.0,
            horizontal_aperture: 36.0,
            vertical_aperture: 24.0,
            clip_near: 0.1,
            clip_far: 8.0,
            f_stop: 0.0,
            focus_distance: 0.0,
            lens_radius: 0.0,
            exposure: 0.0,
        };
        Camera::new(&desc, 64, 48)
    }

    #[test]
    fn an_unseen_sphere_never_projects_into_the_image() {
        // 8,000 spheres all around a pinhole camera at several sizes: for those judged unseen, no
        // point on the sphere nor its centre finds a raster position; and the test is not
        // vacuous: many are judged each way.
        let cam = camera();
        let mut rng = Rng::new(11);
        let (mut unseen, mut seen) = (0, 0);
        for _ in 0..8000 {
            let centre = Vec3::new(
                20.0 * rng.f32() - 10.0,
                20.0 * rng.f32() - 10.0,
                20.0 * rng.f32() - 10.0,
            );
            let centre = cam.to_world.transform_point3(centre);
            let radius = [0.0, 0.01, 0.3, 2.0][unseen % 4];
            if may_see(&cam, centre, radius) {
                seen += 1;
                continue;
            }
            unseen += 1;
            assert!(cam.sample_wi(centre, [0.5, 0.5]).is_none());
            for _ in 0..64 {
                let d = crate::sampling::warp::uniform_sphere([rng.f32(), rng.f32()]);
                let p = centre + d * radius;
                assert!(
                    cam.sample_wi(p, [0.5, 0.5]).is_none(),
                    "{centre} {radius} {p}"
                );
            }
        }
        assert!(unseen > 2000 && seen > 200, "{unseen} {seen}");
        // A sphere straight ahead, and one enclosing the camera, are seen.
        let ahead = cam.to_world.transform_point3(Vec3::new(0.0, 0.0, -5.0));
        assert!(may_see(&cam, ahead, 0.1));
        let around = cam.to_world.transform_point3(Vec3::ZERO);
        assert!(may_see(&cam, around, 3.0));
    }

    #[test]
    fn the_mask_keeps_lights_past_the_64th_and_infinite_lights() {
        assert!(may_be_seen(0, 64) && may_be_seen(0, 200));
        assert!(!may_be_seen(0, 3) && may_be_seen(1 << 3, 3));
        assert_eq!(lights_in_view(&camera(), &[]), !0);
    }
}
