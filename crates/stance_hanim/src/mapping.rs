//! Bone-name mapping: which joint of an avatar is which H-Anim 2.0 joint.
//!
//! Sources, most trusted first:
//! 1. the VRM humanoid extension (0.x `VRM.humanoid.humanBones`, 1.0
//!    `VRMC_vrm.humanoid.humanBones`), passed in as `(vrm bone name, joint)` pairs;
//! 2. H-Anim names (and their aliases) themselves;
//! 3. known rig vocabularies: Mixamo (with or without the `mixamorig:` prefix), Unity/VRM
//!    bone names, Unreal (`upperarm_l`), Blender/Rigify (`upper_arm.L`);
//! 4. a name-pattern fallback (`UpperArm_L`, `arm_joint_L_1`, `Bip01 L Thigh`...);
//! 5. a hierarchy/geometry fallback for the limbs, head and spine still missing.
//!
//! The result records how each joint was matched and a confidence in 0..1; the user can
//! override any entry ([`Mapping::set`], [`Mapping::remove`]).

use glam::DVec3;

use crate::{LevelOfArticulation, humanoid_joints, joint_by_name};

/// One joint of the source avatar, as the mapper sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceJoint {
    /// The name in the file.
    pub name: String,
    /// Index of the parent joint in the same list.
    pub parent: Option<usize>,
    /// Rest position in a +Y-up frame whose +X is the body's left where known (metres or
    /// file units: only directions and ratios are used).
    pub position: DVec3,
}

/// How a joint was matched.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum MatchMethod {
    /// The VRM humanoid extension named it.
    Vrm,
    /// The joint is named with its H-Anim name or alias.
    HAnimName,
    /// A known rig vocabulary (Mixamo, Unity, Unreal, Rigify).
    KnownName,
    /// A name pattern (side token + body-part keyword).
    NamePattern,
    /// Position in the hierarchy and geometry.
    Geometry,
    /// Implied by another joint at the same place (e.g. `sacroiliac` at the hips of a rig
    /// without a separate pelvis joint). Such joints carry no DOF of their own.
    Implied,
    /// Set by the user.
    User,
}

/// One mapped H-Anim joint.
#[derive(Debug, Clone, PartialEq)]
pub struct JointMatch {
    /// The H-Anim 2.0 joint name.
    pub hanim: &'static str,
    /// Index of the source joint.
    pub source: usize,
    /// 0..1: how sure the mapper is.
    pub confidence: f32,
    /// How it was found.
    pub method: MatchMethod,
}

/// Errors of user corrections.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MappingError {
    /// Not an H-Anim 2.0 joint name or alias.
    #[error("`{0}` is not an H-Anim 2.0 joint name")]
    UnknownHAnimJoint(String),
    /// No such source joint.
    #[error("source joint {index} does not exist (the avatar has {count})")]
    UnknownSourceJoint {
        /// Index given.
        index: usize,
        /// Number of source joints.
        count: usize,
    },
}

/// A [`JointMatch`] as it is serialised: the H-Anim name as text, read back as the standard's
/// own name (an unknown one is refused).
#[derive(serde::Serialize, serde::Deserialize)]
struct JointMatchWire {
    hanim: String,
    source: usize,
    confidence: f32,
    method: MatchMethod,
}

impl serde::Serialize for JointMatch {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        JointMatchWire {
            hanim: self.hanim.to_owned(),
            source: self.source,
            confidence: self.confidence,
            method: self.method,
        }
        .serialize(serializer)
    }
}

impl<'de> serde::Deserialize<'de> for JointMatch {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let wire = JointMatchWire::deserialize(deserializer)?;
        let (_, joint) = joint_by_name(&wire.hanim).ok_or_else(|| {
            <D::Error as serde::de::Error>::custom(MappingError::UnknownHAnimJoint(wire.hanim))
        })?;
        Ok(Self {
            hanim: joint.name,
            source: wire.source,
            confidence: wire.confidence,
            method: wire.method,
        })
    }
}

/// The mapping of an avatar's joints onto H-Anim 2.0.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Mapping {
    matches: Vec<JointMatch>,
    source_count: usize,
}

/// VRM humanoid bone name -> H-Anim name (VRM 1.0 names; VRM 0.x differs for the thumb and
/// is handled in [`vrm_bone_to_hanim`]).
const VRM_BONES: &[(&str, &str)] = &[
    ("hips", "humanoid_root"),
    ("spine", "vl5"),
    ("chest", "vt10"),
    ("upperChest", "vt1"),
    ("neck", "vc4"),
    ("head", "skullbase"),
    ("leftEye", "l_eyeball_joint"),
    ("rightEye", "r_eyeball_joint"),
    ("jaw", "temporomandibular"),
    ("leftUpperLeg", "l_hip"),
    ("leftLowerLeg", "l_knee"),
    ("leftFoot", "l_talocrural"),
    ("leftToes", "l_metatarsophalangeal_2"),
    ("rightUpperLeg", "r_hip"),
    ("rightLowerLeg", "r_knee"),
    ("rightFoot", "r_talocrural"),
    ("rightToes", "r_metatarsophalangeal_2"),
    ("leftShoulder", "l_sternoclavicular"),
    ("leftUpperArm", "l_shoulder"),
    ("leftLowerArm", "l_elbow"),
    ("leftHand", "l_radiocarpal"),
    ("rightShoulder", "r_sternoclavicular"),
    ("rightUpperArm", "r_shoulder"),
    ("rightLowerArm", "r_elbow"),
    ("rightHand", "r_radiocarpal"),
];

/// Finger part of a VRM bone name -> (H-Anim stem, finger number).
fn vrm_finger(bone: &str, vrm0: bool) -> Option<String> {
    let (side, rest) = if let Some(r) = bone.strip_prefix("left") {
        ("l_", r)
    } else if let Some(r) = bone.strip_prefix("right") {
        ("r_", r)
    } else {
        return None;
    };
    let fingers = [
        ("Thumb", 1),
        ("Index", 2),
        ("Middle", 3),
        ("Ring", 4),
        ("Little", 5),
    ];
    let (finger, part) = fingers
        .iter()
        .find_map(|(f, n)| rest.strip_prefix(f).map(|p| (*n, p)))?;
    let stem = if finger == 1 {
        match (part, vrm0) {
            ("Metacarpal", false) | ("Proximal", true) => "carpometacarpal",
            ("Proximal", false) | ("Intermediate", true) => "metacarpophalangeal",
            ("Distal", _) => "carpal_interphalangeal",
            _ => return None,
        }
    } else {
        match part {
            "Proximal" => "metacarpophalangeal",
            "Intermediate" => "carpal_proximal_interphalangeal",
            "Distal" => "carpal_distal_interphalangeal",
            _ => return None,
        }
    };
    Some(format!("{side}{stem}_{finger}"))
}

/// The H-Anim joint of a VRM humanoid bone. `vrm0`: the file is VRM 0.x (its thumb bones are
/// proximal/intermediate/distal, VRM 1.0's metacarpal/proximal/distal).
pub fn vrm_bone_to_hanim(bone: &str, vrm0: bool) -> Option<&'static str> {
    if let Some((_, h)) = VRM_BONES.iter().find(|(b, _)| *b == bone) {
        return Some(h);
    }
    let name = vrm_finger(bone, vrm0)?;
    joint_by_name(&name).map(|(_, d)| d.name)
}

/// Lower-case, namespace-free (`mixamorig:`, `Armature|`), alphanumeric tokens of a name.
fn tokens(name: &str) -> Vec<String> {
    let base = name.rsplit([':', '|', '/']).next().unwrap_or(name);
    // Split camelCase too: insert a break before an upper-case letter that follows a lower.
    let mut split = String::new();
    let mut prev_lower = false;
    for c in base.chars() {
        if c.is_uppercase() && prev_lower {
            split.push(' ');
        }
        prev_lower = c.is_lowercase() || c.is_ascii_digit();
        split.push(c);
    }
    let split = split.to_lowercase();
    let split = split
        .strip_prefix("mixamorig")
        .map(|r| r.trim_start_matches(|c: char| c.is_ascii_digit()))
        .unwrap_or(&split)
        .to_owned();
    let mut out = Vec::new();
    let mut cur = String::new();
    for c in split.chars() {
        if c.is_ascii_alphabetic() {
            if cur.chars().last().is_some_and(|l| l.is_ascii_digit()) {
                out.push(std::mem::take(&mut cur));
            }
            cur.push(c);
        } else if c.is_ascii_digit() {
            if cur.chars().last().is_some_and(|l| l.is_ascii_alphabetic()) {
                out.push(std::mem::take(&mut cur));
            }
            cur.push(c);
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Body-part stems that CMU's ASF skeleton writes glued to a one-letter side (`lfemur`,
/// `rclavicle`); a glued `l`/`r` is only split off before these.
const GLUED_SIDE_STEMS: &[&str] = &[
    "femur", "tibia", "foot", "toes", "clavicle", "humerus", "radius", "wrist", "hand", "thigh",
    "shin", "shldr", "collar", "forearm",
];

/// Side from tokens; removes the side tokens.
fn take_side(tokens: &mut Vec<String>) -> Option<char> {
    for t in tokens.iter_mut() {
        if let Some(stem) = t.strip_prefix(['l', 'r'])
            && GLUED_SIDE_STEMS.contains(&stem)
        {
            let side = t.get(..1).unwrap_or_default().to_owned();
            *t = stem.to_owned();
            tokens.insert(0, side);
            break;
        }
    }
    let mut side = None;
    tokens.retain(|t| {
        let s = match t.as_str() {
            "l" | "left" | "lft" => Some('l'),
            "r" | "right" | "rgt" => Some('r'),
            _ => None,
        };
        if s.is_some() && side.is_none() {
            side = s;
            false
        } else {
            s.is_none()
        }
    });
    side
}

/// Body part keyword (sided) -> H-Anim stem; `None` index means "numbered chain" handled
/// separately.
fn sided_part(words: &str) -> Option<&'static str> {
    Some(match words {
        "shoulder" | "clavicle" | "collar" | "collarbone" | "clav" => "sternoclavicular",
        "arm" | "upperarm" | "uparm" | "humerus" | "shldr" => "shoulder",
        "forearm" | "lowerarm" | "elbow" | "radius" | "loarm" => "elbow",
        "hand" | "wrist" => "radiocarpal",
        "upleg" | "upperleg" | "thigh" | "hip" | "femur" => "hip",
        "leg" | "lowerleg" | "calf" | "shin" | "knee" | "loleg" | "tibia" => "knee",
        "foot" | "ankle" => "talocrural",
        "toe" | "toes" | "toebase" | "ball" => "metatarsophalangeal_2",
        "eye" => "eyeball_joint",
        _ => return None,
    })
}

fn finger_number(word: &str) -> Option<u32> {
    Some(match word {
        "thumb" => 1,
        "index" | "pointer" => 2,
        "middle" | "mid" => 3,
        "ring" => 4,
        "pinky" | "little" | "small" => 5,
        _ => return None,
    })
}

/// Matches a name by vocabulary / pattern. Returns (H-Anim name, method).
fn match_name(name: &str) -> Option<(&'static str, MatchMethod)> {
    if let Some((_, d)) = joint_by_name(name) {
        return Some((d.name, MatchMethod::HAnimName));
    }
    let mut toks = tokens(name);
    if toks.is_empty() {
        return None;
    }
    let had_prefix = name.to_lowercase().starts_with("mixamorig");
    let side = take_side(&mut toks);
    // Trailing number (segment index), possibly "01".
    let number = toks
        .last()
        .and_then(|t| t.parse::<u32>().ok())
        .inspect(|_| {
            toks.pop();
        });
    toks.retain(|t| !t.chars().all(|c| c.is_ascii_digit()));
    toks.retain(|t| {
        !matches!(
            t.as_str(),
            "bip"
                | "bip01"
                | "def"
                | "org"
                | "mch"
                | "j"
                | "bn"
                | "bone"
                | "c"
                | "joint"
                | "jnt"
                | "character"
                | "bend"
        )
    });
    // Twist helpers (Daz `lShldrTwist`, Unreal `upperarm_twist_01_l`) carry no joint.
    if toks.iter().any(|t| t == "twist") {
        return None;
    }
    let words: String = toks.concat();
    let known = if had_prefix {
        MatchMethod::KnownName
    } else {
        MatchMethod::NamePattern
    };
    let found = |n: String, m: MatchMethod| joint_by_name(&n).map(|(_, d)| (d.name, m));
    match side {
        None => {
            let hanim = match (words.as_str(), number) {
                ("hips" | "pelvis" | "hip", _) => "humanoid_root",
                ("spine", None | Some(0))
                | ("abdomen" | "lowerspine" | "lowerback" | "abdomenlower", _) => "vl5",
                ("spine", Some(1)) | ("chest", None | Some(1)) | ("upperback", _) => "vt10",
                ("spine", Some(2)) | ("upperchest" | "thorax", _) | ("chest", Some(2)) => "vt1",
                ("lowerneck", _) => "vc7",
                ("neck" | "upperneck", _) => "vc4",
                ("head", None) => "skullbase",
                ("jaw", _) => "temporomandibular",
                _ => return None,
            };
            let method = if matches!(
                words.as_str(),
                "hips"
                    | "spine"
                    | "neck"
                    | "head"
                    | "chest"
                    | "upperchest"
                    | "lowerback"
                    | "upperback"
                    | "thorax"
                    | "lowerneck"
                    | "upperneck"
            ) {
                MatchMethod::KnownName
            } else {
                known
            };
            found(hanim.to_owned(), method)
        }
        Some(s) => {
            let prefix = if s == 'l' { "l_" } else { "r_" };
            // Fingers: "hand thumb 1", "thumb 01", "index proximal"...
            let finger_words: Vec<&str> = toks
                .iter()
                .map(String::as_str)
                .filter(|t| !matches!(*t, "hand" | "finger" | "fingers"))
                .collect();
            if let Some(finger) = finger_words.first().and_then(|w| finger_number(w)) {
                let segment = match (finger_words.get(1).copied(), number) {
                    (Some("metacarpal"), _) => 0,
                    (Some("proximal"), _) => 1,
                    (Some("intermediate" | "middle"), _) => 2,
                    (Some("distal"), _) => 3,
                    (None, Some(n)) => n,
                    _ => return None,
                };
                let stem = if finger == 1 {
                    match segment {
                        0 | 1 => "carpometacarpal",
                        2 => "metacarpophalangeal",
                        3 => "carpal_interphalangeal",
                        _ => return None,
                    }
                } else {
                    match segment {
                        0 => "carpometacarpal",
                        1 => "metacarpophalangeal",
                        2 => "carpal_proximal_interphalangeal",
                        3 => "carpal_distal_interphalangeal",
                        _ => return None,
                    }
                };
                // Mixamo's `LeftHandIndex1` (the `hand` token) is a known vocabulary.
                let method = if toks.iter().any(|t| t == "hand") {
                    MatchMethod::KnownName
                } else {
                    known
                };
                return found(format!("{prefix}{stem}_{finger}"), method);
            }
            // Numbered chains: arm_joint_L_1 -> shoulder, elbow, wrist; leg_1.. -> hip...
            if let Some(n) = number
                && matches!(words.as_str(), "arm" | "leg")
            {
                let chain: &[&str] = if words == "arm" {
                    &["shoulder", "elbow", "radiocarpal"]
                } else {
                    &["hip", "knee", "talocrural", "metatarsophalangeal_2"]
                };
                let stem = chain.get((n as usize).checked_sub(1)?)?;
                return found(format!("{prefix}{stem}"), MatchMethod::NamePattern);
            }
            if number.is_some_and(|n| n > 1) {
                return None;
            }
            let stem = sided_part(&words)?;
            // "Left shoulder" names the clavicle in Mixamo/Unity/VRM rigs.
            let method = if matches!(
                words.as_str(),
                "shoulder"
                    | "arm"
                    | "forearm"
                    | "hand"
                    | "upleg"
                    | "leg"
                    | "foot"
                    | "toebase"
                    | "upperarm"
                    | "lowerarm"
                    | "upperleg"
                    | "lowerleg"
                    | "toes"
            ) {
                MatchMethod::KnownName
            } else {
                known
            };
            found(format!("{prefix}{stem}"), method)
        }
    }
}

fn confidence_of(method: MatchMethod) -> f32 {
    match method {
        MatchMethod::Vrm | MatchMethod::HAnimName | MatchMethod::User => 1.0,
        MatchMethod::KnownName => 0.95,
        MatchMethod::NamePattern => 0.75,
        MatchMethod::Geometry => 0.5,
        MatchMethod::Implied => 0.5,
    }
}

impl Mapping {
    /// An empty mapping over `source_count` source joints.
    pub fn empty(source_count: usize) -> Self {
        Self {
            matches: Vec::new(),
            source_count,
        }
    }

    /// Maps automatically. `vrm_bones`: `(VRM humanoid bone, source joint)` pairs from a VRM
    /// extension, with `vrm0` true for VRM 0.x; they take precedence over names.
    pub fn auto(joints: &[SourceJoint], vrm_bones: &[(String, usize)], vrm0: bool) -> Self {
        let mut m = Self::empty(joints.len());
        for (bone, source) in vrm_bones {
            if *source < joints.len()
                && let Some(h) = vrm_bone_to_hanim(bone, vrm0)
            {
                m.insert(h, *source, MatchMethod::Vrm);
            }
        }
        // VRM `chest` without `upperChest`: the shoulders hang from it, as from vt1.
        if m.source_of("vt1").is_none()
            && let Some(i) = m.matches.iter().position(|j| j.hanim == "vt10")
            && vrm_bones.iter().all(|(b, _)| b != "upperChest")
        {
            m.matches[i].hanim = "vt1";
        }
        let vrm_used = !m.matches.is_empty();
        for (i, joint) in joints.iter().enumerate() {
            if m.hanim_of(i).is_some() {
                continue;
            }
            if let Some((h, method)) = match_name(&joint.name) {
                let h = m.resolve_taken(h, i, joints);
                // With a VRM extension only fill what it left out.
                if vrm_used && method != MatchMethod::HAnimName && m.source_of(h).is_some() {
                    continue;
                }
                if m.source_of(h).is_none() {
                    m.insert(h, i, method);
                }
            }
        }
        m.fix_spine_by_hierarchy(joints);
        m.fill_by_geometry(joints);
        m.imply_sacroiliac();
        m.sort();
        m
    }

    /// Where a name's joint is already taken by an ancestor: a `shoulder` under a `collar`
    /// or `clavicle` (Daz, 3ds Max-friendly CMU: `LeftCollar` > `LeftShoulder`) is the upper
    /// arm; a `pelvis` under the `hip` root (Daz Genesis) is the sacroiliac.
    fn resolve_taken(&self, h: &'static str, i: usize, joints: &[SourceJoint]) -> &'static str {
        let Some(taken) = self.source_of(h) else {
            return h;
        };
        let mut ancestor = joints.get(i).and_then(|j| j.parent);
        let mut steps = 0;
        while let Some(a) = ancestor {
            if a == taken {
                let next = match h {
                    "l_sternoclavicular" => "l_shoulder",
                    "r_sternoclavicular" => "r_shoulder",
                    "humanoid_root" => "sacroiliac",
                    _ => return h,
                };
                let free = self
                    .get(next)
                    .is_none_or(|m| m.method == MatchMethod::Implied);
                return if free { next } else { h };
            }
            steps += 1;
            if steps > joints.len() {
                break;
            }
            ancestor = joints.get(a).and_then(|j| j.parent);
        }
        h
    }

    fn insert(&mut self, hanim: &'static str, source: usize, method: MatchMethod) {
        self.matches.retain(|j| j.hanim != hanim);
        self.matches.push(JointMatch {
            hanim,
            source,
            confidence: confidence_of(method),
            method,
        });
    }

    fn sort(&mut self) {
        self.matches
            .sort_by_key(|j| joint_by_name(j.hanim).map_or(usize::MAX, |(i, _)| i));
    }

    /// `sacroiliac` at the root joint when the rig has no separate pelvis joint.
    fn imply_sacroiliac(&mut self) {
        if self.source_of("sacroiliac").is_none()
            && let Some(root) = self.source_of("humanoid_root")
        {
            self.insert("sacroiliac", root, MatchMethod::Implied);
        }
    }

    /// Spine joints found by name keep their order; when the rig has a chain of spine joints
    /// between the hips and the shoulders' parent, they are spread over vl5..vt1 in order.
    fn fix_spine_by_hierarchy(&mut self, joints: &[SourceJoint]) {
        let (Some(hips), Some(mut top)) = (
            self.source_of("humanoid_root"),
            self.source_of("l_sternoclavicular")
                .or_else(|| self.source_of("l_shoulder"))
                .and_then(|s| joints.get(s)?.parent),
        ) else {
            return;
        };
        // 3ds Max Biped hangs the clavicles from the neck: the spine ends below it.
        let mut steps = 0;
        while matches!(self.hanim_of(top), Some("vc4" | "vc7" | "skullbase"))
            && steps <= joints.len()
        {
            let Some(p) = joints.get(top).and_then(|j| j.parent) else {
                return;
            };
            top = p;
            steps += 1;
        }
        // Chain from `top` up to (excluding) the hips.
        let mut chain = Vec::new();
        let mut j = Some(top);
        while let Some(i) = j {
            if i == hips || chain.len() > joints.len() {
                break;
            }
            chain.push(i);
            j = joints.get(i).and_then(|n| n.parent);
        }
        if j != Some(hips) || chain.is_empty() {
            return;
        }
        chain.reverse();
        // Only re-spread joints matched by name, never VRM or user ones.
        if chain.iter().any(|&i| {
            self.matches.iter().any(|m| {
                m.source == i
                    && matches!(
                        m.method,
                        MatchMethod::Vrm | MatchMethod::User | MatchMethod::HAnimName
                    )
            })
        }) {
            return;
        }
        const SPINE: [&str; 6] = ["vl5", "vl3", "vl1", "vt10", "vt6", "vt1"];
        let slots: Vec<usize> = match chain.len() {
            1 => vec![5],
            2 => vec![0, 5],
            3 => vec![0, 3, 5],
            4 => vec![0, 2, 3, 5],
            5 => vec![0, 1, 2, 3, 5],
            _ => (0..chain.len().min(6)).collect(),
        };
        for name in SPINE {
            self.matches
                .retain(|m| !(m.hanim == name && m.method != MatchMethod::User));
        }
        for (k, &slot) in slots.iter().enumerate() {
            let source = chain[k];
            self.matches
                .retain(|m| m.source != source || m.method == MatchMethod::Implied);
            let named = match_name(&joints[source].name).is_some();
            let method = if named {
                MatchMethod::KnownName
            } else {
                MatchMethod::Geometry
            };
            self.insert(SPINE[slot], source, method);
        }
    }

    /// Hierarchy/geometry fallback for the LOA1 limbs and head when names did not find them.
    fn fill_by_geometry(&mut self, joints: &[SourceJoint]) {
        let n = joints.len();
        let mut children = vec![Vec::new(); n];
        for (i, j) in joints.iter().enumerate() {
            if let Some(p) = j.parent
                && p < n
            {
                children[p].push(i);
            }
        }
        let mut depth_below = vec![0usize; n];
        // Joints come in any order; iterate to a fixed point a bounded number of times.
        for _ in 0..64 {
            let mut changed = false;
            for i in 0..n {
                let d = children[i]
                    .iter()
                    .map(|&c| depth_below[c] + 1)
                    .max()
                    .unwrap_or(0);
                if d != depth_below[i] && d <= n {
                    depth_below[i] = d;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // The longest-path child chain from a joint.
        let chain_from = |start: usize, max: usize| {
            let mut chain = vec![start];
            let mut cur = start;
            while chain.len() < max {
                let Some(&next) = children[cur].iter().max_by_key(|&&c| depth_below[c]) else {
                    break;
                };
                chain.push(next);
                cur = next;
            }
            chain
        };
        let hips = match self.source_of("humanoid_root") {
            Some(h) => h,
            None => {
                // A joint with two children going down on either side and one going up.
                let candidate = (0..n).find(|&i| {
                    let p = joints[i].position;
                    let kids = &children[i];
                    let down_l = kids.iter().any(|&c| {
                        let d = joints[c].position - p;
                        d.x > 0.0
                            && depth_below[c] >= 2
                            && joints[chain_from(c, 3)[2]].position.y < p.y
                    });
                    let down_r = kids.iter().any(|&c| {
                        let d = joints[c].position - p;
                        d.x < 0.0
                            && depth_below[c] >= 2
                            && joints[chain_from(c, 3)[2]].position.y < p.y
                    });
                    let up = kids.iter().any(|&c| {
                        depth_below[c] >= 2 && joints[chain_from(c, 3)[2]].position.y > p.y
                    });
                    down_l && down_r && up
                });
                let Some(h) = candidate else {
                    return;
                };
                self.insert("humanoid_root", h, MatchMethod::Geometry);
                h
            }
        };
        let hp = joints[hips].position;
        // Legs.
        for &c in &children[hips] {
            if depth_below[c] < 2 {
                continue;
            }
            let chain = chain_from(c, 4);
            if joints[chain[chain.len() - 1]].position.y >= hp.y {
                continue;
            }
            let side = if joints[chain[0]].position.x - hp.x >= 0.0 {
                "l_"
            } else {
                "r_"
            };
            let names = ["hip", "knee", "talocrural", "metatarsophalangeal_2"];
            for (k, &j) in chain.iter().enumerate() {
                self.fill(&format!("{side}{}", names[k]), j, joints);
            }
        }
        // Spine up to the joint where the arms branch off.
        let Some(&up) = children[hips]
            .iter()
            .find(|&&c| depth_below[c] >= 2 && joints[chain_from(c, 3)[2]].position.y > hp.y)
        else {
            return;
        };
        let mut chest = up;
        let mut spine = vec![up];
        while children[chest].len() < 3 {
            let Some(&next) = children[chest].iter().max_by_key(|&&c| depth_below[c]) else {
                return;
            };
            chest = next;
            spine.push(next);
            if spine.len() > 8 {
                return;
            }
        }
        if self.source_of("vl5").is_none() && spine.len() >= 2 {
            self.fill("vl5", spine[0], joints);
        }
        if self.source_of("vt1").is_none() {
            self.fill("vt1", chest, joints);
        }
        let cp = joints[chest].position;
        for &c in &children[chest] {
            let d = joints[c].position - cp;
            let chain = chain_from(c, 5);
            let end = joints[chain[chain.len() - 1]].position - cp;
            if end.x.abs() < end.y.abs() && end.y > 0.0 {
                // Neck and head.
                if chain.len() >= 2 {
                    self.fill("vc4", chain[0], joints);
                    self.fill("skullbase", chain[1], joints);
                } else {
                    self.fill("skullbase", chain[0], joints);
                }
                continue;
            }
            let side = if d.x + end.x >= 0.0 { "l_" } else { "r_" };
            // Clavicle when the first segment is short compared with the next.
            let has_clavicle = chain.len() >= 4 && {
                let a = (joints[chain[1]].position - joints[chain[0]].position).length();
                let b = (joints[chain[2]].position - joints[chain[1]].position).length();
                a < 0.7 * b
            };
            let names: &[&str] = if has_clavicle {
                &["sternoclavicular", "shoulder", "elbow", "radiocarpal"]
            } else {
                &["shoulder", "elbow", "radiocarpal"]
            };
            for (k, &j) in chain.iter().enumerate().take(names.len()) {
                self.fill(&format!("{side}{}", names[k]), j, joints);
            }
        }
    }

    fn fill(&mut self, hanim: &str, source: usize, joints: &[SourceJoint]) {
        if source >= joints.len() || self.hanim_of(source).is_some() {
            return;
        }
        if let Some((_, d)) = joint_by_name(hanim)
            && self.source_of(d.name).is_none()
        {
            self.insert(d.name, source, MatchMethod::Geometry);
        }
    }

    /// All matches, in H-Anim table order.
    pub fn matches(&self) -> &[JointMatch] {
        &self.matches
    }

    /// The match of an H-Anim joint.
    pub fn get(&self, hanim: &str) -> Option<&JointMatch> {
        self.matches.iter().find(|m| m.hanim == hanim)
    }

    /// The source joint of an H-Anim joint.
    pub fn source_of(&self, hanim: &str) -> Option<usize> {
        self.get(hanim).map(|m| m.source)
    }

    /// The H-Anim joint a source joint is mapped to (implied joints aside).
    pub fn hanim_of(&self, source: usize) -> Option<&'static str> {
        self.matches
            .iter()
            .find(|m| m.source == source && m.method != MatchMethod::Implied)
            .map(|m| m.hanim)
    }

    /// Number of source joints this mapping refers to.
    pub fn source_count(&self) -> usize {
        self.source_count
    }

    /// User correction: maps `hanim` (a name or alias) to source joint `source`, replacing
    /// whatever either was mapped to before.
    pub fn set(&mut self, hanim: &str, source: usize) -> Result<(), MappingError> {
        let (_, d) =
            joint_by_name(hanim).ok_or_else(|| MappingError::UnknownHAnimJoint(hanim.into()))?;
        if source >= self.source_count {
            return Err(MappingError::UnknownSourceJoint {
                index: source,
                count: self.source_count,
            });
        }
        self.matches
            .retain(|m| m.source != source || m.method == MatchMethod::Implied);
        self.insert(d.name, source, MatchMethod::User);
        if d.name == "sacroiliac" {
            self.matches
                .retain(|m| !(m.hanim == "sacroiliac" && m.method == MatchMethod::Implied));
        }
        self.imply_sacroiliac();
        self.sort();
        Ok(())
    }

    /// User correction: unmaps `hanim`. Returns whether it was mapped.
    pub fn remove(&mut self, hanim: &str) -> bool {
        let before = self.matches.len();
        let name = joint_by_name(hanim).map_or(hanim, |(_, d)| d.name);
        self.matches.retain(|m| m.hanim != name);
        before != self.matches.len()
    }

    /// The same mapping over a renumbered (or reduced) list of source joints:
    /// `new_index_of_source[s]` is the new index of old source joint `s`, `None` where it is
    /// dropped. Matches whose joint is dropped, has no entry, or whose new index is not below
    /// `source_count` are left out; the others keep their H-Anim joint, method and
    /// confidence (and the table order).
    pub fn remapped(&self, new_index_of_source: &[Option<usize>], source_count: usize) -> Mapping {
        Mapping {
            matches: self
                .matches
                .iter()
                .filter_map(|m| {
                    let source = new_index_of_source
                        .get(m.source)
                        .copied()
                        .flatten()
                        .filter(|&n| n < source_count)?;
                    Some(JointMatch {
                        source,
                        ..m.clone()
                    })
                })
                .collect(),
            source_count,
        }
    }

    /// The joints of `loa` that are not mapped (by name).
    pub fn missing(&self, loa: LevelOfArticulation) -> Vec<&'static str> {
        humanoid_joints(loa)
            .iter()
            .map(|j| j.definition.name)
            .filter(|n| self.get(n).is_none())
            .collect()
    }
}

#[cfg(test)]
mod tests;
