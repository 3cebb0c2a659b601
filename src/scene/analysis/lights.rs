//! What the analysis needs to know about each light: its prim, whether it is point-like
//! (delta, or so small that BSDF sampling rarely finds it), infinite, textured or shaped.
//! The triangles of one emissive mesh are one light here.

use crate::light::Light;
use crate::scene::Scene;
use glam::Vec3;

/// The share of a cosine-weighted hemisphere a light may cover, seen from one scene radius
/// away, below which it is point-like: a BSDF-sampled ray from a diffuse surface hits it
/// with a probability under 0.25 % (a light of under a tenth of the scene's radius, or a
/// distant light of angular radius under 2.9°), so paths that reach it only through a
/// specular surface are found by path tracing as rarely as from a point light.
pub const POINT_LIKE_SHARE: f32 = 0.0025;

/// One light (one prim) as the analysis sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct LightInfo {
    pub prim: String,
    pub kind: &'static str,
    /// The share of a cosine-weighted hemisphere it covers from a scene radius away
    /// (sin²θ of the cone it subtends; 1 for a dome).
    pub share: f32,
    pub point_like: bool,
    pub infinite: bool,
    pub textured: bool,
    pub shaped: bool,
}

/// The scene's lights, one per prim, in scene order.
pub fn lights(scene: &Scene) -> Vec<LightInfo> {
    let mut out: Vec<LightInfo> = Vec::new();
    let mut mesh_bounds: Vec<(Vec3, Vec3)> = Vec::new();
    for light in &scene.lights {
        let prim = light.prim_path().to_string();
        if let Light::Triangle(t) = light {
            // Consecutive triangles of one mesh: grow its bounds.
            if let Some(last) = out
                .last_mut()
                .filter(|l| l.prim == prim && l.kind == "mesh")
            {
                let b = mesh_bounds.last_mut().expect("bounds of each mesh light");
                for p in t.p {
                    *b = (b.0.min(p), b.1.max(p));
                }
                last.textured |= t.texture.is_some();
                continue;
            }
            let lo = t.p[0].min(t.p[1]).min(t.p[2]);
            let hi = t.p[0].max(t.p[1]).max(t.p[2]);
            mesh_bounds.push((lo, hi));
        }
        out.push(info(light, prim, scene.radius));
    }
    // Mesh lights: the share of their bounding sphere.
    let mut bounds = mesh_bounds.into_iter();
    for l in out.iter_mut().filter(|l| l.kind == "mesh") {
        let (lo, hi) = bounds.next().expect("bounds of each mesh light");
        l.share = sphere_share(0.5 * (hi - lo).length(), scene.radius);
        l.point_like = l.share < POINT_LIKE_SHARE;
    }
    out
}

/// sin²θ of the cone a sphere of radius `r` subtends from `d` away (1 when within it).
fn sphere_share(r: f32, d: f32) -> f32 {
    (r * r / (d * d)).min(1.0)
}

fn info(light: &Light, prim: String, scene_radius: f32) -> LightInfo {
    let (kind, share, shaped, textured) = match light {
        Light::Triangle(t) => ("mesh", 0.0, false, t.texture.is_some()),
        Light::Rect(l) => {
            let r = 0.5 * l.edge_u.length().max(l.edge_v.length());
            (
                "rect",
                sphere_share(r, scene_radius),
                l.shaping.is_some(),
                false,
            )
        }
        Light::Disk(l) => (
            "disk",
            sphere_share(l.radius, scene_radius),
            l.shaping.is_some(),
            false,
        ),
        Light::Sphere(l) => (
            "sphere",
            sphere_share(l.radius, scene_radius),
            l.shaping.is_some(),
            false,
        ),
        Light::Cylinder(l) => {
            let r = l.radius.max(0.5 * l.length);
            (
                "cylinder",
                sphere_share(r, scene_radius),
                l.shaping.is_some(),
                false,
            )
        }
        // sin²θmax = (1 − cos)(1 + cos), from the exact 1 − cos.
        Light::Distant(l) => (
            "distant",
            l.one_minus_cos * (1.0 + l.cos_theta_max),
            false,
            false,
        ),
        Light::Dome(l) => ("dome", 1.0, false, l.map.is_some()),
        Light::Point(l) => ("point", 0.0, l.sphere.shaping.is_some(), false),
        Light::Line(l) => (
            "line",
            sphere_share(0.5 * l.length(), scene_radius),
            l.cylinder.shaping.is_some(),
            false,
        ),
    };
    LightInfo {
        prim,
        kind,
        share,
        point_like: share < POINT_LIKE_SHARE,
        infinite: light.is_infinite(),
        textured,
        shaped,
    }
}
