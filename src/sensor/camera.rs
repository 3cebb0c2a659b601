//! The UsdGeomCamera as a perspective pinhole or thin-lens camera (PBR 4ed §5.2).
//!
//! The field of view follows from focalLength and the apertures (only their ratio matters);
//! when the image aspect differs from the aperture aspect, the aperture is expanded to fit
//! (UsdRenderSettings' default `aspectRatioConformPolicy = "expandAperture"`). The camera
//! looks along its local −Z with +Y up. Pixel values are radiance: the camera's importance is
//! normalised so that a sample's weight is 1 (a box filter of one pixel).
//!
//! Importance for light transport from the light side (PBR 4ed §5.4.1, `PerspectiveCamera::We`,
//! `PDF_We`, `SampleWi`): a ray leaving lens point `p_lens` (pinhole: the camera position)
//! along direction ω with cos θ = ω·forward carries
//!   We = 1 / (A · A_lens · cos⁴θ)
//! where A is the image-plane area at distance 1 (`4 half_w half_h`) and A_lens = π r²
//! (1 for the pinhole). Camera rays are generated with p_pos = 1/A_lens on the lens and
//! p_dir = 1/(A cos³θ) per solid angle (dA_film = dω / cos³θ, for the thin lens too because
//! the focal plane is parallel to the film). These are normalised over the *whole* image, so a
//! light path splatting into pixel j estimates (pixel j's value) / N_pixels, and the film
//! divides splats by light paths per pixel (pbrt-v4's `splatScale = 1/spp`).

use crate::desc::CameraDesc;
use crate::geometry::Ray;
use crate::sampling::warp::concentric_disk;
use glam::{Mat4, Quat, Vec3};
use std::f32::consts::PI;

/// A lens point sampled towards a reference point, with the importance arriving there
/// (PBR 4ed §5.4.1, `CameraWiSample`).
#[derive(Clone, Copy, Debug)]
pub struct CameraWiSample {
    /// Unit direction from the reference point towards the lens point.
    pub wi: Vec3,
    pub p_lens: Vec3,
    /// Distance from the reference point to the lens point.
    pub dist: f32,
    /// Importance We of the ray from the lens point through the reference point.
    pub we: f32,
    /// Solid-angle density of `wi` at the reference point: dist² / (cos θ · A_lens).
    pub pdf_w: f32,
    /// Density per solid angle with which camera rays leave `p_lens` along −wi (for MIS).
    pub pdf_dir_w: f32,
    /// Continuous raster position (pixels, origin top left).
    pub raster: [f32; 2],
    /// Fraction of the segment reference → lens beyond the near clipping plane: occluders
    /// are looked for only there, as camera rays start on that plane.
    pub visible_fraction: f32,
}

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
    /// The camera's `exposure` in stops.
    pub exposure: f32,
    /// 2^exposure: the image scale UsdLux asks renderers to apply.
    pub exposure_scale: f32,
    /// Inverse of `to_world` (a rigid transform).
    pub from_world: Mat4,
    /// The smallest change of a camera ray's unit direction per pixel step in x and in y, in
    /// the frame where the ray looks along −Z (pbrt-v4 `minDirDifferentialX/Y`), for
    /// [`Camera::approximate_dp_dxy`].
    pub min_dir_differentials: [Vec3; 2],
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
        let min_dir_differentials = min_dir_differentials(half_w, half_h, width, height);
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
            exposure: desc.exposure,
            exposure_scale: desc.exposure.exp2(),
            from_world: desc.to_world.inverse(),
            min_dir_differentials,
        }
    }

    /// World to OpenEXR's camera space (the `worldToCamera` attribute, as a column-vector
    /// matrix): RenderMan's left-handed frame, x right, y up, z along the view, so our
    /// camera frame (looking along −Z, right-handed) with z negated.
    pub fn world_to_exr_camera(&self) -> Mat4 {
        Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0)) * self.from_world
    }

    /// World to OpenEXR's NDC (the `worldToNDC` attribute, column-vector form): after the
    /// homogeneous divide, (0, 0) is the image's top-left corner and (1, 1) its bottom-right
    /// (x right, y down), by the pinhole projection through the lens centre; z/w is 1/depth.
    pub fn world_to_ndc(&self) -> Mat4 {
        let (a, b) = (0.5 / self.half_w, -0.5 / self.half_h);
        let projection = Mat4::from_cols_array_2d(&[
            [a, 0.0, 0.0, 0.0],
            [0.0, b, 0.0, 0.0],
            [0.5, 0.5, 0.0, 1.0],
            [0.0, 0.0, 1.0, 0.0],
        ]);
        projection * self.world_to_exr_camera()
    }

    /// ∂p/∂x and ∂p/∂y at a surface point `p` with normal `n`, per pixel step, times `scale`,
    /// without ray differentials (pbrt-v4 `CameraBase::Approximate_dp_dxy`, PBR 4ed
    /// §10.1.1): the camera's smallest direction differentials are rotated from −Z onto the
    /// direction towards `p`, the two offset rays from the camera's centre intersected with
    /// the tangent plane at `p`, and their offsets from `p` returned. Both camera models have
    /// no position differential (pbrt's thin lens keeps the lens point for its differential
    /// rays, and the minimum is taken at the lens centre), so the rays start at the camera's
    /// position. A plane seen exactly edge-on gives non-finite offsets, returned as 0
    /// (the finest level); nearly edge-on ones give large finite offsets (coarse levels).
    pub fn approximate_dp_dxy(&self, p: Vec3, n: Vec3, scale: f32) -> [Vec3; 2] {
        let pc = self.from_world.transform_point3(p);
        let nc = self.from_world.transform_vector3(n);
        let Some(dir) = pc.try_normalize() else {
            return [Vec3::ZERO; 2];
        };
        let rot = Quat::from_rotation_arc(Vec3::NEG_Z, dir);
        let plane = nc.dot(pc);
        self.min_dir_differentials.map(|dd| {
            let w = rot * (Vec3::NEG_Z + dd);
            let t = plane / nc.dot(w);
            let dp = self.to_world.transform_vector3(w * t - pc) * scale;
            if dp.is_finite() {
                dp
            } else {
                Vec3::ZERO
            }
        })
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

    /// Unit viewing direction (world-space local −Z).
    pub fn forward(&self) -> Vec3 {
        self.to_world.transform_vector3(Vec3::NEG_Z).normalize()
    }

    /// Image-plane area at distance 1, A of PBR 4ed eq. 5.3 ff.
    pub fn image_area(&self) -> f32 {
        4.0 * self.half_w * self.half_h
    }

    /// Lens area π r² (1 for the pinhole, as pbrt-v4).
    pub fn lens_area(&self) -> f32 {
        if self.lens_radius > 0.0 {
            PI * self.lens_radius * self.lens_radius
        } else {
            1.0
        }
    }

    /// The world-space lens point that [`Camera::generate_ray`] uses for `u_lens`.
    pub fn lens_point(&self, u_lens: [f32; 2]) -> Vec3 {
        self.to_world.transform_point3(self.lens_local(u_lens))
    }

    fn lens_local(&self, u_lens: [f32; 2]) -> Vec3 {
        if self.lens_radius > 0.0 {
            let l = concentric_disk(u_lens) * self.lens_radius;
            Vec3::new(l.x, l.y, 0.0)
        } else {
            Vec3::ZERO
        }
    }

    /// Importance We of the ray leaving lens point `p_lens` in unit direction `w`, and the
    /// raster position it passes through; 0 and None outside the image (PBR 4ed §5.4.1).
    pub fn we(&self, p_lens: Vec3, w: Vec3) -> (f32, Option<[f32; 2]>) {
        let o = self.from_world.transform_point3(p_lens);
        let d = self.from_world.transform_vector3(w);
        let cos = -d.z;
        let Some(raster) = self.raster_of_ray(o, d) else {
            return (0.0, None);
        };
        let cos2 = cos * cos;
        (
            1.0 / (self.image_area() * self.lens_area() * cos2 * cos2),
            Some(raster),
        )
    }

    /// Densities of camera-ray generation for the ray leaving lens point `p_lens` along unit
    /// direction `w`: (per lens area, per solid angle) = (1/A_lens, 1/(A cos³θ)), zero outside
    /// the image (PBR 4ed §5.4.1, `PerspectiveCamera::PDF_We`).
    pub fn pdf_we(&self, p_lens: Vec3, w: Vec3) -> (f32, f32) {
        let o = self.from_world.transform_point3(p_lens);
        let d = self.from_world.transform_vector3(w);
        if self.raster_of_ray(o, d).is_none() {
            return (0.0, 0.0);
        }
        (1.0 / self.lens_area(), self.ray_pdf_dir(w))
    }

    /// 1/(A cos³θ) for a ray this camera generated along unit direction `w` (no image-bounds
    /// test, which rounding could fail at the image border).
    pub fn ray_pdf_dir(&self, w: Vec3) -> f32 {
        let cos = -self.from_world.transform_vector3(w).z;
        if cos <= 0.0 {
            return 0.0;
        }
        1.0 / (self.image_area() * cos * cos * cos)
    }

    /// Samples a lens point seen from `p_ref` (PBR 4ed §5.4.1, `PerspectiveCamera::SampleWi`);
    /// None when `p_ref` is outside the clipping range or the image.
    pub fn sample_wi(&self, p_ref: Vec3, u_lens: [f32; 2]) -> Option<CameraWiSample> {
        let q = self.from_world.transform_point3(p_ref);
        let depth = -q.z;
        if !(depth > self.clip_near && depth < self.clip_far) {
            return None;
        }
        let lens = self.lens_local(u_lens);
        let to_ref = q - lens;
        let dist = to_ref.length();
        if dist == 0.0 || !dist.is_finite() {
            return None;
        }
        let d = to_ref / dist;
        let cos = -d.z;
        let raster = self.raster_of_ray(lens, d)?;
        let cos2 = cos * cos;
        let we = 1.0 / (self.image_area() * self.lens_area() * cos2 * cos2);
        let pdf_w = dist * dist / (cos * self.lens_area());
        let p_lens = self.to_world.transform_point3(lens);
        Some(CameraWiSample {
            wi: (p_lens - p_ref).normalize(),
            p_lens,
            dist,
            we,
            pdf_w,
            pdf_dir_w: 1.0 / (self.image_area() * cos2 * cos),
            raster,
            visible_fraction: (depth - self.clip_near) / depth,
        })
    }

    /// Raster position of the camera-space ray (o on the lens, unit d): where it crosses the
    /// film at distance 1 (pinhole) or the focal plane (thin lens, PBR 4ed §5.2.3).
    fn raster_of_ray(&self, o: Vec3, d: Vec3) -> Option<[f32; 2]> {
        let cos = -d.z;
        if cos <= 0.0 {
            return None;
        }
        let (sx, sy) = if self.lens_radius > 0.0 {
            let f = o + d * (self.focus_distance / cos);
            (f.x / self.focus_distance, f.y / self.focus_distance)
        } else {
            (d.x / cos, d.y / cos)
        };
        let x = (sx / self.half_w + 1.0) * 0.5 * self.width as f32;
        let y = (1.0 - sy / self.half_h) * 0.5 * self.height as f32;
        let inside =
            (0.0..self.width as f32).contains(&x) && (0.0..self.height as f32).contains(&y);
        inside.then_some([x, y])
    }

    /// The pixel index of a raster position.
    pub fn pixel_index(&self, raster: [f32; 2]) -> Option<u32> {
        let (x, y) = (raster[0] as u32, raster[1] as u32);
        (x < self.width && y < self.height).then(|| y * self.width + x)
    }
}

/// The shortest change of the unit ray direction for a one-pixel step in x and in y, over
/// points along the film's diagonal (pbrt-v4 `CameraBase::FindMinimumDifferentials`), each
/// expressed in the frame that turns its ray to −Z.
fn min_dir_differentials(half_w: f32, half_h: f32, width: u32, height: u32) -> [Vec3; 2] {
    const N: usize = 512;
    let (w, h) = (width as f32, height as f32);
    let dir = |fx: f32, fy: f32| {
        let sx = (2.0 * fx / w - 1.0) * half_w;
        let sy = (1.0 - 2.0 * fy / h) * half_h;
        Vec3::new(sx, sy, -1.0).normalize()
    };
    let mut best = [Vec3::INFINITY; 2];
    for i in 0..N {
        let f = i as f32 / (N - 1) as f32;
        let (fx, fy) = (f * w, f * h);
        let d = dir(fx, fy);
        let to_axis = Quat::from_rotation_arc(d, Vec3::NEG_Z);
        for (k, next) in [dir(fx + 1.0, fy), dir(fx, fy + 1.0)]
            .into_iter()
            .enumerate()
        {
            let dd = to_axis * next - Vec3::NEG_Z;
            if dd.length_squared() < best[k].length_squared() {
                best[k] = dd;
            }
        }
    }
    best.map(|d| if d.is_finite() { d } else { Vec3::ZERO })
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

    #[test]
    fn exr_matrices_put_a_raster_point_at_its_ndc() {
        let mut d = desc();
        d.to_world = Mat4::from_translation(Vec3::new(1.0, -2.0, 0.5)) * Mat4::from_rotation_y(0.3);
        let cam = Camera::new(&d, 40, 30);
        let (r, _) = cam.generate_ray([10.0, 20.0], [0.5, 0.5]);
        let p = r.at(3.0);
        let ndc = cam.world_to_ndc().project_point3(p);
        assert!(
            (ndc.x - 0.25).abs() < 1e-5 && (ndc.y - 20.0 / 30.0).abs() < 1e-5,
            "{ndc}"
        );
        // In front of the camera: positive z in OpenEXR's camera space.
        let c = cam.world_to_exr_camera().transform_point3(p);
        assert!(c.z > 0.0 && c.x < 0.0 && c.y < 0.0, "{c}");
    }

    fn thin_lens() -> Camera {
        let mut d = desc();
        d.lens_radius = 0.05;
        d.focus_distance = 2.0;
        d.to_world = Mat4::from_rotation_y(0.3) * d.to_world;
        Camera::new(&d, 48, 32)
    }

    #[test]
    fn sample_wi_and_we_find_the_pixel_of_a_camera_ray() {
        let mut s = crate::sampling::Sampler::new(9, 0, 0);
        for cam in [Camera::new(&desc(), 40, 30), thin_lens()] {
            for _ in 0..200 {
                let film = [s.get_1d() * 40.0, s.get_1d() * 30.0];
                let film = [
                    film[0] * cam.width as f32 / 40.0,
                    film[1] * cam.height as f32 / 30.0,
                ];
                let u = s.get_2d();
                let (ray, _) = cam.generate_ray(film, u);
                let p_lens = cam.lens_point(u);
                let (we, raster) = cam.we(p_lens, ray.d);
                let r = raster.unwrap();
                assert!((r[0] - film[0]).abs() < 2e-3 && (r[1] - film[1]).abs() < 2e-3);
                let ws = cam.sample_wi(ray.at(1.5), u).unwrap();
                assert!((ws.raster[0] - film[0]).abs() < 2e-3);
                assert!((ws.raster[1] - film[1]).abs() < 2e-3);
                assert!((ws.we / we - 1.0).abs() < 1e-3 && (ws.wi + ray.d).length() < 1e-3);
                let (pos, dir) = cam.pdf_we(p_lens, ray.d);
                assert!((pos * cam.lens_area() - 1.0).abs() < 1e-5);
                assert!((dir / ws.pdf_dir_w - 1.0).abs() < 1e-3);
            }
        }
    }

    #[test]
    fn importance_integrates_to_one_over_the_image() {
        // ∫ We cos θ dω = 1 / A_lens (PBR 4ed §5.4.1), by uniform sampling of the hemisphere.
        let mut s = crate::sampling::Sampler::new(10, 0, 0);
        for cam in [Camera::new(&desc(), 64, 32), thin_lens()] {
            let n = 400_000;
            let fwd = cam.forward();
            let frame = crate::math::Frame::from_normal(fwd);
            let p_lens = cam.lens_point([0.3, 0.6]);
            let mut sum = 0.0f64;
            for _ in 0..n {
                let w = frame.to_world(crate::sampling::warp::uniform_sphere(s.get_2d()));
                let (we, _) = cam.we(p_lens, w);
                sum += (we * w.dot(fwd).max(0.0)) as f64 * 4.0 * std::f64::consts::PI;
            }
            let est = sum / n as f64 * cam.lens_area() as f64;
            assert!((est - 1.0).abs() < 0.02, "{est}");
        }
    }

    #[test]
    fn points_outside_the_clipping_range_are_not_seen() {
        let cam = Camera::new(&desc(), 16, 16);
        assert!(cam
            .sample_wi(Vec3::new(0.0, 0.0, 3.9 - 0.0005), [0.5; 2])
            .is_none());
        assert!(cam
            .sample_wi(Vec3::new(0.0, 0.0, 3.9 - 200.0), [0.5; 2])
            .is_none());
        assert!(cam.sample_wi(Vec3::new(0.0, 0.0, 5.0), [0.5; 2]).is_none());
        let ws = cam.sample_wi(Vec3::new(0.0, 0.0, 0.0), [0.5; 2]).unwrap();
        assert!((ws.visible_fraction - (3.9 - 0.001) / 3.9).abs() < 1e-5);
    }

    #[test]
    fn footprint_of_a_plane_facing_the_camera() {
        // 256 pixels over 2·half_w at distance 1: a pixel at distance 2 spans 2·2·half_w/256
        // near the centre; the minimum (at the image corners, 27° off axis) is ~cos² of it.
        let cam = Camera::new(&desc(), 256, 256);
        let p = Vec3::new(0.0, 0.0, 3.9 - 2.0);
        let [dx, dy] = cam.approximate_dp_dxy(p, Vec3::Z, 1.0);
        let pixel = 4.0 * cam.half_w / 256.0;
        for d in [dx, dy] {
            assert!(d.z.abs() < 1e-6 * pixel, "{d}");
            assert!(
                d.length() < pixel && d.length() > 0.75 * pixel,
                "{d} vs {pixel}"
            );
        }
        // Not orthogonal (the two minima come from different film points, pbrt's too), but
        // spanning the plane.
        assert!(dx.cross(dy).length() > 0.5 * pixel * pixel);
        // Scaled by the factor, and linear in distance.
        let [sx, _] = cam.approximate_dp_dxy(p, Vec3::Z, 0.25);
        assert!((sx.length() / dx.length() - 0.25).abs() < 1e-5);
        let far = Vec3::new(0.0, 0.0, 3.9 - 6.0);
        let [fx, _] = cam.approximate_dp_dxy(far, Vec3::Z, 1.0);
        assert!((fx.length() / dx.length() - 3.0).abs() < 1e-3);
    }

    #[test]
    fn footprint_grows_at_grazing_angles_and_never_is_nan() {
        let cam = Camera::new(&desc(), 64, 64);
        let p = Vec3::new(0.0, 0.0, 0.0);
        let flat = cam.approximate_dp_dxy(p, Vec3::Z, 1.0);
        let tilted = cam.approximate_dp_dxy(p, Vec3::new(0.0, 0.995, 0.0998).normalize(), 1.0);
        let longest = |d: [Vec3; 2]| d[0].length().max(d[1].length());
        assert!(longest(tilted) > 5.0 * longest(flat));
        for n in [Vec3::Y, Vec3::X, Vec3::ZERO, Vec3::splat(f32::NAN)] {
            for d in cam.approximate_dp_dxy(p, n, 1.0) {
                assert!(d.is_finite(), "{n}: {d}");
            }
        }
        // At the camera's own position.
        for d in cam.approximate_dp_dxy(cam.position(), Vec3::Z, 1.0) {
            assert_eq!(d, Vec3::ZERO);
        }
    }
}
