//! UsdLux PortalLight: a rectangle (local XY, `width` × `height`) through which a dome light
//! enters an interior; the dome's light passes along the portal's local −Z. UsdLux makes
//! portals a sampling hint that does not change the image, so a dome with portals samples a
//! one-sample mixture (Veach 1997 §9.2.2, the balance heuristic in its one-sample form):
//! with probability α a point uniform on a portal facing the receiver (the direction towards
//! it, area density converted to solid angle by PBR 4ed eq. 4.9), else the dome's own
//! distribution; the density of either is the mixture
//!   p(ω) = α · (1/k) Σ_portals p_portal(ω) + (1 − α) · p_dome(ω),
//! positive wherever the dome's is, so every direction stays reachable and the estimate
//! unbiased (light arriving other than through the portals included). α = ½ for a receiver on
//! the inner side of at least one portal, 0 elsewhere (outside, nothing is guided). pbrt-v4's
//! `PortalImageInfiniteLight` samples only through its portal instead, which is exact only
//! for a room closed everywhere else.

use glam::Vec3;

/// The probability of the portal strategy for a receiver that faces a portal.
pub const PORTAL_SHARE: f32 = 0.5;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    /// A corner and the two edges from it.
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Unit normal towards the dome side (the portal's local +Z).
    pub n_out: Vec3,
    pub area: f32,
}

impl Portal {
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3, out: Vec3) -> Option<Portal> {
        let c = edge_u.cross(edge_v);
        let area = c.length();
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
        let n = c / area;
        Some(Portal {
            corner,
            edge_u,
            edge_v,
            n_out: if n.dot(out) < 0.0 { -n } else { n },
            area,
        })
    }

    /// True when `p` is on the inner side (where the portal's light arrives).
    pub fn faces(&self, p: Vec3) -> bool {
        self.n_out.dot(p - self.corner) < 0.0
    }

    /// The direction from `p` towards the point of the portal at `u`, with its solid-angle
    /// density.
    pub fn sample(&self, p: Vec3, u: [f32; 2]) -> Option<(Vec3, f32)> {
        let q = self.corner + u[0] * self.edge_u + u[1] * self.edge_v;
        let d = q - p;
        let dist2 = d.length_squared();
        let wi = d / dist2.sqrt();
        let cos = self.n_out.dot(wi);
        let pdf = dist2 / (self.area * cos);
        (cos > 0.0 && pdf.is_finite()).then_some((wi, pdf))
    }

    /// The solid-angle density of [`Portal::sample`] from `p` towards unit `wi`: d²/(A cos)
    /// where the ray meets the rectangle, 0 elsewhere.
    pub fn pdf(&self, p: Vec3, wi: Vec3) -> f32 {
        let cos = self.n_out.dot(wi);
        if cos <= 0.0 {
            return 0.0;
        }
        let t = self.n_out.dot(self.corner - p) / cos;
        if !(t > 0.0 && t.is_finite()) {
            return 0.0;
        }
        // q = a·e_u + b·e_v by the dual basis (a parallelogram under a sheared transform too).
        let q = p + t * wi - self.corner;
        let n = self.edge_u.cross(self.edge_v);
        let n2 = n.length_squared();
        let (a, b) = (
            q.cross(self.edge_v).dot(n) / n2,
            self.edge_u.cross(q).dot(n) / n2,
        );
        if !(0.0..=1.0).contains(&a) || !(0.0..=1.0).contains(&b) {
            return 0.0;
        }
        t * t / (self.area * cos)
    }
}

/// The portals facing `p` (indices into `portals`), and the share α of the portal strategy.
pub fn facing(portals: &[Portal], p: Vec3) -> (Vec<usize>, f32) {
    let f: Vec<usize> = (0..portals.len())
        .filter(|&i| portals[i].faces(p))
        .collect();
    let alpha = if f.is_empty() { 0.0 } else { PORTAL_SHARE };
    (f, alpha)
}

/// The density of the portal strategy from `p` towards `wi` (the mean over facing portals).
pub fn pdf(portals: &[Portal], facing: &[usize], p: Vec3, wi: Vec3) -> f32 {
    if facing.is_empty() {
        return 0.0;
    }
    let sum: f32 = facing.iter().map(|&i| portals[i].pdf(p, wi)).sum();
    sum / facing.len() as f32
}
