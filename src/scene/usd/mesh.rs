//! UsdGeomMesh: topology validation, fan triangulation, winding, primvars (normals, texture
//! coordinates) and the transform to world space.
//!
//! Texture coordinates: a mesh piece keeps the one float2 primvar its material reads
//! (`MaterialDesc::texcoord`, `st` by default), with any interpolation (constant, uniform,
//! vertex/varying, faceVarying) and optional `:indices`, expanded per triangle corner.

use glam::{DMat3, DMat4, DVec3, Vec2, Vec3};
use openusd::usd;

use super::shapes::Shape;
use super::values::Ctx;
use crate::desc::MeshDesc;
use crate::error::Result;

/// A validated polygon mesh triangulated in world space, before it is split by GeomSubset.
pub(super) struct MeshGeometry {
    /// All of the mesh's points, world space (metres, Y up).
    pub positions: Vec<Vec3>,
    pub triangles: Vec<Triangle>,
    /// Shading normals per triangle corner, world space, unit length.
    pub normals: Option<Vec<[Vec3; 3]>>,
    pub double_sided: bool,
    /// The polygon topology (for reading primvars later).
    topology: Topology,
    /// Number of polygons (for GeomSubset face indices).
    pub face_count: usize,
}

/// One triangle of the fan triangulation, already wound front-face counter-clockwise.
#[derive(Clone, Copy, Debug)]
pub(super) struct Triangle {
    /// The polygon it came from.
    pub face: usize,
    pub corners: [Corner; 3],
}

/// A triangle corner: its face-vertex (index into `faceVertexIndices`) and its point.
#[derive(Clone, Copy, Debug)]
pub(super) struct Corner {
    pub face_vertex: usize,
    pub point: u32,
}

/// The validated polygon topology.
struct Topology {
    counts: Vec<usize>,
    indices: Vec<u32>,
    point_count: usize,
}

/// How a primvar's elements map onto the mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Interpolation {
    Constant,
    Uniform,
    /// `vertex` and `varying` (identical for polygon meshes).
    Vertex,
    FaceVarying,
}

/// A primvar's values, optional indices and interpolation.
struct Primvar<T> {
    name: String,
    values: Vec<T>,
    indices: Option<Vec<i64>>,
    interpolation: Interpolation,
}

/// Reads a Mesh prim into world-space triangles; `None` (with a warning) when it has nothing
/// to render. `local_to_world` is in stage space.
pub(super) fn read_geometry(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    local_to_world: DMat4,
) -> Result<Option<MeshGeometry>> {
    let Some((topology, points)) = read_topology(ctx, prim)? else {
        return Ok(None);
    };
    let Some(to_world) = world_matrix(ctx, prim, local_to_world) else {
        return Ok(None);
    };
    let holes = hole_mask(ctx, prim, topology.counts.len())?;
    let triangles = triangulate(&topology, &holes, flips(ctx, prim, &to_world)?);
    let normals = read_normals(ctx, prim, &topology, &triangles)?;
    assemble(ctx, prim, &to_world, &points, triangles, normals, topology).map(Some)
}

/// Turns a tessellated intrinsic shape (Sphere, Cube, ...) into world-space triangles.
pub(super) fn shape_geometry(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    local_to_world: DMat4,
    shape: Shape,
) -> Result<Option<MeshGeometry>> {
    let Some(to_world) = world_matrix(ctx, prim, local_to_world) else {
        return Ok(None);
    };
    let topology = Topology {
        counts: shape.counts,
        indices: shape.indices,
        point_count: shape.points.len(),
    };
    let triangles = triangulate(&topology, &[], flips(ctx, prim, &to_world)?);
    let normal = |c: &Corner| {
        shape
            .normals
            .get(c.point as usize)
            .copied()
            .unwrap_or(DVec3::Z)
    };
    let normals = triangles
        .iter()
        .map(|t| t.corners.each_ref().map(normal))
        .collect();
    assemble(
        ctx,
        prim,
        &to_world,
        &shape.points,
        triangles,
        Some(normals),
        topology,
    )
    .map(Some)
}

/// Stage-space `local_to_world` to world; `None` (warned) for a degenerate transform.
fn world_matrix(ctx: &mut Ctx, prim: &usd::Prim, local_to_world: DMat4) -> Option<DMat4> {
    let to_world = ctx.stage_to_world * local_to_world;
    let det = to_world.determinant();
    if !det.is_finite() || det.abs() < 1e-300 {
        ctx.warn(prim, "degenerate transform (zero scale); skipped");
        return None;
    }
    Some(to_world)
}

/// Whether the winding must be reversed: a leftHanded `orientation` or a mirroring
/// transform (but not both).
fn flips(ctx: &Ctx, prim: &usd::Prim, to_world: &DMat4) -> Result<bool> {
    Ok(left_handed(ctx, prim)? != (to_world.determinant() < 0.0))
}

/// Transforms points and object-space corner normals to world space; `doubleSided`
/// defaults to the schema fallback (true only for a Plane).
fn assemble(
    ctx: &Ctx,
    prim: &usd::Prim,
    to_world: &DMat4,
    points: &[DVec3],
    triangles: Vec<Triangle>,
    normals: Option<Vec<[DVec3; 3]>>,
    topology: Topology,
) -> Result<MeshGeometry> {
    let positions: Vec<Vec3> = points
        .iter()
        .map(|&p| to_world.transform_point3(p).as_vec3())
        .collect();
    let normals = normals.map(|n| world_normals(&n, &triangles, &positions, to_world));
    Ok(MeshGeometry {
        positions,
        triangles,
        normals,
        double_sided: ctx.bool_or(prim, "doubleSided", ctx.type_name(prim)? == "Plane")?,
        face_count: topology.counts.len(),
        topology,
    })
}

/// Reads and validates `points`, `faceVertexCounts` and `faceVertexIndices`.
fn read_topology(ctx: &mut Ctx, prim: &usd::Prim) -> Result<Option<(Topology, Vec<DVec3>)>> {
    let points: Vec<DVec3> = ctx
        .vec3_array(prim, "points")?
        .unwrap_or_default()
        .into_iter()
        .map(DVec3::from_array)
        .collect();
    let counts = ctx.int_array(prim, "faceVertexCounts")?.unwrap_or_default();
    let indices = ctx
        .int_array(prim, "faceVertexIndices")?
        .unwrap_or_default();
    if points.is_empty() || counts.is_empty() {
        ctx.warn(prim, "mesh has no points or no faces; skipped");
        return Ok(None);
    }
    let counts = validate_counts(ctx, prim, &counts, indices.len())?;
    let indices = validate_indices(ctx, prim, &indices, points.len())?;
    Ok(Some((
        Topology {
            counts,
            indices,
            point_count: points.len(),
        },
        points,
    )))
}

/// Every face has at least 3 vertices and the counts add up to the number of indices.
fn validate_counts(
    ctx: &Ctx,
    prim: &usd::Prim,
    counts: &[i64],
    index_count: usize,
) -> Result<Vec<usize>> {
    let mut sum = 0usize;
    let mut out = Vec::with_capacity(counts.len());
    for (face, &count) in counts.iter().enumerate() {
        let Some(n) = usize::try_from(count).ok().filter(|&n| n >= 3) else {
            let reason =
                format!("faceVertexCounts[{face}] = {count}: a face needs at least 3 vertices");
            return Err(ctx.err(prim, reason));
        };
        sum = sum.saturating_add(n);
        out.push(n);
    }
    if sum != index_count {
        let reason = format!(
            "faceVertexCounts add up to {sum} but faceVertexIndices has {index_count} entries"
        );
        return Err(ctx.err(prim, reason));
    }
    Ok(out)
}

/// Every face-vertex index names an existing point.
fn validate_indices(
    ctx: &Ctx,
    prim: &usd::Prim,
    indices: &[i64],
    point_count: usize,
) -> Result<Vec<u32>> {
    let mut out = Vec::with_capacity(indices.len());
    for (i, &index) in indices.iter().enumerate() {
        match u32::try_from(index)
            .ok()
            .filter(|&v| (v as usize) < point_count)
        {
            Some(v) => out.push(v),
            None => {
                let reason =
                    format!("faceVertexIndices[{i}] = {index} is out of range (the mesh has {point_count} points)");
                return Err(ctx.err(prim, reason));
            }
        }
    }
    Ok(out)
}

/// `orientation`: `true` for leftHanded.
fn left_handed(ctx: &Ctx, prim: &usd::Prim) -> Result<bool> {
    match ctx.token(prim, "orientation")?.as_deref() {
        None | Some("rightHanded") => Ok(false),
        Some("leftHanded") => Ok(true),
        Some(other) => Err(ctx.err(
            prim,
            format!("orientation '{other}' is not rightHanded or leftHanded"),
        )),
    }
}

/// Per face: `true` when `holeIndices` makes it a hole.
fn hole_mask(ctx: &Ctx, prim: &usd::Prim, face_count: usize) -> Result<Vec<bool>> {
    let mut holes = vec![false; face_count];
    for &face in &ctx.int_array(prim, "holeIndices")?.unwrap_or_default() {
        match usize::try_from(face).ok().and_then(|f| holes.get_mut(f)) {
            Some(hole) => *hole = true,
            None => return Err(ctx.err(prim, format!("holeIndices: face {face} does not exist"))),
        }
    }
    Ok(holes)
}

/// Fan-triangulates every non-hole face; `flip` reverses the winding.
fn triangulate(topology: &Topology, holes: &[bool], flip: bool) -> Vec<Triangle> {
    let mut triangles = Vec::with_capacity(topology.indices.len());
    let mut start = 0;
    for (face, &n) in topology.counts.iter().enumerate() {
        if !holes.get(face).copied().unwrap_or(false) {
            let corner = |k: usize| Corner {
                face_vertex: start + k,
                point: topology.indices[start + k],
            };
            for k in 1..n - 1 {
                let (b, c) = if flip { (k + 1, k) } else { (k, k + 1) };
                triangles.push(Triangle {
                    face,
                    corners: [corner(0), corner(b), corner(c)],
                });
            }
        }
        start += n;
    }
    triangles
}

/// Reads the normals primvar (`primvars:normals` wins over `normals`) per triangle corner, in
/// object space; `None` when absent or invalid (warned).
fn read_normals(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    topology: &Topology,
    triangles: &[Triangle],
) -> Result<Option<Vec<[DVec3; 3]>>> {
    let (name, default_interpolation) = if ctx.raw(prim, "primvars:normals")?.is_some() {
        ("primvars:normals", Interpolation::Constant)
    } else {
        ("normals", Interpolation::Vertex)
    };
    let Some(values) = ctx.vec3_array(prim, name)? else {
        return Ok(None);
    };
    let values = values.into_iter().map(DVec3::from_array).collect();
    let Some(primvar) = primvar(ctx, prim, name, values, default_interpolation)? else {
        return Ok(None);
    };
    Ok(expand(ctx, prim, &primvar, topology, triangles))
}

/// Reads the float2 primvar `primvars:<name>` (texture coordinates) per triangle corner;
/// `None` when absent or invalid (warned).
pub(super) fn read_texcoords(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    geometry: &MeshGeometry,
    name: &str,
) -> Result<Option<Vec<[Vec2; 3]>>> {
    let name = &format!("primvars:{name}");
    let Some(values) = ctx.vec2_array(prim, name)? else {
        return Ok(None);
    };
    let values = values
        .into_iter()
        .map(|v| Vec2::new(v[0] as f32, v[1] as f32))
        .collect();
    let Some(primvar) = primvar(ctx, prim, name, values, Interpolation::Constant)? else {
        return Ok(None);
    };
    Ok(expand(
        ctx,
        prim,
        &primvar,
        &geometry.topology,
        &geometry.triangles,
    ))
}

/// Completes a primvar with its `interpolation` metadata and `:indices`.
fn primvar<T>(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    name: &str,
    values: Vec<T>,
    default: Interpolation,
) -> Result<Option<Primvar<T>>> {
    let interpolation = match ctx
        .attr_token_metadata(prim, name, "interpolation")?
        .as_deref()
    {
        None => default,
        Some("constant") => Interpolation::Constant,
        Some("uniform") => Interpolation::Uniform,
        Some("vertex" | "varying") => Interpolation::Vertex,
        Some("faceVarying") => Interpolation::FaceVarying,
        Some(other) => {
            ctx.warn(
                prim,
                format!("{name}: unknown interpolation '{other}'; ignored"),
            );
            return Ok(None);
        }
    };
    let indices = ctx.int_array(prim, &format!("{name}:indices"))?;
    Ok(Some(Primvar {
        name: name.to_string(),
        values,
        indices,
        interpolation,
    }))
}

/// The primvar's value for every triangle corner; `None` (warned) when its size does not fit
/// the interpolation or an index is out of range.
fn expand<T: Copy>(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    primvar: &Primvar<T>,
    topology: &Topology,
    triangles: &[Triangle],
) -> Option<Vec<[T; 3]>> {
    let needed = match primvar.interpolation {
        Interpolation::Constant => 1,
        Interpolation::Uniform => topology.counts.len(),
        Interpolation::Vertex => topology.point_count,
        Interpolation::FaceVarying => topology.indices.len(),
    };
    let available = primvar
        .indices
        .as_ref()
        .map_or(primvar.values.len(), Vec::len);
    if available < needed {
        let message = format!(
            "{} has {available} elements but {:?} interpolation needs {needed}; ignored",
            primvar.name, primvar.interpolation
        );
        ctx.warn(prim, message);
        return None;
    }
    let lookup = |tri: &Triangle, c: &Corner| -> Option<T> {
        let element = match primvar.interpolation {
            Interpolation::Constant => 0,
            Interpolation::Uniform => tri.face,
            Interpolation::Vertex => c.point as usize,
            Interpolation::FaceVarying => c.face_vertex,
        };
        let value_index = match &primvar.indices {
            Some(indices) => usize::try_from(*indices.get(element)?).ok()?,
            None => element,
        };
        primvar.values.get(value_index).copied()
    };
    let expanded: Option<Vec<[T; 3]>> = triangles
        .iter()
        .map(|t| {
            Some([
                lookup(t, &t.corners[0])?,
                lookup(t, &t.corners[1])?,
                lookup(t, &t.corners[2])?,
            ])
        })
        .collect();
    if expanded.is_none() {
        ctx.warn(
            prim,
            format!(
                "{}:indices has an index out of range; {} ignored",
                primvar.name, primvar.name
            ),
        );
    }
    expanded
}

/// Object-space normals to world space (inverse transpose), normalised; a zero normal is
/// replaced by the triangle's geometric normal.
fn world_normals(
    normals: &[[DVec3; 3]],
    triangles: &[Triangle],
    positions: &[Vec3],
    to_world: &DMat4,
) -> Vec<[Vec3; 3]> {
    let normal_matrix = DMat3::from_mat4(*to_world).inverse().transpose();
    normals
        .iter()
        .zip(triangles)
        .map(|(corners, tri)| {
            let fallback = geometric_normal(tri, positions);
            corners.map(|n| {
                let n = (normal_matrix * n).as_vec3();
                n.try_normalize().unwrap_or(fallback)
            })
        })
        .collect()
}

/// The unit normal `(p1 - p0) x (p2 - p0)` of a triangle (+Y if degenerate).
fn geometric_normal(tri: &Triangle, positions: &[Vec3]) -> Vec3 {
    let p = |k: usize| {
        positions
            .get(tri.corners[k].point as usize)
            .copied()
            .unwrap_or(Vec3::ZERO)
    };
    (p(1) - p(0))
        .cross(p(2) - p(0))
        .try_normalize()
        .unwrap_or(Vec3::Y)
}

/// Builds a `MeshDesc` from the triangles whose face `keep` selects, with the positions
/// compacted to the points they use and `all_uvs` (per triangle of the whole mesh, from
/// [`read_texcoords`]) kept for them. Material and light are left for the caller.
pub(super) fn to_desc(
    geometry: &MeshGeometry,
    prim_path: &str,
    keep: impl Fn(usize) -> bool,
    all_uvs: Option<&[[Vec2; 3]]>,
) -> MeshDesc {
    let mut remap = vec![u32::MAX; geometry.positions.len()];
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut normals = geometry.normals.as_ref().map(|_| Vec::new());
    let mut uvs = all_uvs.map(|_| Vec::new());
    for (t, tri) in geometry
        .triangles
        .iter()
        .enumerate()
        .filter(|(_, tri)| keep(tri.face))
    {
        indices.push(tri.corners.map(|c| {
            let slot = &mut remap[c.point as usize];
            if *slot == u32::MAX {
                *slot = positions.len() as u32;
                positions.push(geometry.positions[c.point as usize]);
            }
            *slot
        }));
        if let (Some(out), Some(all)) = (normals.as_mut(), geometry.normals.as_ref()) {
            out.push(all[t]);
        }
        if let (Some(out), Some(all)) = (uvs.as_mut(), all_uvs) {
            out.push(all[t]);
        }
    }
    MeshDesc {
        prim_path: prim_path.to_string(),
        positions,
        indices,
        normals,
        uvs,
        material: None,
        double_sided: geometry.double_sided,
        light: None,
    }
}
