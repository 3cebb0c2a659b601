//! USD text of the stages the tests write: headers, cameras, materials, meshes, and the
//! fixtures several test files share (the white furnace, the cube, a plane under a dome).

use glam::DVec3;

/// A stage that does not parse (an unterminated tuple).
pub const MALFORMED_USDA: &str = "#usda 1.0\ndef Xform \"A\"\n{\n    float x = (1, \n";

/// The API schema list of a mesh bound to a material.
pub const BINDING_API: &str = "\"MaterialBindingAPI\"";
/// The API schema list of an emissive mesh bound to a material.
pub const MESH_LIGHT_API: &str = "\"MeshLightAPI\", \"MaterialBindingAPI\"";

/// A USD stage header with the given `metersPerUnit` and `upAxis`.
pub fn stage_header(meters_per_unit: f64, up_axis: &str) -> String {
    format!(
        "#usda 1.0\n(\n    metersPerUnit = {meters_per_unit}\n    upAxis = \"{up_axis}\"\n)\n\n"
    )
}

/// A USD stage header in metres, Y up.
pub fn header() -> String {
    stage_header(1.0, "Y")
}

/// A camera at `pos` looking down −Z with a square 2·half_tan field at distance 1, near clip
/// `near` and `extra` lines before its transform.
fn camera_prim(pos: [f32; 3], half_tan: f32, near: f32, extra: &str) -> String {
    let focal = 10.0 / half_tan;
    format!(
        "def Camera \"Cam\"\n{{\n    float focalLength = {focal}\n    float horizontalAperture = 20\n    float verticalAperture = 20\n    float2 clippingRange = ({near}, 1000)\n{extra}    double3 xformOp:translate = ({}, {}, {})\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n\n",
        pos[0], pos[1], pos[2]
    )
}

/// A camera at `z` on +Z looking down −Z with a square 2·half_tan field at distance 1.
pub fn camera(z: f32, half_tan: f32, exposure: f32) -> String {
    camera_prim(
        [0.0, 0.0, z],
        half_tan,
        0.001,
        &format!("    float exposure = {exposure}\n"),
    )
}

/// A camera at `pos` looking down −Z with a square field of half-tangent `half_tan`.
pub fn camera_at(pos: [f32; 3], half_tan: f32, extra: &str) -> String {
    camera_prim(pos, half_tan, 0.01, extra)
}

/// `def <ty> "<name>"` with `body` lines.
pub fn prim(ty: &str, name: &str, body: &str) -> String {
    format!("def {ty} \"{name}\"\n{{\n{body}}}\n\n")
}

/// `xformOp`s in order (outermost first): ("translate", "(x, y, z)") or ("rotateX", "deg").
pub fn xform(ops: &[(&str, String)]) -> String {
    let mut s = String::new();
    let mut order = Vec::new();
    for (op, value) in ops {
        let ty = if *op == "translate" {
            "double3"
        } else {
            "float"
        };
        s += &format!("    {ty} xformOp:{op} = {value}\n");
        order.push(format!("\"xformOp:{op}\""));
    }
    s + &format!(
        "    uniform token[] xformOpOrder = [{}]\n",
        order.join(", ")
    )
}

/// A material with one shader; `inputs` are the shader's input lines.
pub fn material(name: &str, id: &str, inputs: &str) -> String {
    format!(
        "def Material \"{name}\"\n{{\n    token outputs:surface.connect = </Looks/{name}/S.outputs:surface>\n    def Shader \"S\"\n    {{\n        uniform token info:id = \"{id}\"\n{inputs}        token outputs:surface\n    }}\n}}\n"
    )
}

/// The shader input line of a spectrally flat reflectance `rho`.
pub fn flat_reflectance(rho: impl std::fmt::Display) -> String {
    format!("        float2[] inputs:reflectance:samples = [(360, {rho}), (830, {rho})]\n")
}

/// A Lambertian (`spectral:diffuse`) material of spectrally flat reflectance `rho`.
pub fn flat_diffuse(name: &str, rho: impl std::fmt::Display) -> String {
    material(name, "spectral:diffuse", &flat_reflectance(rho))
}

/// The `/Looks` scope holding `materials`.
pub fn looks_scope(materials: &str) -> String {
    format!("def Scope \"Looks\"\n{{\n{materials}}}\n\n")
}

pub fn binding(name: &str) -> String {
    format!("    rel material:binding = </Looks/{name}>\n")
}

/// A point as USD writes it, `(x, y, z)`, in the precision of its type.
pub trait UsdPoint {
    fn usd(&self) -> String;
}

impl UsdPoint for [f32; 3] {
    fn usd(&self) -> String {
        format!("({}, {}, {})", self[0], self[1], self[2])
    }
}

impl UsdPoint for DVec3 {
    fn usd(&self) -> String {
        format!("({}, {}, {})", self.x, self.y, self.z)
    }
}

fn usd_list(points: &[impl UsdPoint]) -> String {
    points
        .iter()
        .map(UsdPoint::usd)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A Mesh prim with API schemas `apis` (e.g. [`BINDING_API`], or "" for none): polygons
/// `faces` (vertex indices) over `points`, then `extra` lines.
pub fn mesh(
    name: &str,
    apis: &str,
    points: &[impl UsdPoint],
    faces: &[Vec<usize>],
    extra: &str,
) -> String {
    let counts: Vec<String> = faces.iter().map(|f| f.len().to_string()).collect();
    let idx: Vec<String> = faces.iter().flatten().map(|i| i.to_string()).collect();
    format!(
        "def Mesh \"{name}\" (\n    prepend apiSchemas = [{apis}]\n)\n{{\n    int[] faceVertexCounts = [{}]\n    int[] faceVertexIndices = [{}]\n    point3f[] points = [{}]\n{extra}}}\n\n",
        counts.join(", "),
        idx.join(", "),
        usd_list(points)
    )
}

/// The faces of a mesh whose only polygon runs over all its `n` points.
pub fn one_face(n: usize) -> Vec<Vec<usize>> {
    vec![(0..n).collect()]
}

/// A polygon mesh (one face) with the material binding API, optional per-vertex normals and
/// extra lines.
pub fn polygon<P: UsdPoint>(
    name: &str,
    points: &[P],
    normals: Option<&[P]>,
    extra: &str,
) -> String {
    let normals = normals
        .map(|n| format!("    normal3f[] normals = [{}]\n", usd_list(n)))
        .unwrap_or_default();
    mesh(
        name,
        BINDING_API,
        points,
        &one_face(points.len()),
        &format!("{normals}{extra}"),
    )
}

/// An axis-aligned quad mesh in the z = `z` plane facing +Z, half-size `h`.
pub fn quad(name: &str, z: f32, h: f32, extra: &str, api: &str) -> String {
    let points = [[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]];
    mesh(name, api, &points, &one_face(4), extra)
}

/// The cube [−h, h]³: corners (bit 1 of the index is x, bit 2 y, bit 4 z) and six quads wound
/// to face inwards (a room; reverse them for a solid).
pub fn cube(h: f64) -> (Vec<DVec3>, Vec<Vec<usize>>) {
    let pts = (0..8)
        .map(|i| {
            let c = |bit: usize| if i & bit != 0 { h } else { -h };
            DVec3::new(c(1), c(2), c(4))
        })
        .collect();
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    (pts, faces.iter().map(|f| f.to_vec()).collect())
}

/// The six faces of [`cube`] as separate quads, in the order z, x, y (−, + each) and wound the
/// other way round.
pub fn cube_faces(h: f64) -> [[DVec3; 4]; 6] {
    let (pts, faces) = cube(h);
    [0, 1, 4, 5, 2, 3].map(|f| {
        let q = &faces[f];
        [q[0], q[3], q[2], q[1]].map(|i| pts[i])
    })
}

/// A white furnace: the closed cube [−1, 1]³ whose six walls each emit `le` nits on both sides
/// (so winding does not matter) and reflect a spectrally flat `rho`; the camera sits inside.
pub fn furnace_stage(le: f32, rho: f32) -> String {
    let mut s = header();
    s += &camera(0.5, 0.8, 0.0);
    s += &looks_scope(&flat_diffuse("Wall", rho));
    let light = format!(
        "    uniform bool doubleSided = 1\n    float inputs:intensity = {le}\n{}",
        binding("Wall")
    );
    for (i, f) in cube_faces(1.0).iter().enumerate() {
        s += &mesh(&format!("Face{i}"), MESH_LIGHT_API, f, &one_face(4), &light);
    }
    s
}

/// A plane (the 2 × 2 quad "Plane" in z = 0, facing +Z, with `plane_extra` lines, bound to
/// /Looks/Paint) under a constant dome of `l` nits, seen head-on by `camera(1, 0.2)`;
/// `looks` is the /Looks scope.
pub fn dome_plane_stage(l: f32, looks: &str, plane_extra: &str) -> String {
    let mut s = header();
    s += &camera(1.0, 0.2, 0.0);
    s += &format!("def DomeLight \"Sky\"\n{{\n    float inputs:intensity = {l}\n}}\n\n");
    s += looks;
    s += &quad(
        "Plane",
        0.0,
        1.0,
        &format!("{plane_extra}{}", binding("Paint")),
        BINDING_API,
    );
    s
}
