#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Bad input: each error names the line and the field.

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use stance_motion::{BvhError, BvhLimits, read_bvh};

const GOOD: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 1 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftArm
  {
    OFFSET 0.2 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0.3 0 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.04
0 1 0 0 0 0 0 0 0
0 1 0 0 0 0 0 0 0
";

fn error(text: &str) -> BvhError {
    read_bvh(text.as_bytes(), "bad", &BvhLimits::default()).unwrap_err()
}

fn message(text: &str) -> String {
    error(text).to_string()
}

#[test]
fn the_good_file_reads() {
    let c = read_bvh(GOOD.as_bytes(), "good", &BvhLimits::default()).unwrap();
    assert_eq!(c.frame_count(), 2);
}

#[test]
fn wrong_channel_counts() {
    let m = message(&GOOD.replace(
        "CHANNELS 3 Zrotation Xrotation Yrotation",
        "CHANNELS 4 Zrotation Xrotation Yrotation Xposition",
    ));
    assert_eq!(m, "line 9, CHANNELS: expected 3 or 6 channels, got 4");
    let m = message(&GOOD.replace(
        "CHANNELS 3 Zrotation Xrotation Yrotation",
        "CHANNELS 3 Zrotation Xrotation",
    ));
    assert_eq!(m, "line 9, CHANNELS: 3 channels declared, 2 named");
    let m = message(&GOOD.replace(
        "CHANNELS 3 Zrotation Xrotation Yrotation",
        "CHANNELS 3 Zrotation Xrotation Wrotation",
    ));
    assert_eq!(m, "line 9, CHANNELS: unknown channel \"Wrotation\"");
    let m = message(&GOOD.replace("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS three"));
    assert_eq!(
        m,
        "line 9, CHANNELS: expected the channel count, got \"three\""
    );
}

#[test]
fn missing_motion() {
    let text = GOOD.split("MOTION").next().unwrap();
    assert_eq!(
        message(text),
        "line 15, MOTION: expected MOTION, got the end of the file"
    );
    let m = message(&GOOD.replace("MOTION", "MOTON"));
    assert_eq!(
        m,
        "line 16, MOTION: expected MOTION after the hierarchy, got \"MOTON\""
    );
}

#[test]
fn fewer_or_more_values_than_channels() {
    let m = message(&GOOD.replace("0 1 0 0 0 0 0 0 0\n0 1", "0 1 0 0 0 0 0 0\n0 1"));
    assert_eq!(
        m,
        "line 19, motion row: frame 1: expected 9 values (one per channel), got 8"
    );
    let m = message(&GOOD.replace("0 1 0 0 0 0 0 0 0\n0 1", "0 1 0 0 0 0 0 0 0 0\n0 1"));
    assert_eq!(
        m,
        "line 19, motion row: frame 1: expected 9 values (one per channel), got more"
    );
}

#[test]
fn nan_and_inf_values() {
    let m = message(&GOOD.replace(
        "0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 0 0 0",
        "0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 0 nan 0",
    ));
    assert_eq!(
        m,
        "line 20, motion value 8 of frame 2 (channel Xrotation of LeftArm): expected a number, got \"nan\""
    );
    let m = message(&GOOD.replace(
        "0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 0 0 0",
        "0 1 0 0 0 0 0 0 0\n0 1 0 inf 0 0 0 0 0",
    ));
    assert_eq!(
        m,
        "line 20, motion value 4 of frame 2 (channel Zrotation of Hips): expected a number, got \"inf\""
    );
    let m = message(&GOOD.replace(
        "0 1 0 0 0 0 0 0 0\n0 1 0 0 0 0 0 0 0",
        "0 1 0 0 0 0 0 0 0\n0 1 0 1e999 0 0 0 0 0",
    ));
    assert_eq!(
        m,
        "line 20, motion value 4 of frame 2 (channel Zrotation of Hips): \"1e999\" is not finite"
    );
    let m = message(&GOOD.replace("OFFSET 0.2 0 0", "OFFSET 0.2 NaN 0"));
    assert_eq!(m, "line 8, OFFSET: expected a number, got \"NaN\"");
}

#[test]
fn absurd_frame_counts_do_not_allocate() {
    let m = message(&GOOD.replace("Frames: 2", "Frames: 999999999999"));
    assert_eq!(
        m,
        "line 17, Frames:: 999999999999 frames, over the limit of 2000000"
    );
    let m = message(&GOOD.replace("Frames: 2", "Frames: 100000"));
    assert_eq!(
        m,
        "line 17, Frames:: 100000 frames declared, the file has 2"
    );
    let m = message(&GOOD.replace("Frames: 2", "Frames: -3"));
    assert_eq!(m, "line 17, Frames:: expected a frame count, got \"-3\"");
    let m = message(&GOOD.replace("Frame Time: 0.04", "Frame Time: 0"));
    assert_eq!(
        m,
        "line 18, Frame Time:: the frame time must be positive and finite, got 0"
    );
}

#[test]
fn over_limit_files() {
    let limits = BvhLimits {
        max_bytes: 100,
        ..BvhLimits::default()
    };
    let e = read_bvh(GOOD.as_bytes(), "big", &limits).unwrap_err();
    assert!(matches!(e, BvhError::Limit { .. }));
    assert_eq!(
        e.to_string(),
        format!(
            "line 1, file: {} bytes, over the limit of 100 bytes",
            GOOD.len()
        )
    );
    let limits = BvhLimits {
        max_joints: 1,
        ..BvhLimits::default()
    };
    let e = read_bvh(GOOD.as_bytes(), "big", &limits).unwrap_err();
    assert_eq!(e.to_string(), "line 6, JOINT: more than 1 joints");
    let limits = BvhLimits {
        max_channels: 6,
        ..BvhLimits::default()
    };
    let e = read_bvh(GOOD.as_bytes(), "big", &limits).unwrap_err();
    assert_eq!(e.to_string(), "line 9, CHANNELS: more than 6 channels");
    let limits = BvhLimits {
        max_frames: 1,
        ..BvhLimits::default()
    };
    let e = read_bvh(GOOD.as_bytes(), "big", &limits).unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 17, Frames:: 2 frames, over the limit of 1"
    );
    let limits = BvhLimits {
        max_values: 10,
        ..BvhLimits::default()
    };
    let e = read_bvh(GOOD.as_bytes(), "big", &limits).unwrap_err();
    assert_eq!(
        e.to_string(),
        "line 20, motion row: more than 10 motion values"
    );
}

#[test]
fn missing_braces() {
    let m = message(&GOOD.replacen("{\n  OFFSET 0 1 0", "  OFFSET 0 1 0", 1));
    assert_eq!(m, "line 3, {: expected '{', got \"OFFSET\"");
    let text = GOOD.replacen("    }\n  }\n}\n", "    }\n  }\n", 1);
    assert_eq!(
        message(&text),
        "line 15, }: MOTION before the hierarchy is complete (1 joint(s) still open)"
    );
    let m = message("HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n");
    assert_eq!(
        m,
        "line 4, }: expected '}' to close joint \"Hips\", got the end of the file"
    );
    let m = message(&GOOD.replacen("}\nMOTION", "}\n}\nMOTION", 1));
    assert_eq!(
        m,
        "line 16, MOTION: expected MOTION after the hierarchy, got \"}\""
    );
}

#[test]
fn unknown_keywords() {
    let m = message(&GOOD.replace("JOINT LeftArm", "BONE LeftArm"));
    assert_eq!(m, "line 6, hierarchy: unknown keyword \"BONE\"");
    let m = message(&GOOD.replace("HIERARCHY", "HIERARCHIE"));
    assert_eq!(
        m,
        "line 1, HIERARCHY: expected HIERARCHY, got \"HIERARCHIE\""
    );
    let m = message(&GOOD.replace("Frame Time:", "Frame Rate:"));
    assert_eq!(
        m,
        "line 18, Frame Time:: expected 'Frame Time:', got \"Frame Rate: 0.04\""
    );
    let m = message(&GOOD.replace("OFFSET 0.2 0 0", "OFFSET 0.2 0"));
    assert_eq!(m, "line 8, OFFSET: expected 3 numbers, got 2");
}

#[test]
fn empty_files_and_binary_garbage() {
    assert_eq!(
        message(""),
        "line 1, HIERARCHY: expected HIERARCHY, got an empty file"
    );
    assert_eq!(
        message("\n \r\n\t"),
        "line 1, HIERARCHY: expected HIERARCHY, got an empty file"
    );
    let garbage: Vec<u8> = (0..200u32).map(|i| (i * 97 % 251) as u8).collect();
    let e = read_bvh(&garbage, "bin", &BvhLimits::default()).unwrap_err();
    assert_eq!(e.field(), "HIERARCHY");
    assert!(
        e.to_string().starts_with(&format!(
            "line {}, HIERARCHY: expected HIERARCHY, got ",
            e.line()
        )),
        "{e}"
    );
    let e = read_bvh(
        b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR",
        "png",
        &BvhLimits::default(),
    )
    .unwrap_err();
    assert_eq!(e.line(), 1);
    assert_eq!(e.field(), "HIERARCHY");
}
