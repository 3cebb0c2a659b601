//! Whole stages: the Cornell box, units, up axis, cameras, render settings, traversal rules.

use glam::Vec3;

use super::*;
use crate::desc::MaterialKind;

#[test]
fn cbox_loads() {
    let desc = crate::scene::usd::load(&cbox_path()).expect("cbox loads");
    assert_eq!(desc.meshes.len(), 8);
    assert_eq!(desc.materials.len(), 8);
    assert!(desc.lights.is_empty());
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);

    let light = mesh(&desc, "/CornellBox/Geometry/light");
    let emission = light.light.as_ref().expect("light mesh emits");
    assert!((emission.intensity - 18.387).abs() < 1e-4);
    assert_eq!(emission.color, [1.0, 0.760_716_8, 0.367_301_34]);
    assert!(!emission.normalize);
    assert_eq!(light.indices.len(), 2);
    assert_close(face_normal(light, 0), Vec3::NEG_Y, 1e-5);
    assert!(desc.meshes.iter().filter(|m| m.light.is_some()).count() == 1);

    assert_close(
        face_normal(mesh(&desc, "/CornellBox/Geometry/floor"), 0),
        Vec3::Y,
        1e-4,
    );
    assert_close(
        face_normal(mesh(&desc, "/CornellBox/Geometry/ceiling"), 0),
        Vec3::NEG_Y,
        1e-4,
    );
    assert_close(
        face_normal(mesh(&desc, "/CornellBox/Geometry/back"), 0),
        Vec3::Z,
        1e-4,
    );
    assert_close(
        face_normal(mesh(&desc, "/CornellBox/Geometry/red_wall"), 0),
        Vec3::X,
        1e-4,
    );
    assert_close(
        face_normal(mesh(&desc, "/CornellBox/Geometry/green_wall"), 0),
        Vec3::NEG_X,
        1e-4,
    );

    let red = &desc.materials[mesh(&desc, "/CornellBox/Geometry/red_wall")
        .material
        .expect("bound")];
    assert_eq!(red.prim_path, "/CornellBox/Materials/red_wall");
    match &red.kind {
        MaterialKind::PreviewSurface(p) => {
            assert_eq!(p.diffuse_color, [0.570_068, 0.043_013_5, 0.044_370_6]);
            assert_eq!(p.roughness, 1.0);
            assert!(p.use_specular_workflow);
        }
        other => panic!("expected a preview surface, got {other:?}"),
    }

    assert_eq!(desc.cameras.len(), 1);
    let camera = &desc.cameras[0];
    assert_close(
        camera.to_world.w_axis.truncate(),
        Vec3::new(0.0, 0.0, 3.9),
        1e-6,
    );
    assert!((camera.focal_length - 29.336_958).abs() < 1e-5);
    assert_eq!(camera.vertical_aperture, 20.955);
    assert!((camera.clip_near - 0.001).abs() < 1e-9 && (camera.clip_far - 100.0).abs() < 1e-4);
    assert_eq!(camera.lens_radius, 0.0);
}

#[test]
fn default_meters_per_unit_scales_points_and_lights() {
    let desc = load_text(
        r#"#usda 1.0
def Mesh "M" {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (100, 0, 0), (0, 250, 0)]
}
def RectLight "L" {
    float inputs:width = 50
    double3 xformOp:translate = (0, 300, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Camera "C" {
    float2 clippingRange = (10, 10000)
    float focusDistance = 200
    float fStop = 2
    float focalLength = 50
}
"#,
    );
    let m = mesh(&desc, "/M");
    assert_close(m.positions[1], Vec3::new(1.0, 0.0, 0.0), 1e-6);
    assert_close(m.positions[2], Vec3::new(0.0, 2.5, 0.0), 1e-6);
    let light = &desc.lights[0];
    assert_close(
        light.to_world.w_axis.truncate(),
        Vec3::new(0.0, 3.0, 0.0),
        1e-6,
    );
    // Sizes stay as authored; the unit scale lives in `to_world`.
    assert_eq!(
        light.kind,
        crate::desc::LightKind::Rect {
            width: 50.0,
            height: 1.0,
            texture: None
        }
    );
    assert_close(
        light.to_world.transform_vector3(Vec3::X * 50.0),
        Vec3::X * 0.5,
        1e-6,
    );
    let camera = &desc.cameras[0];
    // The camera frame is rigid (no unit scale): camera space is in metres like the clipping range.
    assert_close(
        camera.to_world.transform_vector3(Vec3::NEG_Z),
        Vec3::NEG_Z,
        1e-6,
    );
    assert!((camera.clip_near - 0.1).abs() < 1e-6 && (camera.clip_far - 100.0).abs() < 1e-3);
    assert!((camera.focus_distance - 2.0).abs() < 1e-6);
    // 50 mm (tenths of a centimetre) at f/2: a 12.5 mm lens radius.
    assert!(
        (camera.lens_radius - 0.0125).abs() < 1e-7,
        "{}",
        camera.lens_radius
    );
}

#[test]
fn z_up_stage_is_rotated_to_y_up() {
    let desc = load_text(
        r#"#usda 1.0
(
    metersPerUnit = 1
    upAxis = "Z"
)
def Mesh "M" {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 1), (1, 0, 0), (0, 1, 0)]
}
def Camera "C" {
    double3 xformOp:translate = (0, -5, 1)
    float3 xformOp:rotateXYZ = (90, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateXYZ"]
}
"#,
    );
    let m = mesh(&desc, "/M");
    assert_eq!(m.positions[0], Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(m.positions[1], Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(m.positions[2], Vec3::new(0.0, 0.0, -1.0));
    // A Z-up camera tilted up by 90 degrees looks along +Y (stage) = -Z (world).
    let camera = &desc.cameras[0];
    assert_close(
        camera.to_world.w_axis.truncate(),
        Vec3::new(0.0, 1.0, 5.0),
        1e-6,
    );
    assert_close(
        camera.to_world.transform_vector3(Vec3::NEG_Z),
        Vec3::NEG_Z,
        1e-6,
    );
    assert_close(camera.to_world.transform_vector3(Vec3::Y), Vec3::Y, 1e-6);
}

#[test]
fn camera_defaults_and_exposure() {
    let desc = load_body(
        r#"def Camera "C" {
    float exposure = 1
    float exposure:iso = 200
}
"#,
    );
    let c = &desc.cameras[0];
    assert_eq!(
        (c.focal_length, c.horizontal_aperture, c.vertical_aperture),
        (50.0, 20.955, 15.2908)
    );
    assert_eq!((c.clip_near, c.clip_far), (1.0, 1e6));
    assert_eq!((c.f_stop, c.focus_distance, c.lens_radius), (0.0, 0.0, 0.0));
    assert!((c.exposure - 2.0).abs() < 1e-6);
}

#[test]
fn render_settings_resolution_and_camera() {
    let desc = load_body(
        r#"def Camera "Cam" {}
def Scope "Render" {
    def RenderSettings "Settings" {
        int2 resolution = (640, 480)
        rel camera = </Cam>
    }
}
"#,
    );
    assert_eq!(desc.render.resolution, Some((640, 480)));
    assert_eq!(desc.render.camera.as_deref(), Some("/Cam"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
}

#[test]
fn invisible_guide_and_proxy_prims_are_skipped() {
    let triangle = r#"int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]"#;
    let desc = load_body(&format!(
        r#"def Xform "Hidden" {{
    token visibility = "invisible"
    def Mesh "A" {{
        {triangle}
    }}
    def SphereLight "L" {{}}
}}
def Mesh "Guide" {{
    uniform token purpose = "guide"
    {triangle}
}}
def Xform "Proxy" {{
    uniform token purpose = "proxy"
    def Mesh "B" {{
        uniform token purpose = "default"
        {triangle}
    }}
    def Mesh "C" {{
        {triangle}
    }}
}}
def Mesh "Render" {{
    uniform token purpose = "render"
    {triangle}
}}
def Mesh "Inactive" (active = false) {{
    {triangle}
}}
"#
    ));
    // An authored purpose overrides the inherited one (as UsdGeomImageable::ComputePurpose).
    assert_eq!(paths(&desc), ["/Proxy/B", "/Render"]);
    assert!(desc.lights.is_empty());
}

#[test]
fn unsupported_prims_are_warned() {
    let desc = load_body(
        r#"def Capsule "Pill" {
    double radius = 2
}
def GeometryLight "Portal" {}
def "Typeless" {}
def Xform "Group" {
    def Scope "S" {}
}
"#,
    );
    assert_warned(&desc, &["/Pill", "unsupported prim type 'Capsule' ignored"]);
    assert_warned(&desc, &["/Portal", "GeometryLight"]);
    assert_eq!(desc.warnings.len(), 2, "{:?}", desc.warnings);
}

#[test]
fn instance_proxies_are_read() {
    let desc = load_body(
        r#"class "Proto" {
    def Mesh "M" {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
def Xform "I1" (
    instanceable = true
    inherits = </Proto>
) {
    double3 xformOp:translate = (5, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
def Xform "I2" (
    instanceable = true
    inherits = </Proto>
) {
    double3 xformOp:translate = (-5, 0, 0)
    uniform token[] xformOpOrder = ["xformOp:translate"]
}
"#,
    );
    assert_eq!(mesh(&desc, "/I1/M").positions[1], Vec3::new(6.0, 0.0, 0.0));
    assert_eq!(mesh(&desc, "/I2/M").positions[1], Vec3::new(-4.0, 0.0, 0.0));
}

#[test]
fn local_references_are_composed() {
    let dir = temp_dir();
    std::fs::write(
        dir.join("part.usda"),
        r#"#usda 1.0
(
    defaultPrim = "Part"
)
def Xform "Part" {
    def Mesh "M" {
        int[] faceVertexCounts = [3]
        int[] faceVertexIndices = [0, 1, 2]
        point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    }
}
"#,
    )
    .expect("write part");
    let stage = dir.join("main.usda");
    std::fs::write(
        &stage,
        format!("{METRES_Y_UP}def Xform \"World\" {{\n    def \"Ref\" (references = @./part.usda@) {{}}\n}}\n"),
    )
    .expect("write main");
    let desc = crate::scene::usd::load(&stage).expect("loads");
    assert_eq!(paths(&desc), ["/World/Ref/M"]);
}

/// A stage with `metadata` whose mesh `/M` is translated by time samples at 0, 10 and 20.
fn animated(metadata: &str) -> SceneDescription {
    load_text(&format!(
        r#"#usda 1.0
(
    metersPerUnit = 1
{metadata}
)
def Mesh "M" {{
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    double3 xformOp:translate.timeSamples = {{
        0: (0, 0, 0),
        10: (1, 0, 0),
        20: (2, 0, 0),
    }}
    uniform token[] xformOpOrder = ["xformOp:translate"]
}}
"#
    ))
}

#[test]
fn time_samples_are_read_at_the_start_time() {
    let ranged = animated("    startTimeCode = 10\n    endTimeCode = 20");
    assert_eq!(mesh(&ranged, "/M").positions[0], Vec3::new(1.0, 0.0, 0.0));
    let unranged = animated("");
    assert_eq!(mesh(&unranged, "/M").positions[0], Vec3::ZERO);
}

#[test]
fn usdz_package_with_references_and_texture() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usd/package.usdz");
    let desc = crate::scene::usd::load(&path).expect("usdz loads");
    // The package holds main.usda referencing assets/part.usda twice (variants small / big)
    // and a payload with a sphere light.
    assert_eq!(
        mesh(&desc, "/World/A/M").positions[0],
        Vec3::new(0.0, 1.0, 0.0)
    );
    assert_eq!(
        mesh(&desc, "/World/B/M").positions[0],
        Vec3::new(0.0, 9.0, 0.0)
    );
    assert_eq!(desc.lights.len(), 3);
    let dome = desc
        .lights
        .iter()
        .find(|l| l.prim_path == "/World/A/Sky")
        .expect("dome");
    let crate::desc::LightKind::Dome {
        texture: Some(texture),
    } = &dome.kind
    else {
        panic!("textured dome expected, got {:?}", dome.kind)
    };
    assert_eq!(
        std::fs::read(texture).expect("extracted texture"),
        b"notreallyexr\n"
    );
    // The extracted copy lives as long as the description, not beyond.
    let texture = texture.clone();
    drop(desc);
    assert!(!texture.exists(), "{} left behind", texture.display());
}

#[test]
fn point_instancer_prototypes_are_not_rendered() {
    let desc = load_body(
        r#"def PointInstancer "Scatter" {
    point3f[] positions = [(0, 0, 0), (2, 0, 0)]
    int[] protoIndices = [0, 0]
    rel prototypes = </Scatter/Protos/Tri>
    def Scope "Protos" {
        def Mesh "Tri" {
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        }
    }
}
"#,
    );
    assert!(desc.meshes.is_empty());
    assert_warned(&desc, &["/Scatter", "PointInstancer is not supported"]);
    assert_eq!(desc.warnings.len(), 1, "{:?}", desc.warnings);
}
