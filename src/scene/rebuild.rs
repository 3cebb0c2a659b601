//! Scenes of a sequence (`--frames`): each frame's scene is built from the previous frame's,
//! reusing what its description did not change. Meshes and materials unchanged (compared
//! as plain data, `PartialEq` of `desc`): the materials with their textures, the meshes, their
//! triangle lights and the BVH are kept. A UsdLux light unchanged: its built light (a dome's
//! map and its sampling tables, an IES profile, a rect light's texture) is kept. Nothing
//! changed in the lights and geometry: the light sampler is kept too. The camera and the
//! scene analysis are always made anew (they are cheap). What is kept is what a fresh build
//! would make from the same description, so every frame equals its own `--frame` render
//! bit for bit.

use super::build::{assemble, geometry, is_portal, light, Geometry};
use super::machinery::Machinery;
use super::render_scene::Scene;
use crate::desc::SceneDescription;
use crate::desc::{CameraDesc, LightDesc, MaterialDesc, MeshDesc, RenderSettingsDesc};
use crate::error::{Error, Result};
use crate::light::{Light, LightSampler};

/// Builds the scenes of a sequence, one frame after another.
pub struct Rebuilder {
    resolution: Option<(u32, u32)>,
    machinery: Machinery,
    last: Option<Last>,
}

/// The description the previous scene was built from (the parts compared).
struct Last {
    meshes: Vec<MeshDesc>,
    materials: Vec<MaterialDesc>,
    lights: Vec<LightDesc>,
    cameras: Vec<CameraDesc>,
    render: RenderSettingsDesc,
    geometry_warnings: Vec<String>,
    mesh_lights: usize,
}

/// What building a frame's scene rebuilt.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rebuilt {
    /// Materials, meshes and the BVH were built (false: the previous frame's were kept).
    pub geometry: bool,
    /// UsdLux lights built anew (their description changed, or there was no previous frame).
    pub lights_built: usize,
    /// UsdLux lights in the frame.
    pub lights: usize,
    /// The light sampler's tables were built.
    pub light_table: bool,
    /// The cameras or the render settings differ from the previous frame's.
    pub camera: bool,
    /// There was no previous frame to reuse from.
    pub first: bool,
}

impl Rebuilt {
    /// One line for the log: "camera, 2 lights changed; geometry reused".
    pub fn line(&self) -> String {
        if self.first {
            return "built".into();
        }
        let mut changed = Vec::new();
        if self.camera {
            changed.push("camera".to_string());
        }
        match self.lights_built {
            0 => {}
            1 => changed.push("1 light".into()),
            n => changed.push(format!("{n} lights")),
        }
        if self.geometry {
            changed.push("geometry".into());
        }
        let head = match changed.is_empty() {
            true => "nothing changed".to_string(),
            false => format!("{} changed", changed.join(", ")),
        };
        let mut kept = Vec::new();
        if !self.geometry {
            kept.push("geometry");
        }
        if !self.light_table {
            kept.push("light table");
        }
        match kept.is_empty() {
            true => head,
            false => format!("{head}; {} reused", kept.join(" and ")),
        }
    }
}

impl Rebuilder {
    /// A builder for frames at `resolution` (overriding RenderSettings) with `machinery`.
    pub fn new(resolution: Option<(u32, u32)>, machinery: Machinery) -> Rebuilder {
        Rebuilder {
            resolution,
            machinery,
            last: None,
        }
    }

    /// The scene of `desc`, reusing the parts of `previous` (the scene this builder made
    /// last, given back) whose description did not change.
    pub fn build(
        &mut self,
        desc: &SceneDescription,
        previous: Option<Scene>,
    ) -> Result<(Scene, Rebuilt)> {
        let last = self.last.take();
        let (kept, old_lights, old_sampler) = match (previous, &last) {
            (Some(scene), Some(last)) => {
                let same = last.meshes == desc.meshes && last.materials == desc.materials;
                let (geometry, lights, sampler) = take_geometry(scene, last);
                (same.then_some(geometry), lights, same.then_some(sampler))
            }
            _ => (None, Vec::new(), None),
        };
        let rebuilt_geometry = kept.is_none();
        let geometry = match kept {
            Some(g) => g,
            None => geometry(desc, self.machinery)?,
        };
        let last_lights = last.as_ref().map_or(&[][..], |l| l.lights.as_slice());
        let mut built = 0;
        let mut lights = Vec::with_capacity(desc.lights.len());
        let mut old = old_lights.into_iter().map(Some).collect::<Vec<_>>();
        // PortalLights are not lights: `assemble` gives them to the domes every frame.
        let usd: Vec<LightDesc> = desc
            .lights
            .iter()
            .filter(|l| !is_portal(l))
            .cloned()
            .collect();
        for (i, l) in usd.iter().enumerate() {
            let kept = match (last_lights.get(i), old.get_mut(i)) {
                (Some(prev), Some(slot)) if prev == l => slot.take(),
                _ => None,
            };
            lights.push(match kept {
                Some(light) => light,
                None => {
                    built += 1;
                    light(l).map_err(|r| Error::prim(&desc.source, &l.prim_path, r))?
                }
            });
        }
        let same_lights = !rebuilt_geometry && built == 0 && old.len() == usd.len();
        let sampler = old_sampler.filter(|_| same_lights);
        let light_table = sampler.is_none();
        let geometry_warnings = geometry.warnings.clone();
        let mesh_lights = geometry.mesh_lights.len();
        let scene = assemble(
            desc,
            geometry,
            lights,
            sampler,
            self.resolution,
            self.machinery,
        )?;
        let camera = last
            .as_ref()
            .is_none_or(|l| l.cameras != desc.cameras || l.render != desc.render);
        let rebuilt = Rebuilt {
            geometry: rebuilt_geometry,
            lights_built: built,
            lights: desc.lights.len(),
            light_table,
            camera,
            first: last.is_none(),
        };
        self.last = Some(Last {
            meshes: desc.meshes.clone(),
            materials: desc.materials.clone(),
            lights: usd,
            cameras: desc.cameras.clone(),
            render: desc.render.clone(),
            geometry_warnings,
            mesh_lights,
        });
        Ok((scene, rebuilt))
    }
}

/// The geometry of `scene` back as [`Geometry`], its UsdLux lights and its light sampler.
fn take_geometry(scene: Scene, last: &Last) -> (Geometry, Vec<Light>, LightSampler) {
    let Scene {
        materials,
        meshes,
        prims,
        bvh,
        center,
        radius,
        mut lights,
        light_sampler,
        ..
    } = scene;
    let usd_lights = lights.split_off(last.mesh_lights);
    let geometry = Geometry {
        materials,
        meshes,
        prims,
        bvh,
        center,
        radius,
        mesh_lights: lights,
        warnings: last.geometry_warnings.clone(),
    };
    (geometry, usd_lights, light_sampler)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::desc::{EmissionDesc, LightKind};
    use glam::{Mat4, Vec3};

    /// A floor, an emissive quad (MeshLightAPI: the scene's first lights) and two lights.
    fn desc() -> SceneDescription {
        let quad = |y: f32| {
            vec![
                Vec3::new(-1.0, y, -1.0),
                Vec3::new(1.0, y, -1.0),
                Vec3::new(1.0, y, 1.0),
                Vec3::new(-1.0, y, 1.0),
            ]
        };
        let mut desc = SceneDescription::default();
        desc.meshes.push(MeshDesc {
            prim_path: "/Floor".into(),
            positions: quad(0.0),
            indices: vec![[0, 2, 1], [0, 3, 2]],
            ..Default::default()
        });
        desc.meshes.push(MeshDesc {
            prim_path: "/Panel".into(),
            positions: quad(3.0),
            indices: vec![[0, 1, 2], [0, 2, 3]],
            light: Some(EmissionDesc {
                intensity: 2.0,
                ..Default::default()
            }),
            ..Default::default()
        });
        for (i, x) in [-0.5f32, 0.5].iter().enumerate() {
            desc.lights.push(LightDesc {
                prim_path: format!("/Bulb{i}"),
                kind: LightKind::Sphere {
                    radius: 0.05,
                    point: false,
                },
                to_world: Mat4::from_translation(Vec3::new(*x, 1.0, 0.0)),
                emission: EmissionDesc {
                    intensity: 100.0,
                    ..Default::default()
                },
                shaping: None,
                shadows: true,
            });
        }
        desc
    }

    /// The scene as a fresh build makes it, in the parts a rebuild keeps or remakes.
    fn fingerprint(scene: &Scene) -> String {
        format!(
            "{:?} {:?} {:?} {:?} {:?} {}",
            scene.lights,
            scene.light_sampler,
            scene.meshes,
            scene.bvh.bounds(),
            scene.camera.prim_path,
            scene.radius
        )
    }

    fn fresh(desc: &SceneDescription) -> Scene {
        crate::scene::build(desc, Some((8, 8))).unwrap()
    }

    #[test]
    fn unchanged_parts_are_kept_and_equal_a_fresh_build() {
        let mut builder = Rebuilder::new(Some((8, 8)), Machinery::default());
        let mut d = desc();
        let (scene, r) = builder.build(&d, None).unwrap();
        assert!(r.first && r.geometry && r.light_table && r.lights_built == 2);
        assert_eq!(r.line(), "built");
        // The same description: everything kept.
        let (scene, r) = builder.build(&d, Some(scene)).unwrap();
        assert!(!r.geometry && !r.light_table && r.lights_built == 0 && !r.camera);
        assert_eq!(r.line(), "nothing changed; geometry and light table reused");
        assert_eq!(fingerprint(&scene), fingerprint(&fresh(&d)));
        // One light moves: it alone is built, with the light table; the geometry is kept.
        d.lights[1].to_world = Mat4::from_translation(Vec3::new(0.7, 1.2, 0.0));
        let (scene, r) = builder.build(&d, Some(scene)).unwrap();
        assert_eq!(
            (r.geometry, r.lights_built, r.light_table),
            (false, 1, true)
        );
        assert_eq!(r.line(), "1 light changed; geometry reused");
        assert_eq!(fingerprint(&scene), fingerprint(&fresh(&d)));
        // The emissive panel's power changes: the geometry (and its triangle lights) again.
        d.meshes[1].light.as_mut().unwrap().intensity = 3.0;
        let (scene, r) = builder.build(&d, Some(scene)).unwrap();
        assert!(r.geometry && r.light_table && r.lights_built == 0);
        assert_eq!(r.line(), "geometry changed");
        assert_eq!(fingerprint(&scene), fingerprint(&fresh(&d)));
        // A light removed and the floor moved: both rebuilt.
        d.lights.pop();
        d.meshes[0].positions[0].y = -0.1;
        let (scene, r) = builder.build(&d, Some(scene)).unwrap();
        assert!(r.geometry && r.lights == 1);
        assert_eq!(fingerprint(&scene), fingerprint(&fresh(&d)));
        // Without the previous scene nothing can be kept.
        let (_, r) = builder.build(&d, None).unwrap();
        assert!(r.geometry && r.lights_built == 1 && !r.first);
    }
}
