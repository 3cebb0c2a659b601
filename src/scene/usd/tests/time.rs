//! Time codes: interpolation of time samples, held interpolation, values that hold, the
//! default time.

use glam::Vec3;

use super::*;
use crate::desc::TimeOrigin;
use crate::scene::usd::{open, ReadTime};

/// A sphere light moving from the origin to (10, 2, 0) over frames 0..10, brightening from 1
/// to 3, and made invisible at frame 10 (a token, which holds); its IES file is usd-core's
/// empty asset at every sample.
const ANIMATED: &str = r#"def SphereLight "lamp" {
    double3 xformOp:translate.timeSamples = { 0: (0, 0, 0), 10: (10, 2, 0) }
    uniform token[] xformOpOrder = ["xformOp:translate"]
    float inputs:intensity.timeSamples = { 0: 1, 10: 3 }
    token visibility.timeSamples = { 0: "inherited", 10: "invisible" }
    asset inputs:shaping:ies:file.timeSamples = { 0: @@, 10: @@ }
}
"#;

fn read(frame: Option<f64>, held: bool) -> SceneDescription {
    let path = write_stage("animated.usda", &format!("{METRES_Y_UP}{ANIMATED}"));
    let stage = open(&path).unwrap_or_else(|e| panic!("open: {e}"));
    stage
        .read(ReadTime { frame, held })
        .unwrap_or_else(|e| panic!("read: {e}"))
}

fn lamp(desc: &SceneDescription) -> (Vec3, f32) {
    let l = &desc.lights[0];
    (l.to_world.w_axis.truncate(), l.emission.intensity)
}

#[test]
fn numeric_samples_interpolate_linearly_at_a_middle_frame() {
    let desc = read(Some(5.0), false);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let (position, intensity) = lamp(&desc);
    assert_eq!(position, Vec3::new(5.0, 1.0, 0.0));
    assert_eq!(intensity, 2.0);
    assert!(desc.time.animated);
    assert_eq!(desc.time.origin, TimeOrigin::Given);
    assert_eq!(desc.time.code, Some(5.0));
    assert!(desc.time.note().is_none());
    let quarter = read(Some(2.5), false);
    assert_eq!(lamp(&quarter), (Vec3::new(2.5, 0.5, 0.0), 1.5));
}

#[test]
fn held_interpolation_holds_the_earlier_sample() {
    let desc = read(Some(5.0), true);
    assert_eq!(lamp(&desc), (Vec3::ZERO, 1.0));
    assert!(desc.time.held);
    // At and after the last sample both modes give it.
    let end = read(Some(12.0), true);
    assert!(end.lights.is_empty(), "invisible from frame 10");
}

#[test]
fn tokens_hold_under_linear_interpolation() {
    // `visibility` is "inherited" up to frame 10 even at 9.99.
    assert_eq!(read(Some(9.99), false).lights.len(), 1);
    assert!(read(Some(10.0), false).lights.is_empty());
}

#[test]
fn without_a_frame_the_earliest_sample_is_read_with_a_note() {
    let desc = read(None, false);
    assert_eq!(lamp(&desc), (Vec3::ZERO, 1.0));
    assert_eq!(desc.time.origin, TimeOrigin::Earliest);
    let note = desc.time.note().expect("an animated stage gets a note");
    assert!(note.contains("--frame"), "{note}");
    // A time range makes startTimeCode the default.
    let ranged = METRES_Y_UP.replace(
        "upAxis",
        "startTimeCode = 10\n    endTimeCode = 20\n    upAxis",
    );
    let path = write_stage("ranged.usda", &format!("{ranged}{ANIMATED}"));
    let desc = open(&path).unwrap().read(ReadTime::default()).unwrap();
    assert_eq!(desc.time.origin, TimeOrigin::StartTimeCode);
    assert!(desc.lights.is_empty(), "read at frame 10: invisible");
    assert!(desc.time.note().unwrap().contains("startTimeCode 10"));
}

#[test]
fn a_static_stage_has_no_note_and_frames_change_nothing() {
    let body = r#"def SphereLight "lamp" { float inputs:intensity = 4 }"#;
    let path = write_stage("static.usda", &format!("{METRES_Y_UP}{body}"));
    let stage = open(&path).unwrap();
    let a = stage.read(ReadTime::default()).unwrap();
    let b = stage
        .read(ReadTime {
            frame: Some(7.0),
            held: false,
        })
        .unwrap();
    assert!(!a.time.animated && a.time.note().is_none());
    assert_eq!(a.lights[0].emission.intensity, 4.0);
    assert_eq!(b.lights[0].emission.intensity, 4.0);
    assert_ne!(
        a.content_hash, b.content_hash,
        "a checkpoint names its frame"
    );
}

#[test]
fn splines_are_refused_naming_the_attribute() {
    let body = r#"def SphereLight "lamp" {
    float inputs:intensity.spline = {
        1: 1; post linear,
        10: 5; post linear,
    }
}"#;
    let path = write_stage("spline.usda", &format!("{METRES_Y_UP}{body}"));
    let e = open(&path).unwrap().read(ReadTime::default()).unwrap_err();
    let message = e.to_string();
    assert!(
        message.contains("/lamp") && message.contains("inputs:intensity.spline"),
        "{message}"
    );
}
