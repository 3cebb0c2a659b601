//! USD stage text shared by the integration tests: transforms, prims, the white furnace, the
//! committed Cornell box, and the closed forms they are checked against.

use super::{binding, camera, header, material, quad};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// The Cornell box committed with the tests (the same scene as Mitsuba 3's
/// `mi.cornell_box()`, in USD).
pub fn cbox_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usd/cbox.usda")
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

/// `def TY "NAME" { BODY }`.
pub fn prim(ty: &str, name: &str, body: &str) -> String {
    format!("def {ty} \"{name}\"\n{{\n{body}}}\n\n")
}

/// The six faces of the cube [−h, h]³, facing inwards.
pub fn cube_faces(h: f32) -> [[[f32; 3]; 4]; 6] {
    let (a, b) = (-h, h);
    [
        [[a, a, a], [a, b, a], [b, b, a], [b, a, a]],
        [[a, a, b], [b, a, b], [b, b, b], [a, b, b]],
        [[a, a, a], [a, a, b], [a, b, b], [a, b, a]],
        [[b, a, a], [b, b, a], [b, b, b], [b, a, b]],
        [[a, a, a], [b, a, a], [b, a, b], [a, a, b]],
        [[a, b, a], [a, b, b], [b, b, b], [b, b, a]],
    ]
}

/// The white furnace: the closed cube [−1, 1]³ whose six walls emit `le` nits on both sides
/// (double-sided, so winding does not matter) and reflect a spectrally flat `rho`; a camera
/// sits inside. Every point sees L = Le / (1 − ρ) in every direction (the Neumann series of a
/// closed, uniformly emitting and reflecting enclosure).
pub fn furnace_stage(le: f32, rho: f32) -> String {
    let flat =
        format!("        float2[] inputs:reflectance:samples = [(360, {rho}), (830, {rho})]\n");
    let light = format!("    float inputs:intensity = {le}\n{}", binding("Wall"));
    let mut s = header();
    s += &camera(0.5, 0.8, 0.0);
    s += "def Scope \"Looks\"\n{\n";
    s += &material("Wall", "spectral:diffuse", &flat);
    s += "}\n\n";
    for (i, face) in cube_faces(1.0).iter().enumerate() {
        let points: Vec<String> = face
            .iter()
            .map(|p| format!("({}, {}, {})", p[0], p[1], p[2]))
            .collect();
        s += &format!(
            "def Mesh \"Face{i}\" (\n    prepend apiSchemas = [\"MeshLightAPI\", \"MaterialBindingAPI\"]\n)\n{{\n    uniform bool doubleSided = 1\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n    point3f[] points = [{}]\n{light}}}\n\n",
            points.join(", ")
        );
    }
    s
}

/// Lambert's polygon formula (Lambert 1760; e.g. Arvo 1995, "Applications of irradiance
/// tensors", eq. 3): the illuminance from a uniform polygon of luminance L at `p` on a
/// surface of normal `n` is E = (L/2) Σᵢ βᵢ n·(rᵢ × rᵢ₊₁)/|rᵢ × rᵢ₊₁|, rᵢ the unit vectors to
/// the vertices and βᵢ the angle between rᵢ and rᵢ₊₁. Valid when the whole polygon is in
/// front of the surface (checked). Returns E/L.
pub fn lambert(p: DVec3, n: DVec3, verts: &[DVec3]) -> f64 {
    assert!(
        verts.iter().all(|v| n.dot(*v - p) > 0.0),
        "polygon not above the horizon"
    );
    let r: Vec<DVec3> = verts.iter().map(|v| (*v - p).normalize()).collect();
    let sum: f64 = (0..r.len())
        .map(|i| {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            let c = a.cross(b);
            c.length().atan2(a.dot(b)) * n.dot(c.normalize())
        })
        .sum();
    0.5 * sum.abs()
}

/// The cube [−h, h]³ as an indexed mesh: its 8 corners (bit k of the index picks +h on axis
/// k) and 6 quads sharing them, so a closed solid (a glass slab) is watertight by index.
pub fn cube_mesh(h: f64) -> (Vec<DVec3>, Vec<Vec<usize>>) {
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

/// A Lambertian plane with `inputs` under a constant dome of `l` nits, seen head-on.
pub fn dome_plane_stage(shader_id: &str, inputs: &str, l: f32) -> String {
    let mut s = header();
    s += &camera(1.0, 0.2, 0.0);
    s += &format!("def DomeLight \"Sky\"\n{{\n    float inputs:intensity = {l}\n}}\n\n");
    s += "def Scope \"Looks\"\n{\n";
    s += &material("Paint", shader_id, inputs);
    s += "}\n\n";
    s += &quad(
        "Plane",
        0.0,
        1.0,
        &binding("Paint"),
        "\"MaterialBindingAPI\"",
    );
    s
}
