//! What a stage calls for: the scene analysis. It runs once on the built scene
//! (`scene::build`) and gives [`SceneFeatures`]: each feature on or off, with the reason and
//! the prims that cause it. `spectral-render info` prints it; `--integrator auto` narrows its
//! candidates with it (`integrator::auto`).
//!
//! - `lobes.rs`: each material's lobe kinds (pbrt's `BxDFFlags`), from which the path
//!   classes follow: L S+ D (caustics) where light meets a specular surface and then one
//!   that scatters it (diffuse or glossy, with some albedo), E S+ D S+ L (SDS) where the
//!   camera also sees specular surfaces;
//! - `lights.rs`: point-like, infinite, textured and shaped lights;
//! - `albedo.rs`: each material's largest albedo, which bounds what a depth cap cuts.

pub mod albedo;
pub mod lights;
pub mod lobes;

use super::render_scene::{Hit, Scene};
use crate::material::Material;
use lights::LightInfo;
use lobes::Lobes;

/// Camera rays per side of the grid that looks for specular surfaces in view.
const PROBE_GRID: u32 = 32;

/// One feature of a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Feature {
    pub on: bool,
    /// Why it is on or off, one sentence.
    pub reason: String,
    /// The prims that cause it (materials, meshes, lights or the camera).
    pub prims: Vec<String>,
}

/// A material the scene's meshes use.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialInfo {
    /// The material prim (`(default material)` for unbound meshes).
    pub prim: String,
    pub lobes: Lobes,
    /// Its largest white-sky albedo over wavelengths (`albedo.rs`).
    pub albedo: f32,
    pub dispersive: bool,
    /// Some input reads a texture (BSDF, opacity or normal).
    pub textured: bool,
    pub opaque: bool,
    pub normal_map: bool,
    /// The meshes bound to it.
    pub meshes: Vec<String>,
}

/// Everything the analysis found. [`SceneFeatures::all`] lists the features by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneFeatures {
    /// Dielectrics whose IOR varies with λ.
    pub dispersion: Feature,
    /// Materials with specular or near-specular lobes.
    pub specular: Feature,
    /// L S+ D paths: light reaching diffuse surfaces through specular ones.
    pub caustics: Feature,
    /// E S+ D S+ L paths: caustics seen through specular surfaces.
    pub sds: Feature,
    /// Point-like lights (delta, or tiny: `lights::POINT_LIKE_SHARE`).
    pub delta_lights: Feature,
    pub infinite_lights: Feature,
    pub textured_lights: Feature,
    pub shaped_lights: Feature,
    /// More than one light (next-event estimation chooses among them).
    pub multiple_lights: Feature,
    pub textures: Feature,
    /// Partially opaque surfaces and cut-outs.
    pub opacity: Feature,
    pub normal_maps: Feature,
    /// A thin-lens camera.
    pub depth_of_field: Feature,
    pub emissive_meshes: Feature,
    /// Interreflection matters: the largest albedo is at least 0.5.
    pub albedo: Feature,
    /// Caustics of point-like lights fall on diffuse-like surfaces (diffuse, or glossy of
    /// α ≥ `lobes::NEAR_SPECULAR_ALPHA`): a path tracer finds them only by hitting the light
    /// with a BSDF-sampled ray, which its small size makes rare. (On near-specular receivers
    /// the narrow lobe aims at the light, as on `scenes/prism.usda`'s satin screen.)
    pub hard_caustics: bool,
    /// The largest albedo of any material in use.
    pub max_albedo: f32,
    /// The share of the camera's view whose first surface is specular-like.
    pub seen_specular: f32,
    pub materials: Vec<MaterialInfo>,
    pub lights: Vec<LightInfo>,
}

impl SceneFeatures {
    /// Every feature with its name (the names of `info --json`).
    pub fn all(&self) -> [(&'static str, &Feature); 15] {
        [
            ("dispersion", &self.dispersion),
            ("specular", &self.specular),
            ("caustics", &self.caustics),
            ("sds", &self.sds),
            ("delta_lights", &self.delta_lights),
            ("infinite_lights", &self.infinite_lights),
            ("textured_lights", &self.textured_lights),
            ("shaped_lights", &self.shaped_lights),
            ("multiple_lights", &self.multiple_lights),
            ("textures", &self.textures),
            ("opacity", &self.opacity),
            ("normal_maps", &self.normal_maps),
            ("depth_of_field", &self.depth_of_field),
            ("emissive_meshes", &self.emissive_meshes),
            ("albedo", &self.albedo),
        ]
    }

    /// An upper bound of the light a cap of `max_depth` scattering events cuts, as a
    /// multiple of the light that arrives after none: every scattering keeps at most
    /// ρ_max of it, so depths beyond the cap carry at most ρ_max^d / (1 − ρ_max) (the
    /// geometric tail). `None` when ρ_max reaches 1 (a lossless material: no bound).
    pub fn bound_cut(&self, max_depth: u32) -> Option<f64> {
        let rho = f64::from(self.max_albedo);
        (rho < 1.0).then(|| rho.powi(max_depth.min(i32::MAX as u32) as i32) / (1.0 - rho))
    }
}

/// The features of `scene`, whose material `i` is the prim `material_paths[i]` (the builder
/// appends a default material for unbound meshes after them).
pub fn analyze(scene: &Scene, material_paths: &[String]) -> SceneFeatures {
    let materials = materials(scene, material_paths);
    let lights = lights::lights(scene);
    let (seen_specular, seen) = probe_specular(scene);
    let mut f = SceneFeatures {
        max_albedo: materials.iter().map(|m| m.albedo).fold(0.0, f32::max),
        seen_specular,
        ..Default::default()
    };
    material_features(&mut f, &materials);
    path_classes(&mut f, scene, &materials, seen);
    light_features(&mut f, &lights);
    camera_feature(&mut f, scene);
    albedo_feature(&mut f, &materials);
    f.hard_caustics = f.caustics.on
        && f.delta_lights.on
        && materials
            .iter()
            .any(|m| m.albedo > 0.0 && m.lobes.diffuse_like());
    f.materials = materials;
    f.lights = lights;
    f
}

/// The materials the meshes use, in material order.
fn materials(scene: &Scene, paths: &[String]) -> Vec<MaterialInfo> {
    let mut out = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        let meshes: Vec<String> = scene
            .meshes
            .iter()
            .filter(|mesh| mesh.material as usize == i)
            .map(|mesh| mesh.prim_path.clone())
            .collect();
        if meshes.is_empty() {
            continue;
        }
        out.push(MaterialInfo {
            prim: paths
                .get(i)
                .cloned()
                .unwrap_or_else(|| "(default material)".into()),
            lobes: lobes::lobes(m),
            albedo: albedo::albedo(m),
            dispersive: m.is_dispersive(),
            textured: m.is_textured()
                || matches!(m, Material::Preview(p) if !p.textures.is_empty()),
            opaque: m.is_opaque(),
            normal_map: m.perturbs_normal(),
            meshes,
        });
    }
    out
}

/// A feature that is on when `prims` is not empty.
fn feature(prims: Vec<String>, on: impl FnOnce(&[String]) -> String, off: &str) -> Feature {
    Feature {
        on: !prims.is_empty(),
        reason: if prims.is_empty() {
            off.to_string()
        } else {
            on(&prims)
        },
        prims,
    }
}

/// The prims of the `items` for which `keep` holds.
fn prims_of<T: HasPrim>(items: &[T], keep: impl Fn(&T) -> bool) -> Vec<String> {
    items
        .iter()
        .filter(|i| keep(i))
        .map(|i| i.prim().to_string())
        .collect()
}

/// Something the analysis names by its prim.
trait HasPrim {
    fn prim(&self) -> &str;
}

impl HasPrim for MaterialInfo {
    fn prim(&self) -> &str {
        &self.prim
    }
}

impl HasPrim for LightInfo {
    fn prim(&self) -> &str {
        &self.prim
    }
}

fn material_features(f: &mut SceneFeatures, materials: &[MaterialInfo]) {
    f.dispersion = feature(
        prims_of(materials, |m| m.dispersive),
        |p| {
            format!(
                "{} refracts each wavelength its own way: paths through it carry their hero \
                 wavelength alone",
                p.join(", ")
            )
        },
        "no dielectric's IOR varies with wavelength: secondary wavelengths are never terminated",
    );
    f.specular = feature(
        prims_of(materials, |m| m.lobes.specular_like()),
        |p| {
            let lobes: Vec<String> = materials
                .iter()
                .filter(|m| p.contains(&m.prim))
                .map(|m| format!("{} ({})", m.prim, m.lobes.names()))
                .collect();
            format!(
                "specular or near-specular (GGX α < {}) lobes: {}",
                lobes::NEAR_SPECULAR_ALPHA,
                lobes.join(", ")
            )
        },
        "every lobe is diffuse or glossy: no specular chains",
    );
    f.textures = feature(
        prims_of(materials, |m| m.textured),
        |p| format!("materials read textures: {}", p.join(", ")),
        "no material reads a texture",
    );
    f.opacity = feature(
        prims_of(materials, |m| !m.opaque),
        |p| {
            format!(
                "partially opaque or cut-out surfaces (UsdPreviewSurface opacity): {}",
                p.join(", ")
            )
        },
        "every surface is opaque",
    );
    f.normal_maps = feature(
        prims_of(materials, |m| m.normal_map),
        |p| format!("normals perturbed by {}", p.join(", ")),
        "no normal maps",
    );
}

/// Caustics (L S+ D) and SDS (E S+ D S+ L) from the lobes, the lights and what the camera
/// sees (`seen`: the specular meshes in view).
fn path_classes(f: &mut SceneFeatures, scene: &Scene, m: &[MaterialInfo], seen: Vec<String>) {
    let focusing: Vec<String> = m
        .iter()
        .filter(|m| m.lobes.specular_like())
        .flat_map(|m| m.meshes.iter().cloned())
        .collect();
    let receives = m
        .iter()
        .any(|m| m.albedo > 0.0 && m.lobes.intersects(Lobes::DIFFUSE | Lobes::GLOSSY));
    let why_not = if focusing.is_empty() {
        Some("no specular surface")
    } else if !receives {
        Some("no diffuse or glossy surface to receive light through the specular ones")
    } else if scene.lights.is_empty() {
        Some("no lights")
    } else {
        None
    };
    if let Some(why) = why_not {
        f.caustics = feature(
            Vec::new(),
            |_| String::new(),
            &format!("{why}: no L S+ D paths"),
        );
        f.sds = feature(
            Vec::new(),
            |_| String::new(),
            &format!("{why}: no SDS paths"),
        );
        return;
    }
    f.caustics = feature(
        focusing,
        |p| {
            format!(
                "light reaches diffuse or glossy surfaces through the specular surfaces of {} \
                 (L S+ D paths)",
                p.join(", ")
            )
        },
        "",
    );
    let share = f.seen_specular;
    f.sds = feature(
        seen,
        |p| {
            format!(
                "the camera sees specular surfaces ({:.0} % of its view: {}), so caustics may \
                 be seen through them (E S+ D S+ L paths)",
                100.0 * share,
                p.join(", ")
            )
        },
        "the camera sees no specular surface: caustics are seen directly only",
    );
}

/// The share of a grid of camera rays whose first hit is specular-like, and the meshes hit.
fn probe_specular(scene: &Scene) -> (f32, Vec<String>) {
    let cam = &scene.camera;
    let mut seen: Vec<String> = Vec::new();
    let mut hits = 0;
    for j in 0..PROBE_GRID {
        for i in 0..PROBE_GRID {
            let film = [
                (i as f32 + 0.5) / PROBE_GRID as f32 * cam.width as f32,
                (j as f32 + 0.5) / PROBE_GRID as f32 * cam.height as f32,
            ];
            if let Some(prim) = specular_at(scene, film) {
                hits += 1;
                if !seen.iter().any(|p| p == prim) {
                    seen.push(prim.to_string());
                }
            }
        }
    }
    (hits as f32 / (PROBE_GRID * PROBE_GRID) as f32, seen)
}

/// The prim of the specular or near-specular surface the camera ray through film point `film`
/// hits first, if it hits one.
fn specular_at(scene: &Scene, film: [f32; 2]) -> Option<&str> {
    let (ray, t_max) = scene.camera.generate_ray(film, [0.5, 0.5]);
    let Some(Hit::Surface(h)) = scene.intersect(&ray, t_max) else {
        return None;
    };
    let specular = lobes::lobes(&scene.materials[h.material as usize]).specular_like();
    specular.then(|| scene.meshes[h.tri.mesh as usize].prim_path.as_str())
}

/// Whether the camera ray through film point `film` (pixels, at the lens centre) first hits
/// an emitter: an analytic light shape, an emissive triangle, or nothing at all while the
/// scene has an infinite light (a dome or distant light seen directly).
pub fn sees_emitter_at(scene: &Scene, film: [f32; 2]) -> bool {
    let (ray, t_max) = scene.camera.generate_ray(film, [0.5, 0.5]);
    match scene.intersect(&ray, t_max) {
        Some(Hit::Light { .. }) => true,
        Some(Hit::Surface(s)) => s.light.is_some(),
        None => !scene.infinite_lights.is_empty(),
    }
}

/// Per pixel (rows of the camera's width), whether an emitter is seen in it or beside it: the
/// pixels whose centre ray sees one ([`sees_emitter_at`]) and their eight neighbours, so that
/// the emitter's rim, pixels it covers in part (the film's box filter is one pixel wide), is
/// included wherever the emitter is at least a pixel across. One ray per pixel.
pub fn emitter_pixels(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let centre: Vec<bool> = (0..w * h)
        .map(|i| sees_emitter_at(scene, [(i % w) as f32 + 0.5, (i / w) as f32 + 0.5]))
        .collect();
    let near = |x: usize, y: usize| {
        let (xs, ys) = (
            x.saturating_sub(1)..(x + 2).min(w),
            y.saturating_sub(1)..(y + 2).min(h),
        );
        ys.into_iter()
            .any(|j| xs.clone().any(|i| centre[j * w + i]))
    };
    (0..w * h).map(|i| near(i % w, i / w)).collect()
}

/// Per pixel (rows of the camera's width), whether the camera ray through its centre sees a
/// specular or near-specular surface first: where paths of the kind E S+ … begin.
pub fn specular_pixels(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| [x as f32 + 0.5, y as f32 + 0.5]))
        .map(|film| specular_at(scene, film).is_some())
        .collect()
}

fn light_features(f: &mut SceneFeatures, lights: &[LightInfo]) {
    f.delta_lights = feature(
        prims_of(lights, |l| l.point_like),
        |p| {
            let each: Vec<String> = lights
                .iter()
                .filter(|l| p.contains(&l.prim))
                .map(|l| format!("{} ({}, {:.2} %)", l.prim, l.kind, 100.0 * l.share))
                .collect();
            format!(
                "point-like lights, covering under {} % of the hemisphere from a scene radius \
                 away (BSDF sampling rarely hits them): {}",
                100.0 * lights::POINT_LIKE_SHARE,
                each.join(", ")
            )
        },
        "no point-like light",
    );
    f.infinite_lights = feature(
        prims_of(lights, |l| l.infinite),
        |p| format!("dome or distant lights: {}", p.join(", ")),
        "no dome or distant light",
    );
    f.textured_lights = feature(
        prims_of(lights, |l| l.textured),
        |p| format!("emission read from textures: {}", p.join(", ")),
        "no textured emission",
    );
    f.shaped_lights = feature(
        prims_of(lights, |l| l.shaped),
        |p| format!("ShapingAPI (cone, focus or IES): {}", p.join(", ")),
        "no shaped light",
    );
    let all = prims_of(lights, |_| true);
    let n = all.len();
    f.multiple_lights = Feature {
        on: n > 1,
        reason: match n {
            0 => "no lights".into(),
            1 => format!("one light: {}", all[0]),
            n => format!(
                "{n} lights: next-event estimation picks one by its importance at the receiver \
                 (over up to 32 prims of bounded lights, down a light tree beyond), else by \
                 luminous power"
            ),
        },
        prims: if n > 1 { all } else { Vec::new() },
    };
    f.emissive_meshes = feature(
        prims_of(lights, |l| l.kind == "mesh"),
        |p| format!("emissive meshes: {}", p.join(", ")),
        "no emissive mesh",
    );
}

fn camera_feature(f: &mut SceneFeatures, scene: &Scene) {
    let cam = &scene.camera;
    f.depth_of_field = if cam.lens_radius > 0.0 {
        Feature {
            on: true,
            reason: format!(
                "thin lens of radius {:.4} m focused at {:.3} m",
                cam.lens_radius, cam.focus_distance
            ),
            prims: vec![cam.prim_path.clone()],
        }
    } else {
        feature(Vec::new(), |_| String::new(), "pinhole camera")
    };
}

fn albedo_feature(f: &mut SceneFeatures, materials: &[MaterialInfo]) {
    let rho = f.max_albedo;
    let prims = prims_of(materials, |m| m.albedo >= rho - 0.005 && rho > 0.0);
    let gain = if rho < 1.0 {
        format!("{:.2}", 1.0 / (1.0 - rho))
    } else {
        "unbounded".into()
    };
    let on = rho >= 0.5;
    f.albedo = Feature {
        on,
        reason: format!(
            "largest albedo {rho:.3} ({}): interreflection multiplies light by up to \
             1/(1 − ρ) = {gain}",
            if prims.is_empty() {
                "no materials".to_string()
            } else {
                prims.join(", ")
            }
        ),
        prims: if on { prims } else { Vec::new() },
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::*;
    use glam::{Mat4, Vec3};

    /// A square of half-side `half` centred on (x, 0, z) facing +Z, bound to `material`.
    fn square(name: &str, x: f32, z: f32, half: f32, material: usize) -> MeshDesc {
        MeshDesc {
            prim_path: name.into(),
            positions: vec![
                Vec3::new(x - half, -half, z),
                Vec3::new(x + half, -half, z),
                Vec3::new(x + half, half, z),
                Vec3::new(x - half, half, z),
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material: Some(material),
            ..Default::default()
        }
    }

    fn material(name: &str, kind: MaterialKind) -> MaterialDesc {
        MaterialDesc {
            prim_path: name.into(),
            kind,
            emission: None,
            textures: Vec::new(),
            texcoord: "st".into(),
        }
    }

    /// A 4 m floor of albedo 0.5 under a 0.6 m glass pane centred at x = `pane_x`, 0.3 m up,
    /// and a sphere light of radius `r` 1 m up, seen from above by a camera looking at the
    /// floor within `view` of its centre.
    fn glass_over_floor(pane_x: f32, r: f32, view: f32) -> Scene {
        let mut desc = SceneDescription::default();
        desc.materials.push(material(
            "/Looks/Floor",
            MaterialKind::Diffuse {
                reflectance: SpectrumDesc::Rgb([0.5; 3]),
                roughness: 0.0,
            },
        ));
        desc.materials.push(material(
            "/Looks/Glass",
            MaterialKind::Dielectric {
                ior: IorDesc::Constant(1.5),
                roughness: 0.0,
                thin: false,
            },
        ));
        desc.meshes.push(square("/Floor", 0.0, 0.0, 2.0, 0));
        desc.meshes.push(square("/Pane", pane_x, 0.3, 0.3, 1));
        desc.lights.push(LightDesc {
            prim_path: "/Bulb".into(),
            kind: LightKind::Sphere {
                radius: r,
                point: false,
            },
            to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)),
            emission: EmissionDesc::default(),
            shaping: None,
            shadows: true,
        });
        let half = 18f32.to_radians().tan();
        desc.cameras.push(CameraDesc {
            prim_path: "/Camera".into(),
            to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, view / half)),
            focal_length: 50.0,
            horizontal_aperture: 100.0 * half,
            vertical_aperture: 100.0 * half,
            clip_near: 0.01,
            clip_far: 100.0,
            f_stop: 0.0,
            focus_distance: 0.0,
            lens_radius: 0.0,
            exposure: 0.0,
        });
        crate::scene::build(&desc, Some((16, 16))).unwrap()
    }

    #[test]
    fn a_small_bulb_over_glass_makes_hard_caustics_and_the_view_decides_sds() {
        // The camera sees only the pane: specular surfaces fill the view.
        let f = glass_over_floor(0.0, 0.01, 0.2).features;
        assert!(f.specular.on && f.caustics.on && f.delta_lights.on && f.hard_caustics);
        assert_eq!(f.caustics.prims, ["/Pane"]);
        assert!(f.sds.on && f.seen_specular > 0.99, "{:?}", f.sds);
        assert_eq!(f.sds.prims, ["/Pane"]);
        assert_eq!(f.delta_lights.prims, ["/Bulb"]);
        // The pane off to the side: its caustic is on the floor, no glass in view.
        let f = glass_over_floor(1.5, 0.01, 0.5).features;
        assert!(f.caustics.on && f.hard_caustics, "{:?}", f.caustics);
        assert!(!f.sds.on && f.seen_specular == 0.0, "{:?}", f.sds);
        // Both in view: the pane covers (0.6 / 4)² of it.
        let f = glass_over_floor(0.0, 0.01, 2.0).features;
        assert!(f.sds.on && f.seen_specular > 0.01 && f.seen_specular < 0.05);
        // A large light: caustics, but not point-like ones.
        let f = glass_over_floor(0.0, 0.4, 0.2).features;
        assert!(f.caustics.on && !f.delta_lights.on && !f.hard_caustics);
        assert!(!f.dispersion.on && !f.opacity.on && !f.textures.on);
        assert!((f.max_albedo - 1.0).abs() < 1e-3, "glass keeps everything");
        assert!(
            f.albedo.on && f.albedo.prims == ["/Looks/Glass"],
            "{:?}",
            f.albedo
        );
    }

    #[test]
    fn the_depth_cap_bound_is_the_geometric_tail() {
        let f = SceneFeatures {
            max_albedo: 0.5,
            ..Default::default()
        };
        assert_eq!(f.bound_cut(7), Some(0.5f64.powi(7) / 0.5));
        let lossless = SceneFeatures {
            max_albedo: 1.0,
            ..Default::default()
        };
        assert_eq!(lossless.bound_cut(7), None);
    }
}
