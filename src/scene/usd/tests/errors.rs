//! Bad input: every case is one `Error` line naming the file, the prim and the reason.

use super::*;

/// A triangle mesh `/M` with the given topology lines.
fn mesh_with(topology: &str) -> String {
    format!("def Mesh \"M\" {{\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n    {topology}\n}}\n")
}

/// The error names `prim` and contains `reason`.
fn assert_prim_error(err: &Error, prim: &str, reason: &str) {
    assert_eq!(err.prim.as_deref(), Some(prim), "{err}");
    let text = err.to_string();
    assert!(text.contains(prim) && text.contains(reason), "{text}");
}

#[test]
fn missing_file() {
    let path = temp_dir().join("does_not_exist.usda");
    let err = crate::scene::usd::load(&path).expect_err("missing");
    assert_one_line(&err, "does_not_exist.usda");
    assert!(err.to_string().contains("no such file"), "{err}");
}

#[test]
fn malformed_usda_names_the_line() {
    let err = load_body_err("def Xform \"A\" {\n    double3 xformOp:translate = (1, 2\n}\n");
    assert_eq!(err.prim, None);
    assert!(err.to_string().contains("line 8 column 1"), "{err}");
}

#[test]
fn not_a_usd_file() {
    let path = write_stage("garbage.usda", "this is not usd\n");
    let err = crate::scene::usd::load(&path).expect_err("garbage");
    assert_one_line(&err, "garbage.usda");
}

#[test]
fn out_of_range_face_vertex_index() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 3]",
    ));
    assert_prim_error(&err, "/M", "faceVertexIndices[2] = 3 is out of range");
}

#[test]
fn negative_face_vertex_index() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, -1, 2]",
    ));
    assert_prim_error(&err, "/M", "out of range");
}

#[test]
fn counts_not_matching_indices() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [3, 3]\n    int[] faceVertexIndices = [0, 1, 2]",
    ));
    assert_prim_error(&err, "/M", "add up to 6");
}

#[test]
fn face_with_two_vertices() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [2, 1]\n    int[] faceVertexIndices = [0, 1, 2]",
    ));
    assert_prim_error(&err, "/M", "at least 3 vertices");
}

#[test]
fn unknown_spectral_attribute_on_a_light() {
    let err = load_body_err("def SphereLight \"L\" {\n    float spectral:temprature = 3000\n}\n");
    assert_prim_error(&err, "/L", "spectral:temprature");
}

#[test]
fn spectral_light_attribute_on_a_plain_mesh() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    token spectral:emission = \"CIE-A\"",
    ));
    assert_prim_error(&err, "/M", "spectral:emission");
}

#[test]
fn unknown_info_id() {
    let err = load_body_err(
        r#"def Material "Mat" {
    token outputs:surface.connect = </Mat/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "spectral:velvet"
        token outputs:surface
    }
}
def Mesh "M" {
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    rel material:binding = </Mat>
}
"#,
    );
    assert_prim_error(&err, "/Mat/S", "unknown shader info:id 'spectral:velvet'");
}

#[test]
fn unknown_input_on_a_spectral_shader() {
    let err = load_body_err(
        r#"def Material "Mat" {
    token outputs:surface.connect = </Mat/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "spectral:diffuse"
        color3f inputs:diffuseColor = (1, 0, 0)
        token outputs:surface
    }
}
def Mesh "M" {
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    rel material:binding = </Mat>
}
"#,
    );
    assert_prim_error(
        &err,
        "/Mat/S",
        "unknown input 'inputs:diffuseColor' for spectral:diffuse",
    );
}

#[test]
fn conflicting_reflectance_inputs() {
    let err = load_body_err(
        r#"def Material "Mat" {
    token outputs:surface.connect = </Mat/S.outputs:surface>
    def Shader "S" {
        uniform token info:id = "spectral:plastic"
        color3f inputs:reflectance = (1, 0, 0)
        token inputs:reflectance:spectrum = "colorchecker/red"
        token outputs:surface
    }
}
def Mesh "M" {
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    rel material:binding = </Mat>
}
"#,
    );
    assert_prim_error(&err, "/Mat/S", "give only one of");
}

#[test]
fn blackbody_without_temperature() {
    let err =
        load_body_err("def SphereLight \"L\" {\n    token spectral:emission = \"blackbody\"\n}\n");
    assert_prim_error(&err, "/L", "spectral:temperature");
}

#[test]
fn orthographic_camera() {
    let err = load_body_err("def Camera \"C\" {\n    token projection = \"orthographic\"\n}\n");
    assert_prim_error(&err, "/C", "orthographic cameras are not supported");
}

#[test]
fn unsupported_dome_texture_format() {
    let err = load_body_err(
        "def DomeLight \"D\" {\n    token inputs:texture:format = \"mirroredBall\"\n}\n",
    );
    assert_prim_error(&err, "/D", "mirroredBall");
}

#[test]
fn missing_dome_texture() {
    let err =
        load_body_err("def DomeLight \"D\" {\n    asset inputs:texture:file = @nowhere.exr@\n}\n");
    assert_prim_error(&err, "/D", "nowhere.exr");
}

#[test]
fn zero_size_rect_light() {
    let err = load_body_err("def RectLight \"R\" {\n    float inputs:width = 0\n}\n");
    assert_prim_error(&err, "/R", "zero-size light");
}

#[test]
fn xform_op_without_value() {
    let err = load_body_err(
        "def Xform \"X\" {\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}\n",
    );
    assert_prim_error(&err, "/X", "xformOp:translate");
}

#[test]
fn binding_to_a_missing_material() {
    let err = load_body_err(&mesh_with(
        "int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    rel material:binding = </Nope>",
    ));
    assert_prim_error(&err, "/M", "</Nope>");
}

#[test]
fn unresolved_reference() {
    let err = load_body_err("def Xform \"X\" (references = @./missing_part.usda@) {}\n");
    assert!(err.to_string().contains("missing_part.usda"), "{err}");
}

#[test]
fn bad_up_axis() {
    let path = write_stage("bad_axis.usda", "#usda 1.0\n(\n    upAxis = \"X\"\n)\n");
    let err = crate::scene::usd::load(&path).expect_err("bad axis");
    assert_one_line(&err, "bad_axis.usda");
    assert!(
        err.to_string()
            .ends_with("upAxis must be \"Y\" or \"Z\" (UsdGeom allows no other), got \"X\""),
        "{err}"
    );
}
