//! The share-link codec: round trips, the LOA2 length target, and every way a link can be
//! broken (never a panic, always a clear error or a valid document).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use crate::common;

use base64::Engine as _;
use base64::engine::general_purpose::URL_SAFE_NO_PAD;
use common::*;
use rand::RngExt;
use stance_document::link::{self, LINK_FORMAT, LinkError, ROTATION_STEP_RAD};
use stance_document::motion::MAX_FRAME_COUNT;
use stance_document::{AvatarReference, Document, LimbName, PostureValues, TaskKindSpec, TaskSpec};
use stance_ik::{Axes, Dof};

fn round_trip(d: &Document) -> Document {
    let text = link::encode(d);
    let back = link::decode(&text).unwrap_or_else(|e| panic!("decode failed: {e}\n{d:?}"));
    if let Err(e) = document_close(d, &back) {
        panic!("round trip differs: {e}");
    }
    // Encoding a decoded document again keeps it (the values are already on the grid).
    let again = link::decode(&link::encode(&back)).unwrap();
    if let Err(e) = document_close(&back, &again) {
        panic!("second round trip differs: {e}");
    }
    assert_eq!(again.posture, back.posture);
    back
}

fn all_kinds() -> Document {
    let mut posture = PostureValues::default();
    posture.set("humanoid_root", Dof::Ty, -0.05);
    posture.set("l_knee", Dof::Rx, 0.3);
    posture.set("l_ankle", Dof::Rz, -0.1);
    let t = |level: u32, weight: f64, active: bool, kind| TaskSpec {
        level,
        weight,
        active,
        kind,
        interval: None,
        on: None,
    };
    Document {
        // Made on an avatar before `rest` existed: the oldest formats hold it.
        rest: stance_document::PostureRest::Avatar,
        clip: None,
        avatar: AvatarReference::Url("https://example.org/models/Jin.glb?x=1#frag".to_owned()),
        posture: posture.clone(),
        tasks: vec![
            t(
                1,
                1.0,
                true,
                TaskKindSpec::Position {
                    joint: "l_radiocarpal".into(),
                    point: [0.01, -0.02, 0.0],
                    axes: Axes::XZ,
                    target: [0.25, 1.1, 0.3],
                },
            ),
            t(
                1,
                0.5,
                false,
                TaskKindSpec::Orientation {
                    joint: "skullbase".into(),
                    target: [0.1, -0.2, 0.3, 0.9],
                },
            ),
            t(
                1,
                2.0,
                true,
                TaskKindSpec::Gaze {
                    joint: "skullbase".into(),
                    axis: [0.0, 0.2, 1.0],
                    point: [0.0, 0.08, 0.1],
                    target: [0.0, 1.6, 2.0],
                },
            ),
            t(
                2,
                1.0,
                true,
                TaskKindSpec::Com {
                    axes: Axes::XZ,
                    target: [0.02, 0.0, 0.03],
                },
            ),
            t(
                4,
                0.1,
                true,
                TaskKindSpec::Posture {
                    joints: Some(vec!["l_hip".into(), "my_custom_joint".into()]),
                    reference: Some(posture),
                },
            ),
            t(
                4,
                0.1,
                true,
                TaskKindSpec::Posture {
                    joints: None,
                    reference: None,
                },
            ),
            t(
                3,
                1.0,
                true,
                TaskKindSpec::Limb {
                    limb: Some(LimbName::RightArm),
                    joints: None,
                    target: [-0.3, 1.2, 0.3],
                    swivel: Some(0.7),
                    orientation: Some([0.0, 0.0, 0.0, 1.0]),
                },
            ),
            t(
                3,
                1.0,
                true,
                TaskKindSpec::Limb {
                    limb: None,
                    joints: Some(["l_hip".into(), "l_knee".into(), "l_talocrural".into()]),
                    target: [0.1, 0.1, 0.1],
                    swivel: None,
                    orientation: None,
                },
            ),
            t(
                9,
                1.0,
                true,
                TaskKindSpec::Comfort {
                    effort: 1.0,
                    range: 0.125,
                    rula: 0.3,
                },
            ),
        ],
        motion: None,
        camera: None,
        stiffness: Default::default(),
    }
}

#[test]
fn every_task_kind_and_the_avatar_url_round_trip() {
    let d = all_kinds();
    d.validate().unwrap();
    let back = round_trip(&d);
    assert_eq!(back.avatar, d.avatar);
    assert_eq!(back.tasks.len(), 9);
    for (a, b) in d.tasks.iter().zip(&back.tasks) {
        assert_eq!(a.kind.name(), b.kind.name());
    }
    // The comfort task's weights exactly, in a format 3 link; without it, format 1.
    assert_eq!(back.tasks[8], d.tasks[8]);
    assert_eq!(frame_of(&d)[0], 3);
    let mut older = d.clone();
    older.tasks.pop();
    assert_eq!(frame_of(&older)[0], 1);
    // The default avatar and an empty document too.
    round_trip(&Document::default());
    let empty = link::encode(&Document::default());
    assert!(empty.len() < 16, "{empty}");
}

#[test]
fn random_documents_round_trip_within_the_quantisation() {
    let mut r = rng(7);
    for _ in 0..300 {
        let d = random_document(&mut r);
        d.validate().unwrap();
        round_trip(&d);
    }
}

#[test]
fn a_whole_url_or_a_hash_is_accepted() {
    let d = all_kinds();
    let f = link::encode(&d);
    for text in [
        format!("https://stance.example/editor/?a=b#{f}"),
        format!("#{f}"),
        format!("  {f}\n"),
    ] {
        assert!(document_close(&d, &link::decode(&text).unwrap()).is_ok());
    }
}

#[test]
fn a_full_loa2_posture_with_six_tasks_fits_in_600_characters() {
    let mut r = rng(2026);
    let mut longest = 0;
    let mut total = 0;
    let n = 50;
    for _ in 0..n {
        let d = Document {
            rest: Default::default(),
            clip: None,
            avatar: AvatarReference::Default,
            posture: loa2_posture(&mut r, 0.6),
            tasks: table1_tasks(&mut r),
            motion: None,
            camera: None,
            stiffness: Default::default(),
        };
        assert_eq!(d.posture.joints.len(), 71);
        let text = link::encode(&d);
        longest = longest.max(text.len());
        total += text.len();
        round_trip(&d);
    }
    let d0 = Document {
        rest: Default::default(),
        clip: None,
        avatar: AvatarReference::Default,
        posture: loa2_posture(&mut r, 0.6),
        tasks: vec![],
        motion: None,
        camera: None,
        stiffness: Default::default(),
    };
    let d1 = Document {
        tasks: table1_tasks(&mut r),
        ..Document::default()
    };
    println!(
        "posture only {} chars, tasks only {} chars",
        link::encode(&d0).len(),
        link::encode(&d1).len()
    );
    println!(
        "LOA2 (71 joints, 216 DOF, |r| <= 0.6 rad) + 6 tasks: mean {} chars, longest {longest}",
        total / n
    );
    assert!(longest < 600, "longest link {longest} characters");
}

#[test]
fn report_link_lengths_and_the_general_compressors() {
    // Not a target: lengths for other value spreads, and what deflate would give.
    let mut r = rng(11);
    // The paper's Table 1 body (~40 DOF) in a relaxed standing posture, with its 6 tasks.
    let body = stance_hanim::scenarios::loa2_body40().unwrap();
    let standing = stance_hanim::scenarios::standing_posture(&body);
    let table1 = Document {
        rest: Default::default(),
        clip: None,
        avatar: AvatarReference::Default,
        posture: PostureValues::from_posture(&body, &standing),
        tasks: table1_tasks(&mut r),
        motion: None,
        camera: None,
        stiffness: Default::default(),
    };
    let text = link::encode(&table1);
    round_trip(&table1);
    println!(
        "Table 1 document ({} joints with DOF, standing posture, 6 tasks): {} chars",
        table1.posture.joints.len(),
        text.len()
    );
    for spread in [0.2, 0.6, 1.0, std::f64::consts::PI] {
        let d = Document {
            rest: Default::default(),
            clip: None,
            avatar: AvatarReference::Default,
            posture: loa2_posture(&mut r, spread),
            tasks: table1_tasks(&mut r),
            motion: None,
            camera: None,
            stiffness: Default::default(),
        };
        let text = link::encode(&d);
        // The same values as 16-bit little-endian integers (the usual fixed-width packing),
        // deflated.
        let mut raw = Vec::new();
        for v in d.posture.joints.values() {
            for (dof, x) in v.iter() {
                let step = if dof.is_rotation() {
                    ROTATION_STEP_RAD
                } else {
                    1e-4
                };
                raw.extend_from_slice(&(((x / step).round()) as i32).to_le_bytes()[..3]);
            }
        }
        let deflated = miniz_oxide::deflate::compress_to_vec(&raw, 10);
        let json = miniz_oxide::deflate::compress_to_vec(d.to_json(false).as_bytes(), 10);
        println!(
            "spread {spread:.2} rad: link {} chars; posture alone as 24-bit ints {} B, deflated {} B \
             (would be >= {} chars); document JSON deflated {} B",
            text.len(),
            raw.len(),
            deflated.len(),
            (deflated.len() * 4).div_ceil(3),
            json.len()
        );
    }
}

fn frame_of(d: &Document) -> Vec<u8> {
    URL_SAFE_NO_PAD.decode(link::encode(d)).unwrap()
}

fn reframe(mut body: Vec<u8>) -> String {
    let crc = crc32fast::hash(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    URL_SAFE_NO_PAD.encode(body)
}

#[test]
fn broken_links_give_distinct_clear_errors() {
    let d = all_kinds();
    let good = link::encode(&d);
    assert_eq!(link::decode(""), Err(LinkError::Empty));
    assert_eq!(link::decode("https://x.org/#"), Err(LinkError::Empty));
    assert!(matches!(
        link::decode(&format!("{}!{}", &good[..5], &good[5..])),
        Err(LinkError::BadCharacter {
            character: '!',
            position: 5
        })
    ));
    let cut = &good[..good.len() / 2];
    let e = link::decode(cut).unwrap_err();
    assert!(matches!(e, LinkError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("incomplete"), "{e}");
    // One character changed.
    let mut chars: Vec<char> = good.chars().collect();
    let k = chars.len() / 2;
    chars[k] = if chars[k] == 'A' { 'B' } else { 'A' };
    let e = link::decode(&chars.into_iter().collect::<String>()).unwrap_err();
    assert_eq!(e, LinkError::Checksum);
    assert!(e.to_string().contains("damaged"));
    // A link from the future, with a valid checksum.
    let mut body = frame_of(&d);
    body.truncate(body.len() - 4);
    body[0] = LINK_FORMAT + 1;
    let e = link::decode(&reframe(body)).unwrap_err();
    assert_eq!(
        e,
        LinkError::FutureVersion {
            found: LINK_FORMAT + 1,
            supported: LINK_FORMAT
        }
    );
    assert_eq!(
        e.to_string(),
        "this link was made by a newer version of Stance (format 12); this version reads format 11"
    );
    // Valid checksum, nonsense inside.
    let e = link::decode(&reframe(vec![1, 3, 0xFF, 0xFF, 0xFF])).unwrap_err();
    assert!(matches!(e, LinkError::Malformed(_)), "{e}");
    let e = link::decode(&reframe(vec![0, 0])).unwrap_err();
    assert!(matches!(e, LinkError::Malformed(_)), "{e}");
    let too_long = "A".repeat(link::MAX_LINK_CHARS + 1);
    assert!(matches!(
        link::decode(&too_long),
        Err(LinkError::TooLong(_))
    ));
}

fn decodes_to_valid_or_errs(text: &str) {
    if let Ok(d) = link::decode(text) {
        d.validate().unwrap();
    }
}

#[test]
fn every_truncation_and_every_bit_flip_is_rejected_or_valid() {
    let mut r = rng(99);
    for round in 0..4 {
        let d = if round == 0 {
            all_kinds()
        } else {
            random_document(&mut r)
        };
        let good = link::encode(&d);
        for n in 0..good.len() {
            let e = link::decode(&good[..n]);
            assert!(e.is_err(), "prefix of {n} characters accepted");
        }
        let frame = frame_of(&d);
        for i in 0..frame.len() {
            for bit in 0..8 {
                let mut f = frame.clone();
                f[i] ^= 1 << bit;
                let text = URL_SAFE_NO_PAD.encode(&f);
                // CRC-32 detects every single-bit error.
                assert!(
                    link::decode(&text).is_err(),
                    "flip at byte {i} bit {bit} accepted"
                );
            }
        }
    }
}

#[test]
fn random_and_mutated_strings_never_panic() {
    let mut r = rng(1234);
    let alphabet: Vec<char> =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_+/=#!é "
            .chars()
            .collect();
    // STANCE_FUZZ_ROUNDS=100000 for a longer run.
    let rounds: usize = std::env::var("STANCE_FUZZ_ROUNDS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3000);
    let base = link::encode(&all_kinds());
    for i in 0..rounds {
        let text: String = if i % 2 == 0 {
            let n = r.random_range(0..300);
            (0..n)
                .map(|_| alphabet[r.random_range(0..alphabet.len())])
                .collect()
        } else {
            let mut c: Vec<char> = base.chars().collect();
            for _ in 0..r.random_range(1..5) {
                let k = r.random_range(0..c.len());
                match r.random_range(0..3) {
                    0 => c[k] = alphabet[r.random_range(0..alphabet.len())],
                    1 => {
                        c.remove(k);
                    }
                    _ => c.insert(k, alphabet[r.random_range(0..alphabet.len())]),
                }
            }
            c.into_iter().collect()
        };
        decodes_to_valid_or_errs(&text);
    }
    // Damaged payloads behind a recomputed, valid checksum reach deep into the payload decoder.
    for _ in 0..rounds / 10 {
        let d = random_document(&mut r);
        let mut body = frame_of(&d);
        body.truncate(body.len() - 4);
        for _ in 0..r.random_range(1..4) {
            let k = r.random_range(1..body.len().max(2));
            if k < body.len() {
                body[k] ^= 1 << r.random_range(0..8);
            }
        }
        decodes_to_valid_or_errs(&reframe(body));
    }
    // Random payloads behind a valid frame and checksum exercise the payload decoder itself.
    for _ in 0..rounds {
        let n = r.random_range(0..200);
        let payload: Vec<u8> = (0..n).map(|_| r.random::<u8>()).collect();
        let mut body = vec![1u8];
        let mut len = payload.len();
        loop {
            let b = (len & 0x7F) as u8;
            len >>= 7;
            if len == 0 {
                body.push(b);
                break;
            }
            body.push(b | 0x80);
        }
        body.extend_from_slice(&payload);
        decodes_to_valid_or_errs(&reframe(body));
    }
}

#[test]
fn quantisation_steps_are_well_under_a_hundredth_of_a_degree() {
    assert!(ROTATION_STEP_RAD.to_degrees() <= 0.005 + 1e-12);
    let mut d = Document::default();
    let x = 0.123_456_789;
    d.posture.set("l_shoulder", Dof::Rx, x);
    let back = link::decode(&link::encode(&d)).unwrap();
    let y = back.posture.get("l_shoulder", Dof::Rx).unwrap();
    assert!((x - y).abs().to_degrees() <= 0.0025 + 1e-12);
}

/// A document with a timeline: `keys` keys of random LOA2 postures, and a task with an
/// active interval.
fn timed_document(keys: usize) -> Document {
    let mut r = rng(77);
    let mut d = all_kinds();
    // Format 2's content only (a comfort task takes a link to format 3).
    d.tasks
        .retain(|t| !matches!(t.kind, TaskKindSpec::Comfort { .. }));
    d.tasks[0].interval = Some(stance_document::TaskInterval {
        start: 0.25,
        end: 1.0 / 3.0 + 1.0,
        ease_in: 0.1,
        ease_out: 0.4,
    });
    d.motion = Some(stance_document::MotionSection {
        frame_time: 1.0 / 120.0,
        frame_count: 4 * keys + 1,
        keys: (0..keys)
            .map(|k| stance_document::MotionKey {
                frame: 4 * k,
                posture: loa2_posture(&mut r, 0.6),
            })
            .collect(),
    });
    d
}

#[test]
fn keys_and_intervals_travel_in_a_format_2_link() {
    let d = timed_document(3);
    let text = link::encode(&d);
    assert_eq!(URL_SAFE_NO_PAD.decode(&text).unwrap()[0], 2, "format 2");
    let back = link::decode(&text).unwrap();
    document_close(&d, &back).unwrap();
    // Intervals and the frame time exactly; key postures on the quantisation grid.
    assert_eq!(back.tasks[0].interval, d.tasks[0].interval);
    assert!(back.tasks[1..].iter().all(|t| t.interval.is_none()));
    let (m, n) = (d.motion.as_ref().unwrap(), back.motion.as_ref().unwrap());
    assert_eq!(n.frame_time.to_bits(), m.frame_time.to_bits());
    assert_eq!(n.frame_count, m.frame_count);
    assert_eq!(n.keys.len(), 3);
    for (a, b) in m.keys.iter().zip(&n.keys) {
        assert_eq!(a.frame, b.frame);
        posture_close(&a.posture, &b.posture).unwrap();
    }
    // Without a timeline (and a comfort task) the link stays format 1, as older versions read
    // it.
    let mut plain = all_kinds();
    plain
        .tasks
        .retain(|t| !matches!(t.kind, TaskKindSpec::Comfort { .. }));
    assert_eq!(URL_SAFE_NO_PAD.decode(link::encode(&plain)).unwrap()[0], 1);
    println!(
        "a link with 3 LOA2 keys and an interval: {} characters (without them {})",
        text.len(),
        link::encode(&plain).len()
    );
}

/// Found by the `document` fuzz target: a key beyond the timeline's last frame (the editor
/// keeps the keys when the timeline is made shorter) is a valid document, and its link opened
/// with "a key at frame 60 of 40". A timeline or a key beyond `MAX_FRAME_COUNT` is refused by
/// the document as by the link.
#[test]
fn a_key_beyond_the_timeline_travels_in_a_link() {
    let mut d = timed_document(3);
    let motion = d.motion.as_mut().unwrap();
    motion.frame_count = motion.keys[1].frame;
    let back = round_trip(&d);
    let motion = back.motion.as_ref().unwrap();
    assert_eq!(motion.frame_count, 4);
    assert_eq!(motion.keys[2].frame, 8);
    assert_eq!(Document::from_json(&back.to_json(false)).unwrap(), back);
    for (frame_count, key) in [(MAX_FRAME_COUNT + 1, 0), (60, MAX_FRAME_COUNT)] {
        let mut far = timed_document(1);
        let motion = far.motion.as_mut().unwrap();
        motion.frame_count = frame_count;
        motion.keys[0].frame = key;
        let e = far.validate().unwrap_err().to_string();
        assert!(e.starts_with("motion.") && e.contains("10000000"), "{e}");
        let e = link::decode(&link::encode(&far)).unwrap_err();
        assert!(matches!(e, LinkError::Malformed(_)), "{e}");
    }
}

/// Found by the `link` fuzz target: a document whose payload ends in a long run of zero bytes
/// (the range coder's final carry turns a pending run of 0xFF bytes into zeros) was written
/// without all of them, more than the reader reads past the end, and its link did not open
/// ("the data ends too early").
#[test]
fn a_payload_ending_in_many_zero_bytes_opens() {
    let d = Document::from_json(ZERO_TAIL).unwrap();
    let frame = URL_SAFE_NO_PAD.decode(link::encode(&d)).unwrap();
    let payload = &frame[..frame.len() - 4];
    let zeros = payload.iter().rev().take_while(|&&b| b == 0).count();
    assert!(zeros > 0, "the payload keeps some of its zero bytes");
    round_trip(&d);
}

/// Found by the `link` fuzz target: a payload with a joint angle of 2^62 steps and more
/// (4e14 rad) opened, and written again held another angle (the writer clamps, the reader did
/// not). Quantised values beyond 2^48 steps are now refused, and within them a decoded link
/// written again holds the same values.
#[test]
fn a_number_beyond_the_quantisation_range_is_refused() {
    let fuzzed = "861b3d66a63a23c05612bf73152f31db1ac42f21f25b4a7ab0d1639520d8c71324d59c6d480037af35\
        12dfe4d5b10036fbc305e7a75e6a82240100000000000042ae42b4133ca53c9323fce8ae00000000000000\
        00000040";
    let payload: Vec<u8> = (0..fuzzed.len() / 2)
        .map(|i| u8::from_str_radix(&fuzzed[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    let mut body = vec![2, payload.len() as u8];
    body.extend_from_slice(&payload);
    let e = link::decode(&reframe(body)).unwrap_err();
    assert!(e.to_string().contains("out of range"), "{e}");
    // Far beyond the range in a document: written as the largest value, which reads back.
    let mut d = Document::default();
    d.posture.set("l_knee", Dof::Rx, 1e20);
    d.posture.set("humanoid_root", Dof::Tx, -1e20);
    let back = link::decode(&link::encode(&d)).unwrap();
    let rx = back.posture.get("l_knee", Dof::Rx).unwrap();
    assert!((rx / ROTATION_STEP_RAD - 2f64.powi(48)).abs() < 1.0, "{rx}");
    let again = link::decode(&link::encode(&back)).unwrap();
    assert_eq!(again.posture, back.posture);
}

const ZERO_TAIL: &str = r#"{"avatar":{"url":"https://example.org/avatars/jin.vrm"},
"posture":{"humanoid_root":{"tx":0.1,"ty":-0.02,"tz":0.0,"rx":0.0,"ry":0.5000368306963754,"rz":0.0},
 "l_knee":{"rx":0.3000220984178253},
 "l_shoulder":{"rx":-0.40002946455710037,"ry":0.10000736613927509,"rz":1.2000011272087014},
 "mixamorig:LeftHand":{"rz":0.20001473227855018}},
"tasks":[
 {"level":1,"kind":"position","joint":"l_talocrural","point":[0.0,0.0,0.01],"axes":"xz","target":[0.1,0.07,0.0]},
 {"level":1,"kind":"orientation","joint":"skullbase","target":[0.0,0.0,0.09949341818939234,0.9950382202392984],"active":false},
 {"level":1,"kind":"gaze","joint":"skullbase","axis":[0.0,0.0,1.0],"point":[0.0,0.08,0.1],"target":[0.0,1.6,2.0]},
 {"level":2,"kind":"direction","joint":"r_radiocarpal","axis":[1.0,0.0,0.0],"target":[0.0,-1.0,0.0]},
 {"level":2,"kind":"com","axes":"xz","target":[0.02,0.0,0.030000000000000002],"weight":0.5},
 {"level":2,"kind":"balance","support":["l_talocrural","r_talocrural"],"margin":0.030000000000000002},
 {"level":3,"kind":"limb","limb":"r_arm","target":[-0.3,1.2,0.3],"swivel":0.5000368306963754,"orientation":[0.0,0.0,0.0,1.0]},
 {"level":3,"kind":"limb","joints":["l_hip","l_knee","l_angxj"],"target":[0.5538000000000001,-0.0097,0.0],"swivel":0.3769038519681755},
 {"level":2,"kind":"limb","joints":["skullbase","l_talocalcaneonavicular","l_talocalcaneonavicular"],"target":[-0.037200000000000004,0.1973,0.7255],"swivel":0.0,"orientation":[-0.2636626098185588,0.0,-0.000043117352382429904,0.9646149627310165]}
]}"#;

#[test]
fn a_long_timeline_is_left_out_of_a_shared_link_and_says_how_long_it_would_be() {
    let short = link::encode_for_sharing(&timed_document(3));
    assert_eq!(short.keys_left_out, None);
    assert!(link::decode(&short.fragment).unwrap().motion.is_some());
    let long = timed_document(200);
    let shared = link::encode_for_sharing(&long);
    let would_be = shared.keys_left_out.expect("200 LOA2 keys do not fit");
    assert!(would_be > link::MAX_SHARE_CHARS);
    assert!(shared.fragment.len() <= link::MAX_SHARE_CHARS);
    let back = link::decode(&shared.fragment).unwrap();
    assert!(back.motion.is_none());
    // The intervals stay: they are small.
    assert_eq!(back.tasks[0].interval, long.tasks[0].interval);
}

/// Fingers posed by the hand presets (every finger DOF away from 0) come back from a link
/// within half a quantisation step, on the LOA 2 and LOA 4 bodies.
#[test]
fn posed_fingers_round_trip_within_the_quantisation() {
    use stance_hanim::hands::{HandPreset, HandRig};
    use stance_hanim::{LevelOfArticulation, Side, SkeletonOptions, default_skeleton};
    for loa in [LevelOfArticulation::Loa2, LevelOfArticulation::Loa4] {
        let body = default_skeleton(&SkeletonOptions {
            loa,
            ..SkeletonOptions::default()
        })
        .unwrap();
        let s = &body.skeleton;
        let mut posture = stance_ik::Posture::rest(s);
        let mut finger_dofs = Vec::new();
        for (side, preset) in [
            (Side::Left, HandPreset::Fist),
            (Side::Right, HandPreset::Pinch),
        ] {
            let rig = HandRig::new(s, side).unwrap();
            for (dof, value) in rig.preset(s, preset) {
                posture.values_mut()[dof] = value;
                finger_dofs.push(dof);
            }
        }
        let flexed = finger_dofs
            .iter()
            .filter(|&&dof| posture.values()[dof].abs() > 0.1)
            .count();
        assert!(flexed >= 25, "{flexed} finger DOF flexed");
        let document = Document {
            posture: PostureValues::from_posture(s, &posture),
            ..Document::default()
        };
        let back = round_trip(&document).posture.to_posture(s).unwrap();
        for dof in finger_dofs {
            let (sent, got) = (posture.values()[dof], back.values()[dof]);
            assert!(
                (sent - got).abs() <= ROTATION_STEP_RAD / 2.0 + 1e-12,
                "{loa:?} {}: {sent} sent, {got} read",
                s.dof_name(dof)
            );
        }
    }
}

/// What a link's values are relative to travels from format 5: a document made on an avatar
/// in the standard pose (what the editor writes) takes format 5; one made on an avatar before
/// (its own rest) keeps the oldest format that holds it and opens as such, as a format 1-4
/// link on an avatar does; on the mannequin both rests are one and older formats hold it.
#[test]
fn the_rest_of_the_values_travels_in_a_format_5_link() {
    use stance_document::PostureRest;
    let mut d = Document::from_json(
        r#"{"avatar": {"url": "https://example.org/a.vrm"}, "rest": "standard",
            "posture": {"l_elbow": {"rx": -0.5}}}"#,
    )
    .unwrap();
    assert_eq!(d.rest, PostureRest::Standard);
    let text = link::encode(&d);
    assert_eq!(URL_SAFE_NO_PAD.decode(&text).unwrap()[0], 5);
    assert_eq!(link::decode(&text).unwrap().rest, PostureRest::Standard);
    d.rest = PostureRest::Avatar;
    let text = link::encode(&d);
    assert_eq!(URL_SAFE_NO_PAD.decode(&text).unwrap()[0], 1);
    assert_eq!(link::decode(&text).unwrap().rest, PostureRest::Avatar);
    d.avatar = AvatarReference::Default;
    d.rest = PostureRest::Standard;
    let text = link::encode(&d);
    assert_eq!(URL_SAFE_NO_PAD.decode(&text).unwrap()[0], 1);
    assert_eq!(link::decode(&text).unwrap().rest, PostureRest::Standard);
    // In JSON: absent with an avatar URL is the avatar's own rest; a wrong word is named.
    let old = Document::from_json(r#"{"avatar": {"url": "https://example.org/a.vrm"}}"#).unwrap();
    assert_eq!(old.rest, PostureRest::Avatar);
    assert_eq!(
        Document::from_json("{}").unwrap().rest,
        PostureRest::Standard
    );
    let e = Document::from_json(r#"{"rest": "t-pose"}"#).unwrap_err();
    assert!(e.to_string().contains("rest"), "{e}");
}

/// Catches a line or plane task lost, misread or rounded beyond the quantisation in a link,
/// written in a format older readers take for their own (they must say "newer version"), or a
/// format 6 link that smuggles one in.
#[test]
fn line_and_plane_tasks_travel_in_a_format_7_link() {
    let mut r = rng(17);
    for _ in 0..50 {
        let mut d = random_document(&mut r);
        for _ in 0..r.random_range(1..4) {
            let point = if r.random_bool(0.5) {
                [0.0; 3]
            } else {
                [uniform(&mut r, -0.2, 0.2), uniform(&mut r, -0.2, 0.2), 0.01]
            };
            let vector = [
                uniform(&mut r, -1.0, 1.0),
                uniform(&mut r, -1.0, 1.0),
                uniform(&mut r, 0.1, 1.0),
            ];
            let origin = [
                uniform(&mut r, -2.0, 2.0),
                uniform(&mut r, 0.0, 2.0),
                uniform(&mut r, -2.0, 2.0),
            ];
            let kind = if r.random_bool(0.5) {
                TaskKindSpec::Line {
                    joint: "l_radiocarpal".into(),
                    point,
                    origin,
                    direction: vector,
                }
            } else {
                TaskKindSpec::Plane {
                    joint: "my_custom_joint".into(),
                    point,
                    origin,
                    normal: if r.random_bool(0.5) {
                        [0.0, 1.0, 0.0]
                    } else {
                        vector
                    },
                    above: r.random_bool(0.5),
                }
            };
            d.tasks.push(TaskSpec::new(kind));
        }
        d.validate().unwrap();
        assert_eq!(frame_of(&d)[0], 7);
        round_trip(&d);
    }
    // The kind symbols of the two kinds in an older format are refused, not misread.
    let mut d = Document::default();
    d.tasks.push(TaskSpec::new(TaskKindSpec::Line {
        joint: "l_radiocarpal".into(),
        point: [0.0; 3],
        origin: [0.0, 1.0, 0.0],
        direction: [0.0, 0.0, 1.0],
    }));
    let mut frame = frame_of(&d);
    frame[0] = 6;
    let body_len = frame.len() - 4;
    let text = reframe(frame[..body_len].to_vec());
    match link::decode(&text) {
        Err(LinkError::Malformed(m)) => assert!(m.contains("unknown task kind 9"), "{m}"),
        other => panic!("{other:?}"),
    }
}

/// Catches a collision task lost or garbled on the way through a link, or written in a
/// format older readers would misread: its margin (to 0.1 mm) and both switches come back,
/// in a format 8 link; the same payload framed as format 6 is refused (format 6 has no
/// collision kind), and the document without it is written as before.
#[test]
fn a_collision_task_travels_in_a_format_8_link() {
    let mut d = all_kinds();
    let mut collision = TaskSpec::new(TaskKindSpec::Collision {
        margin: 0.0137,
        self_collision: false,
        floor: true,
    });
    collision.level = 2;
    d.tasks.push(collision);
    d.validate().unwrap();
    let back = round_trip(&d);
    let Some(TaskKindSpec::Collision {
        margin,
        self_collision,
        floor,
    }) = back.tasks.last().map(|t| t.kind.clone())
    else {
        panic!("no collision task: {:?}", back.tasks.last());
    };
    assert!((margin - 0.0137).abs() < 1e-9, "{margin}");
    assert!(!self_collision && floor);
    assert_eq!(back.tasks.last().map(|t| t.level), Some(2));
    let frame = frame_of(&d);
    assert_eq!(frame[0], 8);
    let mut body = frame;
    body.truncate(body.len() - 4);
    body[0] = 6;
    assert!(matches!(
        link::decode(&reframe(body)),
        Err(LinkError::Malformed(_))
    ));
    let mut without = d.clone();
    without.tasks.pop();
    assert_eq!(frame_of(&without)[0], 3);
}
