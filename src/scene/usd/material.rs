//! UsdShade: material binding resolution and surface shaders (`UsdPreviewSurface` and the
//! `spectral:*` vocabulary of docs/design.md §3).

use openusd::{sdf, usd};

use super::values::{self, Ctx};
use super::vocab;
use crate::desc::{
    ColorSpace, IorDesc, MaterialDesc, MaterialKind, PreviewSurfaceDesc, SpectrumDesc,
    TextureChannel, TextureDesc, Wrap,
};
use crate::error::{Error, Result};
use glam::{Affine2, Vec2};
use std::path::PathBuf;

/// How many connection hops (through NodeGraph / Material interfaces) are followed.
const MAX_CONNECTION_DEPTH: usize = 32;

/// The shader ids that may appear in a network feeding a surface (texture nodes and the like);
/// they are recognised so that a connection to them warns instead of failing.
const KNOWN_NODE_PREFIXES: [&str; 3] = ["UsdUVTexture", "UsdPrimvarReader_", "UsdTransform2d"];

/// The UsdPreviewSurface inputs the renderer understands.
const PREVIEW_INPUTS: [&str; 13] = [
    "diffuseColor",
    "emissiveColor",
    "useSpecularWorkflow",
    "specularColor",
    "metallic",
    "roughness",
    "clearcoat",
    "clearcoatRoughness",
    "opacity",
    "opacityThreshold",
    "ior",
    "opacityMode",
    "normal",
];

/// The Material bound to `prim`: direct bindings, purpose `full` before all-purpose,
/// the closest prim winning unless an ancestor binds `strongerThanDescendants`.
pub(super) fn bound_material(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<sdf::Path>> {
    for rel in ["material:binding:full", "material:binding"] {
        if let Some(material) = bound_for_relationship(ctx, prim, rel)? {
            return Ok(Some(material));
        }
    }
    Ok(None)
}

/// Resolves one binding relationship name up the namespace hierarchy.
fn bound_for_relationship(ctx: &Ctx, prim: &usd::Prim, rel: &str) -> Result<Option<sdf::Path>> {
    let mut winner = None;
    let mut current = Some(prim.path().clone());
    while let Some(path) = current.filter(|p| !p.is_abs_root()) {
        let holder = ctx.stage.prim(path.clone());
        if let Some(target) = ctx.targets(&holder, rel)?.into_iter().next() {
            let stronger = ctx
                .attr_token_metadata(&holder, rel, "bindMaterialAs")?
                .as_deref()
                == Some("strongerThanDescendants");
            if winner.is_none() || stronger {
                winner = Some(checked_material(ctx, &holder, rel, target)?);
            }
        }
        current = path.parent();
    }
    Ok(winner)
}

/// Checks that a binding `target` authored on `holder` is a Material prim.
fn checked_material(
    ctx: &Ctx,
    holder: &usd::Prim,
    rel: &str,
    target: sdf::Path,
) -> Result<sdf::Path> {
    let material = ctx.stage.prim(target.clone());
    let exists = material
        .is_valid()
        .map_err(|e| ctx.usd_err(holder, rel, e))?;
    if !exists {
        return Err(ctx.err(
            holder,
            format!("{rel} targets <{}>, which does not exist", target.as_str()),
        ));
    }
    let type_name = ctx.type_name(&material)?;
    if type_name != "Material" {
        let reason = format!(
            "{rel} targets <{}>, a '{type_name}' rather than a Material",
            target.as_str()
        );
        return Err(ctx.err(holder, reason));
    }
    Ok(target)
}

/// Reads the Material prim at `path`; `None` (with a warning) when it has no surface shader.
pub(super) fn read_material(ctx: &mut Ctx, path: &sdf::Path) -> Result<Option<MaterialDesc>> {
    let material = ctx.stage.prim(path.clone());
    let Some(shader) = surface_shader(ctx, &material)? else {
        ctx.warn(
            &material,
            "no outputs:surface connection to a shader; bound meshes use the default material",
        );
        return Ok(None);
    };
    let (kind, emission, textures) = read_surface(ctx, &shader)?;
    let mut desc = MaterialDesc {
        prim_path: path.as_str().to_string(),
        kind,
        emission,
        textures,
        texcoord: "st".into(),
    };
    desc.texcoord = texcoord(ctx, &material, &desc)?;
    Ok(Some(desc))
}

/// The one texture-coordinate primvar the material's textures read (`st` without textures);
/// an error when two textures read different ones.
fn texcoord(ctx: &Ctx, material: &usd::Prim, desc: &MaterialDesc) -> Result<String> {
    let mut textures = desc.all_textures();
    let Some(first) = textures.next() else {
        return Ok("st".into());
    };
    match textures.find(|t| t.st_primvar != first.st_primvar) {
        None => Ok(first.st_primvar.clone()),
        Some(other) => Err(ctx.err(
            material,
            format!(
                "<{}> reads primvars:{} but <{}> reads primvars:{}; a material may read only \
                 one texture-coordinate primvar",
                first.shader_path, first.st_primvar, other.shader_path, other.st_primvar
            ),
        )),
    }
}

/// Follows the material's `outputs:surface` (through NodeGraphs) to a Shader prim.
fn surface_shader(ctx: &Ctx, material: &usd::Prim) -> Result<Option<usd::Prim>> {
    let mut prim = material.clone();
    let mut output = "outputs:surface".to_string();
    for _ in 0..MAX_CONNECTION_DEPTH {
        let Some(source) = ctx.connections(&prim, &output)?.into_iter().next() else {
            return Ok(None);
        };
        let Some((source_prim, source_attr)) = source.split_property() else {
            return Err(ctx.err(
                &prim,
                format!("{output} connects to <{}>, not an output", source.as_str()),
            ));
        };
        let next = ctx.stage.prim(source_prim);
        if ctx.type_name(&next)? == "Shader" {
            return Ok(Some(next));
        }
        output = source_attr.to_string();
        prim = next;
    }
    Err(ctx.err(
        material,
        "outputs:surface: connection chain too long (cycle?)",
    ))
}

/// What a surface shader defines: the material model, its emission, and the textures on the
/// inputs of a `spectral:*` shader.
type Surface = (MaterialKind, Option<[f32; 3]>, Vec<(String, TextureDesc)>);

/// The material model of a surface shader, by `info:id`, and its emission.
fn read_surface(ctx: &mut Ctx, shader: &usd::Prim) -> Result<Surface> {
    let Some(id) = ctx.token(shader, "info:id")? else {
        return Err(ctx.err(
            shader,
            "surface shader has no info:id (only UsdPreviewSurface and spectral:* are supported)",
        ));
    };
    if id == "UsdPreviewSurface" {
        let preview = preview_surface(ctx, shader)?;
        let emission = preview
            .emissive_color
            .iter()
            .any(|&c| c != 0.0)
            .then_some(preview.emissive_color);
        return Ok((MaterialKind::PreviewSurface(preview), emission, Vec::new()));
    }
    let Some(vocabulary) = vocab::shader_inputs(&id) else {
        let reason = format!(
            "unknown shader info:id '{id}' (supported: UsdPreviewSurface, spectral:diffuse, \
             spectral:conductor, spectral:dielectric, spectral:plastic)"
        );
        return Err(ctx.err(shader, reason));
    };
    check_inputs(ctx, shader, &id, vocabulary)?;
    let mut textures = Vec::new();
    for name in vocab::texturable_inputs(&id) {
        if let Some(t) = texture_input(ctx, shader, name)? {
            textures.push((name.to_string(), t));
        }
    }
    let kind = spectral_material(ctx, shader, &id, &textures)?;
    Ok((kind, None, textures))
}

/// Fails on an authored `inputs:*` that the `spectral:*` shader `id` does not define.
fn check_inputs(ctx: &Ctx, shader: &usd::Prim, id: &str, vocabulary: &[&str]) -> Result<()> {
    for name in ctx.property_names(shader)? {
        let Some(input) = name.strip_prefix("inputs:") else {
            continue;
        };
        if !vocabulary.contains(&input) {
            let reason = match vocab::one_edit_away(input, vocabulary) {
                Some(k) => format!("unknown input '{name}' for {id}; did you mean inputs:{k}?"),
                None => {
                    let known = vocabulary
                        .iter()
                        .map(|i| format!("inputs:{i}"))
                        .collect::<Vec<_>>()
                        .join(", ");
                    format!("unknown input '{name}' for {id} (known: {known})")
                }
            };
            return Err(ctx.err(shader, reason));
        }
    }
    Ok(())
}

/// A `spectral:*` material model; `textures` are its textured inputs (read by the builder).
fn spectral_material(
    ctx: &mut Ctx,
    shader: &usd::Prim,
    id: &str,
    textures: &[(String, TextureDesc)],
) -> Result<MaterialKind> {
    let mut inputs = Inputs {
        ctx,
        shader,
        textured: textures.iter().map(|(n, _)| n.clone()).collect(),
        spectral: Some(id.to_string()),
    };
    let roughness = inputs.f32("roughness")?.unwrap_or(0.0);
    Ok(match id {
        "spectral:diffuse" => MaterialKind::Diffuse {
            reflectance: inputs.reflectance()?,
            roughness,
        },
        "spectral:conductor" => {
            let (eta, k) = inputs.conductor_spectra()?;
            MaterialKind::Conductor { eta, k, roughness }
        }
        "spectral:dielectric" => MaterialKind::Dielectric {
            ior: inputs.dielectric_ior()?,
            roughness,
            thin: inputs.bool("thin")?.unwrap_or(false),
        },
        _ => MaterialKind::Plastic {
            reflectance: inputs.reflectance()?,
            ior: inputs.positive("ior")?.unwrap_or(1.5),
            roughness,
        },
    })
}

/// The UsdPreviewSurface inputs that may be connected to a `UsdUVTexture`.
const TEXTURABLE_INPUTS: [&str; 9] = [
    "diffuseColor",
    "emissiveColor",
    "specularColor",
    "metallic",
    "roughness",
    "clearcoat",
    "clearcoatRoughness",
    "opacity",
    "normal",
];

/// Reads a UsdPreviewSurface, warning about inputs it cannot honour.
fn preview_surface(ctx: &mut Ctx, shader: &usd::Prim) -> Result<PreviewSurfaceDesc> {
    warn_unsupported_preview_inputs(ctx, shader)?;
    let d = PreviewSurfaceDesc::default();
    let mut textures = Vec::new();
    for name in TEXTURABLE_INPUTS {
        if let Some(t) = texture_input(ctx, shader, name)? {
            textures.push((name.to_string(), t));
        }
    }
    let mut inputs = Inputs {
        ctx,
        shader,
        textured: textures.iter().map(|(n, _)| n.clone()).collect(),
        spectral: None,
    };
    let desc = PreviewSurfaceDesc {
        diffuse_color: inputs.rgb("diffuseColor")?.unwrap_or(d.diffuse_color),
        emissive_color: inputs.rgb("emissiveColor")?.unwrap_or(d.emissive_color),
        use_specular_workflow: inputs
            .bool("useSpecularWorkflow")?
            .unwrap_or(d.use_specular_workflow),
        specular_color: inputs.rgb("specularColor")?.unwrap_or(d.specular_color),
        metallic: inputs.f32("metallic")?.unwrap_or(d.metallic),
        roughness: inputs.f32("roughness")?.unwrap_or(d.roughness),
        clearcoat: inputs.f32("clearcoat")?.unwrap_or(d.clearcoat),
        clearcoat_roughness: inputs
            .f32("clearcoatRoughness")?
            .unwrap_or(d.clearcoat_roughness),
        opacity: inputs.f32("opacity")?.unwrap_or(d.opacity),
        opacity_threshold: inputs
            .f32("opacityThreshold")?
            .unwrap_or(d.opacity_threshold),
        ior: inputs.positive("ior")?.unwrap_or(d.ior),
        normal: inputs.vec3("normal")?.unwrap_or(d.normal),
        textures,
    };
    check_unit_inputs(ctx, shader, &desc)?;
    Ok(desc)
}

/// The UsdPreviewSurface inputs defined on [0, 1]: a negative value is an error (a negative
/// roughness is no mirror), a value above 1 is clamped to 1 with a warning.
fn check_unit_inputs(ctx: &mut Ctx, shader: &usd::Prim, p: &PreviewSurfaceDesc) -> Result<()> {
    let inputs = [
        ("metallic", p.metallic),
        ("roughness", p.roughness),
        ("clearcoat", p.clearcoat),
        ("clearcoatRoughness", p.clearcoat_roughness),
        ("opacity", p.opacity),
        ("opacityThreshold", p.opacity_threshold),
    ];
    for (name, v) in inputs {
        if v < 0.0 {
            let reason =
                format!("inputs:{name} = {v} is negative; UsdPreviewSurface defines it on [0, 1]");
            return Err(ctx.err(shader, reason));
        }
        if v > 1.0 {
            let message = format!("inputs:{name} = {v} is above 1; clamped to 1 (UsdPreviewSurface defines it on [0, 1])");
            ctx.warn(shader, message);
        }
    }
    Ok(())
}

/// The UsdPreviewSurface inputs of the specification that are not rendered.
const UNSUPPORTED_PREVIEW_INPUTS: [&str; 2] = ["displacement", "occlusion"];

/// Warns once per authored UsdPreviewSurface input that is ignored: those the specification
/// defines but the renderer does not model, and unknown ones (with a "did you mean").
fn warn_unsupported_preview_inputs(ctx: &mut Ctx, shader: &usd::Prim) -> Result<()> {
    for name in ctx.property_names(shader)? {
        let Some(input) = name.strip_prefix("inputs:") else {
            continue;
        };
        if UNSUPPORTED_PREVIEW_INPUTS.contains(&input) {
            ctx.warn(
                shader,
                format!("UsdPreviewSurface input '{name}' is not supported; ignored"),
            );
        }
    }
    let known: Vec<&str> = PREVIEW_INPUTS
        .iter()
        .chain(&UNSUPPORTED_PREVIEW_INPUTS)
        .copied()
        .collect();
    vocab::warn_unknown_inputs(ctx, shader, &known, "UsdPreviewSurface")
}

/// The inputs of the texture nodes of the UsdPreviewSurface specification.
const UV_TEXTURE_INPUTS: [&str; 8] = [
    "file",
    "st",
    "wrapS",
    "wrapT",
    "fallback",
    "scale",
    "bias",
    "sourceColorSpace",
];
const PRIMVAR_READER_INPUTS: [&str; 2] = ["varname", "fallback"];
const TRANSFORM2D_INPUTS: [&str; 4] = ["in", "rotation", "scale", "translation"];

/// What an input resolves to after following its connections.
enum Resolved {
    Unset,
    Value(sdf::Value),
    /// Connected to the output of another shader node (a texture, a primvar reader, ...).
    Node(sdf::Path, String),
}

/// Typed access to a shader's inputs; texture connections warn and fall back to the default.
struct Inputs<'a, 's> {
    ctx: &'a mut Ctx<'s>,
    shader: &'a usd::Prim,
    /// Inputs already read as textures (their value is unset here, without a warning).
    textured: Vec<String>,
    /// The `info:id` of a `spectral:*` shader, whose other node connections are errors;
    /// `None` for UsdPreviewSurface, where they are warnings.
    spectral: Option<String>,
}

impl Inputs<'_, '_> {
    /// The value of `inputs:<name>`, following interface connections; `None` when unset or
    /// connected to a node (which is warned about).
    fn value(&mut self, name: &str) -> Result<Option<sdf::Value>> {
        match resolve_input(self.ctx, self.shader, &format!("inputs:{name}"))? {
            Resolved::Unset => Ok(None),
            Resolved::Value(v) => Ok(Some(v)),
            Resolved::Node(_, _) if self.textured.iter().any(|t| t == name) => Ok(None),
            Resolved::Node(node, _) => {
                self.warn_node(name, &node)?;
                Ok(None)
            }
        }
    }

    /// Warns that `inputs:<name>` is driven by a shader node, or fails if that node is unknown.
    fn warn_node(&mut self, name: &str, node: &sdf::Path) -> Result<()> {
        let node_prim = self.ctx.stage.prim(node.clone());
        let id = self.ctx.token(&node_prim, "info:id")?.unwrap_or_default();
        if !KNOWN_NODE_PREFIXES.iter().any(|p| id.starts_with(p)) {
            return Err(self
                .ctx
                .err(&node_prim, format!("unknown shader info:id '{id}'")));
        }
        if let Some(shader_id) = &self.spectral {
            let accepted = vocab::texturable_inputs(shader_id)
                .iter()
                .map(|i| format!("inputs:{i}"))
                .collect::<Vec<_>>()
                .join(", ");
            let reason = format!(
                "inputs:{name} is connected to <{}> ({id}), but {shader_id} reads only a value \
                 there (texture connections are accepted on {accepted}, from a UsdUVTexture)",
                node.as_str()
            );
            return Err(self.ctx.err(self.shader, reason));
        }
        let message = format!(
            "inputs:{name} is connected to <{}> ({id}), but this input cannot be read from a texture; using the default",
            node.as_str()
        );
        self.ctx.warn(self.shader, message);
        Ok(())
    }

    /// Converts `inputs:<name>` with `convert`, failing with `expected` on a type mismatch.
    fn typed<T>(
        &mut self,
        name: &str,
        expected: &str,
        convert: impl Fn(&sdf::Value) -> Option<T>,
    ) -> Result<Option<T>> {
        let Some(value) = self.value(name)? else {
            return Ok(None);
        };
        match convert(&value) {
            Some(t) => Ok(Some(t)),
            None => {
                let reason = format!(
                    "'inputs:{name}' is {}, expected {expected}",
                    values::kind(&value)
                );
                Err(self.ctx.err(self.shader, reason))
            }
        }
    }

    /// A finite float.
    fn f32(&mut self, name: &str) -> Result<Option<f32>> {
        let value = self.typed(name, "a float", values::to_f64)?;
        if value.is_some_and(|x| !x.is_finite()) {
            return Err(self
                .ctx
                .err(self.shader, format!("'inputs:{name}' is not finite")));
        }
        Ok(value.map(|x| x as f32))
    }

    /// A float that must be positive (an index of refraction).
    fn positive(&mut self, name: &str) -> Result<Option<f32>> {
        let value = self.f32(name)?;
        if value.is_some_and(|x| x <= 0.0) {
            return Err(self
                .ctx
                .err(self.shader, format!("'inputs:{name}' must be positive")));
        }
        Ok(value)
    }

    /// A bool (ints 0/1 accepted).
    fn bool(&mut self, name: &str) -> Result<Option<bool>> {
        self.typed(name, "a bool", values::to_bool)
    }

    /// A token.
    fn token(&mut self, name: &str) -> Result<Option<String>> {
        self.typed(name, "a token", values::to_token)
    }

    /// A finite 3-vector.
    fn vec3(&mut self, name: &str) -> Result<Option<[f32; 3]>> {
        let value = self.typed(name, "a 3-vector", values::to_vec3)?;
        if value.is_some_and(|v| v.iter().any(|x| !x.is_finite())) {
            return Err(self
                .ctx
                .err(self.shader, format!("'inputs:{name}' is not finite")));
        }
        Ok(value.map(|v| v.map(|x| x as f32)))
    }

    /// An RGB colour.
    fn rgb(&mut self, name: &str) -> Result<Option<[f32; 3]>> {
        self.vec3(name)
    }

    /// `(nm, value)` samples from a `float2[]`.
    fn samples(&mut self, name: &str) -> Result<Option<Vec<(f32, f32)>>> {
        let Some(pairs) = self.typed(name, "float2[]", values::to_vec2_array)? else {
            return Ok(None);
        };
        let samples = values::validate_samples(&pairs).map_err(|reason| {
            self.ctx
                .err(self.shader, format!("'inputs:{name}': {reason}"))
        })?;
        Ok(Some(samples))
    }

    /// Fails when more than one of the mutually exclusive inputs `names` is authored.
    fn exclusive(&mut self, names: &[&str]) -> Result<()> {
        let mut authored = Vec::new();
        for name in names {
            let attr = format!("inputs:{name}");
            let has_value = self.ctx.raw(self.shader, &attr)?.is_some();
            if has_value || !self.ctx.connections(self.shader, &attr)?.is_empty() {
                authored.push(attr);
            }
        }
        if authored.len() > 1 {
            let reason = format!("give only one of {}", authored.join(", "));
            return Err(self.ctx.err(self.shader, reason));
        }
        Ok(())
    }

    /// `inputs:reflectance` (color3f) or `:spectrum` (token) or `:samples` (float2[]);
    /// default RGB 0.5.
    fn reflectance(&mut self) -> Result<SpectrumDesc> {
        self.exclusive(&["reflectance", "reflectance:spectrum", "reflectance:samples"])?;
        if let Some(rgb) = self.rgb("reflectance")? {
            return Ok(SpectrumDesc::Rgb(rgb));
        }
        if let Some(name) = self.token("reflectance:spectrum")? {
            return Ok(SpectrumDesc::Named(name));
        }
        if let Some(samples) = self.samples("reflectance:samples")? {
            return Ok(SpectrumDesc::Samples(samples));
        }
        Ok(SpectrumDesc::Rgb([0.5; 3]))
    }

    /// A conductor's (eta, k): from `inputs:metal` ("Au" -> "metal/Au" for both), or from
    /// `inputs:eta:spectrum` + `inputs:k:spectrum`; copper when neither is given (as pbrt-v4).
    fn conductor_spectra(&mut self) -> Result<(SpectrumDesc, SpectrumDesc)> {
        self.exclusive(&["metal", "eta:spectrum"])?;
        self.exclusive(&["metal", "k:spectrum"])?;
        if let Some(metal) = self.token("metal")? {
            let name = format!("metal/{metal}");
            return Ok((SpectrumDesc::Named(name.clone()), SpectrumDesc::Named(name)));
        }
        match (self.token("eta:spectrum")?, self.token("k:spectrum")?) {
            (Some(eta), Some(k)) => Ok((SpectrumDesc::Named(eta), SpectrumDesc::Named(k))),
            (None, None) => Ok((
                SpectrumDesc::Named("metal/Cu".into()),
                SpectrumDesc::Named("metal/Cu".into()),
            )),
            _ => Err(self.ctx.err(
                self.shader,
                "inputs:eta:spectrum and inputs:k:spectrum must be given together",
            )),
        }
    }

    /// A dielectric's IOR: `inputs:ior`, `inputs:glass` or Sellmeier B and C; default 1.5.
    fn dielectric_ior(&mut self) -> Result<IorDesc> {
        self.exclusive(&["ior", "glass", "sellmeierB"])?;
        self.exclusive(&["ior", "glass", "sellmeierC"])?;
        if let Some(ior) = self.positive("ior")? {
            return Ok(IorDesc::Constant(ior));
        }
        if let Some(glass) = self.token("glass")? {
            return Ok(IorDesc::Glass(glass));
        }
        match (self.vec3("sellmeierB")?, self.vec3("sellmeierC")?) {
            (Some(b), Some(c)) => Ok(IorDesc::Sellmeier { b, c }),
            (None, None) => Ok(IorDesc::Constant(1.5)),
            _ => Err(self.ctx.err(
                self.shader,
                "inputs:sellmeierB and inputs:sellmeierC must be given together",
            )),
        }
    }
}

/// Follows the connections of attribute `attr` on `prim` through Material / NodeGraph
/// interface inputs to a value or to a shader node's output.
fn resolve_input(ctx: &Ctx, prim: &usd::Prim, attr: &str) -> Result<Resolved> {
    let mut prim = prim.clone();
    let mut attr = attr.to_string();
    for _ in 0..MAX_CONNECTION_DEPTH {
        let Some(source) = ctx.connections(&prim, &attr)?.into_iter().next() else {
            return Ok(ctx
                .raw(&prim, &attr)?
                .map_or(Resolved::Unset, Resolved::Value));
        };
        let Some((source_prim, source_attr)) = source.split_property() else {
            return Err(ctx.err(
                &prim,
                format!("{attr} connects to <{}>, not an attribute", source.as_str()),
            ));
        };
        let next = ctx.stage.prim(source_prim.clone());
        if ctx.type_name(&next)? == "Shader" {
            return Ok(Resolved::Node(source_prim, source_attr.to_string()));
        }
        attr = source_attr.to_string();
        prim = next;
    }
    Err(ctx.err(&prim, format!("{attr}: connection chain too long (cycle?)")))
}

/// The `UsdUVTexture` driving `inputs:<name>` of `shader`, if it is connected to one.
fn texture_input(ctx: &mut Ctx, shader: &usd::Prim, name: &str) -> Result<Option<TextureDesc>> {
    let Resolved::Node(node, output) = resolve_input(ctx, shader, &format!("inputs:{name}"))?
    else {
        return Ok(None);
    };
    let prim = ctx.stage.prim(node);
    if ctx.token(&prim, "info:id")?.as_deref() != Some("UsdUVTexture") {
        return Ok(None);
    }
    Ok(Some(uv_texture(ctx, &prim, &output)?))
}

/// Reads a `UsdUVTexture` node whose output `output` is used.
fn uv_texture(ctx: &mut Ctx, prim: &usd::Prim, output: &str) -> Result<TextureDesc> {
    vocab::warn_unknown_inputs(ctx, prim, &UV_TEXTURE_INPUTS, "UsdUVTexture")?;
    let fallback = vec4(ctx, prim, "inputs:fallback", [0.0, 0.0, 0.0, 1.0])?;
    let file = match ctx.asset(prim, "inputs:file")? {
        Some(file) => file,
        None => {
            // UsdPreviewSurface spec, UsdUVTexture `inputs:fallback`: "Fallback value to be
            // used when no texture is connected"; an empty path is a constant texture of it.
            let warning =
                format!("UsdUVTexture has no inputs:file; its fallback {fallback:?} is used");
            ctx.warn(prim, warning);
            PathBuf::new()
        }
    };
    let channel = match output {
        "outputs:rgb" => TextureChannel::Rgb,
        "outputs:r" => TextureChannel::R,
        "outputs:g" => TextureChannel::G,
        "outputs:b" => TextureChannel::B,
        "outputs:a" => TextureChannel::A,
        _ => {
            let reason = format!("unsupported UsdUVTexture output '{output}' (rgb, r, g, b, a)");
            return Err(ctx.err(prim, reason));
        }
    };
    let (st_primvar, st_transform) = st_source(ctx, prim)?;
    Ok(TextureDesc {
        shader_path: prim.path().as_str().to_string(),
        file,
        st_primvar,
        st_transform,
        wrap_s: wrap(ctx, prim, "inputs:wrapS")?,
        wrap_t: wrap(ctx, prim, "inputs:wrapT")?,
        color_space: color_space(ctx, prim)?,
        scale: vec4(ctx, prim, "inputs:scale", [1.0; 4])?,
        bias: vec4(ctx, prim, "inputs:bias", [0.0; 4])?,
        fallback,
        channel,
    })
}

/// A constant (or interface-connected) token input of a texture node.
fn node_token(ctx: &Ctx, prim: &usd::Prim, attr: &str) -> Result<Option<String>> {
    match resolve_input(ctx, prim, attr)? {
        Resolved::Value(v) => values::to_token(&v).map(Some).ok_or_else(|| {
            ctx.err(
                prim,
                format!("'{attr}' is {}, expected a token", values::kind(&v)),
            )
        }),
        _ => Ok(None),
    }
}

/// `inputs:wrapS` / `wrapT`; `useMetadata` and unset are repeat.
fn wrap(ctx: &Ctx, prim: &usd::Prim, attr: &str) -> Result<Wrap> {
    match node_token(ctx, prim, attr)?.as_deref() {
        None | Some("repeat") | Some("useMetadata") => Ok(Wrap::Repeat),
        Some("clamp") => Ok(Wrap::Clamp),
        Some("mirror") => Ok(Wrap::Mirror),
        Some("black") => Ok(Wrap::Black),
        Some(other) => Err(ctx.err(
            prim,
            format!("{attr} '{other}' is not one of repeat, clamp, mirror, black, useMetadata"),
        )),
    }
}

/// `inputs:sourceColorSpace`: auto (default), sRGB or raw.
fn color_space(ctx: &Ctx, prim: &usd::Prim) -> Result<ColorSpace> {
    let attr = "inputs:sourceColorSpace";
    match node_token(ctx, prim, attr)?.as_deref() {
        None | Some("auto") => Ok(ColorSpace::Auto),
        Some("sRGB") => Ok(ColorSpace::Srgb),
        Some("raw") => Ok(ColorSpace::Raw),
        Some(other) => Err(ctx.err(
            prim,
            format!("{attr} '{other}' is not one of auto, sRGB, raw"),
        )),
    }
}

/// A finite float4 input (a float3 gets w from `default`).
fn vec4(ctx: &Ctx, prim: &usd::Prim, attr: &str, default: [f32; 4]) -> Result<[f32; 4]> {
    let Resolved::Value(v) = resolve_input(ctx, prim, attr)? else {
        return Ok(default);
    };
    match values::to_vec4(&v, f64::from(default[3])) {
        Some(x) if x.iter().all(|c| c.is_finite()) => Ok(x.map(|c| c as f32)),
        _ => Err(ctx.err(
            prim,
            format!("'{attr}' is {}, expected a finite float4", values::kind(&v)),
        )),
    }
}

/// The primvar named by the `UsdPrimvarReader_float2` feeding the texture's `inputs:st`
/// ("st" when st is unconnected or the reader names none), and the composition of the
/// `UsdTransform2d` nodes on the way (`None` without any).
fn st_source(ctx: &mut Ctx, prim: &usd::Prim) -> Result<(String, Option<Affine2>)> {
    let mut transform: Option<Affine2> = None;
    let (mut node, mut attr) = (prim.clone(), "inputs:st");
    for _ in 0..MAX_CONNECTION_DEPTH {
        let Resolved::Node(source, _) = resolve_input(ctx, &node, attr)? else {
            return Ok(("st".into(), transform));
        };
        let source = ctx.stage.prim(source);
        match ctx.token(&source, "info:id")?.unwrap_or_default().as_str() {
            "UsdPrimvarReader_float2" => {
                let what = "UsdPrimvarReader_float2";
                vocab::warn_unknown_inputs(ctx, &source, &PRIMVAR_READER_INPUTS, what)?;
                let varname = node_token(ctx, &source, "inputs:varname")?;
                return Ok((varname.unwrap_or_else(|| "st".into()), transform));
            }
            "UsdTransform2d" => {
                // This node is applied before the ones found so far (nearer the texture).
                vocab::warn_unknown_inputs(ctx, &source, &TRANSFORM2D_INPUTS, "UsdTransform2d")?;
                let t = transform2d(ctx, &source)?;
                transform = Some(transform.map_or(t, |outer| outer * t));
                (node, attr) = (source, "inputs:in");
            }
            id => {
                let reason = format!(
                    "{attr} comes from '{id}'; only UsdPrimvarReader_float2 and UsdTransform2d \
                     are supported"
                );
                return Err(ctx.err(&source, reason));
            }
        }
    }
    Err(ctx.err(prim, "inputs:st: connection chain too long (cycle?)"))
}

/// A `UsdTransform2d` node: result = in · scale, rotated by `rotation` degrees
/// counter-clockwise, plus `translation` (UsdPreviewSurface specification, "Transform2d").
fn transform2d(ctx: &Ctx, prim: &usd::Prim) -> Result<Affine2> {
    let rotation = node_float(ctx, prim, "inputs:rotation", 0.0)?;
    let scale = node_vec2(ctx, prim, "inputs:scale", [1.0; 2])?;
    let translation = node_vec2(ctx, prim, "inputs:translation", [0.0; 2])?;
    Ok(Affine2::from_scale_angle_translation(
        Vec2::from_array(scale),
        rotation.to_radians(),
        Vec2::from_array(translation),
    ))
}

/// A finite float input of a node (a value, possibly through interface connections).
fn node_float(ctx: &Ctx, prim: &usd::Prim, attr: &str, default: f32) -> Result<f32> {
    let v = match node_value(ctx, prim, attr)? {
        Some(v) => values::to_f64(&v)
            .filter(|x| x.is_finite())
            .ok_or_else(|| node_type_err(ctx, prim, attr, &v, "a finite float"))?,
        None => return Ok(default),
    };
    Ok(v as f32)
}

/// A finite float2 input of a node.
fn node_vec2(ctx: &Ctx, prim: &usd::Prim, attr: &str, default: [f32; 2]) -> Result<[f32; 2]> {
    let v = match node_value(ctx, prim, attr)? {
        Some(v) => values::to_vec2(&v)
            .filter(|x| x.iter().all(|c| c.is_finite()))
            .ok_or_else(|| node_type_err(ctx, prim, attr, &v, "a finite float2"))?,
        None => return Ok(default),
    };
    Ok(v.map(|c| c as f32))
}

/// The value of a node's input; an error when it is driven by another node.
fn node_value(ctx: &Ctx, prim: &usd::Prim, attr: &str) -> Result<Option<sdf::Value>> {
    match resolve_input(ctx, prim, attr)? {
        Resolved::Unset => Ok(None),
        Resolved::Value(v) => Ok(Some(v)),
        Resolved::Node(node, _) => Err(ctx.err(
            prim,
            format!(
                "'{attr}' is connected to <{}>; only a value is supported here",
                node.as_str()
            ),
        )),
    }
}

fn node_type_err(ctx: &Ctx, prim: &usd::Prim, attr: &str, v: &sdf::Value, what: &str) -> Error {
    ctx.err(
        prim,
        format!("'{attr}' is {}, expected {what}", values::kind(v)),
    )
}
