//! Typed, error-checked access to composed attribute values.
//!
//! openusd hands back raw `sdf::Value`s whose variant depends on how the value was authored
//! (a time sample `1` is an `Int64`, a `double3` is a `Vec3d`, ...). The converters here accept
//! every sensible spelling of a type and the `Ctx` getters turn a mismatch into an
//! [`Error::prim`] naming the attribute.

use glam::DMat4;
use openusd::ar::{self, Resolver};
use openusd::{sdf, usd};
use std::path::{Path, PathBuf};

use crate::desc::ExtractedAssets;
use crate::error::{Error, Result};
use std::sync::Arc;

/// What every reader function needs: the stage, the time to read at, the unit conversion and
/// the list of warnings being collected.
pub(super) struct Ctx<'s> {
    /// The file as the user named it (used in messages).
    pub file: PathBuf,
    pub stage: &'s usd::Stage,
    /// The time code values are read at (time samples win over defaults).
    pub time: usd::TimeCode,
    /// The stage's `metersPerUnit`.
    pub meters_per_unit: f64,
    /// The stage is Z up (rotated to Y up in `stage_to_world`).
    pub z_up: bool,
    /// Stage space (stage units, stage up axis) to world (metres, Y up).
    pub stage_to_world: DMat4,
    pub warnings: Vec<String>,
    /// Where assets packaged in a `.usdz` are copied for the builder.
    pub extracted: Arc<ExtractedAssets>,
    /// Set once an attribute read has two or more time samples.
    pub animated: std::cell::Cell<bool>,
}

impl Ctx<'_> {
    /// An error about `prim`.
    pub fn err(&self, prim: &usd::Prim, reason: impl Into<String>) -> Error {
        Error::prim(&self.file, prim.path().as_str(), reason)
    }

    /// Records a warning about `prim`.
    pub fn warn(&mut self, prim: &usd::Prim, message: impl AsRef<str>) {
        let warning = format!("{}: {}", prim.path().as_str(), message.as_ref());
        if !self.warnings.contains(&warning) {
            self.warnings.push(warning);
        }
    }

    /// Maps an openusd error about `prim` into ours.
    pub fn usd_err(&self, prim: &usd::Prim, what: &str, e: impl std::fmt::Display) -> Error {
        Error {
            kind: crate::error::ErrorKind::Usd,
            ..self.err(prim, format!("{what}: {e:#}"))
        }
    }

    /// The prim's type name, "" when typeless.
    pub fn type_name(&self, prim: &usd::Prim) -> Result<String> {
        let name = prim
            .type_name()
            .map_err(|e| self.usd_err(prim, "reading the prim type", e))?;
        Ok(name.map(|t| t.as_str().to_string()).unwrap_or_default())
    }

    /// The prim's applied API schemas.
    pub fn api_schemas(&self, prim: &usd::Prim) -> Result<Vec<String>> {
        let apis = prim
            .api_schemas()
            .map_err(|e| self.usd_err(prim, "reading apiSchemas", e))?;
        Ok(apis.iter().map(|t| t.as_str().to_string()).collect())
    }

    /// The names of the prim's composed properties.
    pub fn property_names(&self, prim: &usd::Prim) -> Result<Vec<String>> {
        let names = prim
            .property_names()
            .map_err(|e| self.usd_err(prim, "listing properties", e))?;
        Ok(names.iter().map(|t| t.as_str().to_string()).collect())
    }

    /// The composed value of attribute `name` at `self.time`; `None` when unauthored or blocked.
    pub fn raw(&self, prim: &usd::Prim, name: &str) -> Result<Option<sdf::Value>> {
        let attribute = prim.attribute(name);
        let spline = attribute
            .get_metadata::<sdf::Value>("spline")
            .map_err(|e| self.usd_err(prim, &format!("reading '{name}'"), e))?;
        if spline.is_some() {
            let reason = format!(
                "'{name}' is animated by a spline ('{name}.spline'), which this reader does \
                 not evaluate; author time samples instead"
            );
            return Err(self.err(prim, reason));
        }
        let value = attribute
            .get_at::<sdf::Value>(self.time)
            .map_err(|e| self.usd_err(prim, &format!("reading '{name}'"), e))?;
        if value.is_some() && !self.animated.get() {
            let samples = attribute
                .num_time_samples()
                .map_err(|e| self.usd_err(prim, &format!("reading '{name}'"), e))?;
            self.animated.set(samples > 1);
        }
        Ok(value.filter(|v| !matches!(v, sdf::Value::ValueBlock | sdf::Value::None)))
    }

    /// Reads attribute `name` and converts it with `convert`, which names the expected type.
    fn typed<T>(
        &self,
        prim: &usd::Prim,
        name: &str,
        expected: &str,
        convert: impl Fn(&sdf::Value) -> Option<T>,
    ) -> Result<Option<T>> {
        match self.raw(prim, name)? {
            None => Ok(None),
            Some(v) => match convert(&v) {
                Some(t) => Ok(Some(t)),
                None => Err(self.err(
                    prim,
                    format!("'{name}' is {}, expected {expected}", kind(&v)),
                )),
            },
        }
    }

    /// A scalar number; non-finite values are errors.
    pub fn f64(&self, prim: &usd::Prim, name: &str) -> Result<Option<f64>> {
        let value = self.typed(prim, name, "a number", to_f64)?;
        match value {
            Some(x) if !x.is_finite() => Err(self.err(prim, format!("'{name}' is not finite"))),
            other => Ok(other),
        }
    }

    /// A scalar number as `f32`, or `default` when unauthored.
    pub fn f32_or(&self, prim: &usd::Prim, name: &str, default: f32) -> Result<f32> {
        Ok(self.f64(prim, name)?.map_or(default, |x| x as f32))
    }

    /// A boolean (ints 0/1 accepted), or `default` when unauthored.
    pub fn bool_or(&self, prim: &usd::Prim, name: &str, default: bool) -> Result<bool> {
        Ok(self
            .typed(prim, name, "a bool", to_bool)?
            .unwrap_or(default))
    }

    /// A token or string.
    pub fn token(&self, prim: &usd::Prim, name: &str) -> Result<Option<String>> {
        self.typed(prim, name, "a token", to_token)
    }

    /// A 2-vector.
    pub fn vec2(&self, prim: &usd::Prim, name: &str) -> Result<Option<[f64; 2]>> {
        self.typed(prim, name, "a 2-vector", to_vec2)
    }

    /// A 3-vector (point, colour, ...), finite.
    pub fn vec3(&self, prim: &usd::Prim, name: &str) -> Result<Option<[f64; 3]>> {
        let value = self.typed(prim, name, "a 3-vector", to_vec3)?;
        if value.is_some_and(|v| v.iter().any(|x| !x.is_finite())) {
            return Err(self.err(prim, format!("'{name}' is not finite")));
        }
        Ok(value)
    }

    /// An RGB colour as `f32`, or `default` when unauthored.
    pub fn rgb_or(&self, prim: &usd::Prim, name: &str, default: [f32; 3]) -> Result<[f32; 3]> {
        Ok(self
            .vec3(prim, name)?
            .map_or(default, |c| c.map(|x| x as f32)))
    }

    /// An array of 2-vectors, finite.
    pub fn vec2_array(&self, prim: &usd::Prim, name: &str) -> Result<Option<Vec<[f64; 2]>>> {
        let value = self.typed(prim, name, "an array of 2-vectors", to_vec2_array)?;
        if value
            .as_ref()
            .is_some_and(|a| a.iter().flatten().any(|x| !x.is_finite()))
        {
            return Err(self.err(prim, format!("'{name}' has non-finite values")));
        }
        Ok(value)
    }

    /// An array of 3-vectors, finite.
    pub fn vec3_array(&self, prim: &usd::Prim, name: &str) -> Result<Option<Vec<[f64; 3]>>> {
        let value = self.typed(prim, name, "an array of 3-vectors", to_vec3_array)?;
        if value
            .as_ref()
            .is_some_and(|a| a.iter().flatten().any(|x| !x.is_finite()))
        {
            return Err(self.err(prim, format!("'{name}' has non-finite values")));
        }
        Ok(value)
    }

    /// An array of integers.
    pub fn int_array(&self, prim: &usd::Prim, name: &str) -> Result<Option<Vec<i64>>> {
        self.typed(prim, name, "an array of ints", to_int_array)
    }

    /// `(nm, value)` pairs from a `float2[]` (see [`validate_samples`]).
    pub fn samples(&self, prim: &usd::Prim, name: &str) -> Result<Option<Vec<(f32, f32)>>> {
        let Some(pairs) = self.vec2_array(prim, name)? else {
            return Ok(None);
        };
        let samples = validate_samples(&pairs)
            .map_err(|reason| self.err(prim, format!("'{name}': {reason}")))?;
        Ok(Some(samples))
    }

    /// The metadata `key` of attribute `name` as a token (e.g. primvar `interpolation`).
    pub fn attr_token_metadata(
        &self,
        prim: &usd::Prim,
        name: &str,
        key: &str,
    ) -> Result<Option<String>> {
        let value = prim
            .attribute(name)
            .get_metadata::<sdf::Value>(key)
            .map_err(|e| self.usd_err(prim, &format!("reading '{name}' metadata {key}"), e))?;
        Ok(value.as_ref().and_then(to_token))
    }

    /// The targets of relationship `name`.
    pub fn targets(&self, prim: &usd::Prim, name: &str) -> Result<Vec<sdf::Path>> {
        prim.relationship(name)
            .targets()
            .map_err(|e| self.usd_err(prim, &format!("reading relationship '{name}'"), e))
    }

    /// The connection sources of attribute `name`.
    pub fn connections(&self, prim: &usd::Prim, name: &str) -> Result<Vec<sdf::Path>> {
        prim.attribute(name)
            .connections()
            .map_err(|e| self.usd_err(prim, &format!("reading connections of '{name}'"), e))
    }

    /// An asset path, resolved to an absolute file: the resolver's answer when it found the
    /// file, else relative to the root layer's directory. `None` when unauthored or empty.
    pub fn asset(&self, prim: &usd::Prim, name: &str) -> Result<Option<PathBuf>> {
        let asset = match self.raw(prim, name)? {
            None => return Ok(None),
            Some(sdf::Value::AssetPath(a)) => a,
            Some(v) => {
                return Err(self.err(prim, format!("'{name}' is {}, expected an asset", kind(&v))))
            }
        };
        if asset.asset_path().is_empty() {
            return Ok(None);
        }
        if let Some(resolved) = asset.resolved_path() {
            if ar::is_package_relative_path(resolved) {
                let file = extract_packaged(resolved, &self.extracted.dir).map_err(|e| {
                    self.err(prim, format!("'{name}': extracting '{resolved}': {e}"))
                })?;
                return Ok(Some(file));
            }
            return Ok(Some(absolute(Path::new(resolved))));
        }
        let dir = self.file.parent().unwrap_or(Path::new("."));
        let candidate = absolute(&dir.join(asset.asset_path()));
        if candidate.is_file() {
            return Ok(Some(candidate));
        }
        Err(self.err(
            prim,
            format!("'{name}': file '{}' not found", asset.asset_path()),
        ))
    }
}

/// Checks `(nm, value)` pairs: non-empty, finite, wavelengths strictly increasing.
pub(super) fn validate_samples(pairs: &[[f64; 2]]) -> std::result::Result<Vec<(f32, f32)>, String> {
    if pairs.is_empty() {
        return Err("no samples".into());
    }
    if pairs.iter().flatten().any(|x| !x.is_finite()) {
        return Err("non-finite sample".into());
    }
    if pairs.windows(2).any(|w| w[1][0] <= w[0][0]) {
        return Err("wavelengths must increase strictly".into());
    }
    Ok(pairs.iter().map(|p| (p[0] as f32, p[1] as f32)).collect())
}

/// Copies a file packaged in a `.usdz` (`pkg.usdz[tex/sky.exr]`) into `root`, in a
/// subdirectory keyed by its content, so that the scene builder can open it as a plain file.
fn extract_packaged(resolved: &str, root: &Path) -> std::io::Result<PathBuf> {
    use std::hash::{Hash, Hasher};
    let bytes = ar::DefaultResolver::new()
        .open_asset(&ar::ResolvedPath::new(resolved))?
        .read_all()?;
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    bytes.hash(&mut hasher);
    let inner = ar::split_package_relative_path_inner(resolved)
        .map_or(resolved.to_string(), |(_, inner)| inner);
    let file_name = Path::new(&inner)
        .file_name()
        .map_or("asset".into(), |n| n.to_os_string());
    let dir = root.join(format!("{:016x}", hasher.finish()));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(file_name);
    std::fs::write(&path, &bytes)?;
    Ok(path)
}

/// `path` made absolute (canonical when it exists).
fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .unwrap_or_else(|_| path.to_path_buf())
}

/// The variant name of a value, for messages.
pub(super) fn kind(v: &sdf::Value) -> &'static str {
    v.into()
}

/// Any scalar number.
pub(super) fn to_f64(v: &sdf::Value) -> Option<f64> {
    use sdf::Value as V;
    match v {
        V::Float(x) => Some(f64::from(*x)),
        V::Double(x) => Some(*x),
        V::Half(x) => Some(f64::from(x.to_f32())),
        V::Int(x) => Some(f64::from(*x)),
        V::Uint(x) => Some(f64::from(*x)),
        V::Uchar(x) => Some(f64::from(*x)),
        V::Int64(x) => Some(*x as f64),
        V::Uint64(x) => Some(*x as f64),
        _ => None,
    }
}

/// A bool, or an integer 0/1.
pub(super) fn to_bool(v: &sdf::Value) -> Option<bool> {
    match v {
        sdf::Value::Bool(b) => Some(*b),
        other => {
            let x = to_f64(other)?;
            (x == 0.0 || x == 1.0).then_some(x == 1.0)
        }
    }
}

/// A token or a string.
pub(super) fn to_token(v: &sdf::Value) -> Option<String> {
    match v {
        sdf::Value::Token(t) => Some(t.as_str().to_string()),
        sdf::Value::String(s) => Some(s.clone()),
        _ => None,
    }
}

/// Any 2-vector.
pub(super) fn to_vec2(v: &sdf::Value) -> Option<[f64; 2]> {
    use sdf::Value as V;
    match v {
        V::Vec2f(a) => Some([a.x, a.y].map(f64::from)),
        V::Vec2d(a) => Some([a.x, a.y]),
        V::Vec2h(a) => Some([a.x, a.y].map(|h| f64::from(h.to_f32()))),
        V::Vec2i(a) => Some([a.x, a.y].map(f64::from)),
        _ => None,
    }
}

/// Any 3-vector.
pub(super) fn to_vec3(v: &sdf::Value) -> Option<[f64; 3]> {
    use sdf::Value as V;
    match v {
        V::Vec3f(a) => Some([a.x, a.y, a.z].map(f64::from)),
        V::Vec3d(a) => Some([a.x, a.y, a.z]),
        V::Vec3h(a) => Some([a.x, a.y, a.z].map(|h| f64::from(h.to_f32()))),
        V::Vec3i(a) => Some([a.x, a.y, a.z].map(f64::from)),
        _ => None,
    }
}

/// Any array of 2-vectors.
pub(super) fn to_vec2_array(v: &sdf::Value) -> Option<Vec<[f64; 2]>> {
    use sdf::Value as V;
    match v {
        V::Vec2fVec(a) => Some(a.iter().map(|p| [p.x, p.y].map(f64::from)).collect()),
        V::Vec2dVec(a) => Some(a.iter().map(|p| [p.x, p.y]).collect()),
        V::Vec2hVec(a) => Some(
            a.iter()
                .map(|p| [p.x, p.y].map(|h| f64::from(h.to_f32())))
                .collect(),
        ),
        V::Vec2iVec(a) => Some(a.iter().map(|p| [p.x, p.y].map(f64::from)).collect()),
        _ => None,
    }
}

/// Any array of 3-vectors.
pub(super) fn to_vec3_array(v: &sdf::Value) -> Option<Vec<[f64; 3]>> {
    use sdf::Value as V;
    match v {
        V::Vec3fVec(a) => Some(a.iter().map(|p| [p.x, p.y, p.z].map(f64::from)).collect()),
        V::Vec3dVec(a) => Some(a.iter().map(|p| [p.x, p.y, p.z]).collect()),
        V::Vec3hVec(a) => Some(
            a.iter()
                .map(|p| [p.x, p.y, p.z].map(|h| f64::from(h.to_f32())))
                .collect(),
        ),
        V::Vec3iVec(a) => Some(a.iter().map(|p| [p.x, p.y, p.z].map(f64::from)).collect()),
        _ => None,
    }
}

/// Any array of integers.
pub(super) fn to_int_array(v: &sdf::Value) -> Option<Vec<i64>> {
    use sdf::Value as V;
    match v {
        V::IntVec(a) => Some(a.iter().map(|&x| i64::from(x)).collect()),
        V::Int64Vec(a) => Some(a.clone()),
        V::UintVec(a) => Some(a.iter().map(|&x| i64::from(x)).collect()),
        V::UcharVec(a) => Some(a.iter().map(|&x| i64::from(x)).collect()),
        V::Uint64Vec(a) => Some(
            a.iter()
                .map(|&x| i64::try_from(x).unwrap_or(i64::MAX))
                .collect(),
        ),
        _ => None,
    }
}

/// Any 4-vector (a float 3-vector is extended with w = `w3`).
pub(super) fn to_vec4(v: &sdf::Value, w3: f64) -> Option<[f64; 4]> {
    use sdf::Value as V;
    match v {
        V::Vec4f(a) => Some([a.x, a.y, a.z, a.w].map(f64::from)),
        V::Vec4d(a) => Some([a.x, a.y, a.z, a.w]),
        V::Vec4h(a) => Some([a.x, a.y, a.z, a.w].map(|h| f64::from(h.to_f32()))),
        _ => to_vec3(v).map(|[x, y, z]| [x, y, z, w3]),
    }
}

/// A quaternion as `(w, x, y, z)`.
pub(super) fn to_quat(v: &sdf::Value) -> Option<[f64; 4]> {
    use sdf::Value as V;
    match v {
        V::Quatf(q) => Some([q.w, q.x, q.y, q.z].map(f64::from)),
        V::Quatd(q) => Some([q.w, q.x, q.y, q.z]),
        V::Quath(q) => Some([q.w, q.x, q.y, q.z].map(|h| f64::from(h.to_f32()))),
        _ => None,
    }
}

/// A 4x4 matrix, as the 16 numbers in USD's (row-major, row-vector) order.
pub(super) fn to_matrix4(v: &sdf::Value) -> Option<[f64; 16]> {
    match v {
        sdf::Value::Matrix4d(m) => Some(m.0),
        _ => None,
    }
}
