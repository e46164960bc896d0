//! For the tests: a humanoid BVH in any naming, unit and up axis; the default H-Anim body,
//! reshaped or with its legs scaled.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

/// Joint names of a rig, by role.
pub struct Names {
    pub hips: &'static str,
    pub spine: &'static str,
    pub chest: &'static str,
    pub neck: &'static str,
    pub head: &'static str,
    /// `{}` is replaced by the side word of `sides`.
    pub up_leg: &'static str,
    pub leg: &'static str,
    pub foot: &'static str,
    pub toe: &'static str,
    pub collar: &'static str,
    pub arm: &'static str,
    pub fore_arm: &'static str,
    pub hand: &'static str,
    pub sides: [&'static str; 2],
    /// 3ds Max Biped: a `Bip01` root above the pelvis, the thighs under the spine and the
    /// clavicles under the neck.
    pub biped: bool,
}

pub const MIXAMO: Names = Names {
    hips: "mixamorig:Hips",
    spine: "mixamorig:Spine",
    chest: "mixamorig:Spine1",
    neck: "mixamorig:Neck",
    head: "mixamorig:Head",
    up_leg: "mixamorig:{}UpLeg",
    leg: "mixamorig:{}Leg",
    foot: "mixamorig:{}Foot",
    toe: "mixamorig:{}ToeBase",
    collar: "mixamorig:{}Shoulder",
    arm: "mixamorig:{}Arm",
    fore_arm: "mixamorig:{}ForeArm",
    hand: "mixamorig:{}Hand",
    sides: ["Left", "Right"],
    biped: false,
};

/// A BVH of a T-posed humanoid (1.55 m skull base above the ankles when `unit` is 1 m per
/// unit; coordinates divided by `unit`), one frame per row of `rows` (or rest rows when
/// `rows` is empty). `z_up`: written with +Z up and +Y front (file y = -front... see code).
pub fn humanoid(names: &Names, unit: f64, z_up: bool, frames: usize) -> String {
    let fix = |name: &str, side: usize| name.replace("{}", names.sides[side]);
    let mut out = String::from("HIERARCHY\n");
    let v = |x: f64, y: f64, z: f64| {
        // H-Anim (x left, y up, z front) to the file's axes.
        let (a, b, c) = if z_up { (x, -z, y) } else { (x, y, z) };
        format!("{} {} {}", a / unit, b / unit, c / unit)
    };
    let mut channels = 0usize;
    let mut open = |out: &mut String, kw: &str, name: &str, o: String, root: bool| {
        if root {
            out.push_str(&format!(
                "{kw} {name}\n{{\nOFFSET {o}\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
            ));
            channels += 6;
        } else {
            out.push_str(&format!(
                "{kw} {name}\n{{\nOFFSET {o}\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
            ));
            channels += 3;
        }
    };
    let end =
        |out: &mut String, o: String| out.push_str(&format!("End Site\n{{\nOFFSET {o}\n}}\n"));
    let leg = |out: &mut String,
               open: &mut dyn FnMut(&mut String, &str, &str, String, bool),
               s: usize| {
        let x = if s == 0 { 0.1 } else { -0.1 };
        open(out, "JOINT", &fix(names.up_leg, s), v(x, -0.05, 0.0), false);
        open(out, "JOINT", &fix(names.leg, s), v(0.0, -0.42, 0.0), false);
        open(out, "JOINT", &fix(names.foot, s), v(0.0, -0.41, 0.0), false);
        open(out, "JOINT", &fix(names.toe, s), v(0.0, -0.06, 0.12), false);
        end(out, v(0.0, 0.0, 0.05));
        out.push_str("}\n}\n}\n}\n");
    };
    let arm = |out: &mut String,
               open: &mut dyn FnMut(&mut String, &str, &str, String, bool),
               s: usize| {
        let x = if s == 0 { 1.0 } else { -1.0 };
        open(
            out,
            "JOINT",
            &fix(names.collar, s),
            v(0.02 * x, 0.1, 0.0),
            false,
        );
        open(
            out,
            "JOINT",
            &fix(names.arm, s),
            v(0.15 * x, 0.0, 0.0),
            false,
        );
        open(
            out,
            "JOINT",
            &fix(names.fore_arm, s),
            v(0.28 * x, 0.0, 0.0),
            false,
        );
        open(
            out,
            "JOINT",
            &fix(names.hand, s),
            v(0.25 * x, 0.0, 0.0),
            false,
        );
        end(out, v(0.08 * x, 0.0, 0.0));
        out.push_str("}\n}\n}\n}\n");
    };
    if names.biped {
        open(&mut out, "ROOT", "Bip01", v(0.0, 0.95, 0.0), true);
        open(&mut out, "JOINT", names.hips, v(0.0, 0.0, 0.0), false);
    } else {
        open(&mut out, "ROOT", names.hips, v(0.0, 0.95, 0.0), true);
    }
    if !names.biped {
        leg(&mut out, &mut open, 0);
        leg(&mut out, &mut open, 1);
    }
    open(&mut out, "JOINT", names.spine, v(0.0, 0.1, 0.0), false);
    if names.biped {
        leg(&mut out, &mut open, 0);
        leg(&mut out, &mut open, 1);
    }
    open(&mut out, "JOINT", names.chest, v(0.0, 0.3, 0.0), false);
    if !names.biped {
        arm(&mut out, &mut open, 0);
        arm(&mut out, &mut open, 1);
    }
    open(&mut out, "JOINT", names.neck, v(0.0, 0.15, 0.0), false);
    if names.biped {
        arm(&mut out, &mut open, 0);
        arm(&mut out, &mut open, 1);
    }
    open(&mut out, "JOINT", names.head, v(0.0, 0.1, 0.0), false);
    end(&mut out, v(0.0, 0.15, 0.0));
    out.push_str("}\n}\n}\n}\n");
    if names.biped {
        out.push_str("}\n");
    }
    out.push_str("}\n");
    out.push_str(&format!(
        "MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n"
    ));
    for f in 0..frames {
        let mut row = Vec::with_capacity(channels);
        let (x, y, z) = if z_up {
            (0.0, -0.01 * f as f64, 0.95)
        } else {
            (0.0, 0.95, 0.01 * f as f64)
        };
        row.extend([x / unit, y / unit, z / unit]);
        for k in 3..channels {
            row.push(((k * 7 + f * 3) % 23) as f64 - 11.0);
        }
        let row: Vec<String> = row.iter().map(|v| v.to_string()).collect();
        out.push_str(&row.join(" "));
        out.push('\n');
    }
    out
}

use glam::DVec3;
use stance_hanim::{
    HumanoidSkeleton, LevelOfArticulation, Mapping, SkeletonOptions, SourceJoint, build_skeleton,
    default_skeleton,
};
use stance_ik::{Frames, Posture};

/// The default H-Anim body at `loa`.
pub fn body(loa: LevelOfArticulation) -> HumanoidSkeleton {
    default_skeleton(&SkeletonOptions {
        loa,
        ..Default::default()
    })
    .unwrap()
}

/// A body from the default one with each rest position moved by `f`.
pub fn reshaped(loa: LevelOfArticulation, f: impl Fn(&str, DVec3) -> DVec3) -> HumanoidSkeleton {
    let base = body(loa);
    let rest = Frames::new(&base.skeleton, &Posture::rest(&base.skeleton)).joint_position;
    let joints: Vec<SourceJoint> = base
        .skeleton
        .joints()
        .iter()
        .zip(&rest)
        .map(|(j, p)| SourceJoint {
            name: j.name.clone(),
            parent: j.parent,
            position: f(&j.name, *p),
        })
        .collect();
    let mapping = Mapping::auto(&joints, &[], false);
    let positions: Vec<DVec3> = joints.iter().map(|j| j.position).collect();
    build_skeleton(
        &mapping,
        &positions,
        &SkeletonOptions {
            loa,
            ..Default::default()
        },
    )
    .unwrap()
}

/// The default body with its legs scaled by `legs` about the hips, lowered or raised so
/// that the ankles stand where they did.
pub fn legs_scaled(legs: f64) -> HumanoidSkeleton {
    let base = body(LevelOfArticulation::Loa2);
    let rest = Frames::new(&base.skeleton, &Posture::rest(&base.skeleton)).joint_position;
    let at = |n: &str| rest[base.skeleton.joint_index(n).unwrap()];
    let ankle_y = at("l_talocrural").y;
    let leg_joint = |name: &str| {
        [
            "hip",
            "knee",
            "talocrural",
            "tarsal",
            "subtalar",
            "midtarsal",
            "metatars",
            "tarsometa",
        ]
        .iter()
        .any(|k| name.contains(k))
            && (name.starts_with("l_") || name.starts_with("r_"))
    };
    let scaled = |name: &str, p: DVec3| {
        if leg_joint(name) && !name.ends_with("_hip") {
            let hip = at(if name.starts_with("l_") {
                "l_hip"
            } else {
                "r_hip"
            });
            hip + (p - hip) * legs
        } else {
            p
        }
    };
    let drop = scaled("l_talocrural", at("l_talocrural")).y - ankle_y;
    reshaped(LevelOfArticulation::Loa2, |name, p| {
        scaled(name, p) - DVec3::Y * drop
    })
}
