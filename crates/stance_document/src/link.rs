//! Posture links: a [`Document`] in the fragment of a URL (`https://host/#<fragment>`).
//!
//! # Format 1 (see `docs/document-format.md`)
//! ```text
//! base64url, no padding, of:
//!   [format: u8 = 1][payload length: LEB128][payload][CRC-32 (IEEE) of all previous bytes, LE]
//! ```
//! Every format keeps the frame's first byte (the format number) and its CRC-32 trailer, so a
//! link from a newer Stance is recognised as such. The payload is written with an adaptive
//! binary range coder (module `range_coder`): joints as indices into the H-Anim 2.0 joint
//! table (`stance_hanim::all_joints`), the joint set as a level of articulation plus exceptions,
//! rotation DOF quantised to [`ROTATION_STEP_RAD`] (0.005 degrees, so every decoded angle is
//! within 0.0025 degrees), positions to [`POSITION_STEP_M`] (0.1 mm), directions to
//! [`DIRECTION_STEP`]; weights exactly.

use base64::Engine as _;
use base64::alphabet;
use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
use glam::{DQuat, DVec3};
use stance_ik::{Axes, Dof};
use thiserror::Error;

use crate::document::{
    AvatarReference, Document, DofValues, LimbName, PostureValues, TaskKindSpec, TaskSpec, dof_slot,
};
use crate::range_coder::{Bit, Decoder, Encoder, SymbolModel, UintModel};

/// The link format this version writes and reads.
pub const LINK_FORMAT: u8 = 1;
/// Quantisation step of rotation DOF and task angles: 0.005 degrees in radians.
pub const ROTATION_STEP_RAD: f64 = 0.005 * std::f64::consts::PI / 180.0;
/// Quantisation step of positions and translations: 0.1 mm.
pub const POSITION_STEP_M: f64 = 1e-4;
/// Quantisation step of the components of unit directions (gaze axes).
pub const DIRECTION_STEP: f64 = 1e-5;
/// Longest fragment accepted by [`decode`], in characters.
pub const MAX_LINK_CHARS: usize = 64 * 1024;

const MAX_COUNT: u64 = 4096;
const MAX_STRING_BYTES: u64 = 4096;
const MAX_OVERRUN: usize = 16;

/// Why a link cannot be opened. The messages are meant for the person who opened the link.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LinkError {
    /// Nothing after the `#`.
    #[error("the link holds no posture (there is nothing after `#`)")]
    Empty,
    /// Far longer than any posture link.
    #[error("the link is too long to be a Stance posture link ({0} characters)")]
    TooLong(usize),
    /// A character that base64url never produces.
    #[error(
        "the link is damaged: the character `{character}` at position {position} of the fragment cannot appear in a posture link"
    )]
    BadCharacter {
        /// The character.
        character: char,
        /// Its position in the fragment (0-based, in characters).
        position: usize,
    },
    /// Shorter than the length it declares: cut when copied.
    #[error(
        "the link is incomplete: it holds {got} of its {expected} bytes (it was probably cut when copied; copy the whole link)"
    )]
    Truncated {
        /// Bytes present.
        got: usize,
        /// Bytes the link declares.
        expected: usize,
    },
    /// The checksum does not match: characters were changed.
    #[error("the link is damaged: its checksum does not match (characters were changed or lost)")]
    Checksum,
    /// Made by a newer Stance.
    #[error(
        "this link was made by a newer version of Stance (format {found}); this version reads format {supported}"
    )]
    FutureVersion {
        /// The link's format.
        found: u8,
        /// The newest format this version reads.
        supported: u8,
    },
    /// The checksum matches but the content is not a valid document.
    #[error("the link is not a valid posture link: {0}")]
    Malformed(String),
}

fn engine() -> GeneralPurpose {
    GeneralPurpose::new(
        &alphabet::URL_SAFE,
        GeneralPurposeConfig::new()
            .with_encode_padding(false)
            .with_decode_allow_trailing_bits(true)
            .with_decode_padding_mode(DecodePaddingMode::Indifferent),
    )
}

// ---------------------------------------------------------------------------------------------
// Public API

/// The URL fragment (without `#`) that carries `document`. Values are quantised (see the module
/// documentation); non-finite numbers, which a validated document never holds, are written as 0.
pub fn encode(document: &Document) -> String {
    let payload = encode_payload(document);
    let mut frame = Vec::with_capacity(payload.len() + 8);
    frame.push(LINK_FORMAT);
    write_leb128(&mut frame, payload.len() as u64);
    frame.extend_from_slice(&payload);
    let crc = crc32fast::hash(&frame);
    frame.extend_from_slice(&crc.to_le_bytes());
    engine().encode(frame)
}

/// The document in a link: a bare fragment, `#fragment`, or a whole URL containing `#`.
pub fn decode(link: &str) -> Result<Document, LinkError> {
    let fragment = match link.find('#') {
        Some(i) => &link[i + 1..],
        None => link,
    };
    let fragment = fragment.trim();
    let fragment = fragment.trim_end_matches('=');
    if fragment.is_empty() {
        return Err(LinkError::Empty);
    }
    let chars = fragment.chars().count();
    if chars > MAX_LINK_CHARS {
        return Err(LinkError::TooLong(chars));
    }
    let mut text = String::with_capacity(fragment.len());
    for (position, c) in fragment.chars().enumerate() {
        match c {
            'A'..='Z' | 'a'..='z' | '0'..='9' | '-' | '_' => text.push(c),
            // Tolerate the standard alphabet.
            '+' => text.push('-'),
            '/' => text.push('_'),
            character => {
                return Err(LinkError::BadCharacter {
                    character,
                    position,
                });
            }
        }
    }
    // A single dangling character carries no whole byte: a cut link.
    if text.len() % 4 == 1 {
        text.pop();
    }
    let bytes = engine()
        .decode(text.as_bytes())
        .map_err(|e| LinkError::Malformed(format!("not base64url ({e})")))?;
    let declared = declared_length(&bytes);
    if bytes.len() < 5 {
        return Err(LinkError::Truncated {
            got: bytes.len(),
            expected: declared.unwrap_or(5).max(bytes.len() + 1),
        });
    }
    let (body, crc) = bytes.split_at(bytes.len() - 4);
    let crc_ok = crc32fast::hash(body).to_le_bytes() == crc;
    if !crc_ok {
        return Err(match declared {
            Some(expected) if expected > bytes.len() => LinkError::Truncated {
                got: bytes.len(),
                expected,
            },
            _ => LinkError::Checksum,
        });
    }
    let format = bytes[0];
    if format > LINK_FORMAT {
        return Err(LinkError::FutureVersion {
            found: format,
            supported: LINK_FORMAT,
        });
    }
    if format == 0 {
        return Err(LinkError::Malformed("format 0 does not exist".to_owned()));
    }
    let (len, header) = read_leb128(&body[1..])
        .ok_or_else(|| LinkError::Malformed("bad payload length".to_owned()))?;
    let payload = &body[1 + header..];
    if len != payload.len() as u64 {
        return Err(LinkError::Malformed(format!(
            "the payload has {} bytes but declares {len}",
            payload.len()
        )));
    }
    let document = decode_payload(payload).map_err(LinkError::Malformed)?;
    document
        .validate()
        .map_err(|e| LinkError::Malformed(e.to_string()))?;
    Ok(document)
}

/// The whole frame length a link declares, when its header can be read.
fn declared_length(bytes: &[u8]) -> Option<usize> {
    let (len, header) = read_leb128(bytes.get(1..)?)?;
    usize::try_from(len).ok()?.checked_add(1 + header + 4)
}

fn write_leb128(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let byte = (v & 0x7F) as u8;
        v >>= 7;
        if v == 0 {
            out.push(byte);
            return;
        }
        out.push(byte | 0x80);
    }
}

/// The value and the number of bytes it took.
fn read_leb128(bytes: &[u8]) -> Option<(u64, usize)> {
    let mut v = 0u64;
    for (i, &b) in bytes.iter().enumerate().take(9) {
        v |= u64::from(b & 0x7F) << (7 * i);
        if b & 0x80 == 0 {
            return Some((v, i + 1));
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// Payload

/// Typical bit lengths of quantised joint angles (about 0.05 to 1.5 rad), the prior of the
/// rotation model. Part of the format: changing it changes every link.
pub(crate) const ROTATION_PRIOR: [u32; 24] = [
    14, 13, 14, 12, 15, 13, 14, 11, 14, 13, 15, 12, 14, 13, 14, 12, 15, 13, 14, 11, 14, 13, 15, 12,
];
/// Typical bit lengths of quantised positions (0.1 to 2 m at 0.1 mm).
const POSITION_PRIOR: [u32; 16] = [
    14, 15, 13, 15, 14, 12, 15, 14, 13, 15, 14, 15, 13, 14, 12, 15,
];
/// Typical bit lengths of task angles (orientations, swivel).
const ANGLE_PRIOR: [u32; 8] = [15, 16, 14, 15, 16, 13, 15, 14];

/// Adaptive contexts, one per kind of value; the encoder and the decoder evolve them alike.
#[derive(Debug)]
struct Models {
    flags: [Bit; 16],
    rotation: UintModel,
    translation: UintModel,
    position: UintModel,
    direction: UintModel,
    angle: UintModel,
    count: UintModel,
    gap: UintModel,
    level: UintModel,
    weight: UintModel,
    string_len: UintModel,
    loa: SymbolModel<8>,
    kind: SymbolModel<8>,
    limb: SymbolModel<4>,
    mask: SymbolModel<64>,
    joint: SymbolModel<256>,
    byte: SymbolModel<256>,
}

impl Default for Models {
    fn default() -> Self {
        Self {
            flags: Default::default(),
            rotation: UintModel::primed(&ROTATION_PRIOR),
            translation: UintModel::primed(&POSITION_PRIOR),
            position: UintModel::primed(&POSITION_PRIOR),
            direction: UintModel::default(),
            angle: UintModel::primed(&ANGLE_PRIOR),
            count: UintModel::default(),
            gap: UintModel::default(),
            level: UintModel::default(),
            weight: UintModel::default(),
            string_len: UintModel::default(),
            loa: Default::default(),
            kind: Default::default(),
            limb: Default::default(),
            mask: Default::default(),
            joint: Default::default(),
            byte: Default::default(),
        }
    }
}

// Indices into `Models::flags`.
const AVATAR_URL: usize = 0;
const MASKS_DEFAULT: usize = 1;
const JOINT_MASK_DEFAULT: usize = 2;
const ACTIVE: usize = 3;
const WEIGHT_ONE: usize = 4;
const POINT_ZERO: usize = 5;
const AXES_XYZ: usize = 6;
const AXIS_Z: usize = 7;
const HAS_JOINTS: usize = 8;
const HAS_REFERENCE: usize = 9;
const HAS_LIMB: usize = 10;
const HAS_SWIVEL: usize = 11;
const HANIM_JOINT: usize = 12;
const WEIGHT_DECIMAL: usize = 13;
const HAS_ORIENTATION: usize = 14;
const AXIS_Y: usize = 15;

/// `m / 10^k`, correctly rounded (both are exact in f64 for the ranges used).
fn from_decimal(m: u64, k: i32) -> f64 {
    m as f64 / 10f64.powi(k)
}

/// `(m, k)` with `w == m / 10^k` exactly, m < 2^50 and k <= 15, for weights typed as short
/// decimals (0.1, 2.5, 1000); `None` for the others (written as all 64 bits).
fn short_decimal(w: f64) -> Option<(u64, u8)> {
    if !(w.is_finite() && w >= 0.0) {
        return None;
    }
    (0..=15u8).find_map(|k| {
        let m = (w * 10f64.powi(i32::from(k))).round();
        (m < (1u64 << 50) as f64 && from_decimal(m as u64, i32::from(k)) == w)
            .then_some((m as u64, k))
    })
}

const KINDS: [&str; 8] = [
    "position",
    "orientation",
    "gaze",
    "com",
    "posture",
    "limb",
    "direction",
    "balance",
];

fn quantise(x: f64, step: f64) -> i64 {
    const LIMIT: f64 = 4.611_686_018_427_388e18; // 2^62
    let q = (x / step).round();
    if q.is_nan() {
        0
    } else {
        q.clamp(-LIMIT, LIMIT) as i64
    }
}

fn dequantise(q: i64, step: f64) -> f64 {
    q as f64 * step
}

fn mask_of(v: &DofValues) -> usize {
    Dof::ALL
        .into_iter()
        .filter(|&d| v.get(d).is_some())
        .fold(0, |m, d| m | (1 << dof_slot(d)))
}

/// `tx ty tz rx ry rz` for the root, `rx ry rz` for every other joint.
fn default_mask(table_index: usize) -> usize {
    if table_index == 0 {
        0b11_1111
    } else {
        0b11_1000
    }
}

fn in_loa_base(table_index: usize, loa: usize) -> bool {
    loa > 0
        && stance_hanim::all_joints()
            .get(table_index)
            .is_some_and(|d| usize::from(d.first_loa) <= loa)
}

fn hanim_index(name: &str) -> Option<usize> {
    stance_hanim::all_joints()
        .iter()
        .position(|d| d.name == name)
}

fn unit(v: [f64; 3]) -> [f64; 3] {
    let d = DVec3::from_array(v);
    let n = d.length();
    if n.is_finite() && n > 0.0 {
        (d / n).to_array()
    } else {
        [0.0, 0.0, 1.0]
    }
}

struct Writer {
    e: Encoder,
    m: Models,
}

impl Writer {
    fn flag(&mut self, which: usize, value: bool) {
        self.e.bit(&mut self.m.flags[which], value);
    }

    fn count(&mut self, n: usize) {
        self.m.count.encode(&mut self.e, n as u64);
    }

    fn string(&mut self, s: &str) {
        self.m.string_len.encode(&mut self.e, s.len() as u64);
        for &b in s.as_bytes() {
            self.m.byte.encode(&mut self.e, usize::from(b));
        }
    }

    fn position(&mut self, v: [f64; 3]) {
        for x in v {
            self.m
                .position
                .encode_signed(&mut self.e, quantise(x, POSITION_STEP_M));
        }
    }

    fn angle(&mut self, x: f64) {
        self.m
            .angle
            .encode_signed(&mut self.e, quantise(x, ROTATION_STEP_RAD));
    }

    fn joint(&mut self, name: &str) {
        match hanim_index(name) {
            Some(i) => {
                self.flag(HANIM_JOINT, true);
                self.m.joint.encode(&mut self.e, i);
            }
            None => {
                self.flag(HANIM_JOINT, false);
                self.string(name);
            }
        }
    }

    fn axes(&mut self, axes: Axes) {
        let xyz = axes == Axes::XYZ;
        self.flag(AXES_XYZ, xyz);
        if !xyz {
            self.e.direct(
                u64::from(axes.has(0))
                    | (u64::from(axes.has(1)) << 1)
                    | (u64::from(axes.has(2)) << 2),
                3,
            );
        }
    }

    fn dofs(&mut self, v: &DofValues) {
        for (d, x) in v.iter() {
            if d.is_rotation() {
                self.m
                    .rotation
                    .encode_signed(&mut self.e, quantise(x, ROTATION_STEP_RAD));
            } else {
                self.m
                    .translation
                    .encode_signed(&mut self.e, quantise(x, POSITION_STEP_M));
            }
        }
    }

    fn posture(&mut self, p: &PostureValues) {
        let table_len = stance_hanim::all_joints().len();
        let mut hanim: Vec<(usize, &DofValues)> = Vec::new();
        let mut extras: Vec<(&str, &DofValues)> = Vec::new();
        for (name, v) in &p.joints {
            match hanim_index(name) {
                Some(i) => hanim.push((i, v)),
                None => extras.push((name, v)),
            }
        }
        hanim.sort_by_key(|(i, _)| *i);
        let mut present = vec![false; table_len];
        for (i, _) in &hanim {
            present[*i] = true;
        }
        let toggles_for = |loa: usize| -> Vec<usize> {
            (0..table_len)
                .filter(|&i| present[i] != in_loa_base(i, loa))
                .collect()
        };
        let (loa, toggles) = (0..=4)
            .map(|loa| (loa, toggles_for(loa)))
            .min_by_key(|(_, t)| t.len())
            .unwrap_or((0, Vec::new()));
        self.m.loa.encode(&mut self.e, loa);
        self.count(toggles.len());
        let mut next = 0usize;
        for t in toggles {
            self.m.gap.encode(&mut self.e, (t - next) as u64);
            next = t + 1;
        }
        let all_default = hanim.iter().all(|(i, v)| mask_of(v) == default_mask(*i));
        self.flag(MASKS_DEFAULT, all_default);
        if !all_default {
            for (i, v) in &hanim {
                let mask = mask_of(v);
                let is_default = mask == default_mask(*i);
                self.flag(JOINT_MASK_DEFAULT, is_default);
                if !is_default {
                    self.m.mask.encode(&mut self.e, mask);
                }
            }
        }
        for (_, v) in &hanim {
            self.dofs(v);
        }
        self.count(extras.len());
        for (name, v) in extras {
            self.string(name);
            self.m.mask.encode(&mut self.e, mask_of(v));
            self.dofs(v);
        }
    }

    fn task(&mut self, t: &TaskSpec) {
        let kind = KINDS.iter().position(|k| *k == t.kind.name()).unwrap_or(0);
        self.m.kind.encode(&mut self.e, kind);
        self.m
            .level
            .encode(&mut self.e, u64::from(t.level.saturating_sub(1)));
        self.flag(ACTIVE, t.active);
        let one = t.weight == 1.0;
        self.flag(WEIGHT_ONE, one);
        if !one {
            match short_decimal(t.weight) {
                Some((m, k)) => {
                    self.flag(WEIGHT_DECIMAL, true);
                    self.m.weight.encode(&mut self.e, m);
                    self.e.direct(u64::from(k), 4);
                }
                None => {
                    self.flag(WEIGHT_DECIMAL, false);
                    self.e.direct(t.weight.to_bits(), 64);
                }
            }
        }
        match &t.kind {
            TaskKindSpec::Position {
                joint,
                point,
                axes,
                target,
            } => {
                self.joint(joint);
                self.point(*point);
                self.axes(*axes);
                self.position(*target);
            }
            TaskKindSpec::Orientation { joint, target } => {
                self.joint(joint);
                self.quaternion(*target);
            }
            TaskKindSpec::Gaze {
                joint,
                axis,
                point,
                target,
            } => {
                self.joint(joint);
                let axis = unit(*axis);
                let z = axis == [0.0, 0.0, 1.0];
                self.flag(AXIS_Z, z);
                if !z {
                    self.direction(axis);
                }
                self.point(*point);
                self.position(*target);
            }
            TaskKindSpec::Direction {
                joint,
                axis,
                target,
            } => {
                self.joint(joint);
                let axis = unit(*axis);
                let y = axis == [0.0, 1.0, 0.0];
                self.flag(AXIS_Y, y);
                if !y {
                    self.direction(axis);
                }
                self.direction(unit(*target));
            }
            TaskKindSpec::Balance { support, margin } => {
                self.joint_list(support.as_deref());
                self.m
                    .position
                    .encode_signed(&mut self.e, quantise(*margin, POSITION_STEP_M));
            }
            TaskKindSpec::Com { axes, target } => {
                self.axes(*axes);
                self.position(*target);
            }
            TaskKindSpec::Posture { joints, reference } => {
                self.joint_list(joints.as_deref());
                self.flag(HAS_REFERENCE, reference.is_some());
                if let Some(r) = reference {
                    self.posture(r);
                }
            }
            TaskKindSpec::Limb {
                limb,
                joints,
                target,
                swivel,
                orientation,
            } => {
                self.flag(HAS_LIMB, limb.is_some());
                if let Some(l) = limb {
                    let i = LimbName::ALL.iter().position(|x| x == l).unwrap_or(0);
                    self.m.limb.encode(&mut self.e, i);
                }
                self.flag(HAS_JOINTS, joints.is_some());
                if let Some(js) = joints {
                    for j in js {
                        self.joint(j);
                    }
                }
                self.position(*target);
                self.flag(HAS_SWIVEL, swivel.is_some());
                if let Some(s) = swivel {
                    self.angle(*s);
                }
                self.flag(HAS_ORIENTATION, orientation.is_some());
                if let Some(q) = orientation {
                    self.quaternion(*q);
                }
            }
        }
    }

    /// As a rotation vector with `qw >= 0`, at the rotation step.
    fn quaternion(&mut self, q: [f64; 4]) {
        let mut q = DQuat::from_array(q).normalize();
        if q.w < 0.0 {
            q = -q;
        }
        let r = q.to_scaled_axis();
        let r = if r.is_finite() { r } else { DVec3::ZERO };
        for x in r.to_array() {
            self.angle(x);
        }
    }

    /// An optional list of joints (`HAS_JOINTS`, then a count and the joints).
    fn joint_list(&mut self, joints: Option<&[String]>) {
        self.flag(HAS_JOINTS, joints.is_some());
        if let Some(list) = joints {
            self.count(list.len());
            for j in list {
                self.joint(j);
            }
        }
    }

    /// A unit vector, at the direction step.
    fn direction(&mut self, v: [f64; 3]) {
        for x in v {
            self.m
                .direction
                .encode_signed(&mut self.e, quantise(x, DIRECTION_STEP));
        }
    }

    fn point(&mut self, p: [f64; 3]) {
        let zero = p == [0.0; 3];
        self.flag(POINT_ZERO, zero);
        if !zero {
            self.position(p);
        }
    }
}

fn encode_payload(d: &Document) -> Vec<u8> {
    let mut w = Writer {
        e: Encoder::new(),
        m: Models::default(),
    };
    match &d.avatar {
        AvatarReference::Default => w.flag(AVATAR_URL, false),
        AvatarReference::Url(u) => {
            w.flag(AVATAR_URL, true);
            w.string(u);
        }
    }
    w.posture(&d.posture);
    w.count(d.tasks.len());
    for t in &d.tasks {
        w.task(t);
    }
    w.e.finish()
}

struct Reader<'a> {
    d: Decoder<'a>,
    m: Models,
}

type R<T> = Result<T, String>;

impl Reader<'_> {
    fn check(&self) -> R<()> {
        if self.d.overrun() > MAX_OVERRUN {
            Err("the data ends too early".to_owned())
        } else {
            Ok(())
        }
    }

    fn flag(&mut self, which: usize) -> bool {
        self.d.bit(&mut self.m.flags[which])
    }

    fn count(&mut self, what: &str) -> R<usize> {
        let n = self
            .m
            .count
            .decode(&mut self.d)
            .ok_or_else(|| format!("bad {what} count"))?;
        if n > MAX_COUNT {
            return Err(format!("too many {what} ({n})"));
        }
        Ok(n as usize)
    }

    fn string(&mut self) -> R<String> {
        let n = self
            .m
            .string_len
            .decode(&mut self.d)
            .ok_or("bad text length")?;
        if n > MAX_STRING_BYTES {
            return Err(format!("text of {n} bytes"));
        }
        let mut bytes = Vec::with_capacity(n as usize);
        for _ in 0..n {
            bytes.push(self.m.byte.decode(&mut self.d) as u8);
        }
        self.check()?;
        String::from_utf8(bytes).map_err(|_| "text is not UTF-8".to_owned())
    }

    fn signed(model: &mut UintModel, d: &mut Decoder, step: f64) -> R<f64> {
        model
            .decode_signed(d)
            .map(|q| dequantise(q, step))
            .ok_or_else(|| "bad number".to_owned())
    }

    fn position(&mut self) -> R<[f64; 3]> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = Self::signed(&mut self.m.position, &mut self.d, POSITION_STEP_M)?;
        }
        Ok(v)
    }

    /// An optional list of joints (`HAS_JOINTS`, then a count and the joints).
    fn joint_list(&mut self, what: &str) -> R<Option<Vec<String>>> {
        if !self.flag(HAS_JOINTS) {
            return Ok(None);
        }
        let n = self.count(what)?;
        let mut list = Vec::with_capacity(n);
        for _ in 0..n {
            list.push(self.joint()?);
            self.check()?;
        }
        Ok(Some(list))
    }

    fn direction(&mut self) -> R<[f64; 3]> {
        let mut v = [0.0; 3];
        for x in &mut v {
            *x = Self::signed(&mut self.m.direction, &mut self.d, DIRECTION_STEP)?;
        }
        Ok(v)
    }

    fn angle(&mut self) -> R<f64> {
        Self::signed(&mut self.m.angle, &mut self.d, ROTATION_STEP_RAD)
    }

    fn quaternion(&mut self) -> R<[f64; 4]> {
        let r = DVec3::new(self.angle()?, self.angle()?, self.angle()?);
        Ok(DQuat::from_scaled_axis(r).to_array())
    }

    fn joint(&mut self) -> R<String> {
        if self.flag(HANIM_JOINT) {
            let i = self.m.joint.decode(&mut self.d);
            stance_hanim::all_joints()
                .get(i)
                .map(|d| d.name.to_owned())
                .ok_or_else(|| format!("joint index {i} is not in the H-Anim table"))
        } else {
            self.string()
        }
    }

    fn axes(&mut self) -> R<Axes> {
        if self.flag(AXES_XYZ) {
            return Ok(Axes::XYZ);
        }
        let m = self.d.direct(3);
        if m == 0 {
            return Err("no axes selected".to_owned());
        }
        Ok(Axes::new(m & 1 != 0, m & 2 != 0, m & 4 != 0))
    }

    fn point(&mut self) -> R<[f64; 3]> {
        if self.flag(POINT_ZERO) {
            Ok([0.0; 3])
        } else {
            self.position()
        }
    }

    fn dofs(&mut self, mask: usize) -> R<DofValues> {
        let mut v = DofValues::default();
        for d in Dof::ALL {
            if mask & (1 << dof_slot(d)) == 0 {
                continue;
            }
            let x = if d.is_rotation() {
                Self::signed(&mut self.m.rotation, &mut self.d, ROTATION_STEP_RAD)?
            } else {
                Self::signed(&mut self.m.translation, &mut self.d, POSITION_STEP_M)?
            };
            v.set(d, x);
        }
        Ok(v)
    }

    fn posture(&mut self) -> R<PostureValues> {
        let table = stance_hanim::all_joints();
        let loa = self.m.loa.decode(&mut self.d);
        if loa > 4 {
            return Err(format!("level of articulation {loa}"));
        }
        let mut present: Vec<bool> = (0..table.len()).map(|i| in_loa_base(i, loa)).collect();
        let toggles = self.count("joint exceptions")?;
        let mut next = 0usize;
        for _ in 0..toggles {
            let gap = self.m.gap.decode(&mut self.d).ok_or("bad joint gap")?;
            let i = usize::try_from(gap)
                .ok()
                .and_then(|g| g.checked_add(next))
                .filter(|&i| i < table.len())
                .ok_or("joint index beyond the H-Anim table")?;
            present[i] = !present[i];
            next = i + 1;
        }
        let indices: Vec<usize> = (0..table.len()).filter(|&i| present[i]).collect();
        let mut masks: Vec<usize> = indices.iter().map(|&i| default_mask(i)).collect();
        if !self.flag(MASKS_DEFAULT) {
            for mask in &mut masks {
                if !self.flag(JOINT_MASK_DEFAULT) {
                    *mask = self.m.mask.decode(&mut self.d);
                }
            }
        }
        let mut p = PostureValues::default();
        for (&i, &mask) in indices.iter().zip(&masks) {
            let v = self.dofs(mask)?;
            p.joints.insert(table[i].name.to_owned(), v);
        }
        self.check()?;
        let extras = self.count("named joints")?;
        for _ in 0..extras {
            let name = self.string()?;
            let mask = self.m.mask.decode(&mut self.d);
            let v = self.dofs(mask)?;
            self.check()?;
            if p.joints.insert(name.clone(), v).is_some() {
                return Err(format!("joint `{name}` appears twice"));
            }
        }
        Ok(p)
    }

    fn task(&mut self) -> R<TaskSpec> {
        let kind = self.m.kind.decode(&mut self.d);
        let level = self.m.level.decode(&mut self.d).ok_or("bad level")?;
        let level = level
            .checked_add(1)
            .and_then(|l| u32::try_from(l).ok())
            .ok_or("level out of range")?;
        let active = self.flag(ACTIVE);
        let weight = if self.flag(WEIGHT_ONE) {
            1.0
        } else if self.flag(WEIGHT_DECIMAL) {
            let m = self.m.weight.decode(&mut self.d).ok_or("bad weight")?;
            let k = self.d.direct(4) as i32;
            from_decimal(m, k)
        } else {
            f64::from_bits(self.d.direct(64))
        };
        let kind = match KINDS.get(kind).copied() {
            Some("position") => TaskKindSpec::Position {
                joint: self.joint()?,
                point: self.point()?,
                axes: self.axes()?,
                target: self.position()?,
            },
            Some("orientation") => TaskKindSpec::Orientation {
                joint: self.joint()?,
                target: self.quaternion()?,
            },
            Some("gaze") => {
                let joint = self.joint()?;
                let axis = if self.flag(AXIS_Z) {
                    [0.0, 0.0, 1.0]
                } else {
                    self.direction()?
                };
                TaskKindSpec::Gaze {
                    joint,
                    axis,
                    point: self.point()?,
                    target: self.position()?,
                }
            }
            Some("direction") => {
                let joint = self.joint()?;
                let axis = if self.flag(AXIS_Y) {
                    [0.0, 1.0, 0.0]
                } else {
                    self.direction()?
                };
                TaskKindSpec::Direction {
                    joint,
                    axis,
                    target: self.direction()?,
                }
            }
            Some("balance") => {
                let support = self.joint_list("support joints")?;
                let margin = Self::signed(&mut self.m.position, &mut self.d, POSITION_STEP_M)?;
                TaskKindSpec::Balance { support, margin }
            }
            Some("com") => TaskKindSpec::Com {
                axes: self.axes()?,
                target: self.position()?,
            },
            Some("posture") => {
                let joints = self.joint_list("posture joints")?;
                let reference = if self.flag(HAS_REFERENCE) {
                    Some(self.posture()?)
                } else {
                    None
                };
                TaskKindSpec::Posture { joints, reference }
            }
            Some("limb") => {
                let limb = if self.flag(HAS_LIMB) {
                    Some(LimbName::ALL[self.m.limb.decode(&mut self.d) & 3])
                } else {
                    None
                };
                let joints = if self.flag(HAS_JOINTS) {
                    Some([self.joint()?, self.joint()?, self.joint()?])
                } else {
                    None
                };
                let target = self.position()?;
                let swivel = if self.flag(HAS_SWIVEL) {
                    Some(self.angle()?)
                } else {
                    None
                };
                let orientation = if self.flag(HAS_ORIENTATION) {
                    Some(self.quaternion()?)
                } else {
                    None
                };
                TaskKindSpec::Limb {
                    limb,
                    joints,
                    target,
                    swivel,
                    orientation,
                }
            }
            _ => return Err(format!("unknown task kind {kind}")),
        };
        self.check()?;
        Ok(TaskSpec {
            level,
            weight,
            active,
            kind,
        })
    }
}

fn decode_payload(bytes: &[u8]) -> R<Document> {
    let mut r = Reader {
        d: Decoder::new(bytes),
        m: Models::default(),
    };
    let avatar = if r.flag(AVATAR_URL) {
        AvatarReference::Url(r.string()?)
    } else {
        AvatarReference::Default
    };
    let posture = r.posture()?;
    let n = r.count("tasks")?;
    let mut tasks = Vec::with_capacity(n);
    for _ in 0..n {
        tasks.push(r.task()?);
    }
    r.check()?;
    Ok(Document {
        avatar,
        posture,
        tasks,
    })
}
