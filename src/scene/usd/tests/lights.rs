//! UsdLux lights, mesh lights and the `spectral:` light vocabulary.

use glam::Vec3;

use super::*;
use crate::desc::{EmissionDesc, LightDesc, LightKind, SpdDesc};

/// The light with `prim_path`.
fn light<'a>(desc: &'a SceneDescription, prim_path: &str) -> &'a LightDesc {
    let found = desc.lights.iter().find(|l| l.prim_path == prim_path);
    found.unwrap_or_else(|| panic!("no light {prim_path}"))
}

#[test]
fn every_light_type_with_attributes() {
    let dir = temp_dir();
    std::fs::write(dir.join("sky.exr"), b"").expect("write texture");
    let stage = dir.join("lights.usda");
    std::fs::write(
        &stage,
        format!(
            r#"{METRES_Y_UP}def RectLight "Rect" {{
    float inputs:width = 2
    float inputs:height = 3
    float inputs:intensity = 5
    float inputs:exposure = 1
    color3f inputs:color = (1, 0.5, 0.25)
    bool inputs:normalize = 1
    double3 xformOp:translate = (0, 2, 0)
    float xformOp:rotateX = -90
    uniform token[] xformOpOrder = ["xformOp:translate", "xformOp:rotateX"]
}}
def DiskLight "Disk" {{
    float inputs:radius = 0.2
}}
def SphereLight "Sphere" {{
    float inputs:radius = 0.25
}}
def CylinderLight "Cylinder" {{
    float inputs:radius = 0.1
    float inputs:length = 2
}}
def DistantLight "Sun" {{
    float inputs:angle = 1
}}
def DomeLight "Sky" {{
    asset inputs:texture:file = @sky.exr@
    token inputs:texture:format = "latlong"
}}
"#
        ),
    )
    .expect("write stage");
    let desc = crate::scene::usd::load(&stage).expect("loads");
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    assert_eq!(desc.lights.len(), 6);

    let rect = light(&desc, "/Rect");
    assert_eq!(
        rect.kind,
        LightKind::Rect {
            width: 2.0,
            height: 3.0,
            texture: None
        }
    );
    let expected = EmissionDesc {
        color: [1.0, 0.5, 0.25],
        intensity: 5.0,
        exposure: 1.0,
        normalize: true,
        ..EmissionDesc::default()
    };
    assert_eq!(rect.emission, expected);
    assert_close(
        rect.to_world.w_axis.truncate(),
        Vec3::new(0.0, 2.0, 0.0),
        1e-6,
    );
    // Rotated -90 about X: the emission direction -Z points down.
    assert_close(
        rect.to_world.transform_vector3(Vec3::NEG_Z),
        Vec3::NEG_Y,
        1e-6,
    );

    assert_eq!(light(&desc, "/Disk").kind, LightKind::Disk { radius: 0.2 });
    assert_eq!(
        light(&desc, "/Sphere").kind,
        LightKind::Sphere {
            radius: 0.25,
            point: false
        }
    );
    assert_eq!(
        light(&desc, "/Cylinder").kind,
        LightKind::Cylinder {
            radius: 0.1,
            length: 2.0,
            line: false
        }
    );
    assert_eq!(
        light(&desc, "/Sun").kind,
        LightKind::Distant { angle_deg: 1.0 }
    );
    let texture = std::fs::canonicalize(dir.join("sky.exr")).expect("canonical");
    assert_eq!(
        light(&desc, "/Sky").kind,
        LightKind::Dome {
            texture: Some(texture)
        }
    );
}

#[test]
fn light_defaults() {
    let desc = load_body(
        r#"def RectLight "Rect" {}
def DiskLight "Disk" {}
def SphereLight "Sphere" {}
def CylinderLight "Cylinder" {}
def DistantLight "Sun" {}
def DomeLight "Sky" {}
"#,
    );
    assert_eq!(
        light(&desc, "/Rect").kind,
        LightKind::Rect {
            width: 1.0,
            height: 1.0,
            texture: None
        }
    );
    assert_eq!(light(&desc, "/Disk").kind, LightKind::Disk { radius: 0.5 });
    assert_eq!(
        light(&desc, "/Sphere").kind,
        LightKind::Sphere {
            radius: 0.5,
            point: false
        }
    );
    assert_eq!(
        light(&desc, "/Cylinder").kind,
        LightKind::Cylinder {
            radius: 0.5,
            length: 1.0,
            line: false
        }
    );
    assert_eq!(
        light(&desc, "/Sun").kind,
        LightKind::Distant { angle_deg: 0.53 }
    );
    assert_eq!(light(&desc, "/Sky").kind, LightKind::Dome { texture: None });
    for l in &desc.lights {
        // The UsdLux schema gives DistantLight an intensity fallback of 50000.
        let intensity = if l.prim_path == "/Sun" { 50_000.0 } else { 1.0 };
        let expected = EmissionDesc {
            intensity,
            ..EmissionDesc::default()
        };
        assert_eq!(l.emission, expected, "{}", l.prim_path);
    }
}

#[test]
fn legacy_names_and_inputs_precedence() {
    let desc = load_body(
        r#"def SphereLight "Old" {
    float radius = 0.3
    float intensity = 7
    color3f color = (0.5, 0.5, 1)
}
def SphereLight "Both" {
    float radius = 0.3
    float inputs:radius = 0.4
}
"#,
    );
    let old = light(&desc, "/Old");
    assert_eq!(
        old.kind,
        LightKind::Sphere {
            radius: 0.3,
            point: false
        }
    );
    assert_eq!(
        (old.emission.intensity, old.emission.color),
        (7.0, [0.5, 0.5, 1.0])
    );
    assert_eq!(
        light(&desc, "/Both").kind,
        LightKind::Sphere {
            radius: 0.4,
            point: false
        }
    );
}

#[test]
fn point_and_line_hints_and_zero_radii() {
    let desc = load_text(
        r#"#usda 1.0
def SphereLight "P" {
    bool treatAsPoint = 1
}
def SphereLight "Z" {
    float inputs:radius = 0
}
def CylinderLight "L" {
    bool treatAsLine = 1
    float inputs:radius = 2
}
"#,
    );
    // treatAsPoint keeps the radius (the point light emits the sphere's far field) and warns
    // of nothing; a zero radius is 0.1 mm (0.01 units in a centimetre stage), with a warning.
    assert_eq!(
        light(&desc, "/P").kind,
        LightKind::Sphere {
            radius: 0.5,
            point: true
        }
    );
    assert_eq!(
        light(&desc, "/Z").kind,
        LightKind::Sphere {
            radius: 0.01,
            point: false
        }
    );
    assert_eq!(
        light(&desc, "/L").kind,
        LightKind::Cylinder {
            radius: 2.0,
            length: 1.0,
            line: true
        }
    );
    assert_warned(&desc, &["/Z", "radius"]);
    assert!(
        !desc.warnings.iter().any(|w| w.contains("treatAs")),
        "{:?}",
        desc.warnings
    );
}

#[test]
fn spectral_light_vocabulary() {
    let desc = load_body(
        r#"def SphereLight "Bulb" {
    token spectral:emission = "blackbody"
    float spectral:temperature = 2700
    float spectral:luminousFlux = 800
    bool inputs:enableColorTemperature = 1
    float inputs:colorTemperature = 4000
}
def DistantLight "Sun" {
    token spectral:emission = "CIE-D50"
    float spectral:luminousIntensity = 100
}
def RectLight "Led" {
    float2[] spectral:emission:samples = [(400, 0.5), (450, 1), (700, 0.2)]
}
def SphereLight "Plain" {
    float inputs:colorTemperature = 3000
}
"#,
    );
    let bulb = &light(&desc, "/Bulb").emission;
    assert_eq!(bulb.spd, Some(SpdDesc::Blackbody(2700.0)));
    assert_eq!(bulb.luminous_flux, Some(800.0));
    assert_eq!(bulb.color_temperature, Some(4000.0));
    let sun = &light(&desc, "/Sun").emission;
    assert_eq!(sun.spd, Some(SpdDesc::Named("CIE-D50".into())));
    assert_eq!(sun.luminous_intensity, Some(100.0));
    let led = &light(&desc, "/Led").emission;
    assert_eq!(
        led.spd,
        Some(SpdDesc::Samples(vec![
            (400.0, 0.5),
            (450.0, 1.0),
            (700.0, 0.2)
        ]))
    );
    // colorTemperature only counts when enabled.
    assert_eq!(light(&desc, "/Plain").emission.color_temperature, None);
}

#[test]
fn shaping_is_read_and_other_unsupported_inputs_warn() {
    let dir = temp_dir();
    std::fs::write(dir.join("beam.ies"), "TILT=NONE\n").expect("write ies");
    let stage = dir.join("shaping.usda");
    std::fs::write(
        &stage,
        format!(
            r#"{METRES_Y_UP}def SphereLight "Spot" (prepend apiSchemas = ["ShapingAPI"]) {{
    float inputs:shaping:cone:angle = 30
    float inputs:shaping:cone:softness = 1.5
    float inputs:shaping:focus = 2
    color3f inputs:shaping:focusTint = (0.5, 0.25, 1)
    asset inputs:shaping:ies:file = @beam.ies@
    float inputs:shaping:ies:angleScale = -0.5
    bool inputs:shaping:ies:normalize = 1
    float inputs:diffuse = 0.5
}}
def SphereLight "Applied" (prepend apiSchemas = ["ShapingAPI"]) {{
}}
def RectLight "Focused" {{
    float inputs:shaping:focus = 4
}}
def RectLight "Plain" {{
}}
def DistantLight "Sun" {{
    float inputs:shaping:cone:angle = 10
}}
"#
        ),
    )
    .expect("write stage");
    let desc = crate::scene::usd::load(&stage).expect("loads");
    let spot = light(&desc, "/Spot").shaping.clone().expect("shaped");
    assert_eq!(spot.cone_angle_deg, 30.0);
    assert_eq!(spot.cone_softness, 1.0, "softness is clamped to [0, 1]");
    assert_eq!(spot.focus, 2.0);
    assert_eq!(spot.focus_tint, [0.5, 0.25, 1.0]);
    let ies = spot.ies.expect("ies");
    assert_eq!(ies.file, dir.join("beam.ies"));
    assert_eq!((ies.angle_scale, ies.normalize), (-0.5, true));
    // The schema fallback of the cone applies only with the API applied.
    let applied = light(&desc, "/Applied").shaping.clone().expect("shaped");
    assert_eq!(applied.cone_angle_deg, 90.0);
    let focused = light(&desc, "/Focused").shaping.clone().expect("shaped");
    assert_eq!((focused.cone_angle_deg, focused.focus), (180.0, 4.0));
    assert!(light(&desc, "/Plain").shaping.is_none());
    assert!(light(&desc, "/Sun").shaping.is_none());
    assert_warned(&desc, &["/Sun", "ShapingAPI", "DistantLight"]);
    assert_warned(&desc, &["/Spot", "inputs:diffuse"]);
    assert!(
        !desc
            .warnings
            .iter()
            .any(|w| w.starts_with("/Spot") && w.contains("shaping")),
        "{:?}",
        desc.warnings
    );
}

#[test]
fn mesh_light_with_spectral_emission() {
    let desc = load_body(
        r#"def Mesh "Panel" (prepend apiSchemas = ["MeshLightAPI"]) {
    int[] faceVertexCounts = [3]
    int[] faceVertexIndices = [0, 1, 2]
    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    float inputs:intensity = 3
    token spectral:emission = "LED-B3"
}
"#,
    );
    let emission = mesh(&desc, "/Panel").light.clone().expect("emits");
    assert_eq!(emission.intensity, 3.0);
    assert_eq!(emission.spd, Some(SpdDesc::Named("LED-B3".into())));
}

#[test]
fn dome_light_1_with_z_pole_on_z_up_stage() {
    let desc = load_text(
        r#"#usda 1.0
(
    upAxis = "Z"
)
def DomeLight_1 "Sky" {}
"#,
    );
    let sky = light(&desc, "/Sky");
    // The dome's +Y pole maps to the stage's +Z, i.e. world +Y.
    let pole = sky.to_world.transform_vector3(Vec3::Y).normalize();
    assert_close(pole, Vec3::Y, 1e-6);
}
