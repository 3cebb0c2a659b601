//! Meshes: transforms, winding, triangulation, primvars, subsets.

use glam::{Vec2, Vec3};

use super::*;

/// A unit right triangle in the XY plane facing +Z, with `extra` lines inside the prim.
fn triangle_mesh(name: &str, extra: &str) -> String {
    format!(
        r#"def Mesh "{name}" {{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    {extra}
}}
"#
    )
}

/// A mesh with one point at (1, 0, 0) under the given xform lines.
fn point_under(xform: &str) -> Vec3 {
    let desc = load_body(&format!(
        "def Xform \"X\" {{\n{xform}\n{}}}\n",
        triangle_mesh("M", "")
    ));
    mesh(&desc, "/X/M").positions[1]
}

#[test]
fn nested_translate_rotate_scale() {
    let desc = load_body(&format!(
        r#"def Xform "P" {{
    double3 xformOp:translate = (1, 2, 3)
    float xformOp:rotateY = 90
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateY"]
    def Xform "C" {{
        float3 xformOp:scale = (2, 2, 2)
        uniform token[] xformOpOrder = ["xformOp:scale"]
        {}
    }}
}}
"#,
        triangle_mesh("M", "")
    ));
    // scale first: (2, 0, 0); rotateY 90: (0, 0, -2); translate: (1, 2, 1).
    assert_close(
        mesh(&desc, "/P/C/M").positions[1],
        Vec3::new(1.0, 2.0, 1.0),
        1e-6,
    );
}

#[test]
fn xform_op_kinds() {
    let orient = r#"quatf xformOp:orient = (0.70710677, 0, 0, 0.70710677)
        uniform token[] xformOpOrder = ["xformOp:orient"]"#;
    assert_close(point_under(orient), Vec3::Y, 1e-6);

    let invert = r#"double3 xformOp:translate = (4, 5, 6)
        uniform token[] xformOpOrder = ["xformOp:translate", "!invert!xformOp:translate"]"#;
    assert_close(point_under(invert), Vec3::X, 1e-6);

    let matrix = r#"matrix4d xformOp:transform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (5, 6, 7, 1) )
        uniform token[] xformOpOrder = ["xformOp:transform"]"#;
    assert_close(point_under(matrix), Vec3::new(6.0, 6.0, 7.0), 1e-6);

    // rotateXYZ applies X first: (1,0,0) -> X90 -> (1,0,0) -> Z90 -> (0,1,0).
    let xyz = r#"float3 xformOp:rotateXYZ = (90, 0, 90)
        uniform token[] xformOpOrder = ["xformOp:rotateXYZ"]"#;
    assert_close(point_under(xyz), Vec3::Y, 1e-6);
    // rotateZYX applies Z first: (1,0,0) -> Z90 -> (0,1,0) -> X90 -> (0,0,1).
    let zyx = r#"float3 xformOp:rotateZYX = (90, 0, 90)
        uniform token[] xformOpOrder = ["xformOp:rotateZYX"]"#;
    assert_close(point_under(zyx), Vec3::Z, 1e-6);

    let suffixed = r#"double3 xformOp:translate:pivot = (0, 1, 0)
        double xformOp:rotateZ:spin = 180
        uniform token[] xformOpOrder = ["xformOp:translate:pivot", "xformOp:rotateZ:spin", "!invert!xformOp:translate:pivot"]"#;
    assert_close(point_under(suffixed), Vec3::new(-1.0, 2.0, 0.0), 1e-6);
}

#[test]
fn reset_xform_stack_ignores_the_parent() {
    let desc = load_body(&format!(
        r#"def Xform "P" {{
    double3 xformOp:translate = (10, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
    def Xform "C" {{
        double3 xformOp:translate = (0, 1, 0)
        uniform token[] xformOpOrder = ["!resetXformStack!", "xformOp:translate"]
        {}
    }}
}}
"#,
        triangle_mesh("M", "")
    ));
    assert_close(mesh(&desc, "/P/C/M").positions[0], Vec3::Y, 1e-6);
}

#[test]
fn left_handed_orientation_flips_winding() {
    let desc = load_body(&format!(
        "{}{}",
        triangle_mesh("R", ""),
        triangle_mesh("L", r#"uniform token orientation = "leftHanded""#)
    ));
    assert_close(face_normal(mesh(&desc, "/R"), 0), Vec3::Z, 1e-6);
    assert_close(face_normal(mesh(&desc, "/L"), 0), Vec3::NEG_Z, 1e-6);
}

#[test]
fn mirroring_transform_keeps_the_front_face() {
    let desc = load_body(&format!(
        "def Xform \"X\" {{\n float3 xformOp:scale = (-1, 1, 1)\n uniform token[] xformOpOrder = [\"xformOp:scale\"]\n{}}}\n",
        triangle_mesh("M", r#"normal3f[] normals = [(0, 0, 1), (0, 0, 1), (0, 0, 1)]"#)
    ));
    let m = mesh(&desc, "/X/M");
    assert_close(face_normal(m, 0), Vec3::Z, 1e-6);
    assert_close(m.normals.as_ref().expect("normals")[0][0], Vec3::Z, 1e-6);
}

#[test]
fn polygons_are_fan_triangulated() {
    let desc = load_body(
        r#"def Mesh "M" {
    int[] faceVertexCounts = [4, 5, 3]
    int[] faceVertexIndices = [0, 1, 2, 3, 4, 5, 6, 7, 8, 0, 2, 4]
    point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0), (2,0,0), (3,0,0), (3,1,0), (2.5,2,0), (2,1,0)]
}
"#,
    );
    let m = mesh(&desc, "/M");
    assert_eq!(
        m.indices,
        [
            [0, 1, 2],
            [0, 2, 3],
            [4, 5, 6],
            [4, 6, 7],
            [4, 7, 8],
            [0, 2, 4]
        ]
    );
    for t in 0..5 {
        assert_close(face_normal(m, t), Vec3::Z, 1e-6);
    }
}

#[test]
fn hole_faces_are_skipped() {
    let desc = load_body(
        r#"def Mesh "M" {
    int[] faceVertexCounts = [3, 3]
    int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]
    int[] holeIndices = [0]
    point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0)]
}
"#,
    );
    let m = mesh(&desc, "/M");
    assert_eq!(m.indices.len(), 1);
    assert_eq!(m.positions.len(), 3, "unused points are compacted away");
}

#[test]
fn face_varying_normals_follow_corners_and_transform() {
    let desc = load_body(
        r#"def Xform "X" {
    float xformOp:rotateX = 90
    float3 xformOp:scale = (2, 1, 1)
    uniform token[] xformOpOrder = ["xformOp:rotateX", "xformOp:scale"]
    def Mesh "M" {
        int[] faceVertexCounts = [4]
        int[] faceVertexIndices = [0, 1, 2, 3]
        point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0)]
        normal3f[] normals = [(0, 0, 1), (1, 0, 1), (0, 0, 2), (0, 1, 1)] (
            interpolation = "faceVarying"
        )
    }
}
"#,
    );
    let normals = mesh(&desc, "/X/M").normals.clone().expect("normals");
    assert_eq!(normals.len(), 2);
    let s = std::f32::consts::FRAC_1_SQRT_2;
    // Object (0,0,1) -> rotateX 90 -> (0,-1,0).
    assert_close(normals[0][0], Vec3::NEG_Y, 1e-6);
    // Object (1,0,1): the inverse transpose of scale x2 halves x -> (0.5,0,1) normalised.
    let n = Vec3::new(0.5, 0.0, 1.0).normalize();
    assert_close(normals[0][1], Vec3::new(n.x, -n.z, 0.0), 1e-6);
    assert_close(normals[0][2], Vec3::NEG_Y, 1e-6);
    // Second triangle: corners 0, 2, 3.
    assert_close(normals[1][2], Vec3::new(0.0, -s, s), 1e-6);
}

#[test]
fn vertex_uniform_and_indexed_primvars() {
    let desc = load_body(
        r#"def Mesh "M" {
    int[] faceVertexCounts = [3, 3]
    int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]
    point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0)]
    normal3f[] primvars:normals = [(0, 0, 1), (0, 1, 0)] (
        interpolation = "uniform"
    )
    texCoord2f[] primvars:st = [(0, 0), (1, 0), (1, 1), (0, 1)] (
        interpolation = "faceVarying"
    )
    int[] primvars:st:indices = [0, 1, 2, 0, 2, 3]
}
def Mesh "V" {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [2, 1, 0]
    point3f[] points = [(0,0,0), (0,1,0), (1,0,0)]
    normal3f[] normals = [(0, 0, -1), (0, 0, -2), (0, 0, -3)]
    float2[] primvars:st = [(0, 0), (0, 1), (1, 0)] (
        interpolation = "vertex"
    )
}
"#,
    );
    let m = mesh(&desc, "/M");
    let normals = m.normals.as_ref().expect("normals");
    assert_eq!(normals[0], [Vec3::Z; 3]);
    assert_eq!(normals[1], [Vec3::Y; 3]);
    let uvs = m.uvs.as_ref().expect("uvs");
    assert_eq!(
        uvs[1],
        [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0)
        ]
    );

    let v = mesh(&desc, "/V");
    assert_eq!(v.normals.as_ref().expect("normals")[0], [Vec3::NEG_Z; 3]);
    assert_eq!(
        v.uvs.as_ref().expect("uvs")[0],
        [
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.0, 0.0)
        ]
    );
}

#[test]
fn mismatched_primvar_is_dropped_with_a_warning() {
    let desc = load_body(&triangle_mesh(
        "M",
        r#"normal3f[] normals = [(0, 0, 1)] (
        interpolation = "faceVarying"
    )"#,
    ));
    assert!(mesh(&desc, "/M").normals.is_none());
    assert_warned(&desc, &["/M", "normals"]);
}

#[test]
fn double_sided_is_read() {
    let desc = load_body(&triangle_mesh("M", "uniform bool doubleSided = 1"));
    assert!(mesh(&desc, "/M").double_sided);
}

#[test]
fn geom_subsets_split_meshes_by_material() {
    let desc = load_body(
        r#"def Material "Red" {
    token outputs:surface.connect = </Red/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "spectral:diffuse"
        color3f inputs:reflectance = (0.8, 0.1, 0.1)
        token outputs:surface
    }
}
def Material "Grey" {
    token outputs:surface.connect = </Grey/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "spectral:diffuse"
        token outputs:surface
    }
}
def Mesh "M" {
    int[] faceVertexCounts = [3, 3, 3]
    int[] faceVertexIndices = [0, 1, 2, 0, 2, 3, 1, 2, 3]
    point3f[] points = [(0,0,0), (1,0,0), (1,1,0), (0,1,0)]
    rel material:binding = </Grey>
    def GeomSubset "Top" {
        uniform token elementType = "face"
        uniform token familyName = "materialBind"
        int[] indices = [1, 2]
        rel material:binding = </Red>
    }
}
"#,
    );
    let rest = mesh(&desc, "/M");
    let top = mesh(&desc, "/M/Top");
    assert_eq!((rest.indices.len(), top.indices.len()), (1, 2));
    assert_eq!(
        desc.materials[rest.material.expect("grey")].prim_path,
        "/Grey"
    );
    assert_eq!(desc.materials[top.material.expect("red")].prim_path, "/Red");
}

#[test]
fn intrinsic_shapes_are_tessellated() {
    let desc = load_body(
        r#"def Sphere "Ball" {
    double radius = 2
    double3 xformOp:translate = (0, 5, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Cube "Box" {
    double size = 1
}
def Cylinder "Can" {
    double radius = 0.5
    double height = 3
    uniform token axis = "Y"
}
def Cone "Cone" {
    uniform token axis = "X"
}
def Plane "Floor" {
    double width = 10
    double length = 4
    uniform token axis = "Y"
}
"#,
    );
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let centre = Vec3::new(0.0, 5.0, 0.0);
    for (name, radius, centre) in [("/Ball", 2.0, centre)] {
        let m = mesh(&desc, name);
        let normals = m.normals.as_ref().expect("normals");
        for (t, tri) in m.indices.iter().enumerate() {
            let p = m.positions[tri[0] as usize];
            assert!(((p - centre).length() - radius).abs() < 1e-5);
            // Outward: the geometric normal agrees with the direction from the centre.
            let outward =
                (p + m.positions[tri[1] as usize] + m.positions[tri[2] as usize]) / 3.0 - centre;
            assert!(
                face_normal(m, t).dot(outward) > 0.0,
                "{name} triangle {t} faces inwards"
            );
            assert!(normals[t][0].dot(outward) > 0.0);
        }
    }
    for name in ["/Box", "/Can", "/Cone"] {
        let m = mesh(&desc, name);
        let centroid = m.positions.iter().copied().sum::<Vec3>() / m.positions.len() as f32;
        for t in 0..m.indices.len() {
            let [a, b, c] = m.indices[t].map(|i| m.positions[i as usize]);
            let area = (b - a).cross(c - a).length();
            assert!(area > 1e-9, "{name}: degenerate triangle {t}");
            assert!(
                face_normal(m, t).dot((a + b + c) / 3.0 - centroid) > 0.0,
                "{name} triangle {t} faces inwards"
            );
        }
    }
    let can = mesh(&desc, "/Can");
    let max_y = can.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    assert!(
        (max_y - 1.5).abs() < 1e-6,
        "the Y-axis cylinder spans y in [-1.5, 1.5]"
    );
    let cone = mesh(&desc, "/Cone");
    let max_x = cone.positions.iter().map(|p| p.x).fold(f32::MIN, f32::max);
    assert!(
        (max_x - 1.0).abs() < 1e-6,
        "the X-axis cone's apex is at x = 1"
    );
    let floor = mesh(&desc, "/Floor");
    assert!(
        floor.double_sided && !mesh(&desc, "/Box").double_sided,
        "schema fallbacks"
    );
    assert_close(face_normal(floor, 0), Vec3::Y, 1e-6);
    let max_x = floor.positions.iter().map(|p| p.x).fold(f32::MIN, f32::max);
    let max_z = floor.positions.iter().map(|p| p.z).fold(f32::MIN, f32::max);
    // UsdGeomPlane with axis Y: width along X, length along Z.
    assert_eq!((max_x, max_z), (5.0, 2.0));
}
