//! The USD reader: a `.usda` / `.usdc` / `.usdz` stage to a plain [`SceneDescription`].
//!
//! This is the only module of the crate that names `openusd`. Everything it produces is in
//! the renderer's conventions (docs/design.md §2): metres, Y up, world space, front faces wound
//! counter-clockwise. Unsupported standard prims and attributes become `warnings`; malformed
//! input and unknown `spectral:` vocabulary become an [`Error`](crate::Error) naming the file,
//! the prim and the reason.
//!
//! Layout: [`stage`] opens the stage and reads its metadata, [`values`] is typed attribute
//! access, [`xform`] composes transforms, and [`mesh`], [`material`], [`light`], [`camera`]
//! read one kind of prim each; [`vocab`] holds the `spectral:` vocabulary.
//!
//! Hostile input: every layer is read through [`resolver`] (regular files only; text layers
//! checked by [`usda_check`], crate files by [`usdc_check`]), composition arcs are checked by
//! [`arcs`] before the stage is traversed, and [`guard`] turns any panic left inside openusd
//! into a one-line error.

mod arcs;
mod camera;
#[cfg(feature = "testing")]
pub mod every_value;
mod guard;
mod light;
mod lz4;
mod material;
mod mesh;
mod resolver;
mod shapes;
mod stage;
mod usda_check;
mod usdc_check;
mod values;
mod vocab;
mod xform;

#[cfg(test)]
mod tests;

use glam::{DMat4, Vec2};
use openusd::{sdf, usd};
use std::collections::HashMap;
use std::path::Path;

use crate::desc::{ExtractedAssets, MeshDesc, SceneDescription, TimeDesc, TimeOrigin};
use crate::error::Result;
use std::sync::Arc;
use values::Ctx;

/// Prim types that carry nothing to render themselves (grouping, shading networks read
/// through bindings, render settings plumbing).
const PASSIVE_TYPES: [&str; 9] = [
    "",
    "Xform",
    "Scope",
    "Material",
    "Shader",
    "NodeGraph",
    "GeomSubset",
    "RenderProduct",
    "RenderVar",
];

/// Prim types whose transform is not part of the hierarchy's (they are not Xformable).
const NON_XFORMABLE_TYPES: [&str; 6] = [
    "Scope",
    "Material",
    "Shader",
    "NodeGraph",
    "GeomSubset",
    "RenderSettings",
];

/// Reads a .usda/.usdc/.usdz stage (flattened, or with local references) into plain data, at
/// the stage's own time (see [`ReadTime`]).
#[cfg(any(test, feature = "testing"))]
pub fn load(path: &Path) -> Result<SceneDescription> {
    open(path)?.read(ReadTime::default())
}

/// When a stage's attributes are read: a USD time code, and how time samples between two
/// authored ones are evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReadTime {
    /// The time code (`--frame`); `None`: the stage's `startTimeCode` when it authors one,
    /// else its earliest time sample (a value without time samples is its default).
    pub frame: Option<f64>,
    /// Held interpolation (USD's `UsdInterpolationTypeHeld`): every value is the sample at
    /// or before the time. Otherwise linear, USD's default: numeric samples (scalars,
    /// vectors, matrices; quaternions by slerp) are interpolated, and every other type
    /// (assets, tokens, strings, bools, ints) holds the earlier sample.
    pub held: bool,
}

/// A stage opened and checked once, to be read at any number of times.
pub struct OpenStage {
    path: std::path::PathBuf,
    stage: usd::Stage,
    content_hash: u64,
}

/// Opens and checks the stage at `path` (every layer read and checked, composition arcs
/// checked); [`OpenStage::read`] then reads it at a time.
pub fn open(path: &Path) -> Result<OpenStage> {
    guard::catch_panics(path, || {
        let (stage, content_hash) = stage::open(path)?;
        arcs::check(path, &stage)?;
        Ok(OpenStage {
            path: path.to_path_buf(),
            stage,
            content_hash,
        })
    })
}

impl OpenStage {
    /// The stage's description at `time`.
    pub fn read(&self, time: ReadTime) -> Result<SceneDescription> {
        guard::catch_panics(&self.path, || self.read_unguarded(time))
    }

    /// [`OpenStage::read`] without the panic guard.
    fn read_unguarded(&self, time: ReadTime) -> Result<SceneDescription> {
        let (path, stage) = (self.path.as_path(), &self.stage);
        stage.set_interpolation_type(if time.held {
            usd::InterpolationType::Held
        } else {
            usd::InterpolationType::Linear
        });
        let meters_per_unit = stage::meters_per_unit(path, stage)?;
        let z_up = stage::z_up(path, stage)?;
        let (code, origin) = match time.frame {
            Some(f) => (usd::TimeCode::new(f), TimeOrigin::Given),
            None => stage::read_time(stage),
        };
        let ctx = Ctx {
            file: path.to_path_buf(),
            stage,
            time: code,
            meters_per_unit,
            z_up,
            stage_to_world: stage::stage_to_world(meters_per_unit, z_up),
            warnings: Vec::new(),
            extracted: Arc::new(ExtractedAssets::unique()),
            animated: std::cell::Cell::new(false),
        };
        let mut reader = Reader::new(ctx);
        reader.read_stage()?;
        stage::check_composition(path, stage)?;
        let animated = reader.ctx.animated.get();
        let mut desc = reader.finish()?;
        desc.time = TimeDesc {
            code: (!code.is_earliest_time()).then_some(code.value()),
            origin,
            animated,
            held: time.held,
            frames_per_second: stage::metadata_number(stage, "framesPerSecond"),
            time_codes_per_second: stage::metadata_number(stage, "timeCodesPerSecond"),
        };
        desc.content_hash = self.content_hash;
        if time != ReadTime::default() {
            // A checkpoint of one frame does not resume another.
            let mut hash = crate::desc::ContentHash(self.content_hash);
            hash.add(&time.frame.unwrap_or(f64::NAN).to_le_bytes());
            hash.add(&[u8::from(time.held)]);
            desc.content_hash = hash.0;
        }
        Ok(desc)
    }
}

/// What a prim hands down to its children.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Local-to-world in stage space (stage units and up axis).
    local_to_world: DMat4,
    /// `visibility = "invisible"` here or on an ancestor (a child cannot override it).
    invisible: bool,
    /// The prim's own authored purpose, else the closest ancestor's (UsdGeomImageable).
    purpose: Purpose,
}

impl Node {
    /// The pseudo-root's state.
    const ROOT: Node = Node {
        local_to_world: DMat4::IDENTITY,
        invisible: false,
        purpose: Purpose::Rendered,
    };

    /// Not rendered: invisible, or of purpose guide / proxy.
    fn hidden(&self) -> bool {
        self.invisible || self.purpose == Purpose::Hidden
    }
}

/// UsdGeomImageable `purpose`, as far as rendering cares.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Purpose {
    /// `default` or `render`.
    Rendered,
    /// `proxy` or `guide`.
    Hidden,
}

/// The traversal state.
struct Reader<'s> {
    ctx: Ctx<'s>,
    desc: SceneDescription,
    /// Material prim path to its index in `desc.materials` (`None`: no usable surface).
    materials: HashMap<String, Option<usize>>,
    nodes: HashMap<String, Node>,
    render_settings: Vec<sdf::Path>,
}

impl<'s> Reader<'s> {
    fn new(ctx: Ctx<'s>) -> Self {
        let desc = SceneDescription {
            source: ctx.file.clone(),
            ..SceneDescription::default()
        };
        Reader {
            ctx,
            desc,
            materials: HashMap::new(),
            nodes: HashMap::new(),
            render_settings: Vec::new(),
        }
    }

    /// Visits every active, loaded, defined, non-abstract prim (instance proxies included),
    /// parents before children.
    fn read_stage(&mut self) -> Result<()> {
        let mut paths = Vec::new();
        self.ctx
            .stage
            .traverse(usd::PrimPredicate::DEFAULT_PROXIES, |p| {
                paths.push(p.clone())
            })
            .map_err(|e| {
                crate::error::Error::usd(&self.ctx.file, format!("traversing the stage: {e:#}"))
            })?;
        paths.iter().try_for_each(|path| self.read_prim(path))
    }

    /// Resolves the render settings and returns the description.
    fn finish(mut self) -> Result<SceneDescription> {
        self.desc.render =
            camera::read_render_settings(&mut self.ctx, &self.render_settings, &self.desc.cameras)?;
        self.desc.warnings = std::mem::take(&mut self.ctx.warnings);
        self.desc.stage_to_world = self.ctx.stage_to_world;
        self.desc.extracted = Some(self.ctx.extracted.clone());
        Ok(self.desc)
    }

    /// Reads one prim according to its type.
    fn read_prim(&mut self, path: &sdf::Path) -> Result<()> {
        let prim = self.ctx.stage.prim(path.clone());
        let type_name = self.ctx.type_name(&prim)?;
        let apis = self.ctx.api_schemas(&prim)?;
        let parent = self.parent_node(&prim);
        let node = self.node(&prim, &type_name, &parent)?;
        self.nodes.insert(path.as_str().to_string(), node);
        let geometric = type_name == "Mesh" || shapes::SHAPE_TYPES.contains(&type_name.as_str());
        let mesh_light = geometric && light::has_light_api(&apis);
        vocab::check_spectral_names(
            &self.ctx,
            &prim,
            mesh_light || light::is_light_type(&type_name),
        )?;
        self.warn_collection_bindings(&prim)?;
        match type_name.as_str() {
            "Mesh" if !node.hidden() => self.read_mesh(&prim, &node, mesh_light),
            t if shapes::SHAPE_TYPES.contains(&t) && !node.hidden() => {
                self.read_shape(&prim, t, &node, mesh_light)
            }
            "Camera" => {
                let camera = camera::read_camera(&mut self.ctx, &prim, node.local_to_world)?;
                self.desc.cameras.push(camera);
                Ok(())
            }
            "RenderSettings" => {
                self.render_settings.push(path.clone());
                Ok(())
            }
            t if light::is_light_type(t) && !node.hidden() => {
                let light = light::read_light(&mut self.ctx, &prim, t, node.local_to_world)?;
                self.desc.lights.push(light);
                Ok(())
            }
            "PointInstancer" if !parent.hidden() => {
                let message = "PointInstancer is not supported; its prototypes are not rendered";
                self.ctx.warn(&prim, message);
                Ok(())
            }
            t => {
                self.warn_unsupported(&prim, t, &apis, node.hidden());
                Ok(())
            }
        }
    }

    /// The state of the prim's parent (the pseudo-root's for a root prim).
    fn parent_node(&self, prim: &usd::Prim) -> Node {
        let parent = prim.path().parent();
        parent
            .and_then(|p| self.nodes.get(p.as_str()).copied())
            .unwrap_or(Node::ROOT)
    }

    /// The prim's transform, visibility and purpose, composed with its parent's. The
    /// prototypes under a (not supported) PointInstancer are hidden.
    fn node(&self, prim: &usd::Prim, type_name: &str, parent: &Node) -> Result<Node> {
        let local_to_world = if NON_XFORMABLE_TYPES.contains(&type_name) {
            parent.local_to_world
        } else {
            xform::local_xform(&self.ctx, prim)?.under(parent.local_to_world)
        };
        if !local_to_world.is_finite() {
            let reason = "the composed transform overflows (its xformOps multiply past the \
                          range of a double)";
            return Err(self.ctx.err(prim, reason));
        }
        let purpose = self.authored_purpose(prim)?.unwrap_or(parent.purpose);
        let invisible = parent.invisible
            || type_name == "PointInstancer"
            || self.ctx.token(prim, "visibility")?.as_deref() == Some("invisible");
        Ok(Node {
            local_to_world,
            invisible,
            purpose,
        })
    }

    /// The prim's own authored `purpose`.
    fn authored_purpose(&self, prim: &usd::Prim) -> Result<Option<Purpose>> {
        Ok(match self.ctx.token(prim, "purpose")?.as_deref() {
            None => None,
            Some("proxy" | "guide") => Some(Purpose::Hidden),
            Some(_) => Some(Purpose::Rendered),
        })
    }

    /// Reads a Mesh, split into one `MeshDesc` per GeomSubset that binds its own material.
    fn read_mesh(&mut self, prim: &usd::Prim, node: &Node, is_light: bool) -> Result<()> {
        let Some(geometry) = mesh::read_geometry(&mut self.ctx, prim, node.local_to_world)? else {
            return Ok(());
        };
        let (subsets, face_group) = self.material_subsets(prim, geometry.face_count)?;
        let mut pieces = Vec::new();
        let mut uv_sets = Vec::new();
        let material = self.bound_material_index(prim)?;
        let uvs = self.texcoord_set(prim, &geometry, material, &mut uv_sets)?;
        let rest = mesh::to_desc(
            &geometry,
            prim.path().as_str(),
            |f| face_group.get(f).copied().flatten().is_none(),
            uv_sets[uvs].1.as_deref(),
        );
        pieces.push(MeshDesc { material, ..rest });
        for (g, (subset_path, material)) in subsets.iter().enumerate() {
            let uvs = self.texcoord_set(prim, &geometry, *material, &mut uv_sets)?;
            let piece = mesh::to_desc(
                &geometry,
                subset_path,
                |f| face_group.get(f).copied().flatten() == Some(g),
                uv_sets[uvs].1.as_deref(),
            );
            pieces.push(MeshDesc {
                material: *material,
                ..piece
            });
        }
        pieces.retain(|m| !m.indices.is_empty());
        self.push_meshes(prim, pieces, is_light)
    }

    /// Reads an intrinsic shape (Sphere, Cube, ...) as a tessellated mesh.
    fn read_shape(
        &mut self,
        prim: &usd::Prim,
        type_name: &str,
        node: &Node,
        is_light: bool,
    ) -> Result<()> {
        let shape = shapes::tessellate(&self.ctx, prim, type_name)?;
        let Some(geometry) = mesh::shape_geometry(&mut self.ctx, prim, node.local_to_world, shape)?
        else {
            return Ok(());
        };
        let piece = mesh::to_desc(&geometry, prim.path().as_str(), |_| true, None);
        let material = self.bound_material_index(prim)?;
        self.push_meshes(prim, vec![MeshDesc { material, ..piece }], is_light)
    }

    /// The index in `sets` of the texture coordinates that `material` reads on the mesh,
    /// reading them on first use; warns when a textured material's primvar is missing (the
    /// barycentric coordinates are used then).
    fn texcoord_set(
        &mut self,
        prim: &usd::Prim,
        geometry: &mesh::MeshGeometry,
        material: Option<usize>,
        sets: &mut Vec<(String, Option<Vec<[Vec2; 3]>>)>,
    ) -> Result<usize> {
        let (name, textured) = match material.map(|i| &self.desc.materials[i]) {
            Some(m) => (m.texcoord.clone(), m.all_textures().next().is_some()),
            None => ("st".to_string(), false),
        };
        if let Some(i) = sets.iter().position(|(n, _)| *n == name) {
            return Ok(i);
        }
        let uvs = mesh::read_texcoords(&mut self.ctx, prim, geometry, &name)?;
        if uvs.is_none() && textured {
            let message = format!(
                "a textured material reads primvars:{name}, which the mesh does not have; \
                 textures are looked up at the triangles' barycentric coordinates"
            );
            self.ctx.warn(prim, message);
        }
        sets.push((name, uvs));
        Ok(sets.len() - 1)
    }

    /// Adds the meshes of one prim, with its emission when it is a mesh light.
    fn push_meshes(
        &mut self,
        prim: &usd::Prim,
        pieces: Vec<MeshDesc>,
        is_light: bool,
    ) -> Result<()> {
        let emission = if is_light {
            light::warn_unsupported_inputs(&mut self.ctx, prim)?;
            Some(light::read_emission(&self.ctx, prim, 1.0)?)
        } else {
            None
        };
        if emission.as_ref().is_some_and(|e| e.normalize) && pieces.len() > 1 {
            self.ctx.warn(
                prim,
                "a normalized mesh light split by GeomSubsets is normalized per subset",
            );
        }
        for piece in pieces {
            self.desc.meshes.push(MeshDesc {
                light: emission.clone(),
                ..piece
            });
        }
        Ok(())
    }

    /// The GeomSubsets of a mesh that bind a material of their own, as (subset path,
    /// material), and for every face the index of the first such subset that contains it.
    #[allow(clippy::type_complexity)]
    fn material_subsets(
        &mut self,
        mesh: &usd::Prim,
        face_count: usize,
    ) -> Result<(Vec<(String, Option<usize>)>, Vec<Option<usize>>)> {
        let mut subsets = Vec::new();
        let mut face_group = vec![None; face_count];
        let children = mesh
            .children()
            .map_err(|e| self.ctx.usd_err(mesh, "listing children", e))?;
        for subset in children {
            if self.ctx.type_name(&subset)? != "GeomSubset" {
                continue;
            }
            // Every subset's indices are checked, bound or not: out-of-range faces mean the
            // subsets describe another mesh.
            let faces = self.subset_faces(&subset, face_count)?;
            if !self.binds_directly(&subset)? {
                continue;
            }
            if let Some(faces) = faces {
                let group = subsets.len();
                for face in faces {
                    face_group[face].get_or_insert(group);
                }
                subsets.push((
                    subset.path().as_str().to_string(),
                    self.bound_material_index(&subset)?,
                ));
            }
        }
        Ok((subsets, face_group))
    }

    /// `true` when the prim itself authors a material binding.
    fn binds_directly(&self, prim: &usd::Prim) -> Result<bool> {
        for rel in ["material:binding", "material:binding:full"] {
            if !self.ctx.targets(prim, rel)?.is_empty() {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The face indices of a `face` GeomSubset (validated); `None` for other element types.
    fn subset_faces(
        &mut self,
        subset: &usd::Prim,
        face_count: usize,
    ) -> Result<Option<Vec<usize>>> {
        let element_type = self
            .ctx
            .token(subset, "elementType")?
            .unwrap_or_else(|| "face".into());
        if element_type != "face" {
            self.ctx.warn(
                subset,
                format!("GeomSubset elementType '{element_type}' is not supported; ignored"),
            );
            return Ok(None);
        }
        let indices = self.ctx.int_array(subset, "indices")?.unwrap_or_default();
        let mut faces = Vec::with_capacity(indices.len());
        for index in indices {
            match usize::try_from(index).ok().filter(|&f| f < face_count) {
                Some(face) => faces.push(face),
                None => {
                    let reason = format!(
                        "indices: face {index} is out of range (the mesh has {face_count} faces)"
                    );
                    return Err(self.ctx.err(subset, reason));
                }
            }
        }
        Ok(Some(faces))
    }

    /// The index in `desc.materials` of the material bound to `prim`, reading it once.
    fn bound_material_index(&mut self, prim: &usd::Prim) -> Result<Option<usize>> {
        let Some(path) = material::bound_material(&self.ctx, prim)? else {
            return Ok(None);
        };
        if let Some(&index) = self.materials.get(path.as_str()) {
            return Ok(index);
        }
        let index = match material::read_material(&mut self.ctx, &path)? {
            Some(desc) => {
                self.desc.materials.push(desc);
                Some(self.desc.materials.len() - 1)
            }
            None => None,
        };
        self.materials.insert(path.as_str().to_string(), index);
        Ok(index)
    }

    /// Collection-based material bindings are not resolved: say so where they are authored.
    fn warn_collection_bindings(&mut self, prim: &usd::Prim) -> Result<()> {
        let names = self.ctx.property_names(prim)?;
        if names
            .iter()
            .any(|n| n.starts_with("material:binding:collection:"))
        {
            self.ctx.warn(
                prim,
                "collection-based material bindings are not supported; ignored",
            );
        }
        Ok(())
    }

    /// Warns about a prim type (or a light API on a non-mesh) that is not rendered.
    fn warn_unsupported(
        &mut self,
        prim: &usd::Prim,
        type_name: &str,
        apis: &[String],
        hidden: bool,
    ) {
        if hidden {
            return;
        }
        if !PASSIVE_TYPES.contains(&type_name)
            && type_name != "Mesh"
            && !light::is_light_type(type_name)
        {
            let what = if light::is_unsupported_light_type(type_name) {
                "light type"
            } else {
                "prim type"
            };
            self.ctx
                .warn(prim, format!("unsupported {what} '{type_name}' ignored"));
        } else if light::has_light_api(apis) && type_name != "Mesh" {
            self.ctx.warn(
                prim,
                format!("LightAPI on a '{type_name}' is not supported; ignored"),
            );
        }
    }
}
