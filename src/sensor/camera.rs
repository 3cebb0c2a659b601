//! The UsdGeomCamera as a perspective pinhole or thin-lens camera (PBR 4ed §5.2).
//!
//! The field of view follows from focalLength and the apertures (only their ratio matters);
//! when the image aspect differs from the aperture aspect, the aperture is expanded to fit
//! (UsdRenderSettings' default `aspectRatioConformPolicy = "expandAperture"`). The camera
//! looks along its local −Z with +Y up. Pixel values are radiance: the camera's importance is
//! normalised so that a sample's weight is 1 (a box filter of one pixel).

use crate::geometry::Ray;
use crate::sampling::warp::concentric_disk;
use crate::scene::desc::CameraDesc;
use glam::{Mat4, Vec3};

#[derive(Clone, Debug)]
pub struct Camera {
    pub prim_path: String,
    pub to_world: Mat4,
    pub width: u32,
    pub height: u32,
    /// Half extents of the image plane at distance 1 (tan of the half angles).
    pub half_w: f32,
    pub half_h: f32,
    pub lens_radius: f32,
    pub focus_distance: f32,
    pub clip_near: f32,
    pub clip_far: f32,
    /// 2^exposure: the image scale UsdLux asks renderers to apply.
    pub exposure_scale: f32,
}

impl Camera {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Camera {
        let mut half_w = 0.5 * desc.horizontal_aperture / desc.focal_length;
        let mut half_h = 0.5 * desc.vertical_aperture / desc.focal_length;
        let aspect = width as f32 / height as f32;
        if half_w / half_h < aspect {
            half_w = half_h * aspect;
        } else {
            half_h = half_w / aspect;
        }
        let thin_lens = desc.lens_radius > 0.0 && desc.focus_distance > 0.0;
        Camera {
            prim_path: desc.prim_path.clone(),
            to_world: desc.to_world,
            width,
            height,
            half_w,
            half_h,
            lens_radius: if thin_lens { desc.lens_radius } else { 0.0 },
            focus_distance: desc.focus_distance,
            clip_near: desc.clip_near.max(0.0),
            clip_far: desc.clip_far,
            exposure_scale: desc.exposure.exp2(),
        }
    }

    /// The world-space ray through continuous raster position `film` (pixels, origin top
    /// left) and lens sample `u_lens`, plus the largest t before the far clipping plane.
    /// The origin is moved to the near clipping plane.
    pub fn generate_ray(&self, film: [f32; 2], u_lens: [f32; 2]) -> (Ray, f32) {
        let sx = (2.0 * film[0] / self.width as f32 - 1.0) * self.half_w;
        let sy = (1.0 - 2.0 * film[1] / self.height as f32) * self.half_h;
        let mut o = Vec3::ZERO;
        let mut d = Vec3::new(sx, sy, -1.0);
        if self.lens_radius > 0.0 {
            // Thin lens: all rays through the pixel's point on the focal plane (PBR 4ed §5.2.3).
            let lens = concentric_disk(u_lens) * self.lens_radius;
            let focus = d * self.focus_distance;
            o = Vec3::new(lens.x, lens.y, 0.0);
            d = focus - o;
        }
        // Distance along a unit direction per unit of depth −z.
        let d_unit = d.normalize();
        let per_depth = 1.0 / -d_unit.z;
        let o_near = o + d_unit * (self.clip_near * per_depth);
        let t_far = (self.clip_far - self.clip_near) * per_depth;
        let ray = Ray::new(
            self.to_world.transform_point3(o_near),
            self.to_world.transform_vector3(d_unit).normalize(),
        );
        (ray, t_far.max(0.0))
    }

    pub fn position(&self) -> Vec3 {
        self.to_world.transform_point3(Vec3::ZERO)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc() -> CameraDesc {
        CameraDesc {
            prim_path: "/cam".into(),
            to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, 3.9)),
            focal_length: 29.336_958,
            horizontal_aperture: 20.955,
            vertical_aperture: 20.955,
            clip_near: 0.001,
            clip_far: 100.0,
            f_stop: 0.0,
            focus_distance: 0.0,
            lens_radius: 0.0,
            exposure: 1.0,
        }
    }

    #[test]
    fn field_of_view_matches_the_aperture() {
        let cam = Camera::new(&desc(), 256, 256);
        // Mitsuba's cbox: 39.3077° horizontal field of view.
        let fov = 2.0 * cam.half_w.atan().to_degrees();
        assert!((fov - 39.3077).abs() < 1e-3, "{fov}");
        let (center, _) = cam.generate_ray([128.0, 128.0], [0.5, 0.5]);
        assert!((center.d - Vec3::NEG_Z).length() < 1e-6);
        let (left, _) = cam.generate_ray([0.0, 128.0], [0.5, 0.5]);
        assert!(left.d.x < 0.0);
        let (top, _) = cam.generate_ray([128.0, 0.0], [0.5, 0.5]);
        assert!(top.d.y > 0.0);
        assert_eq!(cam.exposure_scale, 2.0);
    }

    #[test]
    fn aperture_expands_to_the_image_aspect() {
        let cam = Camera::new(&desc(), 512, 256);
        assert!((cam.half_w / cam.half_h - 2.0).abs() < 1e-6);
        assert!((cam.half_h - 0.357_14).abs() < 1e-4);
    }

    #[test]
    fn thin_lens_rays_converge_on_the_focal_plane() {
        let mut d = desc();
        d.lens_radius = 0.05;
        d.focus_distance = 2.0;
        let cam = Camera::new(&d, 64, 64);
        let target = |u| {
            let (r, _) = cam.generate_ray([20.0, 40.0], u);
            let t = (3.9 - 2.0 - r.o.z) / r.d.z;
            r.at(t)
        };
        let (a, b) = (target([0.1, 0.2]), target([0.9, 0.7]));
        assert!((a - b).length() < 1e-4, "{a} {b}");
    }
}
