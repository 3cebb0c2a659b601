//! Multiple importance sampling for bidirectional estimators by recurrent partial weights
//! (Georgiev 2012, "Implementing Vertex Connection and Merging", tech. rep.; SmallVCM).
//!
//! For a full path built by technique s (s light vertices), the weight is
//! w_s = m(p_s) / Σ_j m(p_j), with m(x) = x for the balance and m(x) = x² for the power
//! heuristic (Veach 1997 eqs. 9.12, 9.13; m distributes over the products below, so both fit the
//! same recurrence). Dividing by m(p_s) gives [tech. rep. (37)]
//!
//!   w_s = 1 / (w_light + 1 + w_camera),
//!
//! where w_light = Σ_{j<s} m(p_j/p_s) and w_camera = Σ_{j>s} m(p_j/p_s) are computed from three
//! numbers cached at every subpath vertex, [`SubpathMis`] `dvcm`, `dvc`, `dvm`, so a connection
//! costs O(1) instead of O(path length). The quantities (for a light vertex y_i; camera vertices
//! are symmetric, with the camera in place of the light):
//!
//! - `dvcm` = m(1/p→(y_i)), the area density of y_i from its own subpath (after the direct
//!   sampling pdf of the light for i = 1, eq. 31);
//! - `dvc` gathers the techniques that would sample y_{i−1}, y_{i−2}, … from the other side,
//!   up to the geometry of the next, not yet known, connection.
//!
//! Conventions: pdfs named `_w` per solid angle, `_a` per area; "forward" is the direction a
//! subpath was built in, "reverse" the other one. Connections use one light subpath per camera
//! subpath, n_VC = 1, with the camera's importance normalised over the whole image (see
//! `sensor::camera`), so the report's N_L factors of connections drop out. Merging compares
//! against all N_L light subpaths of an iteration: η_VCM = π r² N_L / n_VC [tech. rep. (20)]
//! ([`Mis::vcm`]). Russian roulette is
//! not folded into the pdfs (as pbrt-v4's BDPT): the weights are still a partition of unity for
//! every path, which is all unbiasedness needs.
//!
//! **Merges only where they are available** (`merge_rule.rs`, [`MergeRule::Caustic`]): every
//! merge term of the recurrences below is multiplied by the availability a(x_i) ∈ {0, 1} of
//! merging at the vertex x_i it stands for. Which vertex that is, and which flag it takes, is
//! derived in `merge_rule.rs`; [`Mis::merge_at`] is the η term of a merge at a vertex whose
//! light-order predecessor is (or is not) near-specular.

pub use super::merge_rule::MergeRule;

/// Which heuristic turns technique pdfs into weights.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MisHeuristic {
    /// Veach 1997 eq. 9.10 (β = 1).
    Balance,
    /// Veach 1997 eq. 9.13 with β = 2.
    #[default]
    Power,
}

impl MisHeuristic {
    pub fn name(&self) -> &'static str {
        match self {
            MisHeuristic::Balance => "balance",
            MisHeuristic::Power => "power",
        }
    }
}

/// The MIS configuration of a render: the heuristic, the merging factors of VCM and where
/// merging is available.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mis {
    pub heuristic: MisHeuristic,
    /// At which vertices the merging technique exists (`merge_rule.rs`).
    pub merge_rule: MergeRule,
    /// m(η_VCM), η_VCM = π r² n_VM / n_VC [tech. rep. (20)] ("mMisVmWeightFactor"):
    /// the weight of a merge relative to a connection; 0 when nothing merges (BDPT).
    pub vm_weight: f32,
    /// m(1/η_VCM) ("mMisVcWeightFactor"), used by merging weights only; 0 for BDPT.
    pub vc_weight: f32,
}

impl Mis {
    /// Connections only: bidirectional path tracing and light tracing.
    pub fn bdpt(heuristic: MisHeuristic) -> Mis {
        Mis {
            heuristic,
            merge_rule: MergeRule::All,
            vm_weight: 0.0,
            vc_weight: 0.0,
        }
    }

    /// The same configuration with merging available where `rule` says.
    pub fn with_merge_rule(self, rule: MergeRule) -> Mis {
        Mis {
            merge_rule: rule,
            ..self
        }
    }

    /// True when merges depend on the vertices' materials ([`MergeRule::Caustic`] while
    /// anything merges).
    #[inline]
    pub fn caustic(&self) -> bool {
        self.merge_rule == MergeRule::Caustic && self.vm_weight > 0.0
    }

    /// m(η_VCM) for merging at a vertex whose light-order predecessor is near-specular
    /// (`after_near_specular`), 0 when the merge rule makes that merge unavailable
    /// (`merge_rule.rs`: a(x_i) · m(η)).
    #[inline]
    pub fn merge_at(&self, after_near_specular: bool) -> f32 {
        if after_near_specular || self.merge_rule == MergeRule::All {
            self.vm_weight
        } else {
            0.0
        }
    }

    /// Vertex connection and merging with η_VCM = π r² N_L [tech. rep. (20); SmallVCM's
    /// `mMisVmWeightFactor`, `mMisVcWeightFactor`]: `connect` false leaves only merging
    /// (bidirectional photon mapping, where no connection competes: m(1/η) is 0), `merge`
    /// false only connections (BDPT).
    pub fn vcm(heuristic: MisHeuristic, eta: f32, connect: bool, merge: bool) -> Mis {
        let m = |x: f32| Mis::bdpt(heuristic).m(x);
        Mis {
            heuristic,
            merge_rule: MergeRule::All,
            vm_weight: if merge { m(eta) } else { 0.0 },
            vc_weight: if connect { m(1.0 / eta) } else { 0.0 },
        }
    }

    /// Merging light vertex y_i at the meter point z_0 (an irradiance meter): no technique is
    /// more light-sided, and all others are reached through y_i's partial weights with the
    /// meter's ray density `pdf_dir` towards y_{i−1} (Mis::merge with w_camera = 0).
    #[inline]
    pub fn merge_at_sensor(&self, dvcm_y: f32, dvm_y: f32, pdf_dir: f32) -> f32 {
        weight(1.0 + dvcm_y * self.vc_weight + dvm_y * self.m(pdf_dir))
    }

    /// Merging camera vertex z_j with light vertex y_i (SmallVCM's merge weight, tech. rep.
    /// (38), (39)): w_light = dVCM_y · m(1/η) + dVM_y · m(p→_z(ω_y)), the techniques that
    /// build more of the path from the light side, with `pdf_dir` the camera BSDF's density
    /// towards y_{i−1}; w_camera = dVCM_z · m(1/η) + dVM_z · m(p←_z(ω_z)), with `pdf_rev` its
    /// density of the camera direction from ω_y.
    #[inline]
    pub fn merge(
        &self,
        dvcm_y: f32,
        dvm_y: f32,
        cam: &SubpathMis,
        pdf_dir: f32,
        pdf_rev: f32,
    ) -> f32 {
        let w_light = dvcm_y * self.vc_weight + dvm_y * self.m(pdf_dir);
        let w_camera = cam.dvcm * self.vc_weight + cam.dvm * self.m(pdf_rev);
        weight(w_light + 1.0 + w_camera)
    }

    /// m(x): the heuristic applied to one pdf or pdf ratio.
    #[inline]
    pub fn m(&self, x: f32) -> f32 {
        match self.heuristic {
            MisHeuristic::Balance => x,
            MisHeuristic::Power => x * x,
        }
    }

    /// Connecting light vertex y_{s−1} to camera vertex z_{t−1} (s, t ≥ 2)
    /// [tech. rep. (37), (40), (41)]; the densities are described at [`ConnectionPdfs`]. The
    /// η term of w_light is merging at y_{s−1} (`light_merges`: y_{s−1}'s own availability),
    /// that of w_camera merging at z_{t−1}, whose light-order predecessor is y_{s−1}
    /// (`light_near_specular`) (`merge_rule.rs`).
    #[inline]
    pub fn connect(
        &self,
        light: &SubpathMis,
        cam: &SubpathMis,
        pdfs: ConnectionPdfs,
        light_merges: bool,
        light_near_specular: bool,
    ) -> f32 {
        let w_light = self.m(pdfs.cam_fwd_a)
            * (self.merge_at(light_merges) + light.dvcm + light.dvc * self.m(pdfs.light_rev_w));
        let w_camera = self.m(pdfs.light_fwd_a)
            * (self.merge_at(light_near_specular) + cam.dvcm + cam.dvc * self.m(pdfs.cam_rev_w));
        weight(w_light + 1.0 + w_camera)
    }

    /// Light vertex y_{s−1} (s ≥ 2) connected to the camera, t = 1 [tech. rep. (46), (47),
    /// (37)]; `cam_a` is the density with which a camera ray would find y_{s−1} (with n_L = 1).
    /// `sensor_merge` is the ratio of merging at the meter's point, when VCM does
    /// ([`Mis::sensor_merge_ratio`]), 0 otherwise; `light_merges` whether merging at y_{s−1}
    /// is available (`merge_rule.rs`).
    #[inline]
    pub fn light_to_camera(
        &self,
        light: &SubpathMis,
        cam_a: f32,
        light_rev_w: f32,
        sensor_merge: f32,
        light_merges: bool,
    ) -> f32 {
        let w_light = self.m(cam_a)
            * (self.merge_at(light_merges) + light.dvcm + light.dvc * self.m(light_rev_w));
        weight(w_light + 1.0 + sensor_merge)
    }

    /// Merging at an irradiance meter's point relative to the connection of the same light
    /// vertex to it: m(p_a · η), with `land_a` the density per area at the meter point (on its
    /// normal) with which the light subpath would have landed there; `light_near_specular`:
    /// the light vertex connected, the merge's light-order predecessor, is near-specular.
    #[inline]
    pub fn sensor_merge_ratio(&self, land_a: f32, light_near_specular: bool) -> f32 {
        if land_a > 0.0 {
            self.m(land_a) * self.merge_at(light_near_specular)
        } else {
            0.0
        }
    }

    /// The light's own point y_0 seen by the camera (s = 1, t = 1): the only other technique
    /// for this two-vertex path is the camera ray hitting it (s = 0), so
    /// w = 1 / (1 + m(p_cam_a / (pmf · p_pos_a))) (eq. (37) with n = 2). For an infinite
    /// light connected to a meter both densities are per solid angle at the meter: the
    /// meter's ray density and pmf · p_dir of the light's emitted direction.
    #[inline]
    pub fn origin_to_camera(&self, cam_a: f32, emit_pos_a: f32, sensor_merge: f32) -> f32 {
        weight(1.0 + self.m(cam_a / emit_pos_a) + sensor_merge)
    }

    /// Next-event estimation at camera vertex z_{t−1}, s = 1 [tech. rep. (44), (45), (37)].
    /// `direct_w` = pmf · the light-sampling density at z (1 relative to a delta);
    /// `emit` = pmf · p_pos_a · p_dir_w of emitting the same ray from the light;
    /// `cos_cam` (geometric, at z) and `cos_light` (1 for infinite lights) convert it;
    /// `bsdf_fwd_w` / `bsdf_rev_w` are z's BSDF densities towards the light / back. The η term
    /// is merging at z, whose light-order predecessor is the light itself: never
    /// near-specular (`merge_rule.rs`).
    #[inline]
    pub fn direct(&self, cam: &SubpathMis, p: DirectPdfs) -> f32 {
        let w_light = if p.delta {
            0.0
        } else {
            self.m(p.bsdf_fwd_w / p.direct_w)
        };
        let w_camera = self.m(p.emit * p.cos_cam / (p.direct_w * p.cos_light))
            * (self.merge_at(false) + cam.dvcm + cam.dvc * self.m(p.bsdf_rev_w));
        weight(w_light + 1.0 + w_camera)
    }

    /// A camera path that finds an emitter, s = 0 [tech. rep. (42), (43), (37)]:
    /// w_camera = m(direct_a) · dVCM + m(emit) · dVC, with `direct_a` the light-sampling
    /// density of the point per area (per solid angle for infinite lights, whose camera
    /// quantities are not yet divided by the distance, §5.1) and `emit` = pmf · p_pos · p_dir.
    #[inline]
    pub fn emitter_hit(&self, cam: &SubpathMis, direct_a: f32, emit: f32) -> f32 {
        let mut w_camera = self.m(direct_a) * cam.dvcm;
        if cam.dvc != 0.0 {
            w_camera += self.m(emit) * cam.dvc;
        }
        weight(1.0 + w_camera)
    }
}

/// The four densities of a vertex connection, see [`Mis::connect`].
#[derive(Clone, Copy, Debug)]
pub struct ConnectionPdfs {
    /// Density of the light vertex when the camera vertex's BSDF samples it, per area.
    pub cam_fwd_a: f32,
    /// The light vertex's BSDF density towards its predecessor, given the connection.
    pub light_rev_w: f32,
    /// Density of the camera vertex when the light vertex's BSDF samples it, per area.
    pub light_fwd_a: f32,
    /// The camera vertex's BSDF density towards its predecessor, given the connection.
    pub cam_rev_w: f32,
}

/// The densities of next-event estimation, see [`Mis::direct`].
#[derive(Clone, Copy, Debug)]
pub struct DirectPdfs {
    pub direct_w: f32,
    pub emit: f32,
    pub cos_cam: f32,
    pub cos_light: f32,
    pub bsdf_fwd_w: f32,
    pub bsdf_rev_w: f32,
    pub delta: bool,
}

/// 1 / denominator, 0 when the denominator overflowed or is not a number.
#[inline]
fn weight(denominator: f32) -> f32 {
    if denominator.is_finite() && denominator > 0.0 {
        1.0 / denominator
    } else {
        0.0
    }
}

/// Partial MIS weights cached along a subpath ("dVCM", "dVC", "dVM" of SmallVCM).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubpathMis {
    pub dvcm: f32,
    pub dvc: f32,
    pub dvm: f32,
}

impl SubpathMis {
    /// A camera subpath whose first ray has direction density `pdf_dir_w` [tech. rep. (31)–(33),
    /// the part known before tracing]: dVCM = m(n_L / p_dir_w) with n_L = 1, dVC = dVM = 0
    /// (no technique samples the lens from the light side, t = 0).
    #[inline]
    pub fn camera_start(mis: &Mis, pdf_dir_w: f32) -> SubpathMis {
        SubpathMis {
            dvcm: mis.m(1.0 / pdf_dir_w),
            dvc: 0.0,
            dvm: 0.0,
        }
    }

    /// The start of an irradiance meter's subpath when merging also happens at the meter
    /// point (a light vertex within the radius of it, `merge::LightVertexStore::merge_at_sensor`):
    /// that technique, t = 0 through merging, is the most light-sided of all, so it enters
    /// every other technique's weight from the camera side as the light's own start does for
    /// s = 0 [tech. rep. (31)–(33) with the roles of the subpaths exchanged]: dVC = m(cos/p_dir) ·
    /// m(η) (as a merge relative to connections), dVM = m(cos/p_dir), with `cos` the meter's
    /// cosine of its first ray and the meter's position density 1 (a delta).
    #[inline]
    pub fn meter_start_with_sensor_merges(mis: &Mis, pdf_dir_w: f32, cos: f32) -> SubpathMis {
        let hit = mis.m(cos.abs() / pdf_dir_w);
        SubpathMis {
            dvcm: mis.m(1.0 / pdf_dir_w),
            dvc: hit * mis.vm_weight,
            dvm: hit,
        }
    }

    /// A camera subpath whose sensor direction is a Dirac delta (a luminance meter: one point,
    /// one direction). No technique with t ≤ 1 can produce its paths — the light side would
    /// have to hit the sensor's single direction — so everything that would weigh them is 0:
    /// the limit of (31)–(33) as p_dir → ∞, as the specular update (53)–(55) zeroes dVCM
    /// (Veach 1997 §10.3.5: a technique needing to sample a delta by other means has
    /// density 0). Techniques t ≥ 2 then share the weight among themselves.
    #[inline]
    pub fn delta_sensor_start() -> SubpathMis {
        SubpathMis::default()
    }

    /// A light subpath emitted with `emit` = pmf · p_pos_a · p_dir_w [tech. rep. (31)–(33),
    /// delta lights (48)–(50)]: dVCM = m(1/emit) (the direct-sampling density is multiplied in
    /// by [`SubpathMis::light_direct`] once the first hit is known), dVC = m(cos_light/emit),
    /// 0 for a delta direction, which no other technique can sample; dVM = dVC · m(1/η_VCM).
    #[inline]
    pub fn light_start(mis: &Mis, emit: f32, cos_light: f32, delta_dir: bool) -> SubpathMis {
        let dvc = if delta_dir {
            0.0
        } else {
            mis.m(cos_light / emit)
        };
        SubpathMis {
            dvcm: mis.m(1.0 / emit),
            dvc,
            dvm: dvc * mis.vc_weight,
        }
    }

    /// Completes eq. (31) at the first light vertex y_1: multiplies dVCM by the density of
    /// next-event estimation from y_1 choosing y_0, `direct` = pmf · p_direct_a (finite lights,
    /// per area at y_0) or pmf · p_li_w (infinite lights, §5.1). SmallVCM takes this density
    /// from the emitter alone; ours depends on y_1 (cone sampling of spheres), hence it is
    /// applied once y_1 is known.
    #[inline]
    pub fn light_direct(&mut self, mis: &Mis, direct: f32) {
        self.dvcm *= mis.m(direct);
    }

    /// At a newly found vertex, distance² `dist2` from the previous one, geometric cosine
    /// `cos_geo` [tech. rep. (31)–(36), the part after tracing]: dVCM · m(d²) (not for the first
    /// segment of an infinite light, §5.1), all three divided by m(|cos θ|). Returns that
    /// divisor m(|cos θ|), which a pending merge term is divided by too.
    #[inline]
    pub fn at_hit(&mut self, mis: &Mis, dist2: f32, cos_geo: f32, from_infinite: bool) -> f32 {
        if !from_infinite {
            self.dvcm *= mis.m(dist2);
        }
        let c = mis.m(cos_geo.abs());
        self.dvcm /= c;
        self.dvc /= c;
        self.dvm /= c;
        c
    }

    /// After sampling the next direction with density `pdf_fwd_w` (reverse density
    /// `pdf_rev_w`, geometric cosine of the new direction `cos_out`): non-specular
    /// [tech. rep. (34)–(36)], specular [tech. rep. (53)–(55)]. The terms of merging at the
    /// vertex left (m(η) in dVC, the 1 of dVM) are multiplied by `merge` ∈ {0, 1}, its
    /// availability (`merge_rule.rs`). Returns m(|cos| / p_fwd) of a non-specular vertex
    /// (0 for a specular one, where nothing merges): what those terms are multiplied by, for a
    /// walk that learns the availability only at the next vertex ([`SubpathMis::add_merge`]).
    #[inline]
    pub fn scatter(
        &mut self,
        mis: &Mis,
        cos_out: f32,
        pdf_fwd_w: f32,
        pdf_rev_w: f32,
        specular: bool,
        merge: f32,
    ) -> f32 {
        let g = mis.m(cos_out.abs() / pdf_fwd_w);
        let rev = mis.m(pdf_rev_w);
        if specular {
            self.dvcm = 0.0;
            self.dvc *= g * rev;
            self.dvm *= g * rev;
            0.0
        } else {
            self.dvc = g * (self.dvc * rev + self.dvcm + mis.vm_weight * merge);
            self.dvm = g * (self.dvm * rev + self.dvcm * mis.vc_weight + merge);
            self.dvcm = mis.m(1.0 / pdf_fwd_w);
            g
        }
    }

    /// Adds the terms of a merge found available after the walk moved on (camera subpaths
    /// under [`MergeRule::Caustic`], `merge_rule.rs`): `pending` is what [`SubpathMis::scatter`]
    /// returned, divided since by the same cosines as dVC and dVM. dVC gains m(η) · pending,
    /// dVM pending, as if `scatter` had been called with `merge` = 1.
    #[inline]
    pub fn add_merge(&mut self, mis: &Mis, pending: f32) {
        self.dvc += pending * mis.vm_weight;
        self.dvm += pending;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heuristics() {
        let b = Mis::bdpt(MisHeuristic::Balance);
        let p = Mis::bdpt(MisHeuristic::Power);
        assert_eq!(b.m(3.0), 3.0);
        assert_eq!(p.m(3.0), 9.0);
        assert_eq!(weight(f32::INFINITY), 0.0);
        assert_eq!(weight(f32::NAN), 0.0);
    }

    #[test]
    fn two_vertex_paths_split_between_camera_hit_and_light_tracing() {
        // n = 2: w(0,2) + w(1,1) = 1 for any pair of densities.
        for h in [MisHeuristic::Balance, MisHeuristic::Power] {
            let mis = Mis::bdpt(h);
            let (cam_a, pos_a) = (0.7f32, 2.5f32);
            let cam = SubpathMis {
                dvcm: mis.m(1.0 / cam_a),
                ..Default::default()
            };
            let w0 = mis.emitter_hit(&cam, pos_a, 123.0);
            let w1 = mis.origin_to_camera(cam_a, pos_a, 0.0);
            assert!((w0 + w1 - 1.0).abs() < 1e-6);
        }
    }
}
